"""The simulation is exact: checked against analytic solutions and a stiff ODE solver.

The ODE right-hand side used as the oracle is written here directly from the network's
elements (a heat balance per node), independently of the state-space matrices.
"""

import numpy as np
import pytest
from scipy.integrate import quad_vec, solve_ivp
from scipy.linalg import expm

from rczone.simulation import foh, simulate, van_loan, zoh
from tests.netfactory import one_r_one_c, thirteen_state


def node_balance_rhs(net, theta, t_grid, u, m, hold):
    """dT/dt for a network without massless nodes, from its resistors, heat inputs and supply air."""
    vals = net.values(theta)
    states = net.state_names
    idx = {n: i for i, n in enumerate(states)}
    cap = np.array([vals[nd.capacity] for nd in net.nodes])
    inputs = net.input_names

    def inputs_at(t):
        k = min(np.searchsorted(t_grid, t, side="right") - 1, len(t_grid) - 2)
        if hold == "zoh":
            return u[k], m[k]
        w = (t - t_grid[k]) / (t_grid[k + 1] - t_grid[k])
        return (1 - w) * u[k] + w * u[k + 1], m[k]

    def rhs(t, x):
        uk, mk = inputs_at(t)
        temp = dict(zip(inputs, uk, strict=True))
        temp.update(zip(states, x, strict=True))
        q = np.zeros(len(states))
        for r in net.resistors:
            flow = (temp[r.b] - temp[r.a]) / vals[r.resistance]
            if r.a in idx:
                q[idx[r.a]] += flow
            if r.b in idx:
                q[idx[r.b]] -= flow
        for h in net.heat_inputs:
            for nd, g in h.split:
                q[idx[nd]] += (vals[g] if isinstance(g, str) else g) * temp[h.name]
        for j, s in enumerate(net.supply_air):
            q[idx[s.node]] += mk[j] * s.cp * (temp[s.temperature] - temp[s.node])
        return q / cap

    return rhs


def random_inputs(rng, n, p, step=60.0):
    t = np.arange(n) * step
    u = 21.0 + 4.0 * rng.standard_normal((n, p))
    u[:, -1] = rng.uniform(0, 300, n)  # Q, W
    m = rng.choice([0.0, 0.02, 0.06, 0.12], size=(n, 1))  # changes (almost) every sample
    return t, u, m


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_bilinear_13_state_matches_radau_with_m_changing_every_sample(hold):
    rng = np.random.default_rng(7)
    net = thirteen_state(rng)
    ss = net.state_space()
    t, u, m = random_inputs(rng, 61, ss.n_inputs)
    x0 = 20.0 + rng.standard_normal(ss.n_states)
    sim = simulate(ss, t, u, m, x0=x0, hold=hold)
    rhs = node_balance_rhs(net, None, t, u, m, hold)
    x = x0.copy()
    worst = 0.0
    for k in range(len(t) - 1):  # restart at every sample: inputs jump there
        sol = solve_ivp(rhs, (t[k], t[k + 1]), x, method="Radau", rtol=1e-11, atol=1e-11)
        x = sol.y[:, -1]
        worst = max(worst, np.max(np.abs(x - sim.x[k + 1])))
    assert worst < 1e-6, worst


def test_one_r_one_c_step_response_is_analytic_on_irregular_samples():
    R, C, To, Q, T0 = 0.02, 4e5, 10.0, 500.0, 22.0
    ss = one_r_one_c(R, C).state_space()
    t = np.cumsum(np.r_[0.0, np.random.default_rng(1).uniform(1, 900, 200)])
    u = np.column_stack([np.full(t.size, To), np.full(t.size, Q)])
    sim = simulate(ss, t, u, x0=np.array([T0]))
    T_inf = To + R * Q
    exact = T_inf + (T0 - T_inf) * np.exp(-t / (R * C))
    np.testing.assert_allclose(sim.y[:, 0], exact, rtol=0, atol=1e-11)


def test_zoh_reproduces_continuous_step_response_at_samples():
    """Step invariance: the ZOH model's step response equals the continuous one at every sample."""
    rng = np.random.default_rng(3)
    ss = thirteen_state(rng).state_space().lti(0.05)
    dt, n = 300.0, 40
    Phi, Gam = zoh(ss.A, ss.B, dt)
    j = 2  # step in the ceiling temperature
    x = np.zeros(ss.n_states)
    for k in range(1, n):
        x = Phi @ x + Gam[:, j]
        tk = k * dt
        # continuous: x(t) = A^{-1} (e^{At} - I) b for a unit step from rest
        cont = np.linalg.solve(ss.A, (expm(ss.A * tk) - np.eye(ss.n_states)) @ ss.B[:, j])
        np.testing.assert_allclose(x, cont, rtol=1e-9, atol=1e-13)


def test_foh_is_exact_for_ramp_inputs():
    R, C = 0.02, 4e5
    ss = one_r_one_c(R, C).state_space()
    a = 1.0 / (R * C)
    t = np.linspace(0, 7200, 13)
    To = 5.0 + 1e-3 * t  # ramp, K
    u = np.column_stack([To, np.zeros_like(t)])
    sim = simulate(ss, t, u, x0=np.array([5.0]), hold="foh")
    # T' = a (To - T) with To = 5 + s t  =>  T = 5 + s t - s/a (1 - e^{-a t})
    exact = 5.0 + 1e-3 * t - 1e-3 / a * (1 - np.exp(-a * t))
    np.testing.assert_allclose(sim.y[:, 0], exact, atol=1e-12)
    _, G0, G1 = foh(ss.A, ss.B, 600.0)
    np.testing.assert_allclose(G0 + G1, zoh(ss.A, ss.B, 600.0)[1], rtol=1e-12)


def test_van_loan_matches_quadrature():
    rng = np.random.default_rng(11)
    A = thirteen_state(rng).state_space().lti(0.1).A[:4, :4]
    L = rng.standard_normal((4, 4)) * 1e-3
    Qc = L @ L.T
    dt = 1800.0
    ref, _ = quad_vec(lambda s: expm(A * s) @ Qc @ expm(A.T * s), 0.0, dt, epsabs=1e-16, epsrel=1e-12)
    np.testing.assert_allclose(van_loan(A, Qc, dt), ref, rtol=1e-8, atol=1e-14)


def _series(*rs):
    return sum(rs)


@pytest.mark.parametrize("m", [0.0, 0.03, 0.12])
def test_dc_gains_equal_series_parallel_resistance_ratios(m):
    rng = np.random.default_rng(5)
    net = thirteen_state(rng)
    v = net.values()
    cp = 1005.0
    g = {"To": 1 / v["Rwin"] + 1 / _series(v["Row1"], v["Row2"], v["Row3"])}
    for s, far in (("f", "Tf"), ("c", "Tc"), ("n1", "Tn1"), ("n2", "Tn2"), ("hw", "Thw")):
        g[far] = 1 / _series(v[f"R{s}w1"], v[f"R{s}w2"], v[f"R{s}w3"])
    g_total = sum(g.values()) + m * cp
    gain = net.state_space().lti(m).dc_gain()[0]
    names = net.input_names
    for far, gk in g.items():
        assert gain[names.index(far)] == pytest.approx(gk / g_total, rel=1e-10)
    assert gain[names.index("Ts")] == pytest.approx(m * cp / g_total, rel=1e-10, abs=1e-15)
    assert gain[names.index("Q")] == pytest.approx(1 / g_total, rel=1e-10)


def test_energy_balance_over_a_simulation():
    """Stored energy change equals the heat that entered through resistors, gains and supply air."""
    rng = np.random.default_rng(9)
    net = thirteen_state(rng)
    ss = net.state_space()
    v = net.values()
    sub, h = 12, 5.0  # 5 s sub-samples inside each 60 s hold interval
    t60, u60, m60 = random_inputs(rng, 31, ss.n_inputs)
    t = np.arange(0, t60[-1] + 1e-9, h)
    k = np.minimum((t // 60).astype(int), len(t60) - 1)
    sim = simulate(ss, t, u60[k], m60[k], x0=np.full(ss.n_states, 21.0))
    names, states = net.input_names, net.state_names

    def inflow(x, uk, mk):
        """Net heat into the zone's nodes (W) for states x (..., n) and held inputs."""
        q = uk[names.index("Q")] + mk[0] * 1005.0 * (uk[names.index("Ts")] - x[..., 0])
        for r in net.resistors:
            if r.b in net.boundaries:
                q = q + (uk[names.index(r.b)] - x[..., states.index(r.a)]) / v[r.resistance]
        return q

    total = 0.0
    for j in range(len(t60) - 1):  # Simpson on each hold interval, where the state is smooth
        f = inflow(sim.x[j * sub : (j + 1) * sub + 1], u60[j], m60[j])
        total += h / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    stored = np.sum(ss.capacities * (sim.x[-1] - sim.x[0]))
    assert stored == pytest.approx(total, rel=1e-7)
    assert abs(total) > 1e4  # a real exchange happened
