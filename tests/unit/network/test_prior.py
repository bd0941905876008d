"""Declared priors: validated like any parameter setting, densities equal scipy's, kept on the network."""

from __future__ import annotations

import math

import pytest
from scipy import stats

from rczone.errors import ParameterError
from rczone.network import Node, Parameter, Prior, RCNetwork, Resistor
from rczone.network.serialize import network_from_dict, network_to_dict


@pytest.mark.parametrize(
    ("prior", "frozen", "xs"),
    [
        (Prior("lognormal", median=0.01, sigma=0.7), stats.lognorm(s=0.7, scale=0.01), (0.003, 0.01, 0.05)),
        (Prior("normal", mean=2.0e6, sigma=3.0e5), stats.norm(loc=2.0e6, scale=3.0e5), (1.2e6, 2.0e6, 2.9e6)),
        (Prior("uniform", lower=0.0, upper=50.0), stats.uniform(loc=0.0, scale=50.0), (0.0, 12.5, 50.0)),
    ],
)
def test_log_densities_equal_scipys(prior: Prior, frozen, xs: tuple[float, ...]) -> None:
    for x in xs:
        assert prior.logpdf(x) == pytest.approx(frozen.logpdf(x), rel=1e-12)


def test_outside_the_support_the_density_is_zero() -> None:
    assert Prior("lognormal", median=1.0, sigma=0.5).logpdf(0.0) == -math.inf
    assert Prior("uniform", lower=1.0, upper=2.0).logpdf(2.5) == -math.inf


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"dist": "lognorml", "median": 1.0, "sigma": 1.0}, "did you mean 'lognormal'"),
        ({"dist": "lognormal", "median": 1.0, "sigma": 0.0}, "sigma must be > 0"),
        ({"dist": "normal", "mean": 1.0, "sigma": -2.0}, "sigma must be > 0"),
        ({"dist": "lognormal", "median": -1.0, "sigma": 0.5}, "median must be > 0"),
        ({"dist": "uniform", "lower": 2.0, "upper": 1.0}, "lower 2 must be < upper 1"),
        ({"dist": "uniform", "lower": 0.0, "upper": math.inf}, "upper must be a finite number"),
        ({"dist": "normal", "mean": math.nan, "sigma": 1.0}, "mean must be a finite number"),
        ({"dist": "normal", "mean": 1.0}, "sigma must be a finite number"),
        ({"dist": "normal", "mean": 1.0, "sigma": 1.0, "median": 1.0}, "median belongs to another family"),
        ({"dist": "normal", "mean": True, "sigma": 1.0}, "mean must be a finite number"),
    ],
)
def test_bad_priors_are_refused(kwargs: dict, match: str) -> None:
    with pytest.raises(ParameterError, match=match):
        Prior(**kwargs)


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({"median": 1.0, "sigma": 1.0}, "needs dist = one of lognormal, normal, uniform"),
        ({"dist": "gauss", "mean": 1.0, "sigma": 1.0}, "'gauss' is not one of"),
        ({"dist": "normal", "mean": 1.0, "sd": 1.0}, "unknown key 'sd'.*allowed: dist, mean, sigma"),
        ({"dist": "lognormal", "median": 1.0, "sigmaa": 1.0}, "did you mean 'sigma'"),
        ({"dist": "uniform", "lower": 1.0}, "needs upper"),
        ({"dist": "normal", "mean": "20", "sigma": 1.0}, "mean must be a number"),
    ],
)
def test_bad_prior_tables_name_the_key(table: dict, match: str) -> None:
    with pytest.raises(ParameterError, match=match) as info:
        Prior.from_dict(table)
    assert "\n" not in str(info.value)


def test_the_table_scale_converts_all_but_a_lognormal_sigma() -> None:
    # 2 K/kW = 2e-3 K/W; the log-normal's sigma is a ratio and keeps its value
    ln = Prior.from_dict({"dist": "lognormal", "median": 2, "sigma": 0.7}, scale=1e-3)
    assert (ln.median, ln.sigma) == (pytest.approx(2e-3, rel=1e-12), 0.7)
    assert Prior.from_dict({"dist": "normal", "mean": 2, "sigma": 0.5}, scale=1e6).to_dict() == {
        "dist": "normal",
        "mean": 2e6,
        "sigma": 5e5,
    }


def test_lognormal_only_for_a_positive_kind_and_none_for_a_tie() -> None:
    lognormal = Prior("lognormal", median=1.0, sigma=0.5)
    assert Parameter("Rw", "resistance", 0.01, prior=Prior("lognormal", median=0.01, sigma=0.5)).prior
    assert Parameter("Aw", "gain", 2.0, prior=Prior("uniform", lower=0.0, upper=10.0)).prior
    with pytest.raises(ParameterError, match=r"lognormal prior needs a positive parameter.*not a gain"):
        Parameter("Aw", "gain", 2.0, prior=lognormal)
    with pytest.raises(ParameterError, match="tied"):
        Parameter("R1", "resistance", expr="Rw/2", prior=lognormal)
    with pytest.raises(ParameterError, match="prior must be a Prior"):
        Parameter("Rw", "resistance", 0.01, prior={"dist": "lognormal"})


def _net(prior: Prior | None) -> RCNetwork:
    return RCNetwork(
        "one",
        [Node("Ti", "Ci")],
        ["To"],
        [Resistor("Ti", "To", "Rw")],
        [Parameter("Ci", "capacitance", 1e6), Parameter("Rw", "resistance", 0.01, prior=prior)],
    )


def test_priors_are_kept_by_the_network_and_its_json() -> None:
    prior = Prior("lognormal", median=0.012, sigma=0.4)
    net = _net(prior)
    assert net.priors == {"Rw": prior}
    d = network_to_dict(net)
    assert d["parameters"][1]["prior"] == {"dist": "lognormal", "median": 0.012, "sigma": 0.4}
    assert network_from_dict(d).priors == {"Rw": prior}
    # without a prior the JSON has no prior key (saved models are unchanged)
    assert all("prior" not in p for p in network_to_dict(_net(None))["parameters"])
