import numpy as np
import pytest

from rczone.errors import InputShapeError
from rczone.simulation.frequency import frequency_response, gain_error
from tests.netfactory import one_r_one_c, thirteen_state


def test_one_r_one_c_response_is_analytic():
    R, C = 0.02, 4e5
    ss = one_r_one_c(R, C).state_space().lti()
    f = np.logspace(-6, -2, 50)
    fr = frequency_response(ss, f)
    w = 2 * np.pi * f
    np.testing.assert_allclose(fr.to_input("To"), 1 / (1 + 1j * w * R * C), rtol=1e-12)
    np.testing.assert_allclose(fr.to_input("Q"), R / (1 + 1j * w * R * C), rtol=1e-12)


def test_zero_frequency_equals_dc_gain_and_summed_group_adds_columns():
    ss = thirteen_state(np.random.default_rng(0)).state_space().lti(0.12)
    sur = ["Tf", "Tc", "Tn1", "Tn2", "Thw"]
    fr = frequency_response(ss, np.array([0.0, 1e-4]))
    np.testing.assert_allclose(fr.H[0].real, ss.dc_gain(), rtol=1e-10)
    g = fr.summed({"Tsd": sur})
    assert g.input_names == ("To", "Tsd", "Ts", "Q")
    np.testing.assert_allclose(g.to_input("Tsd"), sum(fr.to_input(s) for s in sur), rtol=1e-14)
    # all temperature gains sum to 1 - (Ts gain) at DC: a uniform shift of every temperature shifts Ti
    dc = g.H[0, 0].real
    assert dc[0] + dc[1] + dc[2] == pytest.approx(1.0, rel=1e-12)


def test_gain_error_is_weighted_absolute_gain_difference():
    f = np.logspace(-5, -3, 20)
    a = frequency_response(one_r_one_c(0.02, 4e5).state_space().lti(), f)
    b = frequency_response(one_r_one_c(0.02, 2e5).state_space().lti(), f)
    e = gain_error(a, b, {"To": 25.0})
    expected = np.abs(np.abs(a.to_input("To")) - np.abs(b.to_input("To"))) * 25.0
    np.testing.assert_allclose(e["To"], expected)
    assert e["To"].max() > 0.5


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda fr: fr.to_input("Tx"), "no input 'Tx'"),
        (lambda fr: fr.summed({"Tsd": ["Tf", "Tq"]}), "unknown input 'Tq'"),
        (lambda fr: frequency_response(one_r_one_c().state_space().lti(), np.array([-1.0])), "non-negative"),
    ],
)
def test_bad_frequency_inputs(call, match):
    fr = frequency_response(thirteen_state(np.random.default_rng(0)).state_space().lti(), np.array([1e-4]))
    with pytest.raises(InputShapeError, match=match):
        call(fr)
