"""The floor MPC: its plan is the joint model's response (checked by a stiff ODE solver), without
coupling it is one supervisory MPC per zone, and models it cannot run are refused in one line."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rczone.emulators.floormpc import FloorMPC
from rczone.emulators.supervisory import SupervisoryMPC, SupervisorySettings
from rczone.errors import ParameterError
from rczone.models import load_model
from rczone.models.zone import ZoneModel
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

DT = 900.0
H = 8
ZONES = ("a", "b")
#: Each zone's values of the paper's second-order model (zone b heavier and leakier).
VALUES = {
    "a": {"Cr": 4.5e5, "Cw": 9.7e6, "Rwin": 0.08, "R1": 0.0042, "R2": 0.0042},
    "b": {"Cr": 6.0e5, "Cw": 1.4e7, "Rwin": 0.05, "R1": 0.0030, "R2": 0.0060},
}


def _floor(coupling: float | None, *, supply: bool = True, extra_output: bool = False) -> ZoneModel:
    """Two second-order rooms, each with its own off-floor neighbour ``n<zone>``, a wall between them."""
    nodes, res, params = [], [], []
    for z in ZONES:
        nodes += [Node(f"T{z}", f"Cr_{z}"), Node(f"Tw{z}", f"Cw_{z}")]
        res += [
            Resistor(f"T{z}", "To", f"Rwin_{z}"),
            Resistor(f"T{z}", f"Tw{z}", f"R1_{z}"),
            Resistor(f"Tw{z}", f"Tn{z}", f"R2_{z}"),
        ]
        params += [
            Parameter(f"{k}_{z}", "capacitance" if k.startswith("C") else "resistance", v)
            for k, v in VALUES[z].items()
        ]
    if coupling is not None:
        res.append(Resistor("Ta", "Tb", "Rw_a_b"))
        params.append(Parameter("Rw_a_b", "resistance", coupling))
    net = RCNetwork(
        "two-rooms",
        nodes,
        ["To", "Tna", "Tnb"],
        res,
        params,
        heat_inputs=[HeatInput(f"Q{z}", {f"T{z}": 1.0}) for z in ZONES],
        supply_air=[SupplyAir(f"T{z}", flow=f"m{z}", temperature=f"Ts{z}") for z in ZONES if supply],
        outputs=["Ta", "Tb"] + (["Twa"] if extra_output else []),
    )
    return ZoneModel(net, {p.name: p.value for p in params})


def _measurements(t: float = 0.0, ti=(19.0, 20.5)) -> dict:
    y = {"time": t, "To": -5.0, "Ti_na": 18.0, "Ti_nb": 21.0}
    for z, v, q in zip(ZONES, ti, (300.0, 150.0), strict=True):
        y |= {f"Ti_{z}": v, f"Q_{z}": q, f"m_{z}": 0.1, f"Ts_{z}": 26.0}
    y |= {"Tsd_a": y["Ti_na"], "Tsd_b": y["Ti_nb"]}  # the single-zone models' neighbour
    return y


def _forecast(price=None, start: float = 0.0) -> dict:
    t = start + DT * np.arange(H + 1)
    fc = {"time": t, "To": -5.0 + 2.0 * np.sin(t / 3e4), "price": np.ones(H + 1) if price is None else price}
    for z in ZONES:
        fc |= {
            f"lower_{z}": np.where(t >= 3600.0, 21.0, 16.0),
            f"upper_{z}": np.where(t >= 3600.0, 24.0, 28.0),
            f"heating_min_{z}": np.full(H + 1, 12.0),
            f"heating_max_{z}": np.full(H + 1, 24.0),
            f"cooling_min_{z}": np.full(H + 1, 21.0),
            f"cooling_max_{z}": np.full(H + 1, 32.0),
        }
    return fc


def _settings(cap: float) -> SupervisorySettings:
    return SupervisorySettings(horizon=H, heating_capacity=cap, cooling_capacity=cap)


def test_the_plan_is_the_joint_models_response_to_every_zones_planned_heat():
    model = _floor(0.01)
    mpc = FloorMPC(
        model, zones=ZONES, dt=DT, settings={"a": _settings(3e3), "b": _settings(4e3)}, measured=["na", "nb"]
    )
    y = _measurements()
    u = mpc.inputs(y, _forecast()["To"])
    n = model.state_space().n_states
    x0 = np.r_[19.0, 18.0, 20.5, 20.0, 150.0, -80.0]  # nodes, then each zone's heat disturbance (W)
    fc = _forecast(price=np.where(DT * np.arange(H + 1) >= 4 * 3600.0, 3.0, 1.0))
    lower = np.array([fc["lower_a"], fc["lower_b"]])
    upper = np.array([fc["upper_a"], fc["upper_b"]])
    plan = mpc.solve(x0, u, lower, upper, fc["price"])
    assert plan.heating.max() > 100.0  # the plan does something worth checking
    # independent: the continuous network (its own A, B) integrated by a stiff solver, each zone's
    # planned heat and disturbance entering as extra metered heat Q<zone>, held over each step
    ss = model.state_space()
    iq = [ss.input_names.index(f"Q{z}") for z in ZONES]
    x, want = x0[:n].copy(), [ss.C[:2] @ x0[:n] + ss.D[:2] @ u[0]]
    for k in range(H):
        uk = u[k].copy()
        uk[iq] += plan.heating[:, k] - plan.cooling[:, k] + x0[n:]
        sol = solve_ivp(
            lambda _, s, uk=uk: ss.A @ s + ss.B @ uk, (0.0, DT), x, method="Radau", rtol=1e-10, atol=1e-10
        )
        x = sol.y[:, -1]
        want.append(ss.C[:2] @ x + ss.D[:2] @ u[k + 1])
    np.testing.assert_allclose(plan.y, np.array(want).T, atol=1e-5)
    occupied = lower[:, 1:] > 20
    assert np.all(plan.y[:, 1:][occupied] >= lower[:, 1:][occupied] + 0.1 - 1e-6)
    assert np.all(plan.heating <= np.array([[3e3], [4e3]]) + 1e-6)


def test_without_coupling_each_zone_gets_what_its_own_supervisory_mpc_gives_it():
    caps = {"a": 2.5e3, "b": 5e3}
    floor = FloorMPC(
        _floor(None),
        zones=ZONES,
        dt=DT,
        settings={z: _settings(c) for z, c in caps.items()},
        measured=["na", "nb"],
    )
    alone = [
        SupervisoryMPC(
            load_model("second-order").with_values(VALUES[z]), zone=z, dt=DT, settings=_settings(caps[z])
        )
        for z in ZONES
    ]
    rng = np.random.default_rng(4)
    planned = 0  # set points from the plan's temperature, not the band's edge
    for step in range(6):  # the filters run too: every step's set points agree
        y = _measurements(step * DT, ti=(19.0 + 0.3 * step + rng.normal(0, 0.1), 20.5 + rng.normal(0, 0.1)))
        fc = _forecast(
            price=np.where(DT * np.arange(step, step + H + 1) >= 2 * 3600.0, 3.0, 1.0), start=step * DT
        )
        got = floor.act(step * DT, y, fc)
        want = alone[0].act(step * DT, y, fc) | alone[1].act(step * DT, y, fc)
        assert set(got) == set(want)
        for k in want:
            assert got[k] == pytest.approx(want[k], abs=1e-6), (step, k)
        for j, mpc in enumerate(alone):
            np.testing.assert_allclose(floor.plan.heating[j], mpc.plan.heating, atol=1e-3)
        planned += sum(got[f"heating_{z}"] not in (16.0, 21.0) for z in ZONES)
    assert planned >= 2


@pytest.mark.parametrize(
    ("model", "zones", "measured", "match"),
    [
        (_floor(0.01), ("a", "c"), ("na", "nb"), "no output for zone 'c'"),
        (_floor(0.01), ("a",), ("na", "nb"), "for zones not controlled"),
        (_floor(0.01, extra_output=True), ZONES, ("na", "nb"), "for zones not controlled"),
        (_floor(0.01, supply=False), ZONES, ("na", "nb"), "one supply-air flow into each zone"),
        (_floor(0.01), ZONES, ("na",), "cannot forecast the model input 'Tnb'"),
        (load_model("second-order"), ("Ti",), (), "cannot forecast the model input 'Tsd'"),
        (_floor(0.01), ("a", "a"), ("na", "nb"), "distinct zones"),
    ],
)
def test_models_it_cannot_run_are_refused_in_one_line(model, zones, measured, match):
    with pytest.raises(ParameterError, match=match) as err:
        FloorMPC(model, zones=zones, dt=DT, measured=measured)
    assert "\n" not in str(err.value)


def test_zones_with_different_horizons_are_refused():
    settings = {"a": _settings(1e3), "b": SupervisorySettings(horizon=H + 1)}
    with pytest.raises(ParameterError, match="one horizon"):
        FloorMPC(_floor(0.01), zones=ZONES, dt=DT, settings=settings, measured=["na", "nb"])
