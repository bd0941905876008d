import base64
import json

import numpy as np
import pytest
from matplotlib.figure import Figure

from rczone.files.atomic import write_bytes_atomic, write_json_atomic
from rczone.report import Report


def test_json_is_plain_and_nan_becomes_null(tmp_path):
    p = write_json_atomic(
        tmp_path / "r.json", {"a": np.float64(1.5), "b": np.array([1, 2]), "c": float("nan")}
    )
    assert json.loads(p.read_text()) == {"a": 1.5, "b": [1, 2], "c": None}


def test_failed_write_leaves_previous_file_and_no_temporaries(tmp_path):
    target = tmp_path / "results.json"
    write_json_atomic(target, {"ok": 1})

    class Boom:
        def __bytes__(self):
            raise RuntimeError

    with pytest.raises(TypeError):
        write_bytes_atomic(target, Boom())  # type: ignore[arg-type]
    assert json.loads(target.read_text()) == {"ok": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["results.json"]


def test_report_embeds_figures_and_writes_pngs(tmp_path):
    r = Report("t")
    fig = Figure()
    fig.subplots().plot([0, 1], [1, 0])
    r.heading("Section <1>")
    r.table([{"name": "Rw", "value": 0.0123456}], caption="cap")
    r.figure("f1", fig, "a caption")
    path = r.write(tmp_path)
    html = path.read_text()
    assert "Section &lt;1&gt;" in html and "0.01235" in html
    b64 = html.split("data:image/png;base64,")[1].split('"')[0]
    assert base64.b64decode(b64)[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "f1.png").read_bytes() == base64.b64decode(b64)
