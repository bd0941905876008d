"""Model files with ``[[disturbance]]`` tables: read, written back, saved as JSON; bad tables are one clear error."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest

from rczone.errors import ModelFileError
from rczone.models import ZoneModel, load_model, model_to_toml, read_model_file
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor
from rczone.network.disturbance import LatentForce

TEXT = """
name = "room+gains"
boundaries = ["To"]
resistors = [["Ti", "Te", "Rie"], ["Te", "To", "Rea"]]

[nodes]
Ti = "Ci"
Te = "Ce"

[heat_inputs]
Ph = "Ti"

[[disturbance]]
name = "Qg"
kind = "matern32"
to = { Ti = 0.7, Te = "ge" }
magnitude = "sg"
length_scale = "lg"

[[disturbance]]
name = "Qday"
kind = "periodic"
to = "Ti"
magnitude = "sp"
length_scale = "lp"
period = "Pday"

[parameters]
Ci = { value = 1.2, unit = "MJ/K" }
Ce = { value = 15, unit = "MJ/K" }
Rie = { value = 2, unit = "K/kW" }
Rea = { value = 20, unit = "K/kW" }
ge = { value = 0.3, bounds = [0, 1] }
sg = { value = 0.2, unit = "kW", bounds = [0.001, 5] }
lg = { value = 3, unit = "h" }
sp = { value = 100, unit = "W" }
lp = { value = 5, unit = "d" }
Pday = { value = 1, unit = "d", fixed = true }
"""


def _write(tmp_path, text: str, name: str = "m.toml"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def python_declaration() -> RCNetwork:
    return RCNetwork(
        "room+gains",
        [Node("Ti", "Ci"), Node("Te", "Ce")],
        ["To"],
        [Resistor("Ti", "Te", "Rie"), Resistor("Te", "To", "Rea")],
        [
            Parameter("Ci", "capacitance", 1.2e6),
            Parameter("Ce", "capacitance", 15e6),
            Parameter("Rie", "resistance", 2e-3),
            Parameter("Rea", "resistance", 20e-3),
            Parameter("ge", "gain", 0.3, bounds=(0.0, 1.0)),
            Parameter("sg", "magnitude", 200.0, bounds=(1.0, 5000.0)),
            Parameter("lg", "time", 3 * 3600.0),
            Parameter("sp", "magnitude", 100.0),
            Parameter("lp", "time", 5 * 86400.0),
            Parameter("Pday", "time", 86400.0, fixed=True),
        ],
        [HeatInput("Ph", "Ti")],
        disturbances=[
            LatentForce("Qg", "matern32", {"Ti": 0.7, "Te": "ge"}, magnitude="sg", length_scale="lg"),
            LatentForce("Qday", "periodic", "Ti", magnitude="sp", length_scale="lp", period="Pday"),
        ],
    )


def _same(a, b) -> None:
    for x, y in ((a.A, b.A), (a.B, b.B), (a.C, b.C), (a.D, b.D), (a.diffusion, b.diffusion)):
        np.testing.assert_allclose(x, y, rtol=1e-14, atol=0)
    assert a.state_names == b.state_names


def test_disturbance_tables_equal_the_python_declaration(tmp_path) -> None:
    """Units converted once (kW, h, d), kinds inferred from the roles (magnitude, time, gain)."""
    zm = read_model_file(_write(tmp_path, TEXT))
    net = zm.network
    assert net.state_names == ("Ti", "Te", "Qg", "Qg_d1", "Qday", "Qday_q")
    kinds = {n: net.parameters[n].kind for n in ("ge", "sg", "lg", "Pday")}
    assert kinds == {"ge": "gain", "sg": "magnitude", "lg": "time", "Pday": "time"}
    assert net.parameters["sg"].bounds == (1.0, 5000.0)
    assert "Pday" not in net.default_free and {"sg", "lg", "sp", "lp"} <= set(net.default_free)
    _same(net.state_space(), python_declaration().state_space())


def test_model_file_and_json_round_trips_keep_the_disturbances(tmp_path) -> None:
    zm = read_model_file(_write(tmp_path, TEXT))
    back = read_model_file(_write(tmp_path, model_to_toml(zm), "back.toml"))
    assert back.network.disturbances == zm.network.disturbances
    _same(back.state_space(), zm.state_space())
    saved = load_model(str(zm.save(tmp_path / "m.json")))
    assert saved.network.disturbances == zm.network.disturbances
    _same(saved.state_space(), zm.state_space())
    # a model without disturbances keeps its JSON (no new key)
    assert "disturbances" not in load_model("second-order-paper").to_dict()["network"]


BAD = [
    ('kind = "matern32"', 'kind = "matern12"', "disturbance\\[0\\].*'matern12' is not one of"),
    ('to = { Ti = 0.7, Te = "ge" }', "to = { Tx = 1.0 }", "undeclared node 'Tx'"),
    ('to = { Ti = 0.7, Te = "ge" }', "to = {}", "names no node"),
    ('length_scale = "lg"\n', 'length_scale = "lg"\nspread = 3\n', "unknown key 'spread'"),
    ('magnitude = "sg"\n', "", "needs magnitude"),
    ('magnitude = "sg"', "magnitude = true", "must be a number"),
    ('period = "Pday"\n', "", "needs a period"),
    (
        'sg = { value = 0.2, unit = "kW", bounds = [0.001, 5] }',
        'sg = { value = 0.2, unit = "K/W" }',
        "not a unit of a magnitude",
    ),
    ('lg = { value = 3, unit = "h" }', "lg = { value = -3 }", "must be > 0"),
    (
        'lg = { value = 3, unit = "h" }',
        'lg = { value = 3, unit = "h", kind = "resistance" }',
        "used as a time",
    ),
    ('magnitude = "sp"', 'magnitude = "lp"', "used as magnitude and as time"),
    ('name = "Qg"', 'name = "Ti"', "reuses a node"),
]


@pytest.mark.parametrize(("old", "new", "match"), BAD, ids=[f"bad{i}" for i in range(len(BAD))])
def test_bad_disturbance_tables_are_one_clear_error(tmp_path, old, new, match) -> None:
    assert old in TEXT
    with pytest.raises(ModelFileError, match=match) as exc:
        read_model_file(_write(tmp_path, TEXT.replace(old, new, 1)))
    assert "\n" not in str(exc.value)


def test_bad_disturbance_in_a_saved_model_is_refused(tmp_path) -> None:
    good = ZoneModel(python_declaration()).to_dict()
    bad = json.loads(json.dumps(good))
    bad["network"]["disturbances"][0]["gains"] = ["Ti"]
    with pytest.raises(ModelFileError, match="gains must be an object"):
        load_model(str(_write(tmp_path, json.dumps(bad), "m.json")))
    bad = json.loads(json.dumps(good))
    bad["network"]["disturbances"][1]["colour"] = 1
    with pytest.raises(ModelFileError, match="unknown key 'colour'"):
        load_model(str(_write(tmp_path, json.dumps(bad), "m.json")))


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [BAD[0], BAD[1], BAD[6], BAD[8]],
    ids=["kind", "node", "period", "length"],
)
def test_the_command_line_reports_a_bad_disturbance_in_one_line_with_exit_2(
    tmp_path, capsys, old, new, match
):
    """`rczone fit` on a model file with a bad [[disturbance]]: one error line naming the file, exit 2, no fit."""
    from rczone.cli.main import main

    t = np.arange(50) * 600.0
    pd.DataFrame({"time": t, "Ti": 20 + np.sin(t / 4e3), "To": 5.0, "Ph": 100.0}).to_csv(
        tmp_path / "d.csv", index=False
    )
    model = _write(tmp_path, TEXT.replace(old, new, 1))
    assert main(["fit", str(tmp_path / "d.csv"), "--model", str(model)]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if not ln.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    assert "m.toml" in err
    assert re.search(match, err), err
