"""The harder closed-loop scenarios: a tight comfort band and a demand-response event."""

import numpy as np
import pytest

from rczone.control.closedloop import (
    DR_PRICE,
    TIGHT_BAND_K,
    MPCZoneController,
    closed_loop_test,
    forecast_price,
    price_signal,
    tighten,
)
from rczone.control.mpc import MPC
from rczone.errors import ParameterError
from rczone.models import load_model
from rczone.virtual.building import build_building
from rczone.virtual.emulator import thermostat_configs
from rczone.virtual.scenarios import SURROUNDINGS

H = 3600.0  # s; times are s after 6 pm


@pytest.fixture(scope="module")
def zm():
    return load_model("second-order")


@pytest.fixture(scope="module")
def cfg():
    return thermostat_configs(build_building(), "summer", np.random.default_rng(4), daily=True)["target"]


def test_the_event_price_is_ten_times_from_2_to_4_pm_every_day():
    # 1:59 pm, 2 pm, 3:59 pm, 4 pm, noon (a time-of-use peak, not an event), 2 pm the next day
    t = np.array([19 * H + 3540, 20 * H, 22 * H - 60, 22 * H, 18 * H, 44 * H])
    np.testing.assert_array_equal(price_signal("dr", t), [1, DR_PRICE, DR_PRICE, 1, 1, DR_PRICE])
    assert DR_PRICE == 10.0
    np.testing.assert_array_equal(price_signal("flat", t), np.ones(t.size))


def test_the_event_is_in_the_mpc_forecast_only_from_its_announcement_at_11_am(zm, cfg):
    ctrl = MPCZoneController(MPC(zm), cfg, "summer", "dr")
    ctrl.observe(0.0, {"To": 30.0, **{c: 23.0 for c in SURROUNDINGS}})
    for day in (0, 1):
        d = day * 24 * H
        before = ctrl.forecast(d + 17 * H - 600, 13.0)  # 10:50 am: the horizon reaches 4:50 pm
        np.testing.assert_array_equal(before.price, np.ones(37))
        at = ctrl.forecast(d + 17 * H, 13.0)  # 11 am: steps 18..29 (2 pm to 3:50 pm) are the event
        expected = np.ones(37)
        expected[18:30] = DR_PRICE
        np.testing.assert_array_equal(at.price, expected)
        during = ctrl.forecast(d + 21 * H, 13.0)  # 3 pm: the event's last hour, then normal
        np.testing.assert_array_equal(during.price, np.r_[np.full(6, DR_PRICE), np.ones(31)])
    # the time-of-use price stays known in advance
    t = 6 * H + 600 * np.arange(37)
    np.testing.assert_array_equal(forecast_price("tou", 6 * H, t), price_signal("tou", t))


@pytest.fixture(scope="module")
def dr_runs(zm):
    kw = {"season": "summer", "days": 1, "seed": 4, "controller": "thermostat"}
    return closed_loop_test(zm, **kw), closed_loop_test(zm, **kw, price="dr")


def test_the_event_is_scored_at_its_price_with_its_own_energy_and_peak_flow(dr_runs):
    flat, dr = dr_runs
    s, t = dr.scores, dr.t
    assert s["energy_kWh"] == flat.scores["energy_kWh"]  # the thermostat ignores the event
    ev = (t >= 20 * H) & (t < 22 * H)
    assert ev.sum() == 120  # two hours of minutes
    e_ev = dr.series["power_W"][ev].sum() * 60 / 3.6e6
    assert e_ev > 0.05
    assert s["event_energy_kWh"] == pytest.approx(e_ev)
    assert s["cost"] == pytest.approx(s["energy_kWh"] + (DR_PRICE - 1) * e_ev)
    assert s["event_cost"] == pytest.approx(DR_PRICE * e_ev)
    assert s["event_peak_flow_kg_s"] == dr.series["m"][ev].max()
    s_ = dr.series
    outside = np.clip(s_["lower"] - s_["Ti"], 0, None) + np.clip(s_["Ti"] - s_["upper"], 0, None)
    assert s["event_comfort_Kh"] == pytest.approx((outside * s_["occupied"] * ev).sum() / 60.0)
    assert "event_energy_kWh" not in flat.scores and "DR event" in dr.summary()


def test_the_tight_band_is_narrowed_about_its_centre_for_the_thermostat_and_the_score(zm, cfg):
    tc = tighten(cfg)
    assert tc.cool_occ - tc.heat_occ == pytest.approx(TIGHT_BAND_K)
    assert tc.cool_occ + tc.heat_occ == pytest.approx(cfg.cool_occ + cfg.heat_occ)
    assert (tc.heat_unocc, tc.cool_unocc) == (cfg.heat_unocc, cfg.cool_unocc)
    assert cfg.cool_occ - cfg.heat_occ > TIGHT_BAND_K + 0.5  # tighter than the summer band

    kw = {"season": "summer", "days": 0.5, "seed": 4, "controller": "thermostat"}
    normal, tight = closed_loop_test(zm, **kw), closed_loop_test(zm, **kw, comfort_band="tight")
    occ = tight.series["occupied"]
    assert occ.any() and (~occ).any()
    s, n = tight.series, normal.series
    np.testing.assert_allclose((s["upper"] - s["lower"])[occ], TIGHT_BAND_K)
    np.testing.assert_allclose((s["upper"] + s["lower"])[occ], (n["upper"] + n["lower"])[occ])
    np.testing.assert_array_equal(s["upper"][~occ], n["upper"][~occ])
    outside = np.clip(s["lower"] - s["Ti"], 0, None) + np.clip(s["Ti"] - s["upper"], 0, None)
    assert tight.scores["comfort_Kh"] == pytest.approx((outside * occ).sum() / 60.0)
    # the thermostat itself ran on the tight band (its reheat loop aims at the raised lower edge)
    assert not np.array_equal(s["Ts"], n["Ts"])
    assert tight.setup["band"] == "tight" and normal.setup["band"] == "normal"


def test_an_unknown_band_is_a_one_line_error(zm):
    with pytest.raises(ParameterError, match="wide"):
        closed_loop_test(zm, comfort_band="wide")
