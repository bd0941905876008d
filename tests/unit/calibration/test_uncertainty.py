"""The calibration workflow's residual analysis, saved covariance and prediction bands."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.calibration import calibrate, prediction, saved_covariance
from rczone.errors import DataError
from tests.unit.selection.synthetic import TRUE_MODEL, prbs_zone


@pytest.fixture(scope="module")
def zone():
    return prbs_zone(days=2, seed=3)


@pytest.fixture(scope="module")
def ml(zone):
    return calibrate(TRUE_MODEL, zone.iloc[:400], method="ml", n_starts=2)


def test_ml_fit_carries_its_innovations_and_ls_its_labelled_open_loop_residuals(zone, ml):
    assert ml.innovations is not None and ml.innovations.kind == "innovations"
    assert ml.open_loop_residuals.kind == "open-loop"
    # the open-loop error of even a good fit is far from white; the innovations are not
    assert ml.open_loop_residuals.outputs[0].acf[1] > 0.8 > abs(ml.innovations.outputs[0].acf[1])
    ls = calibrate(TRUE_MODEL, zone.iloc[:400], method="ls", n_starts=1)
    assert ls.innovations is None and "not expected to be white" in ls.open_loop_residuals.note


def test_the_saved_covariance_is_the_fits_and_feeds_the_prediction_band(zone, ml):
    r = ml.result
    names, cov = saved_covariance(ml.model)
    assert names == list(r.names)
    se = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(se, [r.std_errors[n] for n in names], rtol=1e-12)
    later = zone.iloc[400:]
    pred = prediction(ml.model, later)
    assert "covariance" in pred.band_source and pred.steps is None
    np.testing.assert_allclose(pred.sd**2, pred.sd_noise**2 + pred.sd_parameters**2, rtol=1e-12)
    assert 0.0 < np.mean(pred.sd_parameters) < np.mean(pred.sd_noise)
    plain = prediction(ml.model, later, parameters=False)
    assert plain.sd_parameters is None and np.all(plain.sd <= pred.sd + 1e-15)
    ahead = prediction(ml.model, later, steps=3)
    assert ahead.horizon == "3 steps ahead" and np.isnan(ahead.predicted[:3]).all()
    assert np.nanmean(ahead.sd) < np.nanmean(pred.sd)  # three steps ahead is surer than open loop
    frame = ahead.to_frame()
    assert {"Ti_sd_noise", "Ti_sd_parameters", "Ti_lower"} <= set(frame.columns)


def test_k_steps_need_noise_levels_and_a_malformed_covariance_is_an_error(zone, ml):
    ls_model = ml.model.with_values({}, noise={})
    with pytest.raises(DataError, match="noise levels"):
        prediction(ls_model, zone.iloc[400:], steps=2)
    bad = ml.model.with_values({}, covariance={"names": ["Ci"], "matrix": [[1.0, 2.0]]})
    with pytest.raises(DataError, match="covariance is malformed"):
        prediction(bad, zone.iloc[400:])


def test_no_residual_analysis_on_a_handful_of_measurements(zone):
    few = zone.iloc[:200].copy()
    few.loc[few.index[8:], "Ti"] = np.nan  # eight measured samples
    cal = calibrate(TRUE_MODEL, few, method="ml", n_starts=1, uncertainty=False)
    assert cal.innovations is None and cal.open_loop_residuals is None


@pytest.mark.parametrize(
    "kept",
    [
        {"names": ["Ci"], "values": [[1.0, 2.0], [1.0, 2.0]]},  # a column too many
        {"names": ["Ci"], "values": [[1.0]]},  # one draw is no spread
        {"names": ["Ci"], "values": [[1.0], ["x"]]},
        {"names": ["Ci"], "values": [[1.0], [float("nan")]]},
        {"values": [[1.0], [2.0]]},
    ],
)
def test_malformed_saved_draws_are_an_error(zone, ml, kept):
    bad = ml.model.with_values({}, posterior_draws=kept)
    with pytest.raises(DataError, match="posterior draws are malformed"):
        prediction(bad, zone.iloc[400:])


def test_saved_draws_replace_the_covariance_in_the_band(zone, ml):
    # draws spread as the covariance says: the band's parameter part comes from the draws instead
    names, cov = saved_covariance(ml.model)
    mean = np.array([ml.result.estimates[n] for n in names])
    draws = np.random.default_rng(2).multivariate_normal(mean, cov, size=200)
    sampled = ml.model.with_values({}, posterior_draws={"names": names, "values": draws.tolist()})
    later = zone.iloc[400:]
    pred, delta = prediction(sampled, later), prediction(ml.model, later)
    assert "200 posterior draws" in pred.band_source and "covariance" not in pred.band_source
    np.testing.assert_allclose(np.mean(pred.sd_parameters), np.mean(delta.sd_parameters), rtol=0.3)
    lo, hi = pred.band
    assert np.all(lo <= pred.predicted + 1e-9) and np.all(hi >= pred.predicted - 1e-9)


def test_without_analyses_the_fit_and_its_open_loop_check_are_the_full_calibrations(zone, ml):
    # what batch calibration stores is computed as the full calibration computes it; only the analyses
    # a reader of one fit looks at are left out
    lean = calibrate(TRUE_MODEL, zone.iloc[:400], method="ml", n_starts=2, analyses=False)
    assert lean.result.estimates == ml.result.estimates and lean.result.std_errors == ml.result.std_errors
    assert lean.result.flags == ml.result.flags and lean.result.llf == ml.result.llf
    np.testing.assert_array_equal(lean.open_loop.error, ml.open_loop.error)
    assert lean.residuals.p_value == ml.residuals.p_value
    assert (lean.innovations, lean.open_loop_residuals, lean.plausibility) == (None, None, None)
    assert ml.plausibility is not None and ml.model.provenance["band_scale"] is not None
    assert lean.model.provenance["band_scale"] is None and lean.model.provenance["baselines"] is None
    assert lean.summary() and lean.to_dict()["innovations"] is None  # still prints and serializes


def test_a_data_set_built_by_the_caller_gives_the_same_calibration(zone, ml):
    from rczone.calibration.dataset import prepare

    frame = zone.iloc[:400]
    prepared = prepare(TRUE_MODEL, frame)
    given = calibrate(TRUE_MODEL, prepared, method="ml", n_starts=2)
    assert given.data is prepared  # carried unchanged, not built again
    assert given.result.estimates == ml.result.estimates and given.result.std_errors == ml.result.std_errors
    np.testing.assert_array_equal(given.open_loop.error, ml.open_loop.error)
    assert given.model.provenance["stretch"] == ml.model.provenance["stretch"]
