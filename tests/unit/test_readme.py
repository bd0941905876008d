"""The README's Python example runs as written."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_quick_start_has_exactly_the_two_commands():
    text = README.read_text()
    block = re.search(r"## Quick start\s+```\n(.*?)```", text, re.S).group(1)
    assert block.split("\n")[:2] == ["make demo", "make test"] and block.strip().count("\n") == 1


def test_readme_python_example_runs(capsys):
    code = re.search(r"```python\n(.*?)```", README.read_text(), re.S).group(1)
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "('To', 'Tsd', 'Ts', 'Q') ('m',)" in out
    ti = float(out.strip().splitlines()[-1].strip("[]"))
    assert 13.0 < ti < 28.0  # between the coldest and warmest driving temperature


def test_readme_model_file_example_reads(tmp_path):
    from rczone.models import read_model_file

    blocks = re.findall(r"```toml\n(.*?)```", README.read_text(), re.S)
    model = next(b for b in blocks if b.startswith("name ="))
    (tmp_path / "m.toml").write_text(model)
    zm = read_model_file(tmp_path / "m.toml")
    assert zm.network.state_names == ("Ti", "Te") and zm.network.default_free == ("Ci", "Ce", "Rie", "Aw")
