"""The harder closed-loop scenarios: a tight comfort band and a demand-response event."""

import numpy as np
import pytest

from rczone.control.closedloop import closed_loop_test
from rczone.control.signals import DR_PRICE, TIGHT_BAND_K, forecast_price, price_signal, tighten
from rczone.control.virtualplant import VirtualPlant
from rczone.errors import ParameterError
from rczone.models import load_model
from rczone.virtual.building import build_building
from rczone.virtual.emulator import thermostat_configs

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


def test_the_event_is_in_the_forecast_only_from_its_announcement_at_11_am():
    def fc(now):  # the MPC's horizon: 37 values, 10 min apart
        return forecast_price("dr", now, now + 600.0 * np.arange(37))

    for day in (0, 1):
        d = day * 24 * H
        np.testing.assert_array_equal(fc(d + 17 * H - 600), np.ones(37))  # 10:50 am: not yet announced
        expected = np.ones(37)
        expected[18:30] = DR_PRICE  # 11 am: steps 18..29 (2 pm to 3:50 pm) are the event
        np.testing.assert_array_equal(fc(d + 17 * H), expected)
        np.testing.assert_array_equal(fc(d + 21 * H), np.r_[np.full(6, DR_PRICE), np.ones(31)])
    # the time-of-use price stays known in advance
    t = 6 * H + 600 * np.arange(37)
    np.testing.assert_array_equal(forecast_price("tou", 6 * H, t), price_signal("tou", t))


@pytest.fixture(scope="module")
def dr_runs(zm):
    kw = {"days": 1, "seed": 4}
    return (
        closed_loop_test(VirtualPlant("summer", **kw), "naive"),
        closed_loop_test(VirtualPlant("summer", **kw, price="dr"), "naive"),
    )


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

    kw = {"days": 0.5, "seed": 4}
    normal = closed_loop_test(VirtualPlant("summer", **kw), "naive")
    tight = closed_loop_test(VirtualPlant("summer", **kw, comfort_band="tight"), "naive")
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


def test_an_unknown_band_is_a_one_line_error():
    with pytest.raises(ParameterError, match="wide"):
        VirtualPlant("summer", comfort_band="wide")
