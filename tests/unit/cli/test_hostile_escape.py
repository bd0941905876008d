"""Issue 25, the escape: nothing is written outside ``--out``, symlinked or not.

``fit-many`` followed a symbolic link planted at its lock file's name and overwrote the file it
pointed to, outside the output folder. The lock is now opened with ``O_NOFOLLOW`` and must be a
regular file with one name; every file of the folder is written relative to the folder without
following links (a link at a file's name is replaced, one in place of ``parts`` refused). A
``--json`` that names a link, a pipe or ``/dev/stdout`` writes through it: the link or the pipe
stays what it was.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rczone.cli.main import main
from tests.unit.batch.test_faults import quick, write_manifest  # noqa: F401 (fixture)

pytestmark = pytest.mark.skipif(not hasattr(os, "symlink") or os.name == "nt", reason="POSIX links")

SECRET = "precious contents outside the output folder\n"


def one_line_exit_2(args: list[str], capsys, *needles: str) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if not ln.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    for n in needles:
        assert n in err, err
    return err


def outside(tmp_path: Path) -> Path:
    victim = tmp_path / "elsewhere" / "victim.txt"
    victim.parent.mkdir()
    victim.write_text(SECRET)
    return victim


def run_fit_many(tmp_path: Path, out: Path) -> list[str]:
    return [
        "fit-many",
        str(write_manifest(tmp_path, ["a", "b"])),
        "--out",
        str(out),
        "--backend",
        "processes",
    ]


def test_a_link_at_the_lock_files_name_is_refused_and_its_target_untouched(tmp_path, capsys):
    victim = outside(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / ".lock").symlink_to(victim)
    one_line_exit_2(
        run_fit_many(tmp_path, out), capsys, ".lock", "symbolic link", "outside the output folder"
    )
    assert victim.read_text() == SECRET
    assert (out / ".lock").is_symlink()


def test_a_dangling_link_at_the_lock_files_name_creates_nothing_outside(tmp_path, capsys):
    target = tmp_path / "elsewhere" / "created.txt"
    target.parent.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / ".lock").symlink_to(target)
    one_line_exit_2(run_fit_many(tmp_path, out), capsys, "symbolic link")
    assert not target.exists()


def test_a_hard_link_at_the_lock_files_name_is_refused(tmp_path, capsys):
    victim = outside(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    os.link(victim, out / ".lock")
    one_line_exit_2(run_fit_many(tmp_path, out), capsys, "hard link")
    assert victim.read_text() == SECRET


def test_a_fifo_at_the_lock_files_name_is_refused_without_waiting(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    os.mkfifo(out / ".lock")
    one_line_exit_2(run_fit_many(tmp_path, out), capsys, "not a regular file")


def test_a_link_in_place_of_parts_is_refused(tmp_path, capsys):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / "parts").symlink_to(elsewhere, target_is_directory=True)
    one_line_exit_2(run_fit_many(tmp_path, out), capsys, "parts", "symbolic link")
    assert list(elsewhere.iterdir()) == []


def test_links_planted_at_result_names_are_replaced_never_followed(tmp_path, quick, capsys):  # noqa: F811
    from rczone.batch.store import part_name

    victim = outside(tmp_path)
    out = tmp_path / "out"
    (out / "parts").mkdir(parents=True)
    names = [
        "results.parquet",
        "summary.json",
        "report.html",
        "estimates.png",
        f"parts/{part_name('a::ls')}",
        f"parts/{part_name('b::ls')}",
    ]
    for n in names:
        (out / n).symlink_to(victim)
    assert main(run_fit_many(tmp_path, out)) == 0
    assert victim.read_text() == SECRET
    for n in names[:3] + names[4:]:
        assert (out / n).is_file() and not (out / n).is_symlink(), n
    assert json.loads((out / "summary.json").read_text())["ok"] == 2


def test_a_fifo_among_the_parts_does_not_hang_the_run(tmp_path, quick, capsys):  # noqa: F811
    out = tmp_path / "out"
    (out / "parts").mkdir(parents=True)
    os.mkfifo(out / "parts" / "foreign.json")
    assert main(run_fit_many(tmp_path, out)) == 0


def test_a_figure_named_after_an_output_stays_in_the_report_folder(tmp_path):
    from matplotlib.figure import Figure

    from rczone.report import Report

    rep = Report("t")
    rep.figure("fit_../../escaped", Figure(figsize=(1, 1)))
    rep.write(tmp_path / "rep")
    assert not (tmp_path / "escaped.png").exists()
    assert sorted(p.name for p in (tmp_path / "rep").iterdir()) == ["fit__escaped.png", "report.html"]


# ---- --json through a link, a pipe, /dev/stdout -------------------------------------------------


def diagnose_json(target: Path | str) -> list[str]:
    return ["diagnose", "C", "--json", str(target)]


def test_json_through_a_link_keeps_the_link_and_writes_its_target(tmp_path, capsys):
    real = tmp_path / "real.json"
    real.write_text("{}")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    assert main(diagnose_json(link)) == 0
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert "parameters" in json.loads(real.read_text()) or json.loads(real.read_text())


def test_json_into_a_fifo_is_streamed_and_the_fifo_stays(tmp_path, capsys):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    got: list[bytes] = []

    def reader() -> None:
        with open(fifo, "rb") as fh:
            got.append(fh.read())

    t = threading.Thread(target=reader, daemon=True)
    t.start()
    time.sleep(0.1)
    assert main(diagnose_json(fifo)) == 0
    t.join(10)
    assert json.loads(got[0].decode())
    assert fifo.is_fifo()


def test_json_into_a_fifo_without_reader_is_one_line_not_a_hang(tmp_path, capsys):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    one_line_exit_2(diagnose_json(fifo), capsys, "named pipe that no program reads")
    assert fifo.is_fifo()


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_json_through_a_link_to_dev_stdout_prints_it(tmp_path):
    link = tmp_path / "out.json"
    link.symlink_to("/dev/stdout")
    proc = subprocess.run(
        [sys.executable, "-m", "rczone.cli", "diagnose", "C", "--json", str(link)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert link.is_symlink()
    assert json.loads(proc.stdout)["data"] if "data" in json.loads(proc.stdout) else json.loads(proc.stdout)


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_the_batch_store_imports_where_fcntl_does_not_exist():
    """Issue 19: ``import fcntl`` at module level killed fit-many on Windows with a traceback."""
    code = "import sys; sys.modules['fcntl'] = None; import rczone.batch.store, rczone.cli.main; print('ok')"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.stdout.strip() == "ok", proc.stderr
