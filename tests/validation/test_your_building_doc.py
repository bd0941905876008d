"""``docs/your-building.md`` is what ``validation/your_building_doc.py`` makes (issue 22, done-when item 4).

The fast checks need no data: the page's commands are the script's, and the files the script
takes from the page (model files, column maps, the Python example) are there. The slow check
regenerates the page from the real data (the shared folder) and compares: the text must be the
same, the numbers the same to 2 % (another machine's rounding in a search may move the last
digits of a count or of a p-value far below any level, never the words).
"""

from __future__ import annotations

import math
import re

import pytest

from tests.shared_data import SHARED, require
from tests.validation.scripts import load_script

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?", re.I)


def _skeleton(text: str) -> tuple[str, list[float]]:
    """The text with every number replaced by ``#`` and runs of spaces or rule characters collapsed."""
    numbers = [float(m) for m in _NUMBER.findall(text)]
    words = _NUMBER.sub("#", text)
    words = re.sub(r"([━─═┈ ])\1+", r"\1", words)
    return words, numbers


def _close(a: float, b: float) -> bool:
    if abs(a) < 1e-6 and abs(b) < 1e-6:  # p-values far below any level
        return True
    return math.isclose(a, b, rel_tol=0.02, abs_tol=1e-9)


def test_the_pages_commands_are_the_scripts(tmp_path) -> None:
    mod = load_script("your_building_doc")
    page = mod.PAGE.read_text()
    assert mod.shown_commands(page) == [b.commands if b.show_commands else () for b in mod.BLOCKS]
    mod.write_files(page, tmp_path)  # every file the commands use comes from the page
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(mod.FILES)
    held_out = (tmp_path / "held-out-map.toml").read_text()
    assert 'start = "2009-02-09 12:00"' in held_out and "end =" not in held_out
    assert "fixed = true" in (tmp_path / "classroom-fixed-envelope.toml").read_text()


def test_a_block_keeps_the_lines_asked_for_and_marks_the_rest() -> None:
    mod = load_script("your_building_doc")
    lines = ["a", "keep 1", "b", "c", "keep 2", "d"]
    assert mod._elide(lines, r"^keep") == ["...", "keep 1", "...", "keep 2", "..."]
    assert mod._elide(lines, None) == lines


def test_the_comparison_sees_a_changed_word_and_a_moved_number() -> None:
    a = _skeleton("open-loop RMSE 0.434 K, max 1.130 K; ┏━━━┓")
    assert a == _skeleton("open-loop RMSE  0.434 K, max 1.130 K; ┏━━━━━┓")
    assert a[0] != _skeleton("open-loop RMSE 0.434 K, min 1.130 K; ┏━┓")[0]
    assert not all(map(_close, a[1], _skeleton("open-loop RMSE 0.654 K, max 1.130 K")[1]))


@pytest.mark.slow
def test_a_fresh_run_reproduces_the_page(tmp_path) -> None:
    mod = load_script("your_building_doc")
    require(*(SHARED / rel for rel in mod.DATA.values()), what="the page's real data")
    fresh = tmp_path / "your-building.md"
    assert mod.main(["--shared", str(SHARED), "--out", str(fresh)]) == 0
    old_words, old_numbers = _skeleton(mod.PAGE.read_text())
    new_words, new_numbers = _skeleton(fresh.read_text())
    assert new_words == old_words
    moved = [(a, b) for a, b in zip(old_numbers, new_numbers) if not _close(a, b)]
    assert not moved, f"numbers that drifted (page, fresh run): {moved[:10]}"


def test_the_compile_notice_the_script_leaves_out_is_the_commands() -> None:
    from rczone.cli.compile_notice import NOTICE

    assert load_script("your_building_doc").COMPILING == NOTICE
