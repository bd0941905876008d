"""The k-step criterion: against a brute-force sum of the k-step errors, finite differences and the filter."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.calibration.dataset import dataset
from rczone.calibration.prediction import noise_values
from rczone.errors import ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.engines import run_filter
from rczone.estimation.forecast import k_step_bands
from rczone.estimation.kstep import (
    KStepCost,
    _filtered,
    kstep_cost,
    noise_scale,
    sandwich_covariance,
)
from rczone.models import read_model_file
from tests.unit.calibration.test_drift import MODEL, SIGMA_V, SIGMA_W, virtual_zone

HORIZONS = (1, 5, 12)
WRT = ("Ci", "Ce", "Rie", "Rea", "sigma_w_Ti", "sigma_v", "sigma_x0_Te")


@pytest.fixture(scope="module")
def problem(tmp_path_factory):
    d = tmp_path_factory.mktemp("kstep")
    (d / "zone.toml").write_text(MODEL)
    zm = read_model_file(d / "zone.toml")
    zm = zm.with_values(zm.theta, {"sigma_v": SIGMA_V, "sigma_w_Ti": SIGMA_W, "sigma_x0_Te": 2.0})
    data = dataset(zm, virtual_zone(3, days=1.5))
    # the model a little off the truth, so that the gradient is not zero
    values = {**zm.theta, **noise_values(zm), "Rea": 0.012, "Ci": 2.4e6}
    return zm.network, values, data


def _brute(network, values, data, horizons):
    bands = k_step_bands(network, values, data, list(horizons))
    return 0.5 * sum(float(np.nansum((data.y - bands[k].y_hat) ** 2)) for k in horizons)


def test_the_criterion_is_the_sum_of_the_squared_k_step_errors_of_the_filter(problem):
    network, values, data = problem
    cost = kstep_cost(network, values, data, HORIZONS, wrt=WRT)
    assert cost.value == pytest.approx(_brute(network, values, data, HORIZONS), rel=1e-10)
    assert cost.n_errors == sum(data.n_samples - k for k in HORIZONS)


def test_missing_measurements_are_skipped_in_the_filter_and_the_criterion(problem):
    network, values, data = problem
    y = np.array(data.y)
    y[40:70] = np.nan
    y[200] = np.nan
    holed = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
    cost = kstep_cost(network, values, holed, HORIZONS)
    assert cost.value == pytest.approx(_brute(network, values, holed, HORIZONS), rel=1e-10)


def test_the_gradient_equals_central_differences(problem):
    network, values, data = problem
    cost = kstep_cost(network, values, data, HORIZONS, wrt=WRT)
    for i, name in enumerate(WRT):
        h = 1e-5 * values[name]
        up = kstep_cost(network, {**values, name: values[name] + h}, data, HORIZONS).value
        down = kstep_cost(network, {**values, name: values[name] - h}, data, HORIZONS).value
        assert cost.gradient[i] == pytest.approx((up - down) / (2 * h), rel=1e-5, abs=1e-9), name
    assert np.allclose(cost.contributions.sum(axis=0), cost.gradient, rtol=1e-12)


def _filtered_at(network, values, data, wrt=WRT):
    from rczone.estimation.engines import assemble
    from rczone.kernels.discretize import interval_derivatives

    asm = assemble(network, values, data, "zoh", "ml", wrt)
    return _filtered(asm, *interval_derivatives(asm.mod, asm.der, asm.how), data, False)


def test_the_sensitivity_filter_has_the_filters_means_and_their_derivatives(problem):
    """The filtered means equal the filter's without sensitivities; their derivatives, central differences."""
    network, values, data = problem
    xf, dxf = _filtered_at(network, values, data)
    np.testing.assert_allclose(xf, run_filter(network, values, data).x_filt, rtol=1e-9, atol=1e-9)
    for i, name in enumerate(WRT):
        h = 1e-5 * values[name]
        up, _ = _filtered_at(network, {**values, name: values[name] + h}, data, ())
        down, _ = _filtered_at(network, {**values, name: values[name] - h}, data, ())
        fd = (up - down) / (2 * h)
        scale = np.abs(fd).max()
        assert np.abs(dxf[:, i, :] - fd).max() <= 1e-5 * scale, name


def test_the_noise_scale_is_the_only_freedom_the_criterion_leaves(problem):
    network, values, data = problem
    noisy = {k: (3.0 * v if k.startswith("sigma_") else v) for k, v in values.items()}
    a = kstep_cost(network, values, data, HORIZONS)
    b = kstep_cost(network, noisy, data, HORIZONS)
    assert b.value == pytest.approx(a.value, rel=1e-9)  # the gains and the predictions are unchanged
    assert noise_scale(network, noisy, data) == pytest.approx(
        noise_scale(network, values, data) / 3, rel=1e-9
    )


def test_the_sandwich_is_the_bread_and_meat_written_out():
    rng = np.random.default_rng(0)
    g = rng.normal(size=(200, 3))
    a = rng.normal(size=(3, 3))
    cost = KStepCost(0.0, g.sum(axis=0), a @ a.T + 3 * np.eye(3), g, 200)
    meat = sum(np.outer(v, v) for v in g)
    meat = meat + sum(0.5 * (np.outer(g[t], g[t - 1]) + np.outer(g[t - 1], g[t])) for t in range(1, 200))
    hi = np.linalg.inv(cost.gauss_newton)
    np.testing.assert_allclose(sandwich_covariance(cost, 1), hi @ meat @ hi, rtol=1e-10)


@pytest.mark.parametrize("bad", [(), (0, 12), (1.5,), ("x",)])
def test_bad_horizons_are_refused(problem, bad):
    network, values, data = problem
    with pytest.raises(ParameterError, match="horizons must be positive"):
        kstep_cost(network, values, data, bad)


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    from rczone.estimation.fit import fit
    from rczone.estimation.kstep_fit import fit_kstep

    d = tmp_path_factory.mktemp("kstep_fit")
    (d / "zone.toml").write_text(MODEL)
    zm = read_model_file(d / "zone.toml")
    data = dataset(zm, virtual_zone(5, days=3.0))
    ml = fit(zm.network, data, method="ml", n_starts=1)
    return zm.network, data, ml, fit_kstep(zm.network, data, horizons=(1, 12, 72), ml=ml)


@pytest.mark.slow
def test_a_kstep_fit_lowers_its_criterion_and_finds_the_truth_on_data_of_its_own_structure(fitted):
    network, data, ml, res = fitted
    assert res.objective <= res.objective_ml * (1 + 1e-9) and res.converged
    truth = {"Ci": 2.0e6, "Ce": 40.0e6, "Rie": 2.0e-3, "Rea": 10.0e-3}
    for name, value in truth.items():
        assert res.values[name] == pytest.approx(value, rel=0.1), name
        assert 0 < res.std_error[name] < 0.2 * value, name
    # the criterion sees the noise ratios only, and weakly: the scale restores the one-step band
    assert np.isfinite(res.noise_scale) and res.noise_scale > 0
    assert res.values["sigma_v"] == pytest.approx(ml.parameters["sigma_v"].value * res.noise_scale, rel=1e-12)
    at = kstep_cost(network, res.values, data, (1, 12, 72), wrt=("Rie", "Rea"))
    assert np.all(np.abs(at.gradient * np.array([2e-3, 1e-2])) < 1e-3 * res.objective)  # a stationary point
    assert set(res.to_dict()) >= {"horizons", "values", "std_error", "objective_K2", "noise_scale"}
    assert "k-step fit" in res.summary() and list(res.to_frame().name) == list(res.std_error)


def test_the_k_step_search_reports_its_stage_and_evaluations(tmp_path):
    """Issue 37: the k-step search, after the likelihood fit's own progress, says what it does."""
    from rczone.estimation.fit import fit
    from rczone.estimation.kstep_fit import fit_kstep

    class Recorder:
        def __init__(self):
            self.stages, self.steps = [], []

        def __call__(self, message):
            self.stages.append(message)

        def advance(self, done, total=None):
            self.steps.append((done, total))

    (tmp_path / "zone.toml").write_text(MODEL)
    model = read_model_file(tmp_path / "zone.toml")
    data = dataset(model, virtual_zone(5, days=1.0))
    ml = fit(model.network, data, method="ml", n_starts=1)
    rec = Recorder()
    res = fit_kstep(model.network, data, horizons=(1, 12), ml=ml, max_evals=4, progress=rec)
    assert rec.stages == ["k-step criterion at horizons 1, 12 from the ML fit"]
    done = [d for d, _ in rec.steps]
    assert done == sorted(done) and done[0] == 1 and {t for _, t in rec.steps} == {4}
    assert len(rec.steps) == res.n_evals
