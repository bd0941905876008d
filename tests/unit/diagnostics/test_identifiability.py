"""Verdicts on synthetic nights whose answer is known by construction."""

import numpy as np
import pytest

from rczone.diagnostics import diagnose
from rczone.diagnostics.identifiability import IDENTIFIABLE, NOT_IDENTIFIABLE, parameter_boundaries
from rczone.errors import ParameterError
from rczone.models import get_model
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
