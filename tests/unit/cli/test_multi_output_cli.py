"""Two coupled rooms from a model file, through every command: fit, predict, diagnose, fit-many.

The data come from the two-room heat balance written out by hand (``tests.unit.selection.coupled``,
not rczone's network assembly), discretized exactly by ``scipy.linalg.expm`` with a zero-order
hold, with process and measurement noise; the fits must recover the known R, C and per-output noise levels.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from rczone.cli.main import main
from tests.unit.selection.coupled import joint_matrices, zoh

#: Starting values deliberately away from the truth (R12 5x, C1 2x off).
MODEL = """
name = "two rooms"
boundaries = ["To"]
outputs = ["T1", "T2"]
resistors = [["T1", "To", "R1o"], ["T2", "To", "R2o"], ["T1", "T2", "R12"]]

[nodes]
T1 = "C1"
T2 = "C2"

[heat_inputs]
Q1 = "T1"
Q2 = "T2"

[parameters]
C1 = { value = 1.0, unit = "MJ/K", bounds = [0.01, 100] }
C2 = { value = 1.0, unit = "MJ/K", bounds = [0.01, 100] }
R1o = { value = 20, unit = "K/kW", bounds = [0.1, 1000] }
R2o = { value = 20, unit = "K/kW", bounds = [0.1, 1000] }
R12 = { value = 50, unit = "K/kW", bounds = [0.1, 1000] }
"""
TRUTH = {"C1": 2.0e6, "C2": 1.0e6, "R1o": 0.03, "R2o": 0.015, "R12": 0.01}
SIGMA_V = {"T1": 0.03, "T2": 0.05}


def _prbs(rng: np.random.Generator, n: int, lo: int, hi: int) -> np.ndarray:
    out: list[float] = []
    level = 1.0
    while len(out) < n:
        out += [level] * int(rng.integers(lo, hi))
        level = 1.0 - level
    return np.array(out[:n])


def _simulate(n: int = 1440, dt: float = 60.0, seed: int = 1) -> pd.DataFrame:
    """One day at 1 min: C1 dT1/dt = (To-T1)/R1o + (T2-T1)/R12 + Q1, and the same for room 2."""
    rng = np.random.default_rng(seed)
    a, b = joint_matrices(
        {"C1": TRUTH["C1"], "C2": TRUTH["C2"], "R1": TRUTH["R1o"], "R2": TRUTH["R2o"], "R12": TRUTH["R12"]}
    )
    phi, gam, _ = zoh(a, b, np.zeros((2, 2)), dt)  # inputs To, Q1, Q2
    t = np.arange(n) * dt
    to = 5 + 3 * np.sin(2 * np.pi * t / 86400)
    q1, q2 = 1500 * _prbs(rng, n, 30, 150), 1200 * _prbs(rng, n, 20, 120)
    u = np.column_stack([to, q1, q2])
    x = np.empty((n, 2))
    x[0] = np.linalg.solve(a, -b @ u[0])
    for k in range(n - 1):
        x[k + 1] = phi @ x[k] + gam @ u[k] + rng.normal(0, 0.002, 2)
    y = x + rng.normal(0, 1, (n, 2)) * [SIGMA_V["T1"], SIGMA_V["T2"]]
    return pd.DataFrame({"time": t, "To": to, "Q1": q1, "Q2": q2, "T1": y[:, 0], "T2": y[:, 1]})


@pytest.fixture(scope="module")
def rooms(tmp_path_factory):
    d = tmp_path_factory.mktemp("rooms")
    (d / "two.toml").write_text(MODEL)
    _simulate().to_csv(d / "two.csv", index=False)
    return d


@pytest.fixture(scope="module")
def fitted(rooms):
    """The default ML fit from the CLI, with its JSON, saved model and report."""
    rc = main(
        [
            "fit",
            str(rooms / "two.csv"),
            "--model",
            str(rooms / "two.toml"),
            "--json",
            str(rooms / "fit.json"),
            "--save-model",
            str(rooms / "fitted.json"),
            "--report",
            str(rooms / "report"),
        ]
    )
    return rc, json.loads((rooms / "fit.json").read_text())


def test_joint_fit_recovers_every_resistance_capacity_and_noise(fitted):
    rc, out = fitted
    assert rc == 0, out.get("flags")
    for name, true in TRUTH.items():
        assert out["parameters"][name]["estimate"] == pytest.approx(true, rel=0.10), name
    for o, sv in SIGMA_V.items():
        assert out["outputs"][o]["sigma_v_K"] == pytest.approx(sv, rel=0.15), o
        assert out["outputs"][o]["open_loop_rmse_K"] < 3 * sv


def test_console_and_report_show_every_output(rooms, fitted, capsys):
    main(["fit", str(rooms / "two.csv"), "--model", str(rooms / "fitted.json"), "--method", "ls"])
    text = capsys.readouterr().out
    assert "open loop per output: T1 RMSE" in text and "T2 RMSE" in text
    assert "sigma_v_T2" not in text  # LS has no noise model
    rep = rooms / "report"
    assert (rep / "fit.png").exists() and (rep / "fit_T2.png").exists()
    assert "T2: open-loop RMSE" in (rep / "report.html").read_text()


def test_predict_writes_a_band_for_every_output(rooms, fitted):
    out = rooms / "pred.csv"
    assert main(["predict", str(rooms / "fitted.json"), str(rooms / "two.csv"), "--out", str(out)]) == 0
    series = pd.read_csv(out)
    for o in ("T1", "T2"):
        inside = (series[f"{o}_measured"] >= series[f"{o}_lower"]) & (
            series[f"{o}_measured"] <= series[f"{o}_upper"]
        )
        assert inside.mean() > 0.85, o


def test_diagnose_analyses_both_outputs(rooms, fitted, capsys):
    out = rooms / "diag.json"
    assert (
        main(["diagnose", str(rooms / "two.csv"), "--model", str(rooms / "fitted.json"), "--json", str(out)])
        == 0
    )
    rep = json.loads(out.read_text())
    assert set(rep["parameters"]) == set(TRUTH)
    assert "T1, T2" in capsys.readouterr().out


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_fit_many_reads_the_models_columns(rooms, fitted):
    (rooms / "batch.toml").write_text(
        'model = "two.toml"\nmethods = ["ml"]\n[[zone]]\nid = "east"\ndata = "two.csv"\n'
    )
    assert main(["fit-many", str(rooms / "batch.toml"), "--out", str(rooms / "res"), "--workers", "1"]) == 0
    row = pd.read_parquet(rooms / "res" / "results.parquet").iloc[0]
    assert row["status"] == "ok", row["error"]
    assert row["R12"] == pytest.approx(TRUTH["R12"], rel=0.10)
    assert {"sigma_v_T1", "sigma_v_T2", "R12_verdict"} <= set(row.index)
