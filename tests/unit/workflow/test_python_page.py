"""docs/python.md runs: its Python blocks, in order, in an empty folder, on built-in data."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

PAGE = Path(__file__).resolve().parents[3] / "docs" / "python.md"


def code_blocks(text: str) -> list[str]:
    """The ```python blocks of a Markdown page, in order."""
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_the_python_page_runs_and_shows_what_it_prints(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("COLUMNS", "100")
    text = PAGE.read_text()
    blocks = code_blocks(text)
    assert len(blocks) >= 6
    namespace: dict = {"__name__": "python_page"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for block in blocks:
            exec(compile(block, str(PAGE), "exec"), namespace)
    printed = out.getvalue()
    # the page shows the fit's table and the prediction's line as they are printed
    fitted, prediction = namespace["fitted"], namespace["prediction"]
    for line in (
        *fitted.summary(width=100).splitlines()[1:24],  # the header block and the table
        prediction.summary(width=100).splitlines()[-2],
    ):
        assert line.rstrip() in text, line
    assert "office.toml fitted to office.csv by ML" in printed
    assert (tmp_path / "office-fit.json").exists()
