"""Exact derivatives checked against finite differences and hand-derived formulas."""

import numpy as np
import pytest

from rczone.network import Node, Parameter, RCNetwork, Resistor
from rczone.simulation import simulate
from rczone.simulation.sensitivity import output_sensitivities
from tests.netfactory import one_r_one_c, thirteen_state


def test_matrix_derivatives_of_one_r_one_c_are_analytic():
    R, C = 0.02, 4e5
    net = one_r_one_c(R, C)
    dR, dC = net.state_space_derivatives(None, ["R", "C"], log=True)
    # A = -1/(RC): dA/dlogR = 1/(RC) = -A, dA/dlogC = -A; B = [1/(RC), 1/C]
    assert dR.dA[0, 0] == pytest.approx(1 / (R * C), rel=1e-14)
    assert dC.dA[0, 0] == pytest.approx(1 / (R * C), rel=1e-14)
    np.testing.assert_allclose(dR.dB, [[-1 / (R * C), 0.0]], rtol=1e-14)
    np.testing.assert_allclose(dC.dB, [[-1 / (R * C), -1 / C]], rtol=1e-14)
    (dRlin,) = net.state_space_derivatives(None, ["R"], log=False)
    assert dRlin.dA[0, 0] == pytest.approx(1 / (R * R * C), rel=1e-14)


def test_derivatives_through_ties_and_massless_nodes_match_central_differences():
    net = RCNetwork(
        "tied",
        [Node("Ta", None), Node("Tw", "Cw")],
        ["To", "Tsd"],
        [Resistor("Ta", "To", "Rwin"), Resistor("Ta", "Tw", "R1"), Resistor("Tw", "Tsd", "R2")],
        [
            Parameter("Cw", "capacitance", 3e6),
            Parameter("Rwin", "resistance", 0.1),
            Parameter("Rw", "resistance", 0.01),
            Parameter("R1", "resistance", expr="Rw/2"),
            Parameter("R2", "resistance", expr="Rw/2"),
        ],
    )
    theta = {"Rw": 0.013, "Rwin": 0.09}
    (d,) = net.state_space_derivatives(theta, ["Rw"])
    h = 1e-6
    lo = net.state_space({**theta, "Rw": 0.013 * np.exp(-h)})
    hi = net.state_space({**theta, "Rw": 0.013 * np.exp(h)})
    for got, a, b in ((d.dA, lo.A, hi.A), (d.dB, lo.B, hi.B), (d.dC, lo.C, hi.C), (d.dD, lo.D, hi.D)):
        np.testing.assert_allclose(got, (b - a) / (2 * h), rtol=1e-7, atol=1e-16)
    assert np.abs(d.dD).max() > 0  # the massless output node does depend on Rw


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_output_sensitivities_match_finite_differences_of_the_simulation(hold):
    rng = np.random.default_rng(2)
    net = thirteen_state(rng)
    wrt = ["Cr", "Rwin", "Rfw1", "Cn1w2"]
    ss = net.state_space()
    t = np.arange(0, 6 * 3600, 300.0)
    u = 20 + 3 * rng.standard_normal((t.size, ss.n_inputs))
    m = rng.choice([0.02, 0.12], size=(t.size, 1))
    sens = output_sensitivities(net, None, wrt, t, u, m, hold=hold)
    np.testing.assert_allclose(sens.y, simulate(ss, t, u, m, hold=hold).y, atol=1e-12)
    v = net.values()
    h = 1e-3  # central differences: O(h^2) truncation, rounding of the simulation amplified by 1/h
    for j, name in enumerate(wrt):
        ylo = simulate(net.state_space({name: v[name] * np.exp(-h)}), t, u, m, hold=hold).y
        yhi = simulate(net.state_space({name: v[name] * np.exp(h)}), t, u, m, hold=hold).y
        fd = (yhi - ylo) / (2 * h)
        np.testing.assert_allclose(sens.dy[:, :, j], fd, rtol=1e-5, atol=1e-7 * np.abs(fd).max())
        assert np.abs(fd).max() > 1e-3
