"""Issue 25, the wrong successes: what was accepted in silence is now said, or refused with exit 2.

Data dropped without a word, ``--steps`` past the data, names that collide with reserved columns or
name nothing, two Unicode forms of one name, partial outputs on exit 2, and Ctrl-C.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from rczone.cli.main import main
from tests.unit.cli.test_hostile_tracebacks import model_text, one_line_exit_2, zone_frame


@pytest.fixture
def data(tmp_path: Path) -> Path:
    zone_frame().to_csv(tmp_path / "z.csv", index=False)
    return tmp_path / "z.csv"


# ---- data silently dropped -------------------------------------------------------------------------


def test_inputs_with_a_nan_every_50_rows_are_refused_naming_the_fraction(tmp_path, capsys):
    frame = zone_frame(700)
    frame.loc[frame.index % 50 == 25, "To"] = np.nan
    frame.to_csv(tmp_path / "z.csv", index=False)
    one_line_exit_2(
        ["fit", str(tmp_path / "z.csv"), "--model", "TiTe", "--method", "ls", "--starts", "1"],
        capsys,
        r"only 49 of 700 samples \(7%\) .* less than the 50% .*MIN_USED_FRACTION",
    )


def test_a_fit_on_part_of_the_data_says_how_much_in_console_and_json(tmp_path, capsys):
    frame = zone_frame(200)
    frame.loc[frame.index < 40, "To"] = np.nan
    frame.to_csv(tmp_path / "z.csv", index=False)
    out = tmp_path / "fit.json"
    code = main(
        [
            "fit",
            str(tmp_path / "z.csv"),
            "--model",
            "TiTe",
            "--method",
            "ls",
            "--starts",
            "1",
            "--json",
            str(out),
        ]
    )
    assert code in (0, 3)
    assert "fitted on 160 of 200 samples (80%)" in capsys.readouterr().out
    used = json.loads(out.read_text())["data_used"]
    assert (used["samples"], used["of"]) == (160, 200) and used["fraction"] == pytest.approx(0.8)


# ---- predict --steps --------------------------------------------------------------------------------


@pytest.mark.parametrize("steps", ["120", "1000000000"])
def test_predict_steps_at_or_past_the_samples(tmp_path, data, capsys, steps):
    from rczone.models import load_model

    load_model("TiTe").with_values({}, {"sigma_v": 0.1}, method="ml").save(tmp_path / "m.json")
    one_line_exit_2(
        ["predict", str(tmp_path / "m.json"), str(data), "--steps", steps],
        capsys,
        r"--steps .* not less than the 120 samples",
    )


# ---- names ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("edit", "pattern"),
    [
        (lambda t: t.replace('"Te"', '"time"').replace("Te = ", "time = "), r"'time' is reserved"),
        (
            lambda t: t.replace('boundaries = ["To"]', 'boundaries = ["time"]').replace(
                '"To", "Rea"', '"time", "Rea"'
            ),
            r"'time' is reserved",
        ),
        (lambda t: t.replace('outputs = ["Ti"]', 'outputs = ["Ti", "Ti"]'), r"output 'Ti' is listed twice"),
        (lambda t: t + '\n[heat_inputs]\ntime = "Ti"\n', r"'time' is reserved"),
        (
            lambda t: t + '\n[[supply_air]]\nnode = "Ti"\nflow = "m"\ntemperature = "m"\n',
            r"uses 'm' as both its flow and its temperature",
        ),
    ],
    ids=["node", "boundary", "duplicate-output", "heat-input", "supply-is-flow"],
)
def test_reserved_and_colliding_names(tmp_path, data, capsys, edit, pattern):
    (tmp_path / "m.toml").write_text(edit(model_text()))
    one_line_exit_2(["diagnose", str(data), "--model", str(tmp_path / "m.toml")], capsys, pattern)


@pytest.mark.parametrize(
    ("const", "pattern"),
    [("Qx=50", r"constant 'Qx' is not an input of the model"), ("Ti=20", r"cannot hold 'Ti' constant")],
)
def test_const_of_an_unknown_name_or_an_output(data, capsys, const, pattern):
    one_line_exit_2(["diagnose", str(data), "--model", "TiTe", "--const", const], capsys, pattern)


def test_manifest_constants_must_name_inputs(tmp_path, data, capsys):
    (tmp_path / "m.toml").write_text(
        'model = "TiTe"\nconstants = { Qx = 1.0 }\n[[zone]]\nid = "z"\ndata = "z.csv"\n'
    )
    one_line_exit_2(["fit-many", str(tmp_path / "m.toml")], capsys, r"constant 'Qx' is not an input")


def test_workers_zero(tmp_path, data, capsys):
    (tmp_path / "m.toml").write_text('model = "TiTe"\n[[zone]]\nid = "z"\ndata = "z.csv"\n')
    one_line_exit_2(
        ["fit-many", str(tmp_path / "m.toml"), "--workers", "0"], capsys, r"--workers must be at least 1"
    )
    assert not (tmp_path / "m-results").exists()


def test_nfkc_equivalent_names_are_one_name(tmp_path, data, capsys):
    """A parameter declared with the micro sign and tied with the Greek mu: one parameter."""
    micro, mu = "\u00b5", "\u03bc"
    text = model_text(f'"{micro}" = {{ value = 0.02, unit = "K/W" }}\n').replace(
        'Rea = { value = 0.02, unit = "K/W" }', f'Rea = {{ expr = "{mu}*1" }}'
    )
    (tmp_path / "nfkc.toml").write_text(text)
    (tmp_path / "plain.toml").write_text(model_text())
    rmse = []
    for m in ("nfkc.toml", "plain.toml"):
        assert main(["predict", str(tmp_path / m), str(data), "--json", str(tmp_path / f"{m}.json")]) == 0
        rmse.append(json.loads((tmp_path / f"{m}.json").read_text())["rmse_K"])
    assert rmse[0] == pytest.approx(rmse[1])
    assert (
        main(["diagnose", str(data), "--model", str(tmp_path / "nfkc.toml"), "--const", f"T{micro}=1"]) == 2
    )


def test_the_unicode_forms_of_a_column_are_one(tmp_path, capsys):
    frame = zone_frame().rename(columns={"To": "T\u00b5"})
    frame.to_csv(tmp_path / "z.csv", index=False)
    (tmp_path / "map.toml").write_text('[columns]\nTi = "Ti"\nTo = "T\u03bc"\n')
    assert main(["predict", "TiTe", str(tmp_path / "z.csv"), "--columns", str(tmp_path / "map.toml")]) == 0


# ---- outputs: all or nothing -----------------------------------------------------------------------


def test_json_then_a_failing_save_model_leaves_nothing(tmp_path, capsys):
    out = tmp_path / "fit.json"
    args = ["fit", "C", "--model", "TiTe", "--method", "ls", "--starts", "1", "--no-profiles"]
    one_line_exit_2(
        [*args, "--json", str(out), "--save-model", str(tmp_path / "m.txt")], capsys, r"--save-model must end"
    )
    assert not out.exists()
    (tmp_path / "rep").write_text("a file where the report folder should be")
    one_line_exit_2(
        [*args, "--json", str(out), "--report", str(tmp_path / "rep")], capsys, r"is a file, not a folder"
    )
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]


def test_json_then_a_failing_report_leaves_no_report_folder(tmp_path, capsys, monkeypatch):
    import rczone.report.predict as predict_report
    from rczone.errors import OutputError

    def fail(*args, **kwargs):
        raise OutputError("cannot write the report")

    monkeypatch.setattr(predict_report, "prediction_report", fail)
    out, rep = tmp_path / "p.json", tmp_path / "rep"
    one_line_exit_2(
        ["predict", "TiTe", "C", "--json", str(out), "-o", str(tmp_path / "s.csv"), "--report", str(rep)],
        capsys,
        r"cannot write the report",
    )
    assert list(tmp_path.iterdir()) == []


# ---- Ctrl-C ------------------------------------------------------------------------------------------


def as_a_terminal_starts_it() -> None:
    """Default SIGINT and SIGTERM in the command, as a terminal starts a foreground job.

    A test run started as a background job of a non-interactive shell (``make test &``, a CI
    runner's wrapper) inherits SIGINT ignored (POSIX), and so would the command: Ctrl-C would then
    do nothing, by the shell's choice, not rczone's.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _interrupt(args: list[str], wait_for: str, tmp_path: Path, delay: float = 0.5) -> tuple[int, str]:
    err = tmp_path / "err.txt"
    with open(err, "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-m", "rczone.cli", *args],
            stdout=subprocess.DEVNULL,
            stderr=fh,
            start_new_session=True,
            preexec_fn=as_a_terminal_starts_it,
        )
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and wait_for not in err.read_text() and proc.poll() is None:
            time.sleep(0.1)
        time.sleep(delay)
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group
        code = proc.wait(timeout=120)
        # nothing of the command outlives it (a worker pool's processes included)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            try:
                os.killpg(proc.pid, 0)
            except ProcessLookupError:
                break
            time.sleep(0.1)
        else:
            raise AssertionError("processes of the interrupted command are still running")
    finally:
        # whatever failed above (a timeout included), the command's group does not outlive the test
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    return code, err.read_text()


@pytest.mark.skipif(os.name == "nt", reason="process groups")
def test_ctrl_c_in_fit_exits_130_and_writes_nothing(tmp_path):
    out = tmp_path / "fit.json"
    # the 13-state model's fit runs for minutes: the interrupt lands mid-work (loading or compiling
    # kernels, or fitting), never after a fit that already finished
    args = ["fit", "C", "--model", "full-scale", "--starts", "1", "--json", str(out)]
    code, err = _interrupt(args, "", tmp_path, delay=3.0)
    assert code == 130 and "Traceback" not in err, err
    assert not out.exists()


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
@pytest.mark.skipif(os.name == "nt", reason="process groups")
def test_ctrl_c_in_fit_many_exits_130(tmp_path):
    # 100 zones: about 6 s of fitting on one worker, so the interrupt half a second after the run
    # starts lands mid-run (31 zones took 2 s, which a fast moment could finish first)
    (tmp_path / "m.toml").write_text(
        'methods = ["ls"]\nn_starts = 1\ndiagnose = false\n[[generate]]\nseasons = ["autumn"]\nseeds = "0..99"\n'
    )
    code, err = _interrupt(
        [
            "fit-many",
            str(tmp_path / "m.toml"),
            "--out",
            str(tmp_path / "out"),
            "--backend",
            "processes",
            "--workers",
            "1",
        ],
        "already done",
        tmp_path,
    )
    assert code == 130 and "Traceback" not in err, err


def test_an_interrupt_wrapped_by_a_library_is_still_ctrl_c(monkeypatch, capsys):
    """numba turns a Ctrl-C while it loads its cache into another exception caused by the interrupt."""
    import rczone.cli.main as cli_main

    def wrapped(**kwargs):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise RuntimeError("failed to unpickle a compiled kernel") from exc

    monkeypatch.setattr(cli_main, "app", wrapped)
    assert cli_main.main(["models"]) == 130
    assert "aborted" in capsys.readouterr().err


@pytest.fixture
def python_ctrl_c():
    """Python's own Ctrl-C handler in place, as in a terminal (a background job may inherit SIGINT ignored)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_an_error_after_a_dropped_ctrl_c_is_still_ctrl_c(monkeypatch, capsys, python_ctrl_c):
    """A Ctrl-C that Python drops (raised in a finalizer) can leave numba a half-built kernel, whose
    next use fails with an error that does not carry the interrupt: exit 130, no traceback."""
    import rczone.cli.main as cli_main

    def dropped(**kwargs):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)  # the handler runs here and raises
        except KeyboardInterrupt:
            pass  # as Python does with an exception raised in __del__
        raise RuntimeError("no compiled object yet for <Library 'spectral_modal'>")

    monkeypatch.setattr(cli_main, "app", dropped)
    before = set(threading.enumerate())
    assert cli_main.main(["models"]) == 130
    assert "aborted" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored
    # the timer that would end a command going on is gone with the command: called in a process
    # that lives on (these tests), it must not end that process later
    assert not [t for t in set(threading.enumerate()) - before if isinstance(t, threading.Timer)]


@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_a_command_that_ends_well_after_a_dropped_ctrl_c_is_interrupted(
    monkeypatch, capsys, tmp_path, python_ctrl_c
):
    """The command went on and finished: its outputs do not appear, and it exits 130."""
    import rczone.cli.main as cli_main
    from rczone.files.atomic import write_text_atomic

    out = tmp_path / "out.txt"

    def finishes(**kwargs):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:
            pass
        write_text_atomic(out, "a result\n")
        return 0

    monkeypatch.setattr(cli_main, "app", finishes)
    monkeypatch.setattr("rczone.cli.interrupt.CTRL_C_GRACE_S", 60.0)
    assert cli_main.main(["models"]) == 130
    assert not out.exists()


@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_a_command_that_goes_on_after_a_dropped_ctrl_c_is_ended(tmp_path):
    """The command neither fails nor finishes: the process ends, exit 130, after the grace time."""
    script = (
        "import os, signal, time\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "import rczone.cli.interrupt as m\n"
        "m.CTRL_C_GRACE_S = 0.5\n"
        "with m.noting_ctrl_c():\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        time.sleep(5)\n"
        "    except KeyboardInterrupt:\n"
        "        pass\n"
        "    time.sleep(60)\n"
    )
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 130 and "aborted" in proc.stderr, proc.stderr
    assert time.monotonic() - t0 < 30


@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_the_console_script_notes_a_ctrl_c_from_its_first_line():
    """A Ctrl-C dropped outside main() (as while the command modules import) still ends in 130."""
    script = (
        "import os, signal, sys, time\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "import rczone.cli as cli\n"
        "import rczone.cli.main as m\n"
        "def dropped():\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        time.sleep(5)\n"
        "    except KeyboardInterrupt:\n"
        "        pass\n"
        "    return 0\n"
        "m.main = dropped\n"
        "sys.exit(cli.run())\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 130, proc.stderr


def test_an_unrelated_error_is_not_taken_for_ctrl_c(monkeypatch):
    import rczone.cli.main as cli_main

    def broken(**kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(cli_main, "app", broken)
    with pytest.raises(RuntimeError, match="a bug"):
        cli_main.main(["models"])


@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_a_ctrl_c_while_compiled_code_runs_ends_the_process_at_once():
    """A signal's Python handler waits for the main thread to leave C code (an LLVM pass of a numba
    compile, a BLAS call); the watchdog ends the process after CTRL_C_STUCK_S, exit 130, "aborted".
    Without it the handler would run after the product: "finished", then an uncaught interrupt."""
    script = (
        "import os, signal, threading\n"
        "os.environ['OPENBLAS_NUM_THREADS'] = '1'\n"
        "import numpy as np\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "import rczone.cli.interrupt as m\n"
        "m.CTRL_C_STUCK_S = 0.3\n"
        "a = np.ones((4000, 4000))\n"
        "with m.noting_ctrl_c():\n"
        "    threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT)).start()\n"
        "    a @ a  # seconds in BLAS, the GIL released, no signal checked\n"
        "    print('finished', flush=True)\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 130 and "aborted" in proc.stderr, proc.stderr
    assert "finished" not in proc.stdout


@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_the_watchdog_leaves_the_wake_up_descriptor_as_it_found_it():
    import signal

    from rczone.cli.interrupt import noting_ctrl_c

    before = signal.set_wakeup_fd(-1)
    signal.set_wakeup_fd(before)
    previous = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with noting_ctrl_c():
            inside = signal.set_wakeup_fd(-1)
            signal.set_wakeup_fd(inside)
            assert inside != -1  # watched
        after = signal.set_wakeup_fd(-1)
        signal.set_wakeup_fd(after)
        assert after == before
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_a_ctrl_c_python_cannot_raise_is_not_printed_as_a_traceback(python_ctrl_c, monkeypatch):
    """A Ctrl-C in a finalizer (or llvmlite's ctypes callback while numba compiles) is noted, not
    printed as "Exception ignored ... Traceback"; any other unraisable error still reaches the hook."""
    from rczone.cli.interrupt import noting_ctrl_c

    class Raises:
        def __init__(self, exc):
            self.exc = exc

        def __del__(self):
            raise self.exc

    seen = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: seen.append(type(u.exc_value).__name__))
    recorder = sys.unraisablehook
    with noting_ctrl_c():
        Raises(KeyboardInterrupt())
        Raises(ValueError("a real fault"))
    assert seen == ["ValueError"] and sys.unraisablehook is recorder
