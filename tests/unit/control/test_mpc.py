"""The reference MPC: its QP against a brute-force solution, its energy linearization, its bounds."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import minimize

from rczone.control import Disturbance
from rczone.control.energy import zone_power
from rczone.control.mpc import MPC, Forecast, MPCSettings
from rczone.errors import DataError, InputShapeError, ParameterError
from rczone.models import load_model
from rczone.network import CP_AIR


@pytest.fixture(scope="module")
def zm():
    return load_model("second-order")


def forecast(H, *, low=21.0, up=23.0, to=28.0, t_ahu=13.0, price=None, m_min=None):
    return Forecast(
        {"To": np.full(H + 1, to), "Tsd": np.full(H + 1, 24.0)},
        np.full(H + 1, t_ahu),
        np.full(H + 1, low),
        np.full(H + 1, up),
        price,
        m_min=m_min,
    )


def brute_force(mpc, x0, fc, m_nom, p_nom, m_prev):
    """The same linearized problem, condensed and solved by SLSQP from several starts.

    Decisions ``z = [m (kg/s), P (kW), s (K)]``, each of order one.
    """
    s, lim = mpc.settings, mpc.limits
    H = len(m_nom)
    u = mpc._input_matrix(fc, H)
    q = mpc.linearize(x0, u, fc, m_nom, p_nom)
    c = mpc.cm.matrices
    span = (lim.ts_max - fc.t_ahu[:H]) * CP_AIR

    def outputs(z):
        m, p = z[:H], 1e3 * z[H : 2 * H]
        x, ys = x0, []
        for k in range(H):
            x = q.Ad[k] @ x + q.Ed[k] * p[k] + q.G[k] * m[k] + q.c[k]
            ys.append(c.C[0] @ x + c.D[0] @ u[k + 1])
        return np.array(ys)

    def cost(z):
        m, p, sl = z[:H], 1e3 * z[H : 2 * H], z[2 * H :]
        y = np.r_[0.0, outputs(z)[:-1]]  # output at the start of steps 1..H-1
        moves = np.diff(np.r_[m_prev, m]) ** 2 + (np.diff(np.r_[0.0, p]) / 1e3) ** 2
        return (
            q.qm @ m
            + q.qp @ p
            + q.qx[1:] @ y[1:]
            + s.comfort_weight * sl.sum()
            + s.comfort_weight_quadratic * (sl**2).sum()
            + s.move_weight * moves.sum()
        )

    cons = [
        {"type": "ineq", "fun": lambda z: outputs(z) + z[2 * H :] - fc.lower[1 : H + 1]},
        {"type": "ineq", "fun": lambda z: fc.upper[1 : H + 1] - outputs(z) + z[2 * H :]},
        {"type": "ineq", "fun": lambda z: z[:H] * span / 1e3 - z[H : 2 * H]},
    ]
    m_lo = np.maximum(lim.m_min, fc.m_min[:H]) if fc.m_min is not None else np.full(H, lim.m_min)
    bounds = [(lo, lim.m_max) for lo in m_lo] + [(0, None)] * H + [(0, None)] * H
    best = None
    rng = np.random.default_rng(0)
    for _ in range(6):
        z0 = np.r_[rng.uniform(m_lo, lim.m_max, H), rng.uniform(0, 0.5, H), rng.uniform(0, 1, H)]
        r = minimize(
            cost, z0, method="SLSQP", bounds=bounds, constraints=cons, options={"ftol": 1e-14, "maxiter": 500}
        )
        # SLSQP may stop at the optimum with "positive directional derivative": judge by feasibility
        feasible = all(np.all(con["fun"](r.x) > -1e-8) for con in cons)
        if feasible and (best is None or r.fun < best.fun):
            best = r
    return np.r_[best.x[:H], 1e3 * best.x[H : 2 * H], best.x[2 * H :]]


@pytest.mark.parametrize(
    ("x_start", "low", "up"), [(25.5, 21.0, 23.0), (19.5, 21.5, 24.0), (22.0, 21.0, 23.0)]
)
def test_qp_matches_a_brute_force_solution_on_a_three_step_horizon(zm, x_start, low, up):
    mpc = MPC(zm, MPCSettings(horizon=3, linearizations=1, move_weight=1.0), disturbance=None)
    fc = forecast(3, low=low, up=up)
    x0 = np.array([x_start, x_start - 0.5])
    m_nom, p_nom = np.full(3, 0.05), np.full(3, 100.0)
    plan = mpc.plan(x0, fc, nominal=(m_nom, p_nom))
    ref = brute_force(mpc, x0, fc, m_nom, p_nom, mpc.limits.m_min)
    np.testing.assert_allclose(plan.m, ref[:3], atol=2e-5)
    np.testing.assert_allclose(plan.reheat, ref[3:6], atol=0.05)
    np.testing.assert_allclose(plan.slack, ref[6:], atol=1e-4)


def test_a_per_step_flow_minimum_is_a_per_step_bound_of_the_qp(zm):
    # the room sits in its band: the optimum rides the minimum flow, which steps up and down
    mpc = MPC(zm, MPCSettings(horizon=3, linearizations=1, move_weight=1.0), disturbance=None)
    m_min = np.array([0.02, 0.07, 0.05])
    fc = forecast(3, m_min=m_min)
    x0 = np.array([22.0, 21.8])
    m_nom, p_nom = np.full(3, 0.05), np.zeros(3)
    plan = mpc.plan(x0, fc, nominal=(m_nom, p_nom))
    ref = brute_force(mpc, x0, fc, m_nom, p_nom, mpc.limits.m_min)
    np.testing.assert_allclose(plan.m, ref[:3], atol=2e-5)
    assert np.all(plan.m >= m_min - 1e-9)
    np.testing.assert_allclose(plan.m, m_min, atol=1e-4)  # every bound active


def test_the_linearized_energy_cost_is_exact_at_the_nominal_trajectory(zm):
    mpc = MPC(zm, MPCSettings(horizon=4), disturbance=None)
    fc = forecast(4)
    x0 = np.array([24.0, 23.5])
    m, p = np.array([0.03, 0.06, 0.09, 0.12]), np.array([0.0, 200.0, 0.0, 50.0])
    u = mpc._input_matrix(fc, 4)
    q = mpc.linearize(x0, u, fc, m, p)
    x = mpc.simulate(x0, u, m, p)
    ti = x[:4, 0]
    power = zone_power(m, fc.t_ahu[:4] + p / (m * CP_AIR), fc.t_ahu[:4], ti, fc.inputs["To"][:4])
    energy = (power.total * 600.0).sum() / 3.6e6
    # the cost's value at the nominal point: the x-term is the tangent of m*cp*Ti, counted once
    linear = q.qm @ m + q.qp @ p + q.qx @ ti - (q.qx @ ti)
    assert linear == pytest.approx(energy, rel=1e-12)


def test_closed_loop_on_the_model_itself_never_violates_the_input_bounds(zm):
    settings = MPCSettings(horizon=12, flow_min=0.03, flow_max=0.1, ts_max=30.0)
    mpc = MPC(zm, settings, disturbance=Disturbance("heat"))
    plant = MPC(zm, settings, disturbance=None)  # its exact simulation is the plant
    x = np.array([22.0, 21.5])
    rng = np.random.default_rng(3)
    ms, ts, ps = [], [], []
    for k in range(16):
        low = 21.0 if k < 8 else 22.5  # the band moves up: reheat needed
        fc = forecast(12, low=low, up=low + 1.5, to=5.0 + k * 0.3)
        a = mpc.step(600.0 * k, {"Ti": x[0] + rng.normal(0, 0.05)}, fc)
        ms.append(a.m)
        ts.append(a.ts)
        ps.append(a.reheat)
        x = plant.simulate(x, plant._input_matrix(fc, 12)[:1], np.array([a.m]), np.array([a.reheat + 150.0]))[
            1
        ]
    ms, ts, ps = map(np.array, (ms, ts, ps))
    assert np.all((ms >= 0.03) & (ms <= 0.1))
    assert np.all(ps >= 0) and np.all(ts <= 30.0 + 1e-9)
    assert ps.max() > 100.0  # the bounds were exercised: reheat was used
    assert mpc.innovations.shape == (16,)


def test_bounds_are_given_in_the_users_units(zm):
    mpc = MPC(
        zm, MPCSettings(flow_min=40.0, flow_max=200.0, flow_unit="cfm", ts_max=95.0, temperature_unit="degF")
    )
    assert mpc.limits.m_min == pytest.approx(40 * 0.3048**3 / 60 * 1.2)
    assert mpc.limits.ts_max == pytest.approx(35.0)


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda zm: MPC(zm, MPCSettings(flow_min=0.0)), ParameterError, "flow_min"),
        (lambda zm: MPC(zm, MPCSettings(flow_unit="furlong/s")), DataError, "furlong"),
        (lambda zm: MPCSettings(horizon=0), ParameterError, "horizon"),
        (lambda zm: MPC(zm).step(0.0, {"Ti": 22.0}, forecast(3)), InputShapeError, "horizon"),
        (
            lambda zm: MPC(zm, MPCSettings(horizon=3)).step(0.0, {"Ti": 22.0}, forecast(3, low=24.0)),
            InputShapeError,
            "band",
        ),
        (
            lambda zm: MPC(zm, MPCSettings(horizon=3, flow_max=0.1)).step(
                0.0, {"Ti": 22.0}, forecast(3, m_min=np.array([0.05, 0.11, 0.05]))
            ),
            InputShapeError,
            "step 1",
        ),
        (
            lambda zm: MPC(zm, MPCSettings(horizon=3)).step(0.0, {"Ti": 22.0}, forecast(3, m_min=np.ones(2))),
            InputShapeError,
            "m_min",
        ),
        (
            lambda zm: MPC(zm, MPCSettings(horizon=3)).step(0.0, {"Tii": 22.0}, forecast(3)),
            InputShapeError,
            "Tii",
        ),
        (
            lambda zm: MPC(zm, MPCSettings(horizon=3)).plan(
                np.zeros(3), Forecast({"Tf": np.zeros(4)}, np.zeros(4), np.zeros(4), np.ones(4))
            ),
            InputShapeError,
            "Tf",
        ),
    ],
)
def test_bad_settings_and_forecasts_raise_one_line_errors(zm, make, error, match):
    with pytest.raises(error, match=match):
        make(zm)


def _replay(model, formulation, fcs, temps):
    mpc = MPC(model, MPCSettings(horizon=12, formulation=formulation), disturbance=Disturbance("heat"))
    return np.array(
        [
            [(a := mpc.step(600.0 * k, {"Ti": ti}, fc)).m, a.reheat]
            for k, (fc, ti) in enumerate(zip(fcs, temps))
        ]
    )


@pytest.mark.parametrize("name", ["second-order", pytest.param("full-scale", marks=pytest.mark.slow)])
def test_the_condensed_qp_takes_the_actions_of_the_uncondensed_one(name):
    # the same measurements and forecasts through both forms: the same QPs, so the same actions to
    # the solver's tolerance (the band moves up and the weather cools: flow and reheat both move)
    model = load_model(name)
    fcs = [
        forecast(12, low=21.0 if k < 5 else 22.5, up=23.0 if k < 5 else 24.0, to=26.0 - k) for k in range(10)
    ]
    neighbours = [n for n in model.state_space().input_names if n.startswith(("Tn", "Tc", "Tf", "Thw"))]
    fcs = (
        [
            replace(fc, inputs={"To": fc.inputs["To"], **{n: np.full(13, 23.0) for n in neighbours}})
            for fc in fcs
        ]
        if neighbours
        else fcs
    )
    temps = 22.4 - 0.15 * np.arange(10)
    dense = _replay(model, "uncondensed", fcs, temps)
    cond = _replay(model, "condensed", fcs, temps)
    assert dense[:, 1].max() > 100.0 and np.ptp(dense[:, 0]) > 0.01  # reheat and flow both used
    np.testing.assert_allclose(cond[:, 0], dense[:, 0], atol=5e-4)
    np.testing.assert_allclose(cond[:, 1], dense[:, 1], atol=2.0)


def test_the_condensed_solver_is_set_up_once(zm):
    mpc = MPC(zm, MPCSettings(horizon=6), disturbance=None)
    for k in range(3):
        mpc.step(600.0 * k, {"Ti": 22.0}, forecast(6, to=20.0 + k))
    first = mpc._mem.solver._solver
    mpc.step(1800.0, {"Ti": 21.0}, forecast(6, to=15.0))
    assert mpc._mem.solver._solver is first
