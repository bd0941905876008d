"""Every bad-data case reaches the user of the CLI as one `error:` line and exit code 2."""

import re
import tomllib

import pytest

from rczone.cli.main import main
from tests.unit.data.test_load_errors import FRAME_CASES, good_frame


def _toml(doc: dict) -> str:
    """A column-map dict as TOML (the small subset the cases use)."""

    def value(v):
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        if isinstance(v, str):
            return f'"{v}"'
        return repr(v)

    top = [f"{k} = {value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    tables = [
        f"[{k}]\n" + "\n".join(f"{a} = {value(b)}" for a, b in v.items())
        for k, v in doc.items()
        if isinstance(v, dict)
    ]
    text = "\n".join(top) + "\n" + "\n\n".join(tables) + "\n"
    assert tomllib.loads(text) == doc  # the helper writes what the case means
    return text


@pytest.mark.parametrize(
    ("edit", "doc", "pattern"), [c[1:] for c in FRAME_CASES], ids=[c[0] for c in FRAME_CASES]
)
@pytest.mark.parametrize("command", ["fit", "diagnose"])
def test_bad_data_is_one_line_and_exit_2(tmp_path, capsys, edit, doc, pattern, command):
    path = tmp_path / "zone.csv"
    edit(good_frame()).to_csv(path, index=False)
    args = [command, str(path)]
    if doc is not None:
        (tmp_path / "map.toml").write_text(_toml(doc))
        args += ["--columns", str(tmp_path / "map.toml")]
    rc = main(args)
    err = capsys.readouterr().err
    assert rc == 2, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len([ln for ln in lines if ln.startswith("error:")]) == 1 and "Traceback" not in err
    assert re.search(pattern, " ".join(ln.strip() for ln in lines)), err
