"""Export: a python-control StateSpace with the noise as inputs, and plain named arrays."""

import numpy as np
import pytest
from scipy.linalg import expm

from rczone.control import ControlModel, Disturbance
from rczone.control.export import named_arrays, psd_sqrt, to_control
from rczone.models import load_model

control = pytest.importorskip("control")


@pytest.fixture(scope="module")
def zm():
    return load_model("second-order").with_values(
        {}, noise={"sigma_v": 0.05, "sigma_w_Ti": 2e-3, "sigma_w_Tw": 0.0}
    )


def test_continuous_statespace_is_the_model_with_its_noise_as_inputs(zm):
    sys = to_control(zm, m=0.08)
    c = zm.continuous(0.08)
    p = len(c.input_names)
    np.testing.assert_array_equal(sys.A, c.A)
    np.testing.assert_array_equal(sys.B[:, :p], c.B)
    Gw = sys.B[:, p : p + 2]
    np.testing.assert_allclose(Gw @ Gw.T, np.diag([2e-3**2, 0.0]), atol=1e-18)
    assert sys.D[0, -1] == pytest.approx(0.05)
    assert sys.input_labels == [*c.input_names, "w_Ti", "w_Tw", "v_Ti"]


def test_discrete_statespace_carries_qd_at_the_sample_time(zm):
    sys = to_control(zm, m=0.05, dt=600.0)
    d = ControlModel(zm).discrete(600.0, 0.05)
    np.testing.assert_array_equal(sys.A, d.Ad)
    Gw = sys.B[:, 4:6]
    np.testing.assert_allclose(Gw @ Gw.T, d.Qd, rtol=1e-10, atol=1e-20)
    assert sys.dt == 600.0


def test_named_arrays_rebuild_the_discrete_model_by_hand(zm):
    na = named_arrays(zm, disturbance=Disturbance("heat"))
    a = na.arrays
    m, dt = 0.07, 300.0
    A = a["A0"] + m * a["N"][0]
    B = np.hstack([a["B0"] + m * a["M"][0], a["E"]])
    n, p = B.shape
    blk = np.zeros((n + p, n + p))
    blk[:n, :n], blk[:n, n:] = A * dt, B * dt
    E = expm(blk)
    d = ControlModel(zm, disturbance=Disturbance("heat")).discrete(dt, m)
    np.testing.assert_allclose(E[:n, :n], d.Ad, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(E[:n, n:-1], d.Bd, rtol=1e-12, atol=1e-15)
    assert na.names["states"] == ("Ti", "Tw", "d_heat") and na.units["d_heat"] == "W"
    assert na.units["m"] == "kg/s" and na.units["Ts"] == "degC" and na.units["Q"] == "W"
    assert set(na.to_dict()) == {"equation", "arrays", "names", "units"}


def test_psd_square_root_of_a_singular_covariance():
    S = np.array([[4.0, 2.0], [2.0, 1.0]])
    G = psd_sqrt(S)
    np.testing.assert_allclose(G @ G.T, S, atol=1e-12)
