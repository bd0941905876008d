"""The prior on the optimizer's scale, against scipy's densities, and the MAP cost with declared priors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from rczone.errors import ParameterError
from rczone.estimation import Objective, fit, make_spec
from rczone.estimation.priors import log_prior
from rczone.network import Parameter, Prior

from .nets import NET2, data2

# (parameter, prior, scipy's log density of the physical value, two physical values)
CASES = [
    (
        "Rw",
        Prior("lognormal", median=0.012, sigma=0.3),
        stats.lognorm(0.3, scale=0.012).logpdf,
        (0.008, 0.015),
    ),
    ("Rw", Prior("normal", mean=0.011, sigma=0.002), stats.norm(0.011, 0.002).logpdf, (0.009, 0.0125)),
    ("Rw", Prior("uniform", lower=0.005, upper=0.02), stats.uniform(0.005, 0.015).logpdf, (0.006, 0.019)),
    ("g", Prior("normal", mean=1.2, sigma=0.1), stats.norm(1.2, 0.1).logpdf, (1.0, 1.3)),
    ("g", Prior("uniform", lower=0.5, upper=2.0), stats.uniform(0.5, 1.5).logpdf, (0.7, 1.9)),
]


@pytest.mark.parametrize(("name", "prior", "logpdf", "xs"), CASES, ids=[f"{c[0]}-{c[1].dist}" for c in CASES])
def test_prior_is_the_declared_density_of_the_optimizer_variable(name, prior, logpdf, xs) -> None:
    spec = make_spec(NET2, [name])
    lp = log_prior(spec, {name: prior}, default="flat")
    # p_eta(eta) = p_theta(theta) |d theta / d eta|: theta for a log parameter, 1 otherwise
    log = bool(spec.log[0])

    def scipy_neg(x):
        return -(logpdf(x) + (math.log(x) if log else 0.0))

    a, b = (lp.terms(np.array([x]))[0] for x in xs)
    assert a - b == pytest.approx(scipy_neg(xs[0]) - scipy_neg(xs[1]), rel=1e-10)
    # the gradient in theta against central differences
    x = 0.5 * (xs[0] + xs[1])
    h = 1e-6 * x
    fd = (lp.terms(np.array([x + h]))[0] - lp.terms(np.array([x - h]))[0]) / (2 * h)
    assert lp.terms(np.array([x]))[1][0] == pytest.approx(fd, rel=1e-6)


def test_uniform_prior_is_infinite_outside_its_support() -> None:
    spec = make_spec(NET2, ["Rw"])
    lp = log_prior(spec, {"Rw": Prior("uniform", lower=0.005, upper=0.02)}, default="flat")
    assert lp.terms(np.array([0.03]))[0] == math.inf


def test_defaults_construction_log_normal_for_map_and_flat_for_sampling() -> None:
    spec = make_spec(NET2, ["Cr", "Rw", "sigma_v"])
    theta = np.array([2 * 8e5, 0.01 / 4, 0.07])
    s = 0.5
    construction = log_prior(spec, {}, default="construction", spread=s)
    assert construction.terms(theta)[0] == pytest.approx(
        0.5 * (math.log(2) / s) ** 2 + 0.5 * (math.log(4) / s) ** 2, rel=1e-12
    )
    # flat: log-uniform R and C (nothing to add on eta = log theta), a noise level uniform in sigma
    assert log_prior(spec, {}, default="flat").terms(theta)[0] == pytest.approx(-math.log(0.07), rel=1e-12)
    declared = log_prior(spec, {"Rw": Prior("lognormal", median=0.0025, sigma=0.1)}, default="construction")
    assert declared.declared == ("Rw",)
    assert declared.terms(theta)[0] == pytest.approx(0.5 * (math.log(2) / math.log(2)) ** 2, rel=1e-12)


@pytest.mark.parametrize(
    ("kw", "match"), [({"default": "jeffreys"}, "default prior"), ({"spread": 0.0}, "spread")]
)
def test_bad_options_are_refused(kw, match) -> None:
    with pytest.raises(ParameterError, match=match):
        log_prior(make_spec(NET2, ["Rw"]), {}, **kw)


def test_map_cost_uses_a_declared_prior_in_every_engine() -> None:
    data = data2(noise=0.05, rng=np.random.default_rng(3))
    prior = Prior("normal", mean=0.012, sigma=0.001)
    net = NET2.replace_parameters([Parameter("Rw", "resistance", 0.01, prior=prior)])
    spec = make_spec(net, ["Cr", "Rw", "sigma_v"])
    theta = np.array([9e5, 0.011, 0.05])
    eta = spec.to_eta(theta)
    ml = Objective(net, data, spec, "ml", engine="general")
    w = 0.3
    # independent: the tempered likelihood, the construction log-normal on Cr, the declared normal
    # on Rw as a density of log Rw
    expect = (
        w * ml(eta)
        + 0.5 * (math.log(9e5 / 8e5) / 0.5) ** 2
        + 0.5 * ((0.011 - 0.012) / 0.001) ** 2
        - math.log(0.011)
    )
    values = []
    for engine in ("general", "compiled", "auto"):
        mp = Objective(net, data, spec, "map", prior_spread=0.5, likelihood_weight=w, engine=engine)
        assert mp.declared_prior
        # the packed problem carries it where the engine is compiled: the compiled search applies
        assert (mp.compiled is not None) == (mp.engine != "general")
        values.append(mp(eta))
        j, g = mp.value_and_gradient(eta)
        assert j == pytest.approx(expect, rel=1e-9)
        k = 1
        h = 1e-6
        fd = (mp(eta + h * np.eye(3)[k]) - mp(eta - h * np.eye(3)[k])) / (2 * h)
        assert g[k] == pytest.approx(fd, rel=1e-5)
    assert values[0] == pytest.approx(expect, rel=1e-9)
    assert values[1] == pytest.approx(expect, rel=1e-9)
    assert values[2] == pytest.approx(expect, rel=1e-9)
    # the packed problem carries the declared prior too: the compiled kernel evaluates it with the
    # same function (rczone.kernels.problem.prior_terms) as the Python objective
    from rczone.estimation.compiled import compiled_cost, compiled_problem

    packed = compiled_problem(Objective(net, data, spec, "map", prior_spread=0.5, likelihood_weight=w))
    assert packed.penalty.prior_idx.size == 2
    assert compiled_cost(packed, eta) == pytest.approx(expect, rel=1e-9)


def test_map_without_declared_prior_keeps_the_compiled_search() -> None:
    data = data2(noise=0.05, rng=np.random.default_rng(3))
    spec = make_spec(NET2, ["Cr", "Rw", "sigma_v"])
    mp = Objective(NET2, data, spec, "map")
    assert not mp.declared_prior
    assert mp.compiled is not None


def test_a_tight_declared_prior_holds_the_map_estimate_at_its_mean() -> None:
    # a normal prior of 1 % on Rw, 30 % off the value the data say: MAP follows the prior, ML the data
    data = data2(noise=0.02, rng=np.random.default_rng(4))
    net = NET2.replace_parameters(
        [Parameter("Rw", "resistance", 0.01, prior=Prior("normal", mean=0.013, sigma=0.013 * 1e-3))]
    )
    free = ["Cr", "Rw", "sigma_v"]
    fixed = {"sigma_w_Ti": 1e-6}
    ml = fit(net, data, free, method="ml", fixed=fixed, n_starts=1)
    mp = fit(net, data, free, method="map", fixed=fixed, n_starts=1, options={"correlation_time_s": 600.0})
    assert ml.estimates["Rw"] == pytest.approx(0.01, rel=0.02)
    assert mp.estimates["Rw"] == pytest.approx(0.013, rel=1e-3)


# (parameter, prior, scipy's density of the physical value, its mode, a physical value): the
# declared families on a log parameter (Rw) and on a linear one (g), apart from the optimum
FAMILIES = [
    ("Rw", Prior("lognormal", median=0.012, sigma=0.3), stats.lognorm(0.3, scale=0.012), 0.012, 0.0092),
    ("Rw", Prior("normal", mean=0.011, sigma=0.002), stats.norm(0.011, 0.002), 0.011, 0.0093),
    ("Rw", Prior("uniform", lower=0.005, upper=0.02), stats.uniform(0.005, 0.015), 0.01, 0.0094),
    ("g", Prior("normal", mean=1.2, sigma=0.1), stats.norm(1.2, 0.1), 1.2, 1.1),
    ("g", Prior("uniform", lower=0.5, upper=2.0), stats.uniform(0.5, 1.5), 1.0, 1.05),
]


def _neg_log_prior_eta(prior, density, mode, x, log):
    """``-log p_eta`` from scipy's density (``p_eta = p_theta theta`` in log space), zero at the mode,
    and its derivative in ``eta`` written out per family."""
    jac = math.log(x) if log else 0.0
    at_mode = math.log(mode) if log and prior.dist == "lognormal" else 0.0
    value = -(density.logpdf(x) + jac) + (density.logpdf(mode) + at_mode)
    if prior.dist == "lognormal":  # a normal in log theta
        slope = (math.log(x) - math.log(prior.median)) / prior.sigma**2
    elif prior.dist == "normal":
        slope = (x - prior.mean) / prior.sigma**2 * (x if log else 1.0) - (1.0 if log else 0.0)
    else:
        slope = -1.0 if log else 0.0
    return value, slope


@pytest.mark.parametrize("engine", ["rc2-fused", "compiled"])
@pytest.mark.parametrize(
    ("name", "prior", "density", "mode", "x"), FAMILIES, ids=[f"{f[0]}-{f[1].dist}" for f in FAMILIES]
)
def test_the_compiled_map_cost_carries_every_declared_prior(engine, name, prior, density, mode, x) -> None:
    """The kernel's MAP value and gradient are the tempered likelihood plus the declared density
    (scipy's, on the optimizer's scale) and the construction log-normal, to rounding."""
    data = data2(noise=0.05, rng=np.random.default_rng(3))
    kind = "resistance" if name == "Rw" else "gain"
    net = NET2.replace_parameters([Parameter(name, kind, 0.01 if name == "Rw" else 1.0, prior=prior)])
    spec = make_spec(net, ["Cr", name, "sigma_v"])
    theta = np.array([9e5, x, 0.05])
    eta = spec.to_eta(theta)
    w, s = 0.3, 0.5
    mp = Objective(net, data, spec, "map", prior_spread=s, likelihood_weight=w, engine=engine)
    ml = Objective(net, data, spec, "ml", engine=engine)
    assert mp.engine == engine and mp.compiled is not None
    assert mp.compiled.penalty.prior_idx.tolist() == [0, 1]  # nothing stripped
    # independent: the construction log-normal on Cr (log space: no Jacobian) and the declared one
    z = (math.log(9e5) - math.log(8e5)) / s
    p_value, p_slope = _neg_log_prior_eta(prior, density, mode, x, bool(spec.log[1]))
    ml_value, ml_grad = ml.value_and_gradient(eta)
    expect = w * ml_value + 0.5 * z * z + p_value
    expect_grad = w * ml_grad + np.array([z / s, p_slope, 0.0])
    j, g = mp.value_and_gradient(eta)
    assert j == pytest.approx(expect, rel=1e-12)
    # values alone come from the value kernel (the fused 2-state filter): against its likelihood
    assert mp(eta) == pytest.approx(w * ml(eta) + 0.5 * z * z + p_value, rel=1e-12)
    scale = w * np.abs(ml_grad) + np.abs(expect_grad)  # the size of the terms summed
    assert np.all(np.abs(g - expect_grad) <= 1e-12 * scale)
    # the same numbers as the Python prior (rczone.estimation.priors.LogPrior.terms) added to the likelihood
    pen, dpen, _ = mp.map_prior.terms(theta)
    assert j == pytest.approx(w * ml_value + pen, rel=1e-12)
    assert np.all(np.abs(g - (w * ml_grad + dpen * spec.jacobian(eta))) <= 1e-12 * scale)


def test_a_map_fit_with_a_declared_prior_stays_compiled() -> None:
    """The engine of the fit is the compiled one the rules choose, and the compiled direct search
    (Nelder-Mead without leaving compiled code) serves it."""
    from rczone.estimation.compiled import compiled_cost

    data = data2(noise=0.02, rng=np.random.default_rng(4))
    net = NET2.replace_parameters(
        [Parameter("Rw", "resistance", 0.01, prior=Prior("normal", mean=0.011, sigma=0.001))]
    )
    free = ["Cr", "Rw", "sigma_v"]
    spec = make_spec(net, free, fixed={"sigma_w_Ti": 1e-6})
    obj = Objective(net, data, spec, "map", engine="compiled")
    eta = spec.to_eta(spec.start)
    assert obj.compiled is not None and compiled_cost(obj.compiled, eta) == pytest.approx(obj(eta), rel=1e-12)
    res = fit(net, data, free, method="map", fixed={"sigma_w_Ti": 1e-6}, n_starts=1)
    assert res.engine == "rc2-fused"  # the rules' compiled engine for two states and one output
    assert res.to_dict()["engine"] == "rc2-fused"
