"""The example of docs/control.md runs as written and does what it says."""

import re
from pathlib import Path

DOC = Path(__file__).resolve().parents[3] / "docs" / "control.md"


def test_control_doc_example_runs(capsys):
    code = re.search(r"```python\n(.*?)```", DOC.read_text(), re.S).group(1)
    scope: dict = {}
    exec(compile(code, "docs/control.md", "exec"), scope)
    assert "d_heat" in capsys.readouterr().out
    a = scope["action"]
    lim = scope["mpc"].limits
    assert lim.m_min <= a.m <= lim.m_max and a.reheat >= 0 and a.ts <= lim.ts_max + 1e-9
    assert scope["sys"].dt == 600.0 and scope["na"].names["flows"] == ("m",)
