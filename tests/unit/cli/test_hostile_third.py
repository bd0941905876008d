"""Issue 39, the third hostile campaign: each class through the command line and through the API.

Every case here fails before any fit runs (or runs one tiny least-squares fit), so they are quick.
The API's side of the hostile values is fuzzed in ``tests/fuzz/test_public_api.py``.
"""

from __future__ import annotations

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
from rczone.cli.main import main
from rczone.errors import RczoneError

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
    lines = [ln for ln in err.splitlines() if not ln.startswith("warning: ")]
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
    done = subprocess.run([sys.executable, "-c", TERMINATED], env=_env(), timeout=120, capture_output=True)
    assert done.returncode == 130, done.stderr
