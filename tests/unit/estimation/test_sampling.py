"""Posterior sampling: the log density and its gradient, the plumbing, the refusal, an analytic posterior."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from rczone.errors import ParameterError
from rczone.estimation import Objective, fit, make_spec
from rczone.estimation.methods.mcmc import McmcOptions
from rczone.estimation.posterior import ESS_MIN_PER_CHAIN
from rczone.estimation.sampling import posterior_of
from rczone.network import Parameter, Prior
from rczone.simulation import simulate

from .nets import NET2, data2

NOISE = 0.05


def noisy():
    return data2(noise=NOISE, rng=np.random.default_rng(11))


def test_log_posterior_gradient_matches_central_differences() -> None:
    net = NET2.replace_parameters(
        [Parameter("Rw", "resistance", 0.01, prior=Prior("normal", mean=0.011, sigma=0.002))]
    )
    spec = make_spec(net, ["Cr", "Rw", "sigma_v"])
    logp = posterior_of(Objective(net, noisy(), spec, "mcmc"))
    z = logp.to_z(np.array([9e5, 0.0105, 0.06]))
    v, g = logp(z)
    assert math.isfinite(v)
    for k in range(3):
        h = 1e-5
        e = np.eye(3)[k] * h
        fd = (logp(z + e)[0] - logp(z - e)[0]) / (2 * h)
        assert g[k] == pytest.approx(fd, rel=1e-5, abs=1e-6 * abs(v))


def test_log_posterior_includes_the_jacobian_of_the_transform() -> None:
    # the default prior of a noise level is uniform in sigma, i.e. p_eta = sigma on eta = log sigma:
    # log p(z) - log p(z') = log L difference + log sigma difference + log (d eta / d z) difference
    spec = make_spec(NET2, ["sigma_v"], fixed={"Cr": 8e5})
    obj = Objective(NET2, noisy(), spec, "mcmc")
    logp = posterior_of(obj)
    th = np.array([[0.04], [0.07]])
    z = [logp.to_z(t) for t in th]
    lo, hi = spec.eta_lower[0], spec.eta_upper[0]
    f = [(math.log(t[0]) - lo) / (hi - lo) for t in th]
    expect = (
        -(obj(spec.to_eta(th[0])) - obj(spec.to_eta(th[1])))
        + math.log(th[0][0] / th[1][0])
        + math.log(f[0] * (1 - f[0]) / (f[1] * (1 - f[1])))
    )
    assert logp(z[0])[0] - logp(z[1])[0] == pytest.approx(expect, rel=1e-9)


def test_map_objective_is_refused() -> None:
    spec = make_spec(NET2, ["Cr", "sigma_v"])
    with pytest.raises(ParameterError, match="untempered"):
        posterior_of(Objective(NET2, noisy(), spec, "map"))


@pytest.mark.parametrize(
    ("settings", "match"),
    [
        ({"draws": 5}, "draws"),
        ({"chains": 0}, "chains"),
        ({"tune": -1}, "tune"),
        ({"chains": True}, "chains"),
        ({"draw": 10}, "did you mean 'draws'"),
    ],
)
def test_bad_sampler_settings_are_refused(settings, match) -> None:
    with pytest.raises(ParameterError, match=match):
        McmcOptions.of(settings, "mcmc")


def test_short_run_has_the_shapes_and_json_and_refuses_to_call_itself_converged() -> None:
    res = fit(
        NET2,
        noisy(),
        ["Cr", "Rw", "sigma_v"],
        method="mcmc",
        fixed={"sigma_w_Ti": 1e-6},
        options=McmcOptions(draws=20, tune=30, chains=2),
    )
    post = res.posterior
    assert post.draws.shape == (2, 20, 3)
    assert post.rhat.shape == post.ess_bulk.shape == (3,)
    # 40 draws cannot reach ESS_MIN_PER_CHAIN per chain: the run is flagged, never converged
    assert min(post.ess_bulk.min(), post.ess_tail.min()) < ESS_MIN_PER_CHAIN * 2
    assert "ess" in res.issues and not res.converged and not res.trustworthy
    assert np.allclose([res.estimates[n] for n in res.names], post.draws.reshape(-1, 3).mean(axis=0))
    d = json.loads(json.dumps(res.to_dict()))
    assert d["method"] == "mcmc" and d["posterior"]["chains"] == 2 and not d["posterior"]["converged"]
    assert len(d["posterior"]["kept_draws"]["values"]) == 40
    lo, hi = d["posterior"]["parameters"]["Cr"]["interval_90"]
    assert lo < d["parameters"]["Cr"]["estimate"] < hi
    assert d["parameters"]["Cr"]["interval_95"] == d["posterior"]["parameters"]["Cr"]["interval_95"]
    assert set(res.to_frame().columns) >= {"estimate", "std_error", "ci_lower", "ci_upper"}
    frame = post.to_frame()
    assert frame.shape == (40, 5) and list(frame["chain"].unique()) == [0, 1]
    np.testing.assert_array_equal(frame.loc[frame.chain == 1, "Rw"], post.draws[1, :, 1])


@pytest.mark.slow
def test_noise_level_posterior_matches_the_analytic_one() -> None:
    # the model exact and known, the process noise negligible: the innovations are the measurement
    # errors e, and with a flat prior on log sigma the posterior is sigma^2 = S / X, X ~ chi2(n),
    # S = sum e^2 (Gelman et al. 2013, sec. 2.6)
    data = noisy()
    spec_fixed = {"sigma_w_Ti": 1e-9, "sigma_w_Tw": 1e-9, "sigma_x0_Ti": 1e-6, "sigma_x0_Tw": 1e-6}
    clean = data2()
    x0 = simulate(NET2.state_space(), clean.t, clean.u, clean.m).x[0]
    e = data.y[:, 0] - clean.y[:, 0]
    S, n = float(e @ e), e.size
    res = fit(
        NET2,
        data,
        ["sigma_v"],
        method="mcmc",
        fixed={**spec_fixed, "x0_Ti": float(x0[0]), "x0_Tw": float(x0[1])},
        options=McmcOptions(draws=1000, tune=500, chains=4),
    )
    q = res.posterior.interval(0.9)[0]
    exact = np.sqrt(S / stats.chi2(n).ppf([0.95, 0.05]))
    np.testing.assert_allclose(q, exact, rtol=0.03)
    assert res.posterior.rhat[0] < 1.01
