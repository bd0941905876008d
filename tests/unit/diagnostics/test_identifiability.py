"""Verdicts on synthetic nights whose answer is known by construction."""

import numpy as np
import pytest

from rczone.comparison import model_arrays
from rczone.diagnostics import diagnose
from rczone.diagnostics.identifiability import IDENTIFIABLE, NOT_IDENTIFIABLE, parameter_boundaries
from rczone.errors import ParameterError
from rczone.models import get_model
from rczone.simulation.initial import output_consistent_state
from rczone.simulation.sensitivity import output_sensitivities
from tests.unit.diagnostics.synthetic import night


@pytest.fixture(scope="module")
def net():
    return get_model("second-order-paper")


def test_closed_loop_night_cannot_identify_the_wall_resistance(net):
    rep = diagnose(net, night("closed-loop"), free=["Cr", "Rw"])
    rw = rep.parameters["Rw"]
    assert rw.verdict == NOT_IDENTIFIABLE
    assert "stayed within" in rw.reason and "Tsd" in rw.reason
    assert "forced-response test" in rw.advice
    assert rep.to_dict()["parameters"]["Rw"]["verdict"] == NOT_IDENTIFIABLE


def test_forced_response_night_identifies_both(net):
    rep = diagnose(net, night("forced"), free=["Cr", "Rw"])
    assert {k: v.verdict for k, v in rep.parameters.items()} == {"Cr": IDENTIFIABLE, "Rw": IDENTIFIABLE}
    assert all(se < 0.1 for se in rep.expected_se)
    # a tenfold error in either parameter is plainly visible in the data
    assert rep.parameters["Rw"].rms_change_tenth_K > 1.0


def test_fisher_is_symmetric_positive_definite_and_correlation_is_unit_diagonal(net):
    rep = diagnose(net, night("forced"), free=["Cr", "Rw", "Cw"])
    np.testing.assert_allclose(rep.fisher, rep.fisher.T, rtol=1e-10)
    assert np.all(np.linalg.eigvalsh(rep.fisher) > 0)
    np.testing.assert_allclose(np.diag(rep.correlation), 1.0)
    assert rep.condition_number > 1


def test_parameter_boundaries_follow_ties_and_wall_chains(net):
    assert parameter_boundaries(net, "Rw") == ("Tsd",)
    assert parameter_boundaries(net, "Rwin") == ("To",)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"free": ["Rx"]}, r"unknown free parameter 'Rx'"),
        ({"sigma_K": 0.0}, r"must be > 0"),
    ],
)
def test_bad_arguments(net, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        diagnose(net, night("forced", hours=2), **kwargs)


def test_worst_case_bias_bounds_the_shift_a_structured_model_error_causes(net):
    """The bound is attained by a model error along the parameter's marginal sensitivity."""
    frame = night("forced", hours=4)
    free = ["Cr", "Rw"]
    rep = diagnose(net, frame, free=free, model_error_K=0.2, initial_state_nuisance=False, heat_input=None)
    t, u, m = model_arrays(net, frame)
    ss = net.state_space()
    x0 = output_consistent_state(ss, u[0], m[0], float(frame["Ti"].iloc[0]))
    S = output_sensitivities(net, None, free, t, u, m, x0=x0).dy[:, 0, :]
    # worst error of RMS 0.2 K for Rw: along the part of dy/dlogRw not explained by Cr
    q, _ = np.linalg.qr(S[:, :1])
    r = S[:, 1] - q @ (q.T @ S[:, 1])
    e = 0.2 * r / np.sqrt(np.mean(r**2))
    shift = np.linalg.lstsq(S, e, rcond=None)[0]
    assert abs(shift[1]) == pytest.approx(rep.parameters["Rw"].worst_case_bias, rel=1e-6)
    # any other error of the same size shifts it less
    rng = np.random.default_rng(0)
    for _ in range(20):
        e2 = rng.standard_normal(S.shape[0])
        e2 *= 0.2 / np.sqrt(np.mean(e2**2))
        assert abs(np.linalg.lstsq(S, e2, rcond=None)[0][1]) <= rep.parameters["Rw"].worst_case_bias


def test_model_error_check_scales_linearly_and_can_be_disabled(net):
    frame = night("closed-loop", hours=6)
    a = diagnose(net, frame, free=["Cr", "Rw"], model_error_K=0.1).parameters["Rw"]
    b = diagnose(net, frame, free=["Cr", "Rw"], model_error_K=0.3).parameters["Rw"]
    assert b.worst_case_bias == pytest.approx(3 * a.worst_case_bias, rel=1e-12)
    off = diagnose(net, frame, free=["Cr", "Rw"], model_error_K=0.0).parameters["Rw"]
    assert off.worst_case_bias == 0.0
