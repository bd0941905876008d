"""Whiteness statistics of residuals, checked against statsmodels and scipy, and on known models."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal
from statsmodels.stats.diagnostic import acorr_ljungbox
from statsmodels.tsa import stattools

from rczone.errors import ParameterError
from rczone.postfit.innovations import (
    acf,
    analyse_residuals,
    ccf,
    cumulative_periodogram,
    innovation_analysis,
    ljung_box_lags,
    ljung_box_q,
)
from rczone.postfit.openloop import ljung_box

from ..estimation.nets import NET1


def ar1(n: int, phi: float, rng: np.random.Generator) -> np.ndarray:
    e = rng.standard_normal(n)
    x = np.empty(n)
    x[0] = e[0]
    for k in range(1, n):
        x[k] = phi * x[k - 1] + e[k]
    return x


@pytest.mark.parametrize("phi", [0.0, 0.6])
def test_acf_and_ljung_box_equal_statsmodels(phi):
    x = ar1(300, phi, np.random.default_rng(3))
    ours = acf(x, 25)
    np.testing.assert_allclose(ours, stattools.acf(x, nlags=25, fft=False), rtol=1e-12, atol=1e-14)
    ref = acorr_ljungbox(x, lags=[12], return_df=True)
    q = ljung_box_q(ours[1:13], x.size)
    assert q == pytest.approx(float(ref["lb_stat"].iloc[0]), rel=1e-12)
    res = ljung_box(x, n_lags=12)
    assert res.q_statistic == pytest.approx(q, rel=1e-12)
    assert res.p_value == pytest.approx(float(ref["lb_pvalue"].iloc[0]), rel=1e-9, abs=1e-300)


def test_acf_with_missing_samples_equals_statsmodels_conservative():
    x = ar1(200, 0.5, np.random.default_rng(4))
    x[[3, 50, 51, 52, 120]] = np.nan
    ref = stattools.acf(x, nlags=10, fft=False, missing="conservative")
    np.testing.assert_allclose(acf(x, 10), ref, rtol=1e-12)


def test_cross_correlation_equals_statsmodels_with_the_input_leading():
    rng = np.random.default_rng(5)
    u = ar1(400, 0.9, rng)
    x = np.r_[0.0, 0.0, 0.0, u[:-3]] + rng.standard_normal(400)  # x follows u three samples later
    r = ccf(x, u, 10)
    np.testing.assert_allclose(r, stattools.ccf(x, u, adjusted=False, fft=False)[:11], rtol=1e-10)
    assert int(np.argmax(r)) == 3
    assert ccf(x, np.full(400, 20.0), 10) is None  # a constant input has no correlation


def test_cumulative_periodogram_matches_scipy_and_its_band_holds_95_percent():
    rng = np.random.default_rng(6)
    x = ar1(301, 0.3, rng)
    cp = cumulative_periodogram(x)
    f, pxx = signal.periodogram(x, detrend="constant", scaling="spectrum", window="boxcar")
    q = (x.size - 1) // 2
    np.testing.assert_allclose(cp.freq, f[1 : q + 1], rtol=1e-12)
    np.testing.assert_allclose(cp.cumulative, np.cumsum(pxx[1 : q + 1]) / pxx[1 : q + 1].sum(), rtol=1e-10)
    assert cp.cumulative[-1] == pytest.approx(1.0)
    # the band is a 95 % band: white series leave it about 5 % of the time, an AR(1) always
    outside = np.mean([not cumulative_periodogram(rng.standard_normal(201)).inside_band for _ in range(1000)])
    assert 0.03 < outside < 0.075
    assert not cumulative_periodogram(ar1(201, 0.7, rng)).inside_band
    assert cp.periods_s(300.0)[0] == pytest.approx(301 * 300.0)


def test_per_output_statistics_and_the_bonferroni_p_value():
    rng = np.random.default_rng(7)
    n = 500
    e = np.column_stack([rng.standard_normal(n), ar1(n, 0.5, rng)])
    t = np.arange(n) * 600.0
    u = rng.standard_normal((n, 1))
    an = analyse_residuals(e, np.ones_like(e), t, u, ["To"], ["T1", "T2"], "innovations")
    a, b = an.outputs
    assert a.white and not b.white
    assert an.ljung_box_p == pytest.approx(min(1.0, 2 * min(a.p_value, b.p_value)))
    assert not an.white
    # lags span six hours of 10-min samples and read in hours
    assert an.lags_h[1] == pytest.approx(1 / 6) and an.lags_h[-1] == pytest.approx(6.0)
    d = an.to_dict()
    assert set(d["outputs"]) == {"T1", "T2"} and d["outputs"]["T2"]["white"] is False
    assert d["outputs"]["T1"]["acf"]["lag_h"][1] == pytest.approx(1 / 6)
    assert ljung_box_lags(n) == 20 and ljung_box_lags(30) == 6


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"kind": "closed-loop"}, "kind must be"),
        ({"output_names": ["a", "b"]}, r"shape \(N, 2\)"),
    ],
)
def test_analysis_bad_arguments(kwargs, match):
    e = np.random.default_rng(0).standard_normal((50, 1))
    args = {
        "residuals": e,
        "scale": np.ones_like(e),
        "t": np.arange(50.0),
        "inputs": np.zeros((50, 0)),
        "input_names": [],
        "output_names": ["Ti"],
        "kind": "innovations",
        **kwargs,
    }
    with pytest.raises(ParameterError, match=match):
        analyse_residuals(**args)


def test_short_or_constant_series_are_errors():
    with pytest.raises(ParameterError, match="at least 3"):
        acf(np.array([1.0, np.nan, 2.0]), 1)
    with pytest.raises(ParameterError, match="constant"):
        acf(np.ones(20), 3)
    with pytest.raises(ParameterError, match="at least 5"):
        cumulative_periodogram(np.arange(4.0))


def test_innovations_of_the_true_model_are_standard_normal_and_white():
    """Data from the filter's own model: standardized innovations N(0, 1), white, unrelated to inputs."""
    from tests.unit.selection.synthetic import simulate_sde

    rng = np.random.default_rng(11)
    n, dt = 1500, 600.0
    t = np.arange(n) * dt
    u = np.column_stack([5 + 3 * np.sin(2 * np.pi * t / 86400), 400.0 * (rng.random(n) < 0.3)])
    theta = {"Cr": 1e6, "R": 0.01}
    _, y = simulate_sde(NET1, theta, t, u, {"Ti": 2e-3}, 0.03, rng, substeps=30)
    from rczone.estimation import Dataset

    data = Dataset(t, u, None, y, NET1.input_names, (), NET1.outputs)
    values = {**theta, "sigma_v": 0.03, "sigma_w_Ti": 2e-3, "sigma_x0_Ti": 0.1}
    an = innovation_analysis(NET1, values, data)
    z = an.outputs[0].standardized[1:]
    assert abs(z.mean()) < 0.1 and z.var() == pytest.approx(1.0, abs=0.1)
    assert an.white and an.outputs[0].periodogram.inside_band
    worst = an.outputs[0].worst_input()
    assert worst is not None and worst[1] < 3 * an.outputs[0].band
    # a wrong resistance leaves structure
    bad = innovation_analysis(NET1, {**values, "R": 0.003}, data)
    assert not bad.white


def test_two_measured_outputs_get_their_own_statistics():
    from rczone.estimation import Dataset
    from rczone.models import family_network
    from rczone.network import RCNetwork
    from tests.unit.selection.synthetic import simulate_sde

    te = family_network("TiTe")  # room and envelope, both measured here
    net = RCNetwork("two outputs", te.nodes, te.boundaries, te.resistors, te.parameters, outputs=["Ti", "Te"])
    rng = np.random.default_rng(12)
    t = np.arange(1200) * 600.0
    u = (5 + 4 * np.sin(2 * np.pi * t / 86400) + np.cumsum(rng.normal(0, 0.2, t.size)))[:, None]
    sw = {"Ti": 2e-3, "Te": 1e-3}
    _, y = simulate_sde(net, {}, t, u, sw, 0.03, rng, substeps=30)
    data = Dataset(t, u, None, y, net.input_names, (), net.outputs)
    values = {"sigma_v_Ti": 0.03, "sigma_v_Te": 0.03, "sigma_w_Ti": 2e-3, "sigma_w_Te": 1e-3}
    values |= {"sigma_x0_Ti": 0.1, "sigma_x0_Te": 0.1}  # two outputs: one measurement noise each
    an = innovation_analysis(net, values, data)
    assert [o.output for o in an.outputs] == ["Ti", "Te"]
    for o in an.outputs:
        z = o.standardized[1:]
        assert z.var() == pytest.approx(1.0, abs=0.12) and o.white
    # a wrong wall: the wall's own innovations show it
    bad = innovation_analysis(net, {**values, "Rea": 0.06}, data)
    assert not bad.outputs[1].white and not bad.white
