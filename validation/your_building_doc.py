"""Regenerate ``docs/your-building.md``: every command's output on the page is pasted from a real run.

Usage::

    python validation/your_building_doc.py [--shared ../shared] [--page docs/your-building.md] [--out FILE]

The page is both the input and the output. Its ``toml`` and ``python`` blocks are the files the
commands use (:data:`FILES` says which block is which file, and how the two variants are derived
from them), so what the page shows is what ran. Its plain code blocks are the command blocks:
:data:`BLOCKS` lists, in page order, the commands each one shows; the script runs them in a
temporary folder with the two real data sets (read from the shared folder, never copied into the
repository: their licences do not allow it) and writes the page back with each plain block replaced
by the commands and their output (stdout and stderr as a terminal 100 columns wide shows them,
less the notice of a first run that compiles the kernels).
The prose is not touched: after a change of the numbers, read it again.

To add a block, add the prose and an empty plain block (three
backquotes twice) to the page, and a :class:`Block` at the same position in :data:`BLOCKS`.

``tests/validation/test_your_building_doc.py`` checks quickly that the page's commands are this
script's, and (marked slow, needs the shared folder) that a fresh run reproduces the page.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

HERE = Path(__file__).resolve().parent
PAGE = HERE.parent / "docs" / "your-building.md"
DEFAULT_SHARED = HERE.parent.parent / "shared"
WIDTH = 100

#: The notice of a first run that compiles the kernels: it depends on the machine's cache, not on
#: the command, so it is left out (:mod:`rczone.cli.compile_notice`).
COMPILING = "compiling kernels (first run only)…"

#: Data files of the page: name in the work folder -> path under the shared folder.
DATA = {
    "house.csv": "data/bacher_madsen_prbs/inputPRBS1.csv",
    "classroom.csv": "data/leec_classroom_vav/LEEC_classroom_VAV_hourly.csv",
}


class Block(NamedTuple):
    """One plain code block of the page: the commands it shows and which output lines it keeps.

    Attributes
    ----------
    commands : tuple of str
        Shell commands, run in order in the work folder; each is shown after ``$ ``.
    keep : str, optional
        A regular expression: only the output lines it matches are shown, every run of other lines
        becomes one ``...`` line. None shows everything.
    show_commands : bool
        False for a block that shows only the output (of the page's Python example).
    """

    commands: tuple[str, ...]
    keep: str | None = None
    show_commands: bool = True


#: The files the commands use: name -> (index of the page's block of that language, replacements).
FILES: dict[str, tuple[str, int, tuple[tuple[str, str], ...]]] = {
    "house-map.toml": ("toml", 0, ()),
    "held-out-map.toml": (
        "toml",
        0,
        (
            (
                'end = "2009-02-09 12:00"            # calibration: the first four days (the rest is held out)',
                'start = "2009-02-09 12:00"          # held out: the last two days',
            ),
        ),
    ),
    "house-all-map.toml": (
        "toml",
        0,
        (
            (
                'end = "2009-02-09 12:00"            # calibration: the first four days (the rest is held out)',
                "",
            ),
        ),
    ),
    "house.toml": ("toml", 1, ()),
    "controller.py": ("python", 0, ()),
    "classroom-map.toml": ("toml", 2, ()),
    "classroom.toml": ("toml", 3, ()),
    "classroom-fixed-envelope.toml": (
        "toml",
        3,
        (
            (
                'Ria = { value = 6.7, unit = "K/kW", bounds = [0.5, 50] }',
                'Ria = { value = 6.7, unit = "K/kW", fixed = true }',
            ),
        ),
    ),
}

HOUSE = "house.csv --columns house-map.toml"
HELD_OUT = "house.csv --columns held-out-map.toml"
WHOLE = "house.csv --columns house-all-map.toml"
CLASSROOM = "classroom.csv --columns classroom-map.toml"

#: The page's plain code blocks, in order.
BLOCKS: tuple[Block, ...] = (
    Block(("head -3 house.csv; tail -1 house.csv",)),
    Block((f"rczone diagnose {HOUSE} --model house.toml",)),
    Block(
        (f"rczone fit {HOUSE} --model house.toml --save-model house-fit.json --json fit.json --report fit",)
    ),
    Block(
        (
            f"rczone predict house-fit.json {HELD_OUT} -o held-out.csv --report predict",
            "head -3 held-out.csv",
        )
    ),
    Block(
        (
            f"rczone predict house-fit.json {WHOLE} --warmup 2009-02-09T12:00 --horizons 1,12,72,open"
            " --baselines -o held-out.csv --report predict",
            f"rczone fit {WHOLE} --model house.toml --holdout 2009-02-09T12:00",
        ),
    ),
    Block((f"rczone select {HOUSE} --forward --json select.json",)),
    Block(
        (
            f"rczone fit {HOUSE} --model TiTeTh+heater+solar --noise all --save-model house-titeth.json",
            f"rczone predict house-titeth.json {HELD_OUT} -o held-out3.csv",
        )
    ),
    Block(("python controller.py",), show_commands=False),
    Block((f"rczone fit {CLASSROOM} --model classroom.toml --save-model classroom.json --report fit",)),
    Block(
        (f"rczone fit {CLASSROOM} --model classroom-fixed-envelope.toml",),
        keep=r"┃ parameter|┡|│ (Ci|Cm|Rim|sigma_v) |warning: (Ci|Cm) |result flagged",
    ),
)

_FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.S | re.M)


def fenced_blocks(page: str) -> list[tuple[str, str]]:
    """The page's fenced code blocks as ``(language, text)``, in order (``""``: a plain block)."""
    return [(m.group(1), m.group(2)) for m in _FENCE.finditer(page)]


def shown_commands(page: str) -> list[tuple[str, ...]]:
    """The commands each plain block of the page shows (the lines after ``$ ``)."""
    return [
        tuple(line[2:] for line in text.splitlines() if line.startswith("$ "))
        for lang, text in fenced_blocks(page)
        if lang == ""
    ]


def write_files(page: str, folder: Path) -> None:
    """Write :data:`FILES` from the page's blocks into ``folder``."""
    blocks = fenced_blocks(page)
    for name, (lang, index, replacements) in FILES.items():
        text = [t for lg, t in blocks if lg == lang][index]
        for old, new in replacements:
            if old not in text:
                raise SystemExit(f"{name}: the page's {lang} block {index} no longer contains {old!r}")
            text = text.replace(old, new)
        (folder / name).write_text(text)


def _elide(lines: list[str], keep: str | None) -> list[str]:
    if keep is None:
        return lines
    out: list[str] = []
    for line in lines:
        if re.search(keep, line):
            out.append(line)
        elif not out or out[-1] != "...":
            out.append("...")
    return out


def run_block(block: Block, folder: Path) -> str:
    """The text of one plain block: each command after ``$ `` and its output, as a terminal shows it."""
    env = {
        **os.environ,
        "COLUMNS": str(WIDTH),
        "PYTHONUNBUFFERED": "1",  # stdout and stderr in the order they were written
        "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
        "NO_COLOR": "1",
    }
    lines: list[str] = []
    for command in block.commands:
        done = subprocess.run(
            ["bash", "-c", command], cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT
        )
        if done.returncode not in (0, 3):
            raise SystemExit(f"{command!r} failed (exit {done.returncode}):\n{done.stdout.decode()}")
        if block.show_commands:
            lines.append(f"$ {command}")
        shown = [ln for ln in done.stdout.decode().rstrip("\n").splitlines() if ln != COMPILING]
        lines += _elide(shown, block.keep)
    return "\n".join(lines) + "\n"


def regenerate(page: str, shared: Path, progress=print) -> str:
    """The page with every plain block replaced by a fresh run of its :data:`BLOCKS` entry."""
    if shown_commands(page) != [b.commands if b.show_commands else () for b in BLOCKS]:
        raise SystemExit("the page's plain blocks do not match BLOCKS; add the block to both")
    with tempfile.TemporaryDirectory(prefix="your-building-") as tmp:
        folder = Path(tmp)
        for name, rel in DATA.items():
            if not (shared / rel).is_file():
                raise SystemExit(f"{shared / rel} not found (--shared names the shared folder)")
            shutil.copyfile(shared / rel, folder / name)
        write_files(page, folder)
        outputs = iter(BLOCKS)

        def replace(m: re.Match) -> str:
            if m.group(1):
                return m.group(0)
            block = next(outputs)
            progress(f"running {block.commands[0]}")
            return "```\n" + run_block(block, folder) + "```\n"

        return _FENCE.sub(replace, page)


def main(argv: list[str] | None = None) -> int:
    """Command line: regenerate the page in place (or into ``--out``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=DEFAULT_SHARED, help="the shared folder")
    parser.add_argument("--page", type=Path, default=PAGE, help="the page to read")
    parser.add_argument("--out", type=Path, default=None, help="where to write (default: the page)")
    args = parser.parse_args(argv)
    text = regenerate(args.page.read_text(), args.shared)
    (args.out or args.page).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
