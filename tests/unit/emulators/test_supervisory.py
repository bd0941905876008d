"""The supervisory MPC: its plan is the model's response, it is no dearer than holding the band's
edge, and it gives the thermostat the planned temperature as the set point of the side it runs."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.emulators.supervisory import SupervisoryMPC, SupervisorySettings
from rczone.models import load_model

DT = 900.0
H = 24


def _case(model="first-order", **settings):
    mpc = SupervisoryMPC(
        load_model(model), zone="z", dt=DT, settings=SupervisorySettings(horizon=H, **settings)
    )
    t = DT * np.arange(H + 1)
    occupied = t >= 4 * 3600.0
    lower = np.where(occupied, 21.0, 15.0)
    upper = np.where(occupied, 24.0, 28.0)
    u = mpc.inputs({"Tsd_z": 19.0, "Q_z": 200.0, "Ti_z": 17.0}, np.full(H + 1, -3.0))
    x0 = np.r_[np.full(mpc.cm.n_states - 1, 17.0), 0.0]
    return mpc, x0, u, lower, upper


@pytest.mark.parametrize("model", ["first-order", "second-order"])
def test_the_planned_temperature_is_the_models_response_to_the_planned_heat(model):
    mpc, x0, u, lower, upper = _case(model)
    plan = mpc.solve(x0, u, lower, upper, np.ones(H + 1))
    d = mpc.cm.discrete(DT, 0.0)
    x, y = x0.copy(), [float(d.C[0] @ x0 + d.D[0] @ u[0])]
    for k in range(H):
        x = d.Ad @ x + d.Bd @ u[k] + d.Ed[:, 0] * (plan.heating[k] - plan.cooling[k])
        y.append(float(d.C[0] @ x + d.D[0] @ u[k + 1]))
    np.testing.assert_allclose(plan.y, y, atol=1e-6)
    occupied = lower[1:] > 20
    assert np.all(plan.y[1:][occupied] >= lower[1:][occupied] + 0.1 - 1e-6)  # the capacity suffices
    assert plan.cooling.max() < 1e-6


def test_the_plan_is_no_dearer_than_holding_the_band_edge_and_shifts_heat_off_the_peak():
    mpc, x0, u, lower, upper = _case("second-order", heating_capacity=20e3)
    price = np.where(DT * np.arange(H + 1) >= 4 * 3600.0, 3.0, 1.0)
    plan = mpc.solve(x0, u, lower, upper, price)
    # a feasible rival: just enough heat each step to sit on the (narrowed) band's edge
    d = mpc.cm.discrete(DT, 0.0)
    x, rival = x0.copy(), []
    for k in range(H):
        free = d.C[0] @ (d.Ad @ x + d.Bd @ u[k]) + d.D[0] @ u[k + 1]
        gain = d.C[0] @ d.Ed[:, 0]
        h = max(0.0, (lower[k + 1] + 0.1 - free) / gain)
        rival.append(h)
        x = d.Ad @ x + d.Bd @ u[k] + d.Ed[:, 0] * h
    cost = lambda h: float(np.sum(price[:H] * np.asarray(h)) * DT / 3.6e6)  # noqa: E731
    assert cost(plan.heating) <= cost(rival) + 1e-6
    assert plan.heating[:16].sum() > np.asarray(rival)[:16].sum()  # heat bought before the peak price
    assert plan.slack.max() < 1e-6


def test_the_thermostat_gets_the_planned_temperature_on_the_side_that_runs():
    mpc = _case()[0]
    t = DT * np.arange(H + 1)
    fc = {"time": t, "To": np.full(H + 1, -3.0), "price": np.ones(H + 1)}
    fc["lower_z"], fc["upper_z"] = np.full(H + 1, 21.0), np.full(H + 1, 24.0)
    limits = {
        "heating_min_z": [18.0],
        "heating_max_z": [24.0],
        "cooling_min_z": [21.0],
        "cooling_max_z": [27.0],
    }
    fc.update({k: np.array(v) for k, v in limits.items()})
    y = {"Ti_z": 17.0, "Tsd_z": 19.0, "Q_z": 200.0, "To": -3.0, "m_z": np.nan, "Ts_z": np.nan}
    act = mpc.act(0.0, y, fc)
    assert mpc.plan.heating[0] > 0
    assert act["heating_z"] == pytest.approx(min(max(mpc.plan.y[1], 18.0), 24.0))
    assert act["cooling_z"] == 24.0
    hot = mpc.act(DT, {**y, "Ti_z": 27.0, "Tsd_z": 26.0, "To": 30.0}, {**fc, "To": np.full(H + 1, 30.0)})
    assert hot["heating_z"] == 21.0 and hot["cooling_z"] <= 27.0


def test_bad_settings_are_one_line():
    from rczone.errors import ParameterError

    with pytest.raises(ParameterError, match="heating_capacity"):
        SupervisorySettings(heating_capacity=-1.0)
    with pytest.raises(ParameterError, match="horizon"):
        SupervisorySettings(horizon=0)
