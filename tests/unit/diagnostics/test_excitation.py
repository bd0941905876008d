"""Collinear inputs: three heater powers that switch together, by construction.

The excitation statistics are checked against NumPy written out here (``corrcoef``, the
eigenvalues of the correlation); the diagnosis of a model with three heater gains on data where
the three switch together must name the three, call none of the gains identifiable, and advise a
test that switches them apart or a summed channel -- not wider bounds.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from rczone.data.excitation import CONDITION_INDEX_COLLINEAR, input_excitation
from rczone.models import read_model_file
from rczone.simulation import simulate

MODEL = """
name = "three heaters"
boundaries = ["To"]
outputs = ["Ti"]
resistors = [["Ti", "Te", "Rie"], ["Te", "To", "Rea"]]

[nodes]
Ti = "Ci"
Te = "Ce"

[heat_inputs]
Ph1 = { to = { Ti = "g1" } }
Ph2 = { to = { Ti = "g2" } }
Ph3 = { to = { Ti = "g3" } }

[parameters]
Ci = { value = 2e6, bounds = [1e4, 1e9] }
Ce = { value = 1e7, bounds = [1e5, 1e10] }
Rie = { value = 2e-3, bounds = [1e-6, 1] }
Rea = { value = 4e-3, bounds = [1e-6, 1] }
g1 = { value = 1.0, kind = "gain", bounds = [0, 3] }
g2 = { value = 1.0, kind = "gain", bounds = [0, 3] }
g3 = { value = 1.0, kind = "gain", bounds = [0, 3] }
"""


def _heaters(n: int, rng, together: bool) -> np.ndarray:
    """Three heater powers (W): one PRBS switching all three (with 0.5 % jitter), or three independent ones."""

    def prbs():
        return np.repeat(rng.choice([0.0, 1.0], n // 12 + 1), 12)[:n]

    if together:
        on = prbs()
        return np.column_stack([p * on * (1 + 0.005 * rng.standard_normal(n)) for p in (500.0, 800.0, 300.0)])
    return np.column_stack([p * prbs() for p in (500.0, 800.0, 300.0)])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("collinear")
    (d / "three.toml").write_text(MODEL)
    zm = read_model_file(d / "three.toml")
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 3 * 86400.0, 300.0)
    to = 5 + 3 * np.sin(2 * np.pi * t / 86400.0)
    ph = _heaters(t.size, rng, together=True)
    u = np.column_stack([to, ph])  # the model's inputs: To, Ph1, Ph2, Ph3
    assert list(zm.network.input_names) == ["To", "Ph1", "Ph2", "Ph3"]
    y = simulate(zm.network.state_space(), t, u, x0=np.array([15.0, 10.0])).y[:, 0]
    frame = pd.DataFrame({"time": t, "Ti": y + rng.normal(0, 0.02, t.size), "To": to})
    for j in range(3):
        frame[f"Ph{j + 1}"] = ph[:, j]
    frame.to_csv(d / "zone.csv", index=False)
    return d, frame


def test_the_statistics_equal_numpy_written_out():
    rng = np.random.default_rng(0)
    u = np.column_stack([rng.normal(size=500), _heaters(500, rng, together=True)])
    exc = input_excitation(u, ["To", "Ph1", "Ph2", "Ph3"])
    np.testing.assert_allclose(exc.correlation, np.corrcoef(u.T), atol=1e-12)
    lam = np.linalg.eigvalsh(np.corrcoef(u.T))
    assert exc.condition_index == pytest.approx(np.sqrt(lam[-1] / lam[0]), rel=1e-8)
    assert exc.condition_index >= CONDITION_INDEX_COLLINEAR and exc.groups == (("Ph1", "Ph2", "Ph3"),)
    assert min(abs(r) for *_, r in exc.pairs) >= 0.99
    apart = input_excitation(
        np.column_stack([u[:, 0], _heaters(500, rng, together=False)]), ["To", "Ph1", "Ph2", "Ph3"]
    )
    assert not apart.collinear and apart.condition_index < CONDITION_INDEX_COLLINEAR


def test_a_constant_input_is_set_aside_not_called_collinear():
    rng = np.random.default_rng(1)
    u = np.column_stack([rng.normal(size=100), np.full(100, 50.0), rng.normal(size=100)])
    exc = input_excitation(u, ["To", "Q", "Ph"])
    assert exc.constant == ("Q",) and exc.inputs == ("To", "Ph") and not exc.collinear


@pytest.mark.slow
def test_diagnose_names_the_collinear_heaters_and_calls_no_gain_identifiable(files, capsys):
    from rczone.cli.main import main

    d, _ = files
    out = d / "diag.json"
    code = main(["diagnose", str(d / "zone.csv"), "--model", str(d / "three.toml"), "--json", str(out)])
    assert code in (0, 3)
    text = " ".join(capsys.readouterr().out.split())  # the console wraps long lines
    res = json.loads(out.read_text())
    assert res["excitation"]["collinear"] == [["Ph1", "Ph2", "Ph3"]]
    verdicts = {n: v["verdict"] for n, v in res["parameters"].items()}
    assert all(verdicts[g] != "identifiable" for g in ("g1", "g2", "g3")), verdicts
    for g in ("g1", "g2", "g3"):
        advice = res["parameters"][g]["advice"]
        assert "switches them apart" in advice and "widen the bounds" not in advice
    assert "collinear inputs:" in text and "Ph1 + Ph2 + Ph3" in text


def test_a_value_within_the_margin_of_a_bound_is_not_identifiable():
    from rczone.diagnostics.identifiability import parameters_near_bound

    zm = read_model_file_text(MODEL)
    near = parameters_near_bound(zm.network, ["g1", "g2", "Ci"], {"g1": 2.972, "g2": 2.5, "Ci": 1.05e4})
    assert near == {"g1": "upper", "Ci": "lower"}


def read_model_file_text(text: str):
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "m.toml"
        p.write_text(text)
        return read_model_file(p)


@pytest.mark.slow
def test_fit_names_the_collinear_heaters_in_its_verdict(files, capsys):
    from rczone.cli.main import main

    d, _ = files
    out = d / "fit.json"
    args = ["fit", str(d / "zone.csv"), "--model", str(d / "three.toml"), "--method", "ls", "--starts", "1"]
    main([*args, "--json", str(out), "--no-profiles"])
    text = " ".join(capsys.readouterr().out.split())
    res = json.loads(out.read_text())
    assert res["excitation"]["collinear"] == [["Ph1", "Ph2", "Ph3"]]
    assert any("Ph1, Ph2, Ph3 move together" in n for n in res["verdict"]["notes"])
    assert "collinear inputs:" in text
