"""Identification with a known latent force: data simulated from a room with an unmeasured GP heat input.

Truth by construction: a 1-node room (``C``, ``R`` to outdoors, a heater) receives a Matérn-3/2 heat
flow (sigma = 150 W, ell = 3 h) that no column records; the data are drawn with the exact
discretization (checked against scipy's Van Loan in tests/unit/network/test_disturbance.py).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rczone.estimation import Dataset, fit
from rczone.estimation.fit import default_free
from rczone.estimation.kalman import stochastic_matrices
from rczone.models import ZoneModel
from rczone.network import HeatInput, LatentForce, Node, Parameter, RCNetwork, Resistor
from rczone.selection.compare import select_models

TRUTH = {"C": 4e6, "R": 5e-3, "sd": 150.0, "ld": 3 * 3600.0}


def room(with_disturbance: bool) -> RCNetwork:
    params = [
        Parameter("C", "capacitance", 2e6, bounds=(1e5, 1e8)),
        Parameter("R", "resistance", 1e-2, bounds=(1e-4, 1.0)),
    ]
    extra = {}
    if with_disturbance:
        params += [
            Parameter("sd", "magnitude", 60.0, bounds=(1.0, 2000.0)),
            Parameter("ld", "time", 7200.0, bounds=(600.0, 2 * 86400.0)),
        ]
        extra["disturbances"] = [LatentForce("Qd", "matern32", "Ti", magnitude="sd", length_scale="ld")]
    return RCNetwork(
        "room+Qd" if with_disturbance else "room",
        [Node("Ti", "C")],
        ["To"],
        [Resistor("Ti", "To", "R")],
        params,
        [HeatInput("Ph", "Ti")],
        **extra,
    )


def simulate(seed: int = 11, days: int = 12, dt: float = 600.0) -> pd.DataFrame:
    net = room(True)
    ss = net.state_space(TRUTH)
    n = int(days * 86400 / dt)
    t = np.arange(n) * dt
    rng = np.random.default_rng(seed)
    To = 5 + 4 * np.sin(2 * np.pi * (t / 86400 - 0.3)) + np.cumsum(0.03 * rng.standard_normal(n))
    Ph = 1500.0 * (rng.random(n // 12 + 1) > 0.5).repeat(12)[:n]  # a 2-h PRBS-like heater
    u = np.column_stack([To, Ph])
    dyn = stochastic_matrices(ss, t, np.zeros((n, 0)), np.diag(ss.diffusion))
    L = np.linalg.cholesky(dyn.Qd[0] + 1e-18 * np.eye(3))
    x = np.zeros((n, 3))
    x[0] = [18.0, *rng.standard_normal(2)]
    for k in range(n - 1):
        x[k + 1] = dyn.Phi[0] @ x[k] + dyn.G0[0] @ u[k] + L @ rng.standard_normal(3)
    y = x @ ss.C[0] + 0.02 * rng.standard_normal(n)
    return pd.DataFrame({"time": t, "Ti": y, "To": To, "Ph": Ph})


@pytest.fixture(scope="module")
def frame() -> pd.DataFrame:
    return simulate()


@pytest.mark.slow
def test_fit_recovers_R_C_and_the_hyper_parameters(frame):
    net = room(True)
    data = Dataset.from_frame(frame, net, time="time")
    res = fit(net, data, default_free(net, "ml"), method="ml")
    est = res.estimates
    assert est["C"] == pytest.approx(TRUTH["C"], rel=0.15)
    assert est["R"] == pytest.approx(TRUTH["R"], rel=0.10)
    assert est["sd"] == pytest.approx(TRUTH["sd"], rel=0.4)
    assert TRUTH["ld"] / 2 < est["ld"] < TRUTH["ld"] * 2


@pytest.mark.slow
def test_select_prefers_the_model_with_the_disturbance(frame):
    sel = select_models([ZoneModel(room(False)), ZoneModel(room(True))], frame, forward=True)
    assert sel.selected == "room+Qd"
    (step,) = sel.steps
    assert step["accepted"] and step["p_value"] < 1e-3 and step["df"] == 2
