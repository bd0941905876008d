"""The control model: the exact discretization of ZoneModel, the reheat column, the flow derivatives."""

import numpy as np
import pytest

from rczone.control import ControlModel, Disturbance, NoiseModel
from rczone.errors import InputShapeError, ParameterError
from rczone.models import load_model
from rczone.network import CP_AIR
from rczone.simulation.discretize import zoh


@pytest.fixture(scope="module")
def zm():
    return load_model("second-order")


def test_without_disturbance_the_matrices_are_those_of_zone_model_discrete(zm):
    cm = ControlModel(zm)
    d, ref = cm.discrete(600.0, 0.07), zm.discrete(600.0, 0.07)
    np.testing.assert_allclose(d.Ad, ref.Ad, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(d.Bd, ref.Bd, rtol=1e-12, atol=1e-15)


def test_reheat_power_acts_as_supply_air_warmer_by_p_over_m_cp(zm):
    # m cp (Ts + P/(m cp) - Ti) = m cp (Ts - Ti) + P: the Ts column divided by m cp
    m = 0.07
    d = ControlModel(zm).discrete(600.0, m)
    ts = zm.network.input_names.index("Ts")
    np.testing.assert_allclose(d.Ed[:, 0], d.Bd[:, ts] / (m * CP_AIR), rtol=1e-10)


@pytest.mark.parametrize("disturbance", [None, Disturbance("heat"), Disturbance("offset", tau=3600.0)])
def test_flow_derivative_matches_complex_step_and_central_differences(zm, disturbance):
    cm = ControlModel(zm, disturbance=disturbance)
    dt, m = 600.0, 0.06
    der = cm.flow_derivative(dt, m)
    A, BE = cm.continuous(m)
    c = cm.matrices
    h = 1e-20
    dE = np.hstack([c.M[0], 0 * c.E])
    Phi, G = zoh(A + 1j * h * c.N[0], BE + 1j * h * dE, dt)
    p = c.B0.shape[1]
    np.testing.assert_allclose(der.dAd[0], Phi.imag / h, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(der.dBd[0], G.imag[:, :p] / h, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(der.dEd[0], G.imag[:, p:] / h, rtol=1e-9, atol=1e-16)
    if disturbance is None:  # against the public discretization of ZoneModel
        e = 1e-6
        fd = (zm.discrete(dt, m + e).Ad - zm.discrete(dt, m - e).Ad) / (2 * e)
        np.testing.assert_allclose(der.dAd[0], fd, rtol=1e-6, atol=1e-12)


def test_heat_disturbance_enters_the_air_node_as_a_heat_input(zm):
    cm = ControlModel(zm, disturbance=Disturbance("heat"))
    d = cm.discrete(300.0, 0.05)
    # a constant disturbance of P watts acts exactly as the reheat heat input of P watts
    np.testing.assert_allclose(d.Ad[:2, 2], d.Ed[:2, 0], rtol=1e-10)
    assert cm.state_names == ("Ti", "Tw", "d_heat")


def test_offset_disturbance_adds_to_the_output_and_decays_with_tau(zm):
    cm = ControlModel(zm, disturbance=Disturbance("offset", tau=1800.0))
    d = cm.discrete(600.0, 0.05)
    assert d.C[0, 2] == 1.0
    np.testing.assert_allclose(d.Ad[2, 2], np.exp(-600.0 / 1800.0), rtol=1e-12)


def test_noise_defaults_are_reported_and_fitted_values_used(zm):
    assert NoiseModel.from_model(zm).source == "default"
    fitted = zm.with_values({}, noise={"sigma_v": 0.05, "sigma_w_Ti": 0.002, "sigma_w_Tw": 0.0})
    nm = NoiseModel.from_model(fitted)
    assert nm.source == "fitted"
    np.testing.assert_array_equal(np.diag(nm.Qc), [0.002**2, 0.0])
    assert nm.to_dict()["sigma_v_K"] == {"Ti": 0.05}


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda zm: Disturbance("heta"), "did you mean|heat"),
        (lambda zm: Disturbance("heat", tau=-1.0), "tau"),
        (lambda zm: ControlModel(zm, disturbance=Disturbance("heat", node="Tx")), "Tx"),
        (lambda zm: ControlModel(zm).discrete(0.0, 0.05), "dt"),
        (lambda zm: ControlModel(zm).discrete(60.0, -0.1), "flow"),
        (lambda zm: NoiseModel.from_model(zm, overrides={"sigma_q": 1.0}), "sigma_q"),
        (lambda zm: NoiseModel.from_model(zm, overrides={"sigma_v": 0.0}), "sigma_v > 0"),
    ],
)
def test_bad_arguments_raise_typed_errors(zm, call, match):
    with pytest.raises((ParameterError, InputShapeError), match=match):
        call(zm)
