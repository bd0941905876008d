"""docs/control.md carries the tables validation/control_doc.py wrote last, on seeds no test names."""

import re

from tests.validation.scripts import ROOT, load_script


def test_the_pages_tables_are_the_scripts_last_output():
    script = load_script("control_doc")
    written = script.blocks(script.OUT.read_text())
    page = script.blocks(script.PAGE.read_text())
    assert set(written) >= {
        "baselines-summer",
        "baselines-winter",
        "baselines-summer-tou",
        "baselines-summer-dr",
    }
    assert page == written


def test_the_pages_seeds_are_named_by_no_test():
    script = load_script("control_doc")
    named = set()
    for path in (ROOT / "tests").rglob("*.py"):
        if path.name != "test_control_doc.py":
            named |= {int(s) for s in re.findall(r"seeds?\s*=\s*\[?\(?(\d+)", path.read_text())}
    assert not named & set(script.SEEDS)


def test_paste_replaces_a_tables_block_and_nothing_else():
    script = load_script("control_doc")
    page = "intro\n" + script.block("a", "| old |") + "\nprose\n" + script.block("b", "| keep |") + "\n"
    new = script.paste(page, {"a": "| new |"})
    assert script.blocks(new) == {"a": "| new |", "b": "| keep |"}
    assert new.startswith("intro\n") and "\nprose\n" in new
