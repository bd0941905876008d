"""Posterior sampling on the 2-state task with known truth (issue 23, done-when of item 1).

The data are simulated here, independently of rczone's discretization: the 2-state wall/room model
(Tw to outdoor through Ro, Tw to Ti through Ri, heating on Ti) discretized exactly by matrix
exponentials (the inputs held over each half hour, the process noise by Van Loan's method), with
process noise on the room and white measurement noise, at known parameters.

Checks: every R and C's posterior mean lies within two posterior standard deviations of the truth,
R-hat < 1.01 with no divergence, and the 90 % credible interval of each R and C agrees with its 90 %
profile-likelihood interval (Pawitan 2001, sec. 2.9) within 20 % of that interval's width at
either end, where the Hessian of the ML fit is positive definite (flat priors in log R and log C:
the posterior is then the likelihood on that scale, and both intervals are invariant under the log).

The noise levels (sigma_v 0.05 K, sigma_w 1e-3 K/sqrt(s)) are lower than the peer task's: with the
peer task's levels the sampler diverged on this data set (a posterior ridge toward the noise floor),
and a run with divergences is refused as unconverged; that case is not claimed here.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from rczone.estimation import Dataset, Objective, fit, make_spec
from rczone.estimation.methods.mcmc import McmcOptions
from rczone.estimation.uncertainty import profile
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor

TRUTH = {"Ro": 0.0176, "Ri": 0.0020, "Cw": 1.5e7, "Ci": 1.6e6}
SIGMA_W_TI = 1e-3  # K/sqrt(s)
SIGMA_V = 0.05  # K
RC = tuple(TRUTH)

NET = RCNetwork(
    "TwTi_RoRi",
    nodes=[Node("Tw", "Cw"), Node("Ti", "Ci")],
    boundaries=["To"],
    resistors=[Resistor("Tw", "To", "Ro"), Resistor("Tw", "Ti", "Ri")],
    heat_inputs=[HeatInput("Qh", {"Ti": 1.0})],
    parameters=[
        Parameter(k, "resistance" if k[0] == "R" else "capacitance", 1.5 * v) for k, v in TRUTH.items()
    ],
    outputs=["Ti"],
)


def simulate_truth(n: int = 720, dt: float = 1800.0, seed: int = 5) -> Dataset:
    rng = np.random.default_rng(seed)
    Ro, Ri, Cw, Ci = (TRUTH[k] for k in RC)
    A = np.array([[-(1 / Ro + 1 / Ri) / Cw, 1 / (Ri * Cw)], [1 / (Ri * Ci), -1 / (Ri * Ci)]])
    B = np.array([[1 / (Ro * Cw), 0.0], [0.0, 1 / Ci]])
    Qc = np.diag([0.0, SIGMA_W_TI**2])
    # inputs held over the interval: one augmented exponential (Phi, Gamma)
    aug = np.zeros((4, 4))
    aug[:2, :2], aug[:2, 2:] = A, B
    E = expm(aug * dt)
    Phi, Gam = E[:2, :2], E[:2, 2:]
    # Van Loan (1978): the process noise covariance of one interval
    V = expm(np.block([[-A, Qc], [np.zeros((2, 2)), A.T]]) * dt)
    Qd = V[2:, 2:].T @ V[:2, 2:]
    L = np.linalg.cholesky(0.5 * (Qd + Qd.T) + 1e-18 * np.eye(2))
    t = np.arange(n) * dt
    h = t / 3600.0
    To = 10 + 6 * np.sin(2 * np.pi * (h - 9) / 24) + np.cumsum(0.05 * rng.standard_normal(n))
    Qh = np.where((h % 24 > 6) & (h % 24 < 22), 1500.0, 0.0) * (rng.random(n) < 0.7)
    u = np.column_stack([To, Qh])
    x = np.empty((n, 2))
    x[0] = [16.0, 20.0]
    for k in range(n - 1):
        x[k + 1] = Phi @ x[k] + Gam @ u[k] + L @ rng.standard_normal(2)
    y = x[:, 1:2] + SIGMA_V * rng.standard_normal((n, 1))
    return Dataset(t, u, np.zeros((n, 0)), y, NET.input_names, (), NET.outputs)


@pytest.mark.slow
def test_posterior_recovers_the_truth_and_matches_the_profile_likelihood() -> None:
    data = simulate_truth()
    free = [*RC, "x0_Tw", "sigma_w_Ti", "sigma_v"]
    common = {"fixed": {"sigma_x0_Tw": 1.0, "sigma_x0_Ti": 0.1}, "free": free}
    ml = fit(NET, data, method="ml", n_starts=2, **common)
    post_fit = fit(NET, data, method="mcmc", options=McmcOptions(draws=1000, tune=1000, chains=4), **common)
    post = post_fit.posterior
    assert not post_fit.issues, post_fit.flags
    assert post.divergences == 0
    assert np.all(post.rhat < 1.01)
    for n in RC:
        mean, sd = post_fit.estimates[n], post_fit.std_errors[n]
        assert abs(mean - TRUTH[n]) < 2 * sd, (n, mean, sd, TRUTH[n])
    # the 90 % profile-likelihood intervals, where the ML Hessian is positive definite
    assert "hessian" not in ml.issues
    spec = _spec(ml)
    obj = Objective(NET, data, spec, "ml")
    theta_hat = np.array([ml.estimates[k] for k in spec.names])
    q90 = post.interval(0.9)
    for n in RC:
        se = ml.std_errors[n] / ml.estimates[n]  # in log units
        grid = ml.estimates[n] * np.exp(np.linspace(-3.0 * se, 3.0 * se, 25))
        lo, hi = profile(obj, theta_hat, n, grid, optimizer="lbfgs", level=0.9).interval
        width = hi - lo
        i = post.names.index(n)
        assert abs(q90[i, 0] - lo) < 0.2 * width, (n, q90[i], (lo, hi))
        assert abs(q90[i, 1] - hi) < 0.2 * width, (n, q90[i], (lo, hi))
    # the cost of the sampler, next to the ML search's (docs/posterior.md has the benchmark)
    assert post.draws_per_second > 0 and post.mode_seconds > 0
    print(
        f"NUTS {post.draws_per_second:.0f} draws/s, {post.n_gradients} gradients in {post.seconds:.1f} s;"
        f" ML search {post.mode_seconds:.2f} s"
    )


def _spec(res):
    return make_spec(
        NET,
        res.names,
        start={k: res.estimates[k] for k in res.names},
        fixed=dict(res.fixed),
        bounds={k: (e.lower, e.upper) for k, e in res.parameters.items()},
    )
