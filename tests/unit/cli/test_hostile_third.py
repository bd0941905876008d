"""Issue 39, the third hostile campaign: each class through the command line and through the API.

Every case here fails before any fit runs (or runs one tiny least-squares fit), so they are quick.
The API's side of the hostile values is fuzzed in ``tests/fuzz/test_public_api.py``.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import rczone
from rczone.cli.compile_notice import NOTICE
from rczone.cli.main import main
from rczone.errors import RczoneError
from tests.unit.cli.test_hostile_successes import as_a_terminal_starts_it

POSIX = pytest.mark.skipif(os.name == "nt", reason="links, signals and processes as on POSIX")

TITE = """name = "room"
boundaries = ["To"]
outputs = ["Ti"]
resistors = [["Ti", "Te", "Rie"], ["Te", "To", "Rea"]]
[nodes]
Ti = "Ci"
Te = "Ce"
[parameters]
Ci = { value = 1e6, unit = "J/K" }
Ce = { value = 1e7, unit = "J/K" }
Rie = { value = 0.002, unit = "K/W" }
Rea = { value = 0.02, unit = "K/W" }
"""


def zone_frame(n: int = 120) -> pd.DataFrame:
    t = 1.3e9 + np.arange(n) * 300.0
    return pd.DataFrame({"time": t, "Ti": 21 + np.sin(t / 5e3), "To": 10 + np.cos(t / 7e3)})


@pytest.fixture
def data(tmp_path: Path) -> Path:
    zone_frame().to_csv(tmp_path / "z.csv", index=False)
    return tmp_path / "z.csv"


def one_line_exit_2(args: list[str], capsys, pattern: str) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if not ln.startswith("warning: ") and ln != NOTICE]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    assert re.search(pattern, err), err
    return err


def saved(tmp_path: Path, **noise: float) -> Path:
    from rczone.models import load_model

    path = tmp_path / "m.json"
    load_model("TiTe").with_values({}, noise, method="ml").save(path)
    return path


# ---- tracebacks ---------------------------------------------------------------------------------


@pytest.mark.parametrize("rooms", ["²", "①", "٣"])
def test_models_generate_counts_only_ascii_digits(capsys, rooms):
    one_line_exit_2(["models", "generate", "--rooms", rooms], capsys, r"room name .*letters and digits")


def test_mcmc_without_warm_up_is_one_line_before_sampling(data, capsys):
    args = ["fit", str(data), "--model", "TiTe", "--method", "mcmc", "--draws", "10", "--tune", "0"]
    one_line_exit_2([*args, "--chains", "1"], capsys, r"option tune must be an integer from 10")


def test_a_sampler_panic_is_one_line(monkeypatch):
    import nutpie

    from rczone.estimation import sampling
    from rczone.estimation.methods.mcmc import McmcOptions

    class PanicException(BaseException):  # as pyo3 raises a Rust panic
        pass

    def panic(*args, **kwargs):
        raise PanicException("Poisond sampler state mutex: PoisonError { .. }")

    monkeypatch.setattr(nutpie, "sample", panic)
    monkeypatch.setattr(
        "nutpie.compiled_pyfunc.from_pyfunc", lambda *a, **k: None, raising=False
    )  # the model is never sampled
    with pytest.raises(RczoneError, match=r"the sampler \(nutpie .*\) failed: Poisond"):
        sampling._run_nuts(None, np.zeros((1, 2)), McmcOptions(draws=10, tune=10, chains=1), 0)


@pytest.mark.parametrize(
    "call",
    [
        lambda f: rczone.fit("TiTe", f, seed=-1, checks=False),
        lambda f: rczone.diagnose("TiTe", f, seed=-5),
        lambda f: rczone.select_models(["Ti", "TiTe"], f, seed=-1),
        lambda f: rczone.VirtualNight("autumn", seed=-1),
    ],
)
def test_negative_seeds_through_the_api(call):
    with pytest.raises(RczoneError, match=r"seed must be an integer from 0 to 2\*\*63 - 1"):
        call(zone_frame())


def test_a_column_of_text_given_to_fit_names_the_column():
    frame = zone_frame()
    frame["To"] = "x"
    with pytest.raises(rczone.DataError, match=r"column 'To' holds .* not numbers"):
        rczone.fit("TiTe", frame, checks=False)


# ---- hangs --------------------------------------------------------------------------------------

PERIODIC = """
[[disturbance]]
name = "d"
kind = "periodic"
to = "Ti"
magnitude = 10.0
length_scale = 3600.0
period = {period}
"""


@pytest.mark.parametrize("period", ["1e-300", "299.0"])
def test_a_period_below_the_sampling_interval_is_refused(tmp_path, data, capsys, period):
    (tmp_path / "m.toml").write_text(TITE + PERIODIC.format(period=period))
    one_line_exit_2(
        ["fit", str(data), "--model", str(tmp_path / "m.toml")],
        capsys,
        r"shorter than the sampling interval 300 s",
    )
    with pytest.raises(RczoneError, match="shorter than the sampling interval"):
        rczone.simulate(tmp_path / "m.toml", zone_frame())


@pytest.mark.parametrize(
    ("kw", "pattern"),
    [
        ({"length_scale": 0}, r"length_scale must be > 0 s, got 0"),
        ({"length_scale": math.inf}, r"length_scale must be > 0 s"),
        ({"length_scale": 60.0, "magnitude": -1.0}, r"magnitude must be >= 0 W"),
    ],
)
def test_latent_force_refuses_what_a_model_file_refuses(kw, pattern):
    with pytest.raises(RczoneError, match=pattern):
        rczone.LatentForce("d", "matern32", "Ti", **{"magnitude": 1.0, **kw})


# ---- wrong successes ----------------------------------------------------------------------------


@pytest.mark.parametrize("value", [math.nan, math.inf, 1e308])
def test_simulate_refuses_a_non_finite_or_huge_initial_state(value):
    with pytest.raises(RczoneError, match=r"x0 of Ti must be a finite number"):
        rczone.simulate("TiTe", zone_frame(), x0={"Ti": value})


def test_predict_steps_past_the_data_through_the_api(tmp_path):
    with pytest.raises(RczoneError, match=r"steps 1000000000000 is not less than the 120 samples"):
        rczone.predict(saved(tmp_path, sigma_v=0.1), zone_frame(), steps=10**12)


@pytest.mark.parametrize("horizons", ["5000", "100000000", "1,120,open"])
def test_predict_horizons_longer_than_the_data(tmp_path, data, capsys, horizons):
    model = saved(tmp_path, sigma_v=0.1)
    one_line_exit_2(
        ["predict", str(model), str(data), "--horizons", horizons],
        capsys,
        r"horizon \d+ is not less than the",
    )


NAN_WORD = re.compile(r"\bnan\b", re.IGNORECASE)


def test_a_prediction_without_a_band_carries_no_nan_through_the_api():
    """A model without noise levels or standard errors has no band: its coverage is None, with a note."""
    pred = rczone.predict("TiTe", zone_frame())
    assert not pred.has_band and pred.coverage is None
    text = pred.summary()
    assert "no 2-sigma band" in text and not NAN_WORD.search(text), text
    d = pred.to_dict()
    assert d["coverage_2sigma"] is None and d["coverage_note"].startswith("no 2-sigma band")
    assert all(math.isfinite(v) for v in (d["rmse_K"], d["max_error_K"]))
    frame = pred.to_frame()
    assert not [c for c in frame.columns if c.endswith(("_lower", "_upper", "_sd_noise"))]
    assert np.isfinite(frame[["Ti_measured", "Ti_predicted"]].to_numpy(float)).all()
    with pytest.raises(RczoneError, match="no 2-sigma band"):
        pred.summary_frame()
    scores = rczone.score_horizons("TiTe", zone_frame(), horizons="open", baselines=True)
    table = scores.to_frame()
    assert table.coverage_2sigma.isna().all()  # missing (pd.NA), not a number
    assert not [c for c in table.columns if table[c].dtype == float and table[c].isna().any()]
    assert "no band" in scores.summary() and not NAN_WORD.search(scores.summary())
    assert all(r["coverage_2sigma"] is None for r in scores.to_dict()["scores"])


def test_a_prediction_without_a_band_prints_no_nan_on_the_command_line(tmp_path, data, capsys):
    out = tmp_path / "p.json"
    assert main(["predict", "TiTe", str(data), "--json", str(out), "-o", str(tmp_path / "s.csv")]) == 0
    printed = capsys.readouterr().out
    assert "no 2-sigma band" in printed and not NAN_WORD.search(printed), printed
    d = json.loads(out.read_text())
    assert d["coverage_2sigma"] is None and "no noise levels" in d["coverage_note"]
    series = pd.read_csv(tmp_path / "s.csv")
    assert "Ti_lower" not in series and series["Ti_predicted"].notna().all()
    assert main(["predict", "TiTe", str(data), "--horizons", "open", "--baselines"]) == 0
    printed = capsys.readouterr().out
    assert "no band" in printed and not NAN_WORD.search(printed), printed


def test_a_prediction_that_scores_no_sample_is_one_line(tmp_path, data, capsys):
    frame = zone_frame()
    frame.loc[60:, "Ti"] = np.nan  # measured only in the warm-up
    with pytest.raises(rczone.DataError, match=r"scores no sample of 'Ti'"):
        rczone.predict("TiTe", frame, warmup="5h")
    frame.to_csv(tmp_path / "gappy.csv", index=False)
    one_line_exit_2(
        ["predict", "TiTe", str(tmp_path / "gappy.csv"), "--warmup", "5h"],
        capsys,
        r"scores no sample of 'Ti'",
    )


def test_a_gap_of_1e15_s_in_time_is_refused():
    frame = zone_frame()
    frame.loc[60:, "time"] += 1e15
    with pytest.raises(rczone.DataError, match=r"more than a century"):
        rczone.simulate("TiTe", frame)


def test_select_prints_one_line_when_it_fails(data, capsys, monkeypatch):
    import rczone.selection.compare as compare

    def failing(zms, frame, *args, progress=None, **kwargs):
        progress(zms[0].label)  # a candidate fitted, then the next fails
        raise rczone.DataError("the second candidate cannot be fitted")

    monkeypatch.setattr(compare, "select_models", failing)
    one_line_exit_2(["select", str(data), "--model", "Ti", "--model", "TiTe"], capsys, "second candidate")


# ---- escape -------------------------------------------------------------------------------------


@POSIX
def test_a_link_planted_at_a_report_subfolder_is_refused(tmp_path):
    from rczone.errors import OutputError
    from rczone.report.html import Report

    (tmp_path / "outer").mkdir()
    (tmp_path / "rep").mkdir()
    (tmp_path / "rep" / "holdout").symlink_to("../outer")
    report = Report("held out")
    report.figures["horizons"] = b"png"
    with pytest.raises(OutputError, match="symbolic link"):
        report.write(tmp_path / "rep", under="holdout")
    assert list((tmp_path / "outer").iterdir()) == []


@POSIX
@pytest.mark.parametrize("command", ["fit", "select"])
def test_holdout_report_does_not_follow_a_link_planted_at_its_subfolder(tmp_path, data, capsys, command):
    (tmp_path / "outer").mkdir()
    rep = tmp_path / "rep"
    rep.mkdir()
    (rep / "holdout").symlink_to("../outer")
    models = (
        ["--model", "TiTe", "--method", "ls"] if command == "fit" else ["--model", "Ti", "--model", "TiTe"]
    )
    args = [command, str(data), *models, "--starts", "1", "--holdout", "0.25"]
    one_line_exit_2([*args, "--report", str(rep)], capsys, r"holdout'? is a symbolic link")
    assert list((tmp_path / "outer").iterdir()) == []
    assert (rep / "holdout").is_symlink() and not (rep / "report.html").exists()  # all or nothing


@POSIX
@pytest.mark.parametrize("sub", ["parts", "stream"])
def test_fit_many_does_not_follow_a_link_planted_at_its_subfolders(tmp_path, capsys, sub):
    """The other subfolders rczone names itself in an output folder: fit-many's ``parts`` and ``stream``."""
    frame = zone_frame()
    frame.to_csv(tmp_path / "a.csv", index=False)
    (tmp_path / "m.toml").write_text(
        'methods = ["ls"]\nn_starts = 1\ndiagnose = false\nmodel = "TiTe"\n'
        '[[zone]]\nid = "a"\ndata = "a.csv"\n'
    )
    (tmp_path / "outer").mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / sub).symlink_to("../outer")
    args = ["fit-many", str(tmp_path / "m.toml"), "--out", str(out), "--backend", "processes"]
    one_line_exit_2([*args, "--workers", "1"], capsys, rf"{sub}'? is a symbolic link")
    assert list((tmp_path / "outer").iterdir()) == []


# ---- left from the second campaign ---------------------------------------------------------------


@pytest.mark.parametrize("steps", [[], ["--steps", "1"]])
def test_predict_with_zero_noise_is_one_line(tmp_path, data, capsys, steps):
    one_line_exit_2(
        ["predict", str(saved(tmp_path, sigma_v=0.0)), str(data), *steps],
        capsys,
        r"cannot use the noise levels of model 'm\.json' \(sigma_v = 0\)",
    )


def test_a_huge_noise_level_is_refused_when_the_model_is_made():
    from rczone.models import load_model

    with pytest.raises(RczoneError, match=r"noise level 'sigma_v' = 1e\+300"):
        load_model("TiTe").with_values({}, {"sigma_v": 1e300}, method="ml")


@pytest.mark.parametrize(("const", "pattern"), [("To=1e300", r"-273\.15 to 10000, got 1e\+300")])
def test_a_huge_constant_is_one_line(data, capsys, const, pattern):
    one_line_exit_2(
        ["fit", str(data), "--model", "TiTe", "--const", const], capsys, r"constant To must be .*" + pattern
    )
    with pytest.raises(RczoneError, match=pattern):
        rczone.simulate("TiTe", zone_frame(), constants={"To": 1e300})


def test_inputs_missing_at_the_head_flag_the_fit_naming_the_channel_and_times():
    frame = zone_frame(200)
    frame.loc[:59, "To"] = np.nan
    cal = rczone.fit("TiTe", frame, method="ls", n_starts=1, checks=False)
    assert cal.exit_code == 3
    reason = next(r for r in cal.verdict.reasons if "fitted on 140 of 200" in r)
    assert "To is missing at 60 sample(s) between t = 1300000000 s and 1300017700 s" in reason


def test_a_short_drop_is_a_note_not_a_flag():
    from rczone.results.verdict import dropped_samples

    assert dropped_samples({"samples": 195, "of": 200, "fraction": 0.975}) is None
    assert "fitted on 100 of 200" in dropped_samples({"samples": 100, "of": 200, "fraction": 0.5})


@pytest.mark.parametrize(
    ("extra", "pattern"),
    [
        ('[columns]\nTi = { value = 21 }\nTo = "To"\n', r"the measured Ti is 21 at every sample"),
        ('[time]\nend = "today"\n[columns]\nTi = "Ti"\nTo = "To"\n', r"end = 'today' changes with the day"),
        ('[time]\nstart = "Now"\n[columns]\nTi = "Ti"\nTo = "To"\n', r"start = 'Now' changes with the day"),
    ],
)
def test_column_maps_that_fit_nothing_or_change_with_the_day(tmp_path, data, capsys, extra, pattern):
    (tmp_path / "map.toml").write_text(extra)
    one_line_exit_2(
        ["fit", str(data), "--model", "TiTe", "--columns", str(tmp_path / "map.toml")], capsys, pattern
    )


@pytest.mark.parametrize(
    ("zone", "pattern"),
    [
        ('data = "C"\nfree = ["Cw", "Rxx"]', r"zone 2 \(b\): unknown free parameter 'Rxx'"),
        ('virtual = { season = "autumn", seed = -3 }', r"zone 2 \(b\): seed must be an integer from 0"),
    ],
)
def test_a_manifest_is_validated_whole_before_anything_runs(tmp_path, capsys, zone, pattern):
    (tmp_path / "m.toml").write_text(
        f'methods = ["ls"]\nn_starts = 1\n[[zone]]\nid = "a"\ndata = "C"\n[[zone]]\nid = "b"\n{zone}\n'
    )
    one_line_exit_2(["fit-many", str(tmp_path / "m.toml"), "--out", str(tmp_path / "out")], capsys, pattern)
    assert not (tmp_path / "out" / "results").exists()


# The coordinator's pid is taken before the fork, as the runner passes it (initargs=(os.getpid(),)):
# read in the child with os.getppid(), it would name the reaper if the coordinator died first. The
# worker says when it is watching, so the kill cannot come before the watch is in place.
WATCHED = """
import os, sys, time
from rczone.batch.runner import _leave_ctrl_c_to_the_parent
parent = os.getpid()
r, w = os.pipe()
child = os.fork()
if child == 0:
    _leave_ctrl_c_to_the_parent(parent)
    os.write(w, b"x")
    time.sleep(60)
    os._exit(0)
os.read(r, 1)
print(child, flush=True)
time.sleep(60)
"""


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
@POSIX
def test_a_worker_ends_with_its_coordinator_killed_outright(tmp_path):
    # the coordinator (the middle process) forks a worker, then is killed with SIGKILL: no handler runs
    middle = subprocess.Popen([sys.executable, "-c", WATCHED], stdout=subprocess.PIPE, text=True, env=_env())
    worker = int(middle.stdout.readline())
    middle.kill()
    middle.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and _alive(worker):
        time.sleep(0.1)
    assert not _alive(worker)


def _env() -> dict:
    src = str(Path(rczone.__file__).resolve().parents[1])
    return {**os.environ, "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(") ")[1][0] != "Z"
    except FileNotFoundError:
        return False
    except OSError:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        return True


def test_a_fit_that_holds_every_r_and_c_says_it_is_an_evaluation():
    fixed = dict.fromkeys(["Ci", "Ce", "Rie", "Rea"])
    cal = rczone.fit("TiTe", zone_frame(), fixed=fixed, n_starts=1, checks=False)
    assert set(cal.result.parameters) <= {"sigma_v", "sigma_w_Ti"}
    assert any("evaluation of the model at its values" in n for n in cal.verdict.notes)


TERMINATED = """
import os, signal, sys
from rczone.cli.interrupt import noting_ctrl_c
with noting_ctrl_c() as ctrl_c:
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        signal.pause()
    except KeyboardInterrupt:
        sys.exit(130 if ctrl_c() else 1)
sys.exit(0)
"""


@POSIX
def test_sigterm_ends_a_command_as_ctrl_c_does():
    done = subprocess.run(
        [sys.executable, "-c", TERMINATED],
        env=_env(),
        timeout=120,
        capture_output=True,
        preexec_fn=as_a_terminal_starts_it,
    )
    assert done.returncode == 130, done.stderr


# ---- each class through the side the tests above do not take (issue 39: "through the CLI and the API")


def test_control_test_values_through_the_api():
    from rczone.control.virtualplant import VirtualPlant

    for days in (1e-9, 0.0001, math.nan, True):
        with pytest.raises(RczoneError, match="days must be"):
            VirtualPlant("summer", days=days)
    with pytest.raises(RczoneError, match=r"seed must be an integer from 0"):
        VirtualPlant("summer", days=0.1, seed=-1)


def test_mcmc_without_warm_up_through_the_api():
    with pytest.raises(RczoneError, match=r"tune must be an integer from 10"):
        rczone.fit("TiTe", zone_frame(), method="mcmc", options={"draws": 10, "tune": 0, "chains": 1})


@pytest.mark.parametrize(
    "args",
    [
        ["fit", "{data}", "--model", "TiTe", "--seed", "-1"],
        ["diagnose", "{data}", "--model", "TiTe", "--seed", "-5"],
        ["select", "{data}", "--model", "Ti", "--model", "TiTe", "--seed", "-1"],
    ],
)
def test_negative_seeds_through_the_command_line(data, capsys, args):
    one_line_exit_2([a.format(data=data) for a in args], capsys, r"seed must be an integer")


@pytest.mark.parametrize("rooms", [True, 2.5, math.nan, "²", ["²"], ["1", 2]])
def test_multizone_room_counts_through_the_api(rooms):
    from rczone.models.multizone import multizone

    with pytest.raises(RczoneError, match=r"room"):
        multizone(rooms)


def test_a_column_of_text_through_the_command_line(tmp_path, capsys):
    frame = zone_frame()
    frame["To"] = "x"
    frame.to_csv(tmp_path / "text.csv", index=False)
    one_line_exit_2(["fit", str(tmp_path / "text.csv"), "--model", "TiTe"], capsys, r"'To'")


def test_predict_steps_past_the_data_through_the_command_line(tmp_path, data, capsys):
    model = saved(tmp_path, sigma_v=0.1)
    one_line_exit_2(
        ["predict", str(model), str(data), "--steps", str(10**12)], capsys, r"steps .* not less than the"
    )


@pytest.mark.parametrize("horizons", [[5000], [10**8], [1, 120, "open"]])
def test_predict_horizons_longer_than_the_data_through_the_api(tmp_path, horizons):
    with pytest.raises(RczoneError, match=r"horizon \d+ is not less than the"):
        rczone.score_horizons(saved(tmp_path, sigma_v=0.1), zone_frame(), horizons=horizons)


def test_a_fit_that_holds_every_r_and_c_through_the_command_line(data, capsys):
    fix = ["--fix", "Ci", "--fix", "Ce", "--fix", "Rie", "--fix", "Rea"]
    assert main(["fit", str(data), "--model", "TiTe", "--starts", "1", *fix]) in (0, 3)
    out = " ".join(capsys.readouterr().out.split())  # the console wraps at its width
    assert "evaluation of the model at its values" in out


def test_a_gap_of_1e15_s_through_the_command_line(tmp_path, capsys):
    frame = zone_frame()
    frame.loc[60:, "time"] += 1e15
    frame.to_csv(tmp_path / "gap.csv", index=False)
    one_line_exit_2(
        ["fit", str(tmp_path / "gap.csv"), "--model", "TiTe"],
        capsys,
        r"more than a century|outside the years",
    )


def test_a_latent_force_of_zero_length_scale_in_a_model_file(tmp_path, data, capsys):
    force = (
        '\n[[disturbance]]\nname = "d"\nkind = "matern32"\nto = "Ti"\nmagnitude = 1.0\nlength_scale = 0.0\n'
    )
    (tmp_path / "m.toml").write_text(TITE + force)
    one_line_exit_2(["fit", str(data), "--model", str(tmp_path / "m.toml")], capsys, r"length_scale")


def test_predict_with_zero_noise_through_the_api(tmp_path):
    for steps in (None, 1):
        with pytest.raises(RczoneError, match=r"cannot use the noise levels of model 'm\.json'"):
            rczone.predict(saved(tmp_path, sigma_v=0.0), zone_frame(), steps=steps)


def test_inputs_missing_at_the_head_through_the_command_line(tmp_path, capsys):
    frame = zone_frame(200)
    frame.loc[:59, "To"] = np.nan
    frame.to_csv(tmp_path / "gappy.csv", index=False)
    args = ["fit", str(tmp_path / "gappy.csv"), "--model", "TiTe", "--method", "ls", "--starts", "1"]
    assert main(args) == 3
    assert "fitted on 140 of 200" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("extra", "pattern"),
    [
        ('[columns]\nTi = { value = 21 }\nTo = "To"\n', r"the measured Ti is 21 at every sample"),
        ('[time]\nend = "today"\n[columns]\nTi = "Ti"\nTo = "To"\n', r"end = 'today' changes with the day"),
    ],
)
def test_column_maps_that_fit_nothing_or_change_with_the_day_through_the_api(tmp_path, data, extra, pattern):
    (tmp_path / "map.toml").write_text(extra)
    with pytest.raises(RczoneError, match=pattern):
        rczone.fit("TiTe", data, columns=tmp_path / "map.toml", checks=False)


def test_a_manifest_is_validated_whole_through_the_api(tmp_path):
    from rczone.batch import read_manifest

    (tmp_path / "m.toml").write_text(
        'methods = ["ls"]\n[[zone]]\nid = "a"\ndata = "C"\n[[zone]]\nid = "b"\ndata = "C"\nfree = ["Cw", "Rxx"]\n'
    )
    with pytest.raises(RczoneError, match=r"zone 2 \(b\): unknown free parameter 'Rxx'"):
        read_manifest(tmp_path / "m.toml")


def test_scores_per_horizon_check_the_measurements_as_predict_does(tmp_path, capsys):
    """Found by the long fuzz round: a measured 1e308 degC started an open loop whose scores were inf."""
    frame = zone_frame()
    frame.loc[0, "Ti"] = 1e308
    with pytest.raises(RczoneError, match=r"column 'Ti' \(temperature\) is 1e\+308 at sample 1"):
        rczone.score_horizons("TiTe", frame, horizons="open", baselines=True)
    frame.to_csv(tmp_path / "hot.csv", index=False)
    one_line_exit_2(
        ["predict", "TiTe", str(tmp_path / "hot.csv"), "--horizons", "open"], capsys, r"'Ti'.*1e\+308"
    )


def test_a_huge_noise_level_in_a_saved_model_through_the_command_line(tmp_path, data, capsys):
    path = saved(tmp_path, sigma_v=0.1)
    doc = json.loads(path.read_text())
    doc["noise"]["sigma_v"] = 1e300  # edited by hand: a model file is untrusted
    path.write_text(json.dumps(doc))
    one_line_exit_2(
        ["predict", str(path), str(data), "--steps", "1"], capsys, r"noise level 'sigma_v' = 1e\+300"
    )
