"""The unrolled 2-state filter against the general one and a NumPy oracle, and the bands it gives.

A 2-state, 1-output problem runs :func:`rczone.kernels.rc2.filter_rc2` instead of the general
compiled filter (issue 37, item 7: a first run that calibrates a 2-state model's bands then
compiles a small kernel, not the general filter). Both filter the same model, so every
intermediate result agrees within the general filter's steady-state tolerance (1e-14, relative);
the bands calibrated from them agree with those of the general filter.
"""

from __future__ import annotations

import numpy as np
import pytest

import rczone.estimation.kalman as kalman
from rczone.calibration.bands import calibrate_band
from rczone.estimation.costs import filter_arrays
from rczone.estimation.forecast import k_step_bands, open_loop_band
from rczone.estimation.kalman import kalman_filter_arrays
from tests.oracles import kalman_filter_reference

from ..estimation.nets import NET2, data2

NOISE2 = {"sigma_v": 0.05, "sigma_w_Ti": 3e-3, "sigma_w_Tw": 1e-3, "sigma_x0_Ti": 0.2, "sigma_x0_Tw": 0.5}
FIELDS = ("innovations", "S", "x_pred", "x_filt", "P_pred", "P_filt")


def _data(n: int = 400, missing: bool = False):
    data = data2(n, noise=0.05, rng=np.random.default_rng(5))
    if missing:
        y = data.y.copy()
        y[np.random.default_rng(6).random(n) < 0.2] = np.nan
        data = type(data)(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    return data


@pytest.mark.parametrize("hold", ["zoh", "foh"])
@pytest.mark.parametrize("missing", [False, True])
def test_the_two_state_filter_equals_the_general_filter_and_the_oracle(hold, missing):
    problem = filter_arrays(NET2, NOISE2, _data(missing=missing), hold)
    assert problem.Phi.shape[0] > 1  # the flow switches: several distinct intervals
    two = kalman_filter_arrays(problem)
    general = kalman_filter_arrays(problem, general=True)
    oracle = kalman_filter_reference(problem)
    assert two.n_obs == general.n_obs == oracle.n_obs
    for ref in (general, oracle):
        assert two.nll == pytest.approx(ref.nll, rel=1e-11)
        for name in FIELDS:
            np.testing.assert_allclose(
                getattr(two, name), getattr(ref, name), rtol=1e-9, atol=1e-12, equal_nan=True, err_msg=name
            )


def test_an_invalid_noise_model_is_refused_by_both_filters():
    bad = {**NOISE2, "sigma_v": 0.0, "sigma_x0_Ti": 0.0, "sigma_x0_Tw": 0.0}
    problem = filter_arrays(NET2, bad, _data(50))
    for general in (False, True):
        with pytest.raises(np.linalg.LinAlgError, match="innovation variance"):
            kalman_filter_arrays(problem, general=general)


def _bands_and_scale(data):
    bands = k_step_bands(NET2, NOISE2, data, [1, 6, 24])
    y_ol, sd_ol = open_loop_band(NET2, NOISE2, data)
    return bands, (y_ol, sd_ol), calibrate_band(NET2, NOISE2, data)


@pytest.mark.parametrize("missing", [False, True])
def test_a_two_state_models_bands_equal_those_of_the_general_filter(missing, monkeypatch):
    data = _data(600, missing=missing)
    new = _bands_and_scale(data)
    monkeypatch.setattr(kalman, "_two_state", lambda problem: False)
    old = _bands_and_scale(data)
    for k in (1, 6, 24):
        np.testing.assert_allclose(new[0][k].y_hat, old[0][k].y_hat, rtol=1e-10, equal_nan=True)
        np.testing.assert_allclose(new[0][k].sd, old[0][k].sd, rtol=1e-9, equal_nan=True)
    np.testing.assert_allclose(new[1], old[1], rtol=1e-9)
    assert new[2].horizon_s == old[2].horizon_s
    np.testing.assert_allclose(new[2].scale, old[2].scale, rtol=1e-9)
    assert new[2].open_loop == pytest.approx(old[2].open_loop, rel=1e-9)
