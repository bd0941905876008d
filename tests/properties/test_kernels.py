"""Compiled kernels and the spectral discretization against independent plain references.

References used: ``scipy.linalg.expm`` block exponentials (``zoh``, ``foh``, a Van Loan
integral with exact doubling written here), the plain-NumPy propagation loop, and the
reference Kalman filter of :mod:`rczone.estimation.kalman` fed with expm-based matrices.
Models are random RC networks declared with :mod:`rczone.network` (random topology,
massless nodes, supply air, positive R and C).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

from rczone.estimation.kalman import FilterProblem, kalman_nll_rc2
from rczone.kernels.propagate import propagate_kernel
from rczone.kernels.rankone import simulate_rank_one
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from rczone.simulation import foh, simulate, zoh
from rczone.simulation.discretize import interval_discretization, rank_one_form, symmetrizing_scale
from rczone.simulation.intervals import interval_groups
from rczone.simulation.simulate import transition_matrices
from tests.netfactory import random_network
from tests.oracles import (
    kalman_filter_reference,
    phi_weights,
    propagate_reference,
    spectral_decomposition,
    spectral_noise_covariance,
    spectral_transition,
    transition_matrices_expm,
)

RTOL = 1e-10
SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def nets(max_cap: int = 5) -> st.SearchStrategy:
    return st.builds(
        lambda seed, nc, nz, nb: (random_network(np.random.default_rng(seed), nc, nz, nb), seed),
        st.integers(0, 2**32 - 1),
        st.integers(1, max_cap),
        st.integers(0, 2),
        st.integers(1, 2),
    )


def relerr(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300))


def van_loan_doubling(A: np.ndarray, Qc: np.ndarray, dt: float) -> np.ndarray:
    """Reference ``Qd``: Van Loan's block exponential on a short step, then exact doubling."""
    s = max(0, int(np.ceil(np.log2(max(np.linalg.norm(A, 1) * dt, 1e-300) / 0.25))))
    h = dt / 2.0**s
    n = A.shape[0]
    blk = np.zeros((2 * n, 2 * n))
    blk[:n, :n], blk[:n, n:], blk[n:, n:] = -A * h, Qc * h, A.T * h
    E = expm(blk)
    Q, Phi = E[n:, n:].T @ E[:n, n:], expm(A * h)
    for _ in range(s):
        Q, Phi = Q + Phi @ Q @ Phi.T, Phi @ Phi
    return 0.5 * (Q + Q.T)


@SETTINGS
@given(nets(), st.floats(0.0, 0.5), st.floats(10.0, 3600.0))
def test_spectral_discretization_equals_the_matrix_exponential(net_seed, m, dt):
    net, seed = net_seed
    ss = net.state_space()
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    assert scale is not None  # every RC network with supply air on a capacitive node qualifies
    A, B = ss.matrices(m)
    lam, V = spectral_decomposition(A[None], scale)
    for hold, ref in (("zoh", (*zoh(A, B, dt), np.zeros_like(B))), ("foh", foh(A, B, dt))):
        got = spectral_transition(lam, V, scale, B[None], np.array([dt]), hold)
        for g, r in zip(got, ref):
            if np.any(r):
                assert relerr(g[0], r) < RTOL, (hold, seed)
    Qc = np.diag(np.random.default_rng(seed).uniform(0.1, 2.0, ss.n_states)) * 1e-6
    Qd = spectral_noise_covariance(lam, V, scale, Qc, np.array([dt]))[0]
    assert relerr(Qd, van_loan_doubling(A, Qc, dt)) < RTOL


@settings(max_examples=10, deadline=None)
@given(nets(max_cap=4), st.sampled_from(["zoh", "foh"]))
def test_transition_matrices_with_m_varying_equal_one_expm_per_interval(net_seed, hold):
    net, seed = net_seed
    ss = net.state_space()
    rng = np.random.default_rng(seed)
    t = np.cumsum(np.r_[0.0, rng.uniform(30, 900, 12)])
    m = rng.uniform(0, 0.4, (t.size, 1))
    m[5:8] = 0.1  # repeated keys share one discretization
    Phi, G0, G1, which = transition_matrices(ss, t, m, hold)
    for k in range(t.size - 1):
        A, B = ss.matrices(m[k])
        ref = zoh(A, B, t[k + 1] - t[k]) if hold == "zoh" else foh(A, B, t[k + 1] - t[k])
        assert relerr(Phi[which[k]], ref[0]) < RTOL
        assert relerr(G0[which[k]], ref[1]) < RTOL
        if hold == "foh":
            assert relerr(G1[which[k]], ref[2]) < RTOL


def test_jacobi_rotation_diagonalizes_symmetric_2x2_including_degenerate_cases():
    rng = np.random.default_rng(7)
    a, b, d = rng.standard_normal((3, 200))
    b[:5] = 0.0  # already diagonal
    d[5:10] = a[5:10]  # equal diagonal
    b[10:15] = 1e-300  # tiny coupling
    S = np.stack([np.stack([a, b], -1), np.stack([b, d], -1)], -2)
    lam, V = spectral_decomposition(S, np.ones(2))
    np.testing.assert_allclose(V @ np.swapaxes(V, -1, -2), np.broadcast_to(np.eye(2), S.shape), atol=1e-15)
    recon = (V * lam[:, None, :]) @ np.swapaxes(V, -1, -2)
    assert np.max(np.abs(recon - S)) < 1e-14 * np.max(np.abs(S))
    np.testing.assert_allclose(np.sort(lam, -1), np.linalg.eigvalsh(S), rtol=1e-13, atol=1e-15)


def test_phi_weights_match_extended_precision():
    x = np.concatenate([-np.logspace(-12, 2.5, 300), np.logspace(-12, 1.5, 300), [0.0]])
    e, w1, w2 = phi_weights(x)
    xl = x.astype(np.longdouble)
    with np.errstate(invalid="ignore", divide="ignore"):
        em1 = np.expm1(xl)
        ref1 = np.where(xl == 0, 1, em1 / xl)
        # Taylor series (truncation < 1e-18) where the extended-precision cancellation would be too large
        series = 1 / 2 + xl / 6 + xl**2 / 24 + xl**3 / 120 + xl**4 / 720
        ref2 = np.where(np.abs(xl) < 1e-3, series, (em1 - xl) / (xl * xl))
    np.testing.assert_allclose(e, np.exp(xl).astype(float), rtol=1e-15)
    np.testing.assert_allclose(w1, ref1.astype(float), rtol=1e-15)
    np.testing.assert_allclose(w2, ref2.astype(float), rtol=5e-15)


@SETTINGS
@given(st.integers(0, 2**32 - 1), st.integers(1, 6), st.integers(1, 4), st.integers(2, 40))
def test_compiled_propagation_equals_the_plain_loop(seed, n, p, N):
    rng = np.random.default_rng(seed)
    K = rng.integers(1, 5)
    Phi = rng.standard_normal((K, n, n)) / n
    G0, G1 = rng.standard_normal((2, K, n, p))
    which = rng.integers(0, K, N - 1)
    u = rng.standard_normal((N, p))
    x0 = rng.standard_normal(n)
    ref = propagate_reference(Phi, G0, G1, which, u, x0)
    got = propagate_kernel(Phi, G0, G1, which, u, x0)
    assert np.max(np.abs(got - ref)) <= RTOL * max(np.max(np.abs(ref)), 1.0)


def reference_nll(ss, t, m, u, y, x0, P0, Qc, R, hold):
    """The reference filter on matrices from one expm per interval (no spectral path involved)."""
    K = t.size - 1
    Phi = np.empty((K, 2, 2))
    G0 = np.empty((K, 2, ss.n_inputs))
    G1 = np.zeros((K, 2, ss.n_inputs))
    Qd = np.empty((K, 2, 2))
    for k in range(K):
        A, B = ss.matrices(m[k])
        dt = t[k + 1] - t[k]
        if hold == "zoh":
            Phi[k], G0[k] = zoh(A, B, dt)
        else:
            Phi[k], G0[k], G1[k] = foh(A, B, dt)
        Qd[k] = van_loan_doubling(A, Qc, dt)
    return kalman_filter_reference(
        FilterProblem(Phi, G0, G1, Qd, np.arange(K), u, y, x0, P0, ss.C, ss.D, R)
    ).nll


def filter_problem(rng: np.random.Generator, p: int, N: int) -> tuple[np.ndarray, ...]:
    """Random inputs, measurements (5 missing), prior and noise of a 2-state filter problem."""
    u = 20 + 3 * rng.standard_normal((N, p))
    y = 20 + rng.standard_normal((N, 1))
    y[rng.integers(0, N, 5)] = np.nan
    x0 = 20 + rng.standard_normal(2)
    P0 = np.diag(rng.uniform(0.1, 2, 2))
    Qc = np.diag(10 ** rng.uniform(-8, -4, 2))
    R = np.array([[10 ** rng.uniform(-4, -1)]])
    return u, y, x0, P0, Qc, R


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 1), st.sampled_from(["zoh", "foh"]))
def test_compiled_two_state_likelihood_equals_the_reference_filter(seed, n_massless, hold):
    rng = np.random.default_rng(seed)
    net = random_network(rng, 2, n_massless, 2)
    ss = net.state_space()
    N = 60
    t = np.cumsum(np.r_[0.0, rng.uniform(30, 900, N - 1)])
    m = rng.uniform(0, 0.4, (N, 1))
    m[10:20] = 0.2  # repeated (dt, m) reuse the previous discretization
    t[10:20] = t[10] + 60.0 * np.arange(10)
    t[20:] = t[20:] - t[20] + t[19] + 60.0
    u, y, x0, P0, Qc, R = filter_problem(rng, ss.n_inputs, N)
    ref = reference_nll(ss, t, m, u, y, x0, P0, Qc, R, hold)
    got = kalman_nll_rc2(ss, t, m, u, y, x0, P0, Qc, R, hold)
    assert got == pytest.approx(ref, rel=RTOL, abs=RTOL)


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["zoh", "foh"]))
def test_table_of_distinct_intervals_gives_the_reference_likelihood(seed, hold):
    """Quantized flows on a partly irregular grid: each distinct (dt, m) discretized once."""
    rng = np.random.default_rng(seed)
    net = random_network(rng, 2, 0, 2)
    ss = net.state_space()
    N = 80
    dt = rng.choice([60.0, 60.0, 60.0, 120.0, 37.5], N - 1)
    t = np.cumsum(np.r_[0.0, dt])
    m = rng.choice(np.round(rng.uniform(0, 0.4, 6), 3), (N, 1))  # six flow levels, any order
    u, y, x0, P0, Qc, R = filter_problem(rng, ss.n_inputs, N)
    groups = interval_groups(t, m)
    assert groups is not None and groups.max() + 1 <= 18
    _, first = np.unique(groups, return_index=True)  # each group's first interval
    key = np.column_stack([np.diff(t), m[:-1]])
    assert np.array_equal(key, key[first][groups])  # every interval is equal to its group's first
    assert len({tuple(r) for r in key[first]}) == first.size  # and groups are distinct
    ref = reference_nll(ss, t, m, u, y, x0, P0, Qc, R, hold)
    e_plain, e_table = np.full(N, np.nan), np.full(N, np.nan)
    plain = kalman_nll_rc2(ss, t, m, u, y, x0, P0, Qc, R, hold, e_plain)
    table = kalman_nll_rc2(ss, t, m, u, y, x0, P0, Qc, R, hold, e_table, groups)
    assert table == pytest.approx(ref, rel=RTOL, abs=RTOL)
    assert table == plain  # same arithmetic, fewer discretizations
    np.testing.assert_array_equal(e_table, e_plain)


def test_interval_groups_declines_when_most_intervals_differ():
    t = np.arange(100.0) * 60
    assert interval_groups(t, np.linspace(0, 1, 100)[:, None]) is None
    assert interval_groups(t[:1], np.zeros((1, 1))) is None
    g = interval_groups(t, np.zeros((100, 0)))  # no flows: one group of equal steps
    assert g.shape == (99,) and np.all(g == 0)


def identical_branches(n_branches: int, rng: np.random.Generator) -> RCNetwork:
    """A room node with identical wall branches: repeated eigenvalues, so deflation is exercised."""
    nodes = [Node("Ti", "Cr")]
    res = [Resistor("Ti", "To", "Rwin")]
    for b in range(n_branches):
        nodes.append(Node(f"W{b}", "Cw"))
        res += [Resistor("Ti", f"W{b}", "R1"), Resistor(f"W{b}", "Tsd", "R2")]
    params = [
        Parameter("Cr", "capacitance", float(rng.uniform(1e5, 1e6))),
        Parameter("Cw", "capacitance", float(rng.uniform(1e6, 1e7))),
        Parameter("Rwin", "resistance", float(rng.uniform(0.02, 0.2))),
        Parameter("R1", "resistance", float(rng.uniform(0.005, 0.05))),
        Parameter("R2", "resistance", float(rng.uniform(0.005, 0.05))),
    ]
    return RCNetwork(
        "branches",
        nodes,
        ["To", "Tsd"],
        res,
        params,
        heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
        supply_air=[SupplyAir("Ti", "m", "Ts")],
    )


def simulate_with_expm(ss, t, u, m, x0, hold):
    uniq = np.column_stack([np.diff(t), m[:-1]])
    Phi, G0, G1 = transition_matrices_expm(ss, uniq, hold)
    return propagate_reference(Phi, G0, G1, np.arange(t.size - 1), u, x0)


@settings(max_examples=12, deadline=None)
@given(
    st.one_of(
        nets(max_cap=6),
        st.builds(
            lambda s, b: (identical_branches(b, np.random.default_rng(s)), s),
            st.integers(0, 2**32 - 1),
            st.integers(2, 4),
        ),
    ),
    st.sampled_from(["zoh", "foh"]),
)
def test_rank_one_simulation_equals_one_expm_per_interval(net_seed, hold):
    net, seed = net_seed
    ss = net.state_space()
    if ss.n_states < 3:
        return
    rng = np.random.default_rng(seed)
    N = 80
    t = np.cumsum(np.r_[0.0, rng.uniform(30, 600, N - 1)])
    m = rng.uniform(0, 0.4, (N, 1))
    m[20:30] = 0.0  # no flow: the unmodified eigenproblem
    m[40:50] = 0.15  # constant stretch: one decomposition reused
    m[60:66] = -rng.uniform(0.0, 0.01, (6, 1))  # rho > 0: the other branch of the secular solver
    u = 20 + 3 * rng.standard_normal((N, ss.n_inputs))
    x0 = 20 + rng.standard_normal(ss.n_states)
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    form = rank_one_form(ss.A, ss.N, scale, float(np.abs(m).max()))
    assert form is not None
    got = simulate_rank_one(form, ss.B, ss.M[0], t, m[:, 0], u, x0, hold)
    ref = simulate_with_expm(ss, t, u, m, x0, hold)
    assert np.max(np.abs(got - ref)) <= RTOL * np.max(np.abs(ref)), seed
    # simulate() takes this path for m varying like this
    y = simulate(ss, t, u, m, x0=x0, hold=hold).y
    assert np.max(np.abs(y - ref @ ss.C.T)) <= RTOL * np.max(np.abs(ref))


def test_rank_one_form_deflates_repeated_eigenvalues():
    ss = identical_branches(3, np.random.default_rng(1)).state_space()
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    form = rank_one_form(ss.A, ss.N, scale, 0.5)
    # three identical branches: two antisymmetric wall modes are invisible from Ti
    assert form.r == ss.n_states - 2
    S = scale[:, None] * ss.A / scale[None, :]
    recon = form.Q @ np.diag(form.d) @ form.Q.T
    assert np.max(np.abs(recon - S)) < 1e-14 * np.max(np.abs(S))
    np.testing.assert_allclose(form.Q.T @ form.Q, np.eye(ss.n_states), atol=1e-14)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_fast_modes_keep_their_relative_accuracy(n):
    """Every eigenvalue of ``A h`` near -20 (``e^x`` about 1e-9 to 1e-11): ``Phi`` is tiny and must
    still be accurate to rounding relative to itself. Reference: ``A = R diag(l) R'`` built from
    known eigenvalues and a rotation by a known angle, and ``R diag(e^{l h}) R'`` formed in extended
    precision. ``expm1(x) + 1`` instead of ``exp(x)`` kept only ~7 digits of such an ``e^x``
    (the 2-state closed form did that: 7e-10 relative on random networks, 1e-7 here)."""
    h = 600.0
    lam = -np.array([20.0, 23.0, 25.5])[:n] / h
    th = np.longdouble(0.3)
    c, s = np.cos(th), np.sin(th)
    R = np.eye(n, dtype=np.longdouble)
    if n >= 2:
        R[:2, :2] = [[c, -s], [s, c]]
    if n == 3:
        R = R @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=np.longdouble)
    A = np.array((R * lam.astype(np.longdouble)) @ R.T, dtype=float)
    A = 0.5 * (A + A.T)
    # rounding A moves its eigenvalues by ~1e-16 |A|, e^{l h} by h 1e-16 |A| ~ 1e-17 relative
    ref = np.array((R * np.exp(lam.astype(np.longdouble) * np.longdouble(h))) @ R.T, dtype=float)
    B = np.ones((n, 1))
    dyn = interval_discretization(A, np.zeros((0, n, n)), B, np.zeros((0, n, 1)), np.ones(n), np.array([[h]]))
    assert relerr(dyn.Phi[0], ref) < 1e-12
    assert np.max(np.abs(ref)) < 1e-8  # the case is the one it claims: every mode fast
