"""The compiled Kalman filter against its NumPy twin, in original and modal coordinates, and the fused 2-state kernel.

References: ``tests/oracles.py`` (plain NumPy, same step
functions, no steady-state shortcut) fed with the discretization of
:mod:`rczone.simulation.discretize` (whose spectral formulas are checked against scipy's ``expm``
and their NumPy form in ``tests/properties/test_kernels.py``); the brute-force joint Gaussian density is the oracle of
the twin itself (``test_estimation_kalman_mvn.py``). Models are random RC networks (random
topology, massless nodes, several outputs, one or two supply-air flows); data have
irregular steps, flows that change and repeat, and outputs missing one at a time.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from rczone.estimation.kalman import (
    FilterProblem,
    kalman_filter_arrays,
    kalman_nll_rc2,
    stochastic_matrices,
)
from rczone.kernels.arrays import (
    Discretization,
    Dynamics,
    FilterOptions,
    FilterStart,
    Observation,
    Series,
    dynamics_model,
)
from rczone.kernels.discretize import modal_matrices
from rczone.kernels.kalman import kalman_filter, modal_pays, no_sensitivities, outputs
from rczone.simulation.discretize import symmetrizing_scale
from rczone.simulation.intervals import interval_groups, unique_rows
from tests.netfactory import random_network
from tests.oracles import kalman_filter_reference

RTOL = 1e-10
SETTINGS = settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def problem(rng: np.random.Generator, net, N: int, regular: bool = False) -> tuple:
    """Times, flows, inputs, measurements (outputs missing alone and together), prior and noise."""
    ss = net.state_space()
    n, ny = ss.n_states, len(net.outputs)
    if regular:
        t = np.arange(N) * 600.0
        m = np.full((N, ss.n_flows), 0.1)
    else:
        t = np.cumsum(np.r_[0.0, rng.choice([60.0, 60.0, 300.0, rng.uniform(30, 900)], N - 1)])
        m = np.round(rng.uniform(0, 0.4, (N, ss.n_flows)), 2)
        m[N // 3 : N // 2] = 0.1  # a stretch of equal intervals
    u = 20 + 3 * rng.standard_normal((N, ss.n_inputs))
    y = 20 + rng.standard_normal((N, ny))
    y[rng.integers(0, N, N // 10), rng.integers(0, ny, N // 10)] = np.nan
    y[rng.integers(1, N)] = np.nan
    x0 = 20 + rng.standard_normal(n)
    P0 = np.diag(rng.uniform(0.1, 2, n))
    Qc = np.diag(10 ** rng.uniform(-8, -4, n))
    R = np.diag(10 ** rng.uniform(-4, -1, ny))
    return ss, t, m, u, y, x0, P0, Qc, R


def rel(a: np.ndarray, b: np.ndarray) -> float:
    ok = np.isfinite(b)
    return float(np.max(np.abs(a[ok] - b[ok])) / max(np.max(np.abs(b[ok])), 1e-300))


@SETTINGS
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 5),
    st.integers(0, 2),
    st.integers(1, 3),
    st.integers(1, 2),
    st.sampled_from(["zoh", "foh"]),
)
def test_compiled_filter_equals_its_numpy_twin(seed, n_cap, n_massless, n_outputs, n_flows, hold):
    rng = np.random.default_rng(seed)
    net = random_network(rng, n_cap, n_massless, 2, min(n_outputs, n_cap + n_massless), n_flows)
    ss, t, m, u, y, x0, P0, Qc, R = problem(rng, net, 60)
    args = (*stochastic_matrices(ss, t, m, Qc, hold), u, y, x0, P0, ss.C, ss.D, R)
    ref = kalman_filter_reference(FilterProblem(*args))
    got = kalman_filter_arrays(FilterProblem(*args))
    assert got.n_obs == ref.n_obs == np.isfinite(y).sum()
    assert got.nll == pytest.approx(ref.nll, rel=RTOL, abs=RTOL)
    for a, b in ((got.innovations, ref.innovations), (got.x_filt, ref.x_filt), (got.x_pred, ref.x_pred)):
        assert rel(a, b) < RTOL
    assert rel(got.P_pred, ref.P_pred) < RTOL
    assert rel(got.S, ref.S) < RTOL
    np.testing.assert_array_equal(np.isnan(got.innovations), np.isnan(y))


def _compiled_nll(args: tuple, steady_rtol: float) -> float:
    Phi, G0, G1, Qd, which, u, y, x0, P0, C, D, R = args
    n, p, ny = x0.size, u.shape[1], y.shape[1]
    value = kalman_filter(
        Dynamics(Phi, G0, G1, Qd),
        no_sensitivities(Phi.shape[0], n, p),
        Observation(C, D, np.diag(R).copy(), np.empty((ny, 0, n)), np.empty((ny, 0, p)), np.empty((ny, 0))),
        FilterStart(x0, P0, np.empty((0, n)), np.empty((0, n, n))),
        Series(u, y, which.astype(np.int64)),
        FilterOptions(bool(np.any(G1)), False, steady_rtol),
        outputs(y.shape[0], n, ny, 0, False, False),
    )
    return value.nll


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 4), st.integers(1, 3))
def test_steady_state_shortcut_changes_nothing_but_rounding(seed, n_cap, n_outputs):
    """Long regular stretches (the covariance converges), broken by missing outputs and a step change."""
    rng = np.random.default_rng(seed)
    net = random_network(rng, n_cap, 0, 2, min(n_outputs, n_cap))
    ss, t, m, u, y, x0, P0, Qc, R = problem(rng, net, 400, regular=True)
    Qc = 1e3 * Qc  # process noise that makes the covariance converge within the first stretch
    t[250:] += 120.0  # one longer interval: a new discretization, the steady state is left
    m[300:] = 0.2  # and a new flow from here on
    y[:, 0][rng.integers(0, 400, 10)] = np.nan
    args = (*stochastic_matrices(ss, t, m, Qc, "zoh"), u, y, x0, P0, ss.C, ss.D, R)
    twin = kalman_filter_reference(FilterProblem(*args))
    P = twin.P_pred[:250]
    # the case exercises the shortcut: the predicted covariance repeats before the step change
    assume(any(np.abs(P[k + 1] - P[k]).max() <= 1e-14 * np.abs(P[k + 1]).max() for k in range(1, 249)))
    plain = _compiled_nll(args, 0.0)
    steady = _compiled_nll(args, 1e-14)
    ref = twin.nll - 0.5 * np.isfinite(y).sum() * np.log(2 * np.pi)
    assert steady == pytest.approx(plain, rel=1e-11, abs=1e-9)
    assert plain == pytest.approx(ref, rel=1e-11, abs=1e-9)


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 1), st.sampled_from(["zoh", "foh"]), st.booleans())
def test_fused_two_state_kernel_equals_the_general_filter(seed, n_massless, hold, grouped):
    """The fused kernel (closed-form discretization inside the loop) is the general filter, specialized."""
    rng = np.random.default_rng(seed)
    net = random_network(rng, 2, n_massless, 2)
    ss, t, m, u, y, x0, P0, Qc, R = problem(rng, net, 80)
    groups = interval_groups(t, m) if grouped else None
    general = kalman_filter_arrays(
        FilterProblem(*stochastic_matrices(ss, t, m, Qc, hold), u, y, x0, P0, ss.C, ss.D, R)
    )
    e = np.full(t.size, np.nan)
    fused = kalman_nll_rc2(ss, t, m, u, y, x0, P0, Qc, R, hold, e, groups)
    assert fused == pytest.approx(general.nll, rel=RTOL, abs=RTOL)
    np.testing.assert_allclose(e, general.innovations[:, 0], rtol=1e-9, atol=1e-9)


@settings(max_examples=15, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(3, 6),
    st.integers(0, 2),
    st.integers(1, 3),
    st.sampled_from(["zoh", "foh"]),
)
def test_modal_coordinates_equal_the_numpy_twin(seed, n_cap, n_massless, n_outputs, hold):
    """The one filter given a modal basis (a diagonal transition, coordinates changed where the
    interval changes) against the textbook filter in the original coordinates; flows constant
    over stretches (few coordinate changes), irregular steps, outputs missing alone; with and
    without the steady-state shortcut, and the innovations (coordinate-free) too."""
    rng = np.random.default_rng(seed)
    net = random_network(rng, n_cap, n_massless, 2, min(n_outputs, n_cap + n_massless))
    ss, t, m, u, y, x0, P0, Qc, R = problem(rng, net, 90)
    m = np.repeat(m[::15], 15, axis=0)[: t.size]  # a damper held for 15 samples at a time
    args = (*stochastic_matrices(ss, t, m, Qc, hold), u, y, x0, P0, ss.C, ss.D, R)
    ref = kalman_filter_reference(FilterProblem(*args))
    keys = np.column_stack([np.diff(t), m[:-1]])
    uniq, _, which = unique_rows(keys)
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    mod = dynamics_model(ss.A, ss.N, ss.B, ss.M, np.diag(Qc).copy())
    mats, basis = modal_matrices(mod, Discretization(uniq, scale, hold == "foh", True))
    assert np.array_equal(mats.Phi, np.einsum("kii->ki", mats.Phi)[:, :, None] * np.eye(x0.size))  # diagonal
    n, p, ny = x0.size, u.shape[1], y.shape[1]
    obs = Observation(
        ss.C, ss.D, np.diag(R).copy(), np.empty((ny, 0, n)), np.empty((ny, 0, p)), np.empty((ny, 0))
    )
    prior = FilterStart(x0, P0, np.empty((0, n)), np.empty((0, n, n)))
    for steady_rtol in (0.0, 1e-14):
        trace = outputs(t.size, n, ny, 0, True, False)
        nll, n_obs, _, _ = kalman_filter(
            mats,
            no_sensitivities(uniq.shape[0], n, p),
            obs,
            prior,
            Series(u, y, which),
            FilterOptions(hold == "foh", False, steady_rtol),
            trace,
            basis,
        )
        assert n_obs == ref.n_obs
        assert nll + 0.5 * n_obs * np.log(2 * np.pi) == pytest.approx(ref.nll, rel=RTOL, abs=RTOL)
        assert rel(trace.e, ref.innovations) < 1e-9


def test_modal_coordinates_compute_values_only():
    """With a basis the filter refuses derivatives and state traces (they would be in modal coordinates)."""
    rng = np.random.default_rng(5)
    net = random_network(rng, 3, 0, 2, 1)
    ss, t, m, u, y, x0, P0, Qc, R = problem(rng, net, 10)
    uniq, _, which = unique_rows(np.column_stack([np.diff(t), m[:-1]]))
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    mod = dynamics_model(ss.A, ss.N, ss.B, ss.M, np.diag(Qc).copy())
    mats, basis = modal_matrices(mod, Discretization(uniq, scale, False, True))
    n, p, ny = x0.size, u.shape[1], y.shape[1]
    obs = Observation(
        ss.C, ss.D, np.diag(R).copy(), np.empty((ny, 0, n)), np.empty((ny, 0, p)), np.empty((ny, 0))
    )
    prior = FilterStart(x0, P0, np.empty((0, n)), np.empty((0, n, n)))
    dyn0 = no_sensitivities(uniq.shape[0], n, p)
    opts = FilterOptions(False, False, 0.0)
    with pytest.raises(ValueError, match="values and innovations only"):
        kalman_filter(
            mats, dyn0, obs, prior, Series(u, y, which), opts, outputs(t.size, n, ny, 0, False, True), basis
        )


def test_modal_rule_declines_frequent_changes_and_two_states():
    """The rule of ``modal_pays`` (docstring there): modal coordinates for 3+ states whose matrices
    change at most at a quarter of the steps, one interval included; the cases are built so that
    each clause decides one of them."""
    stretches = np.repeat(np.arange(24), 30)[:-1]  # nll_13state's layout: 23 changes in 719 steps
    lti = np.zeros(999, dtype=np.int64)  # nll_4zone's: one interval
    alternating = np.arange(100) % 2  # a change at every step
    assert modal_pays(stretches, 13)
    assert not modal_pays(stretches, 2)  # two states: the fused kernel's domain
    assert modal_pays(lti, 8)
    assert not modal_pays(alternating, 8)
    assert not modal_pays(np.repeat(np.arange(30), 3), 5)  # 29 changes in 90 steps: more than a quarter
    assert modal_pays(np.repeat(np.arange(20), 5), 5)  # 19 changes in 100 steps
    assert not modal_pays(np.zeros(0, dtype=np.int64), 5)  # one sample: no interval at all
