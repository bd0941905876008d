"""A model with a latent-force disturbance nests the same model without one (magnitude -> 0)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rczone.estimation.data import Dataset
from rczone.estimation.engines import general_cost
from rczone.estimation.fit import default_free
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor
from rczone.network.disturbance import LatentForce
from rczone.selection.compare import chi_bar_sf
from rczone.selection.nesting import nesting, realize

PARAMS = [
    Parameter("Ci", "capacitance", 1e6),
    Parameter("Ce", "capacitance", 1e7),
    Parameter("Rie", "resistance", 2e-3),
    Parameter("Rea", "resistance", 2e-2),
]
GP = [Parameter("sd", "magnitude", 150.0), Parameter("ld", "time", 7200.0)]
DAY = [
    Parameter("sp", "magnitude", 80.0),
    Parameter("lp", "time", 4e5),
    Parameter("Pd", "time", 86400.0, fixed=True),
]
QD = LatentForce("Qd", "matern32", "Ti", magnitude="sd", length_scale="ld")
QP = LatentForce("Qp", "periodic", {"Ti": 0.5, "Te": 0.5}, magnitude="sp", length_scale="lp", period="Pd")


def tite(name, params=(), disturbances=()):
    return RCNetwork(
        name,
        [Node("Ti", "Ci"), Node("Te", "Ce")],
        ["To"],
        [Resistor("Ti", "Te", "Rie"), Resistor("Te", "To", "Rea")],
        [*PARAMS, *params],
        [HeatInput("Ph", "Ti")],
        disturbances=disturbances,
    )


def free(net):
    return default_free(net, "ml", noise="all")


def test_the_disturbance_is_removed_by_a_zero_magnitude_at_the_boundary():
    plain, rich = tite("TiTe"), tite("TiTe+Qd", GP, [QD])
    assert "sigma_w_Qd" not in free(rich) and {"sd", "ld", "sigma_w_Te"} <= set(free(rich))
    nest = nesting(plain, rich, free(plain), free(rich))
    assert nest is not None
    assert nest.describe() == "sd -> 0" and nest.df == 2 and nest.n_boundary == 1
    assert nesting(rich, plain, free(rich), free(plain)) is None
    # chi-bar-squared 1/2 chi2(1) + 1/2 chi2(2) lies below chi2(2): the decision by chi2(2) is conservative
    assert chi_bar_sf(5.0, 2, 1) < chi_bar_sf(5.0, 2, 0)


def test_two_disturbances_nest_one_and_none_but_not_a_different_one():
    plain, one, two = tite("TiTe"), tite("+Qd", GP, [QD]), tite("+Qd+Qp", [*GP, *DAY], [QD, QP])
    nest = nesting(one, two, free(one), free(two))
    assert nest is not None and nest.describe() == "sp -> 0" and nest.df == 2
    assert nesting(plain, two, free(plain), free(two)).describe() == "sd -> 0, sp -> 0"
    other = tite("+Qd'", GP, [dataclasses.replace(QD, kind="matern52")])
    assert nesting(other, two, free(other), free(two)) is None  # not declared identically
    fixed_mag = tite("+Qd fixed", [dataclasses.replace(GP[0], fixed=True), GP[1]], [QD])
    assert nesting(plain, fixed_mag, free(plain), free(fixed_mag)) is None  # a fixed magnitude cannot vanish


def test_realized_values_reproduce_the_simpler_likelihood():
    """realize() gives the rich model values whose -log L equals the plain model's (magnitude at eps)."""
    plain, rich = tite("TiTe"), tite("TiTe+Qd", GP, [QD])
    nest = nesting(plain, rich, free(plain), free(rich))
    rng = np.random.default_rng(5)
    t = np.arange(200) * 900.0
    u = np.column_stack([5 + 2 * np.sin(t / 2e4), 500.0 * (rng.random(200) > 0.5)])
    y = 15 + np.cumsum(0.05 * rng.standard_normal(200))[:, None]
    data = Dataset(t, u, None, y, ("To", "Ph"), (), ("Ti",))
    noise = {"sigma_v": 0.05, "sigma_w_Ti": 1e-3, "sigma_w_Te": 1e-4, "sigma_x0_Ti": 1.0, "sigma_x0_Te": 1.0}
    values = realize(nest, plain.values(), rich.values())
    assert values["sd"] == pytest.approx(150.0 * 1e-6)
    lat = {"sigma_w_Qd": 0.0, "sigma_w_Qd_d1": 0.0, "sigma_x0_Qd": 1.0, "sigma_x0_Qd_d1": 1.0}
    a = general_cost(plain, {**plain.values(), **noise}, data, "zoh", "ml")[0]
    b = general_cost(rich, {**values, **noise, **lat}, data, "zoh", "ml")[0]
    assert b == pytest.approx(a, rel=1e-8)
