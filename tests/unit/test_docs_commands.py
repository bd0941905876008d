"""The guides' commands can be followed: a data file a command reads is written before it.

``docs/multizone.md`` fitted ``multizone-1.csv`` without saying where it came from. Here every
``rczone`` command in a page's code blocks is read, and each CSV or Parquet file it names must
be written by an earlier line of the page (``to_csv('...')``, ``-o``, ``--out``, ``>``) or ship in
the repository. (``docs/python.md`` runs whole in ``tests/unit/workflow/test_python_page.py``;
``docs/your-building.md`` runs on licensed data, ``validation/your_building_doc.py``.)
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = ["multizone.md"]
WRITES = re.compile(r"""to_(?:csv|parquet)\(\s*['"]([^'"]+)['"]|(?:-o|--out|>)\s+(\S+)""")


def command_lines(text: str) -> list[str]:
    blocks = re.findall(r"^```[a-z]*\n(.*?)^```", text, re.S | re.M)
    return [line.strip() for b in blocks for line in b.splitlines() if line.strip()]


@pytest.mark.parametrize("page", PAGES)
def test_every_data_file_a_command_reads_is_made_first(page):
    written: set[str] = set()
    for line in command_lines((ROOT / "docs" / page).read_text(encoding="utf-8")):
        if line.startswith("rczone "):
            args = line.split()
            data = [a for a in args[1:] if a.endswith((".csv", ".parquet")) and not a.startswith("-")]
            for name in data:
                made = name in written or (ROOT / name).exists()
                assert made, f"{page}: `{line[:60]}...` reads {name}, which no earlier line writes"
        for m in WRITES.finditer(line):
            written.add(m.group(1) or m.group(2))
