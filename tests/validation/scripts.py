"""Loading the validation scripts (they live outside the package), and their tables on docs/validation.md."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: The page the scripts' tables are on.
PAGE = ROOT / "docs" / "validation.md"


def load_script(name: str):
    """The module ``validation/<name>.py``."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "validation" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _first_cell(line: str) -> str:
    return line.strip("|").split("|", 1)[0].strip()


def assert_on_page(tables: str, *, after: str = "", some_rows: bool = False) -> None:
    """Every Markdown table of ``tables`` (blank-line separated) is on the page: the words the same, numbers within 2 %.

    Each table is compared with the first table on :data:`PAGE` after the text ``after`` that starts
    with the same header line. ``some_rows``: the fresh table has only some of the page's rows
    (a run of some data sets); the page's rows are those whose first cell a fresh row has.
    """
    from tests.validation.test_your_building_doc import _close, _skeleton

    page = PAGE.read_text()
    for table in tables.strip().split("\n\n"):
        head = table.splitlines()[0]
        start = page.index(head, page.index(after) if after else 0)
        shown = page[start:].split("\n\n", 1)[0]
        if some_rows:
            firsts = {_first_cell(line) for line in table.splitlines()[2:]}
            lines = shown.splitlines()
            shown = "\n".join(lines[:2] + [x for x in lines[2:] if _first_cell(x) in firsts])
        (words, numbers), (page_words, page_numbers) = _skeleton(table), _skeleton(shown)
        assert words == page_words, f"the table differs from docs/validation.md:\n{table}\npage:\n{shown}"
        moved = [(a, b) for a, b in zip(numbers, page_numbers) if not _close(a, b)]
        assert not moved, f"numbers moved (fresh run, page): {moved[:10]}\n{table}"
