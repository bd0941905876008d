"""The k-step forecast of a model with a latent force: from its stationary start, the force relaxes to its mean along its kernel.

Oracles: the matrix exponential of the continuous-time state space (scipy's ``expm``) applied to the
filtered state, and the closed-form kernels (Rasmussen & Williams 2006, eq. 4.17; the damped
cosine): for a unit-variance force whose stationary covariance is the identity, the conditional mean
``E[s1(t + tau) | s(t)]`` has ``k(tau) / sigma^2`` as the coefficient of ``s1(t)``.
"""

import numpy as np
import pytest
from scipy.linalg import expm, solve_continuous_lyapunov

from rczone.estimation import Dataset
from rczone.estimation.costs import run_filter
from rczone.estimation.forecast import k_step_band
from rczone.network.disturbance import covariance_function
from rczone.network.stochastic import (
    default_value,
    initial_spread_names,
    process_noise_name,
    process_noise_names,
)
from tests.unit.network.test_disturbance import ELL, PERIOD, one_node, synthetic


@pytest.mark.parametrize("kind", ["matern32", "periodic"])
def test_k_step_forecast_carries_the_filtered_force_forward_along_its_kernel(kind):
    net = one_node(kind)
    measured = synthetic(net, None)
    # no inputs: the forecast is the state's free evolution, exp(A tau) x_filt
    data = Dataset(
        measured.t,
        np.zeros_like(measured.u),
        None,
        measured.y,
        measured.input_names,
        (),
        measured.output_names,
    )
    states = net.state_space().state_names
    values = {**net.values(), **dict.fromkeys(process_noise_names(states), 0.0), "sigma_v": 0.02}
    # the initial spreads a fit uses when none is given
    values.update({n: default_value(n) for n in initial_spread_names(states)})
    values[process_noise_name("Ti")] = 1e-4
    k, dt = 12, 600.0
    y_hat, _ = k_step_band(net, values, data, k)
    out = run_filter(net, values, data)
    x_filt = out.x_filt
    ss = net.state_space()
    # the force starts from its stationary law: mean zero, the Lyapunov covariance of its SDE
    p_inf = solve_continuous_lyapunov(ss.A[1:, 1:], -np.diag(ss.diffusion[1:]))
    np.testing.assert_allclose(out.P_pred[0][1:, 1:], p_inf, atol=1e-12)
    assert not out.x_pred[0][1:].any()
    M = expm(ss.A * k * dt)
    np.testing.assert_allclose(y_hat[k:], x_filt[:-k] @ M.T @ ss.C.T, rtol=1e-9, atol=1e-9)
    assert np.isnan(y_hat[:k]).all()
    # the force's own forecast: the nodes do not feed it, and its first state keeps k(tau)/sigma^2 of itself
    assert not M[1:, 0].any()
    rho = covariance_function(kind, k * dt, magnitude=1.0, length_scale=ELL, period=PERIOD)
    assert M[1, 1] == pytest.approx(float(rho), rel=1e-9)
    assert 0.0 < float(rho) < 1.0  # it relaxes towards zero, the mean of the unmeasured gains
