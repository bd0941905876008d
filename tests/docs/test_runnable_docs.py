"""Every command in the guides runs as written (issue 37, item 8).

The commands are read from the Markdown pages (``docs/*.md`` and the README): fenced blocks that
are plain or marked ``console``, ``bash``, ``sh``, ``shell``; in a block with ``$ `` prompts only
the prompted lines are commands (the rest is output), elsewhere every line that starts with
``rczone`` or ``python -c``; a trailing ``\\`` joins the next line, a ``#`` comment is dropped. A
command is one of:

* a synopsis (``[--option]``, ``A | B``, ``...``, a placeholder such as ``DATA``): not run;
* in :data:`SKIP`, with its reason (the user's own data, a cluster, a 16-minute run, ...);
* fast (:data:`FAST`: listings and model files): run in ``make test``;
* the rest: run, page by page in the page's order, in a fresh temporary folder, marked slow.

A slow command runs as ``python -m rczone.cli ...`` (``python -c`` as given) with no shell, and passes
when it exits 0, or 3 for a fit whose verdict is "do not trust" (the result is written all the
same, ``rczone fit --help``), with no traceback; a quick one and ``--help`` run through the same
entry point in this process (one import for all). Files a page names from the repository (the
model files under ``validation/`` that ``docs/multizone.md`` reads from a clone) are copied into
the folder first. Besides, every subcommand a page uses answers ``--help`` (fast).
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

import pytest

from rczone.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
PAGES = [*sorted((ROOT / "docs").glob("*.md")), ROOT / "README.md"]
SHELL_BLOCKS = ("", "console", "bash", "sh", "shell")
#: Arguments that stand for something the reader fills in: a line with one is a synopsis.
PLACEHOLDERS = re.compile(r"^(DATA|MODEL|MANIFEST|NAME|DIR|FILE|MAP|M\d?|F|N|K|S|W)(=|/|$)")

#: Commands not run, by (page, a piece of the command), and why. Kept short: each is data or an
#: installation the test machine cannot have, or a run another test already makes.
SKIP = {
    ("your-building.md", "house"): "the Bacher & Madsen data are downloaded by the reader (the page says"
    " how; their licence forbids shipping them); validation/your_building_doc.py runs the page on them",
    ("your-building.md", "classroom"): "the LEEC classroom trends, downloaded and converted by the reader"
    " (the page says how); validation/your_building_doc.py runs them",
    ("validation.md", "house"): "the Bacher & Madsen data (see your-building.md); tests/validation runs them",
    ("batch.md", "fit-many"): "the page's manifest generates 1000 zone-nights and one runs on a Dask"
    " cluster; tests/unit/batch runs fit-many on small manifests",
    ("posterior.md", "fit-many manifest.toml"): "the reader's own manifest (batch.md)",
    ("extending.md", "--method huber"): "needs the plug-in package the page writes and installs",
    ("energyplus.md", "--days"): "EnergyPlus runs of days (tests/unit/emulators run short ones)",
    ("energyplus.md", "small/"): "reads the EnergyPlus run's export",
    ("energyplus.md", "floor1.toml"): "reads the EnergyPlus run's export",
    ("README.md", "demo"): "16 minutes on a loaded machine; tests/e2e/test_demo.py runs it",
}
#: Commands quick enough for ``make test`` (a listing, a model file, nothing fitted).
FAST = re.compile(
    r"^rczone (models|methods|version|--version)\b|^rczone emulate .*--list$|^rczone \S+ --help$"
)


class Command(NamedTuple):
    page: str
    text: str


def commands_of(path: Path) -> list[Command]:
    """The commands of a page, in order (see the module notes)."""
    text = path.read_text(encoding="utf-8")
    out = []
    for info, body in re.findall(r"^```([^\n`]*)\n(.*?)^```", text, re.S | re.M):
        if info.strip() not in SHELL_BLOCKS:
            continue
        lines = body.splitlines()
        prompted = any(x.startswith("$ ") for x in lines)
        joined, acc = [], ""
        for line in lines:
            if prompted and not acc:
                if not line.startswith("$ "):
                    continue
                line = line[2:]
            if not acc and not line.startswith(("rczone ", "python -c ")):
                continue  # output, a diagram, another program
            acc += line.strip() + " "
            if line.rstrip().endswith("\\"):
                acc = acc.rstrip()[:-1]
                continue
            joined.append(acc.strip())
            acc = ""
        for cmd in joined:
            plain = shlex.join(shlex.split(cmd, comments=True)) if cmd.startswith("rczone") else cmd
            out.append(Command(path.name, plain))
    return out


def is_synopsis(cmd: str) -> bool:
    if "[" in cmd or " | " in cmd or "..." in cmd:
        return True
    return any(PLACEHOLDERS.match(a) for a in shlex.split(cmd, comments=True)[1:])


def skip_reason(c: Command) -> str | None:
    for (page, piece), why in SKIP.items():
        if c.page == page and piece in c.text:
            return why
    return None


ALL = [c for p in PAGES for c in commands_of(p)]
RUNNABLE = [c for c in ALL if not is_synopsis(c.text) and skip_reason(c) is None]


def run(cmd: str, cwd: Path, timeout: float = 1800) -> subprocess.CompletedProcess:
    """``cmd`` in ``cwd``: rczone through this interpreter, ``python -c`` as given; no shell."""
    args = shlex.split(cmd, comments=cmd.startswith("rczone"))
    argv = (
        [sys.executable, "-m", "rczone.cli", *args[1:]]
        if args[0] == "rczone"
        else [sys.executable, *args[1:]]
    )
    env = {**os.environ, "COLUMNS": "100", "RCZONE_PROGRESS_INTERVAL": "3600"}
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def check(c: Command, res: subprocess.CompletedProcess) -> None:
    ok = {0, 3} if re.match(r"rczone (fit|select)\b", c.text) else {0}
    where = f"{c.page}: `{c.text[:90]}`"
    assert "Traceback" not in res.stderr, f"{where} raised:\n{res.stderr[-2000:]}"
    assert res.returncode in ok, f"{where} exit {res.returncode}:\n{res.stderr[-1500:]}"


def copy_repository_files(cmds: list[Command], folder: Path) -> None:
    """Files the page names from a clone of the repository (``validation/...``), copied into ``folder``."""
    for c in cmds:
        for a in shlex.split(c.text, comments=True):
            src = ROOT / a
            if a.startswith("validation/") and src.is_file():
                (folder / a).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy(src, folder / a)


def test_the_pages_have_commands_and_every_skip_is_used():
    assert len(ALL) > 40 and len(RUNNABLE) > 20
    used = {key for key in SKIP for c in ALL if c.page == key[0] and key[1] in c.text}
    assert used == set(SKIP), f"skip entries matching no command: {set(SKIP) - used}"
    # the two pages issue 37 named: the data's origin is given, the CSV a command reads is written first
    page = (ROOT / "docs" / "your-building.md").read_text(encoding="utf-8")
    assert "## Getting the data" in page and "sha256" in page
    multizone = [c.text for c in ALL if c.page == "multizone.md"]
    first_read = next(i for i, t in enumerate(multizone) if "multizone-1.csv" in t and t.startswith("rczone"))
    assert any("to_csv('multizone-1.csv'" in t for t in multizone[:first_read])


@pytest.mark.parametrize(
    "sub", sorted({c.text.split()[1] for c in ALL if not c.text.split()[1].startswith("-")})
)
def test_every_subcommand_a_page_uses_answers_help(sub, capsys):
    assert main([sub, "--help"]) == 0, f"a page uses `rczone {sub}`, which does not answer --help"
    assert "Usage" in capsys.readouterr().out


@pytest.mark.parametrize(
    "c", [c for c in RUNNABLE if FAST.match(c.text)], ids=lambda c: f"{c.page}:{c.text[:40]}"
)
def test_the_quick_commands_run_as_written(c, tmp_path, monkeypatch, capsys):
    if c.text.startswith("rczone emulate") and importlib.util.find_spec("pyenergyplus") is None:
        pytest.skip("the EnergyPlus extra (rczone[energyplus]) is not installed")
    monkeypatch.chdir(tmp_path)  # in this process (one import for all): the same entry point as the script
    code = main(shlex.split(c.text)[1:])
    err = capsys.readouterr().err
    check(c, subprocess.CompletedProcess(c.text, code, "", err))


SLOW_PAGES = sorted({c.page for c in RUNNABLE if not FAST.match(c.text)})


@pytest.mark.slow
@pytest.mark.parametrize("page", SLOW_PAGES)
def test_each_page_runs_as_written_in_order(page, tmp_path):
    cmds = [c for c in RUNNABLE if c.page == page]
    copy_repository_files(cmds, tmp_path)
    for c in cmds:
        check(c, run(c.text, tmp_path))
