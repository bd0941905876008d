"""Model files: a person's TOML, read into the same networks rczone declares in Python; hostile files fail cleanly."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rczone.errors import ModelFileError, ParameterError
from rczone.models import ZoneModel, builtin_names, load_model, model_to_toml, read_model_file
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

GOOD = """
name = "office 3.12"
description = "air and envelope"
boundaries = ["To"]
outputs = ["Ti"]
resistors = [
    ["Ti", "Te", "Rie"],
    ["Te", "To", "Rea"],
]

[nodes]
Ti = { capacity = "Ci", description = "room air" }
Te = "Ce"

[heat_inputs]
Ph = "Ti"
Ps = { to = { Ti = "Aw" }, unit = "W/m2" }

[[supply_air]]
node = "Ti"

[parameters]
Ci  = { value = 1.2, unit = "MJ/K", bounds = [0.01, 100] }
Ce  = { value = 15, unit = "MJ/K" }
Rie = { value = 2, unit = "K/kW" }
Rea = { value = 20, unit = "K/kW", fixed = true }
Aw  = { value = 2, unit = "m2", bounds = [0, 50] }

[inputs]
Ph = { default = 0, description = "heater, W" }
"""


def _write(tmp_path, text: str, name: str = "m.toml"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_model_file_equals_the_python_declaration(tmp_path) -> None:
    """Units are converted once, kinds follow from use, fixed and bounds travel; same matrices."""
    zm = read_model_file(_write(tmp_path, GOOD))
    ref = RCNetwork(
        "office 3.12",
        [Node("Ti", "Ci"), Node("Te", "Ce")],
        ["To"],
        [Resistor("Ti", "Te", "Rie"), Resistor("Te", "To", "Rea")],
        [
            Parameter("Ci", "capacitance", 1.2e6, bounds=(1e4, 1e8)),
            Parameter("Ce", "capacitance", 1.5e7),
            Parameter("Rie", "resistance", 2e-3),
            Parameter("Rea", "resistance", 2e-2, fixed=True),
            Parameter("Aw", "gain", 2.0, unit="m2", bounds=(0.0, 50.0)),
        ],
        heat_inputs=[HeatInput("Ph", {"Ti": 1.0}), HeatInput("Ps", {"Ti": "Aw"}, unit="W/m2")],
        supply_air=[SupplyAir("Ti")],
    )
    a, b = zm.state_space(), ref.state_space()
    for x, y in ((a.A, b.A), (a.B, b.B), (a.N, b.N), (a.M, b.M), (a.C, b.C)):
        np.testing.assert_allclose(x, y, rtol=1e-15)
    net = zm.network
    assert net.parameters["Ci"].kind == "capacitance" and net.parameters["Ci"].bounds == pytest.approx(
        (1e4, 1e8)
    )
    assert net.parameters["Rie"].value == pytest.approx(2e-3) and net.parameters["Rie"].unit == "K/W"
    assert net.default_free == ("Ci", "Ce", "Rie", "Aw")  # Rea is fixed
    assert zm.inputs.defaults == {"Ph": 0.0}
    assert zm.signal_quantities()["Ps"] == "irradiance" and zm.required_signals() == (
        "Ti",
        "To",
        "Ts",
        "Ps",
        "m",
    )
    assert zm.label == "m.toml"


@pytest.mark.parametrize("name", [*builtin_names(), "TiTe+heater+solar+air+gain", "TiTeTh+solar", "TiTm+air"])
def test_written_model_files_read_back_identically(tmp_path, name) -> None:
    zm = load_model(name)
    back = read_model_file(_write(tmp_path, model_to_toml(zm, header="a header")))
    a, b = zm.state_space(), back.state_space()
    for x, y in ((a.A, b.A), (a.B, b.B), (a.N, b.N), (a.M, b.M), (a.C, b.C), (a.D, b.D)):
        np.testing.assert_array_equal(x, y)
    assert back.network.default_free == zm.network.default_free
    assert dict(back.inputs.defaults) == dict(zm.inputs.defaults)
    assert dict(back.inputs.mean_of) == dict(zm.inputs.mean_of)
    assert {n: p.bounds for n, p in back.network.parameters.items()} == {
        n: p.bounds for n, p in zm.network.parameters.items()
    }


def test_a_parameter_used_only_in_ties_takes_their_kind(tmp_path) -> None:
    text = GOOD.replace('["Ti", "Te", "Rie"]', '["Ti", "Te", "R1"]').replace(
        'Rie = { value = 2, unit = "K/kW" }', 'Rw = { value = 4, unit = "K/kW" }\nR1 = { expr = "Rw/2" }'
    )
    net = read_model_file(_write(tmp_path, text)).network
    assert net.parameters["Rw"].kind == "resistance" and net.parameters["Rw"].value == pytest.approx(4e-3)
    assert net.values()["R1"] == pytest.approx(2e-3) and "R1" not in net.default_free


BAD = [
    ("name = 1\n" + GOOD.split("\n", 2)[2], r"name: must be a non-empty string"),
    (GOOD.replace("[parameters]", "[parameter]"), r"unknown key 'parameter'.*did you mean 'parameters'"),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', 'Ce  = { value = 15, unit = "MJ" }'),
        r"'MJ' is not a unit of a capacitance",
    ),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', "Ce  = { value = nan }"),
        r"Ce.value: must be finite",
    ),
    (GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', "Ce  = { value = -1 }"), r"Ce.*must be > 0"),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', "Ce  = { value = true }"),
        r"Ce.value: must be a number",
    ),
    (GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', ""), r"undeclared parameter 'Ce'"),
    (GOOD.replace('["Te", "To", "Rea"]', '["Te", "Tx", "Rea"]'), r"undeclared node 'Tx'"),
    (GOOD.replace('Ph = "Ti"', "Ph = { to = { Ti = nan } }"), r"Ph.to.Ti: must be finite"),
    (GOOD.replace('node = "Ti"', 'node = "Ti"\ncp = nan'), r"cp: must be finite"),
    (GOOD.replace('node = "Ti"', 'node = "Ti"\ncp = -5'), r"cp.*must be > 0"),
    (GOOD.replace("bounds = [0.01, 100]", "bounds = [100, 0.01]"), r"lower < upper"),
    (GOOD.replace("bounds = [0.01, 100]", "bounds = [2, 100]"), r"not strictly inside its bounds"),
    (GOOD.replace("fixed = true", 'fixed = "yes"'), r"fixed: must be true or false"),
    (GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', 'Ce  = { expr = "9**9**9**9" }'), r"overflows"),
    (GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', 'Ce  = { expr = "10**400" }'), r"exponent 400"),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', 'Ce  = { expr = "(-1)**0.5" }'),
        r"not a real number",
    ),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', 'Ce  = { expr = "__import__(1)" }'),
        r"only numbers",
    ),
    (
        GOOD.replace(
            'Ce  = { value = 15, unit = "MJ/K" }', 'Ce  = { expr = "' + "+".join(["Ci"] * 20000) + '" }'
        ),
        r"longer than the limit",
    ),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', 'Ce  = { expr = "' + "-" * 100000 + 'Ci" }'),
        r"longer than the limit",
    ),
    (GOOD.replace("[inputs]", "[inputs]\nTx = { default = 1 }"), r"no such input"),
    (GOOD.replace("[inputs]", "[inputs]\nTo = { mean_of = [] }"), r"lists no column"),
    (
        GOOD.replace('Ti = { capacity = "Ci", description = "room air" }', 'Ti = { capacity = "Rie" }'),
        r"used as capacitance and as resistance",
    ),
    ("resistors = 3\n[nodes]\nTi = 'C'\n[parameters]\nC = 1", r"resistors: must be a list"),
    ("x = " + "[" * 5000 + "]" * 5000, r"nested more than 32 levels"),
    ("[nodes]\n[parameters]\n", r"missing 'resistors'"),
    (
        GOOD.replace(
            'Rie = { value = 2, unit = "K/kW" }',
            'Rie = { value = 2, prior = { dist = "lognormal", median = 2, sigm = 1 } }',
        ),
        r"Rie.prior: lognormal prior: unknown key 'sigm'; did you mean 'sigma'",
    ),
    (
        GOOD.replace(
            'Rie = { value = 2, unit = "K/kW" }',
            'Rie = { value = 2, prior = { dist = "normal", mean = 2, sigma = 0 } }',
        ),
        r"Rie.prior: normal prior: sigma must be > 0",
    ),
    (
        GOOD.replace(
            'Aw  = { value = 2, unit = "m2", bounds = [0, 50] }',
            'Aw  = { value = 2, prior = { dist = "lognormal", median = 2, sigma = 1 } }',
        ),
        r"Aw: parameter 'Aw': a lognormal prior needs a positive parameter",
    ),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', "Ce  = { value = 15, prior = 3 }"),
        r"Ce.prior: must be a table",
    ),
    (
        GOOD.replace('Ce  = { value = 15, unit = "MJ/K" }', "Ce  = { value = 15, prior = { median = 3 } }"),
        r"Ce.prior: a prior needs dist",
    ),
]


@pytest.mark.parametrize(("text", "match"), BAD, ids=[f"bad{i}" for i in range(len(BAD))])
def test_bad_model_files_are_one_clear_error(tmp_path, text, match) -> None:
    with pytest.raises(ModelFileError, match=match) as info:
        load_model(str(_write(tmp_path, text)))
    msg = str(info.value)
    assert "\n" not in msg and str(tmp_path) in msg  # one line naming the file


def test_hostile_files(tmp_path) -> None:
    latin = tmp_path / "latin.toml"
    latin.write_bytes(GOOD.replace("room air", "pièce").encode("latin-1"))
    with pytest.raises(ModelFileError, match="not UTF-8"):
        load_model(str(latin))
    (tmp_path / "dir.toml").mkdir()
    with pytest.raises(ModelFileError, match="is a folder"):
        load_model(str(tmp_path / "dir.toml"))
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * 17_000_000)
    with pytest.raises(ModelFileError, match="more than the limit"):
        load_model(str(big))
    with pytest.raises(ModelFileError, match="does not exist"):
        load_model(str(tmp_path / "missing.toml"))
    with pytest.raises(ModelFileError, match=r"unknown type '\.yaml'"):
        load_model(str(_write(tmp_path, GOOD, "m.yaml")))
    with pytest.raises(ParameterError, match=r"not a built-in model.*did you mean 'TiTe'"):
        load_model("TiTee")
    with pytest.raises(ParameterError, match=r"unknown option 'solr'.*'solar'"):
        load_model("TiTe+solr")


SAVED_BAD = [
    ("[]", "expected a JSON object, got list"),
    ("null", "expected a JSON object, got NoneType"),
    ('{"format": "rczone-model/1"}', "has no 'network'"),
    ('{"format": "rczone-model/1", "network": {}, "theta": null}', "'theta' must be an object"),
    ('{"format": "rczone-model/1", "network": {}, "theta": [1]}', "'theta' must be an object"),
    ('{"format": "rczone-model/1", "network": {}, "theta": "x"}', "'theta' must be an object"),
    ('{"format": "rczone-model/1", "network": [], "theta": {}}', "must be an object"),
    ('{"format": "rczone-model/1", "network": {"format": "rczone-network/1"}}', "has no 'nodes'"),
    ("[" * 100000 + "]" * 100000, "nested more than 32 levels"),
]


@pytest.mark.parametrize(("text", "match"), SAVED_BAD, ids=[f"saved{i}" for i in range(len(SAVED_BAD))])
def test_bad_saved_models(tmp_path, text, match) -> None:
    with pytest.raises(ModelFileError, match=match):
        load_model(str(_write(tmp_path, text, "m.json")))


def test_saved_model_with_non_finite_element_is_refused(tmp_path) -> None:
    good = load_model("second-order-paper").to_dict()
    bad = json.loads(json.dumps(good))
    bad["network"]["heat_inputs"][0]["split"]["Ti"] = 1e400  # JSON parses it as inf
    text = json.dumps(bad).replace("Infinity", "1e400")
    with pytest.raises(ModelFileError, match="not finite"):
        load_model(str(_write(tmp_path, text, "m.json")))
    nan_theta = json.loads(json.dumps(good))
    nan_theta["theta"]["Rw"] = float("nan")
    with pytest.raises(ModelFileError, match="'Rw' = nan is not finite"):
        load_model(str(_write(tmp_path, json.dumps(nan_theta), "nan.json")))
    ok = _write(tmp_path, json.dumps(good), "ok.json")
    assert isinstance(load_model(str(ok)), ZoneModel)


def test_saved_values_become_the_start(tmp_path) -> None:
    zm = load_model("second-order-paper").with_values({"Rw": 0.02}, {"sigma_v": 0.05}, method="ml")
    back = load_model(str(zm.save(tmp_path / "fit.json")))
    assert back.theta["Rw"] == 0.02 and back.noise == {"sigma_v": 0.05}
    assert back.network.parameters["Rw"].value == zm.network.parameters["Rw"].value  # construction kept
    assert back.inputs.defaults == {"Q": 50.0} and back.provenance["method"] == "ml"


def test_priors_are_read_in_the_parameters_unit_and_written_back(tmp_path) -> None:
    text = (
        GOOD.replace(
            'Rie = { value = 2, unit = "K/kW" }',
            'Rie = { value = 2, unit = "K/kW", prior = { dist = "lognormal", median = 2.5, sigma = 0.7 } }',
        )
        .replace(
            'Ce  = { value = 15, unit = "MJ/K" }',
            'Ce  = { value = 15, unit = "MJ/K", prior = { dist = "normal", mean = 15, sigma = 3 } }',
        )
        .replace(
            'Aw  = { value = 2, unit = "m2", bounds = [0, 50] }',
            'Aw  = { value = 2, unit = "m2", bounds = [0, 50], prior = { dist = "uniform", lower = 0, upper = 10 } }',
        )
    )
    net = read_model_file(_write(tmp_path, text)).network
    # K/kW -> K/W and MJ/K -> J/K on the numbers in the unit; the log-normal sigma is a ratio
    assert {n: p.to_dict() for n, p in net.priors.items()} == {
        "Rie": {"dist": "lognormal", "median": pytest.approx(2.5e-3, rel=1e-12), "sigma": 0.7},
        "Ce": {
            "dist": "normal",
            "mean": pytest.approx(15e6, rel=1e-12),
            "sigma": pytest.approx(3e6, rel=1e-12),
        },
        "Aw": {"dist": "uniform", "lower": 0.0, "upper": 10.0},
    }
    back = read_model_file(_write(tmp_path, model_to_toml(net), "back.toml")).network
    assert back.priors == net.priors
    plain = read_model_file(_write(tmp_path, GOOD, "none.toml"))
    assert plain.network.priors == {} and "prior" not in model_to_toml(plain)
