"""Closed-loop tests on the virtual building: scores, bounds, comparability, and bad arguments."""

from dataclasses import replace

import numpy as np
import pytest

from rczone.control.closedloop import check_comparable, closed_loop_test
from rczone.control.constraints import ZoneConstraints
from rczone.control.energy import zone_power
from rczone.control.mpc import MPCSettings
from rczone.control.signals import PEAK_PRICE, price_signal
from rczone.control.virtualplant import VirtualPlant
from rczone.errors import ParameterError
from rczone.models import load_model

KEYS = {
    "comfort_Kh",
    "energy_kWh",
    "peak_flow_kg_s",
    "prediction_rmse_K",
    "solve_time_s",
    "constraint_violations",
}


@pytest.fixture(scope="module")
def zm():
    return load_model("second-order")


def test_a_short_mpc_run_respects_every_input_bound_and_reports_its_scores(zm):
    settings = MPCSettings(horizon=12, flow_min=0.03, flow_max=0.1, ts_max=32.0)
    r = closed_loop_test(VirtualPlant("winter", days=0.25, seed=2), "mpc", model=zm, settings=settings)
    assert KEYS <= set(r.scores) and set(r.to_dict()["setup"]) >= {"model", "scenario", "controller"}
    m, ts = r.series["m"], r.series["Ts"]
    assert np.all((m >= 0.03) & (m <= 0.1)) and np.all(ts <= 32.0)
    # the zone's ventilation minimum, a per-step bound, held at every minute of the run
    limits = ZoneConstraints(**r.setup["constraints"]["target"])
    occ = limits.occupied(r.t)
    assert occ.any() and (~occ).any()
    assert np.all(m >= limits.flow_min(r.t)) and r.scores["constraint_violations"] == 0
    assert m[occ].min() == pytest.approx(0.05, abs=1e-6)  # the bound was active
    assert r.scores["solve_time_s"]["max"] > 0
    # the energy score is the sum of the power series (zone_power at each minute)
    assert r.scores["energy_kWh"] == pytest.approx(r.series["power_W"].sum() * 60 / 3.6e6)
    assert "QP time" in r.summary()
    assert list(r.to_frame().columns)[:3] == ["Ti", "lower", "upper"] and len(r.to_frame()) == r.t.size


def test_the_comfort_score_integrates_the_distance_outside_the_occupied_band(zm):
    r = closed_loop_test(VirtualPlant("summer", days=0.5, seed=4), "naive", model=zm)
    s = r.series
    outside = np.clip(s["lower"] - s["Ti"], 0, None) + np.clip(s["Ti"] - s["upper"], 0, None)
    assert r.scores["comfort_Kh"] == pytest.approx((outside * s["occupied"]).sum() / 60.0)
    assert r.scores["solve_time_s"] is None
    assert set(np.unique(s["m"])) <= {0.02, 0.05, 0.08, 0.12}  # the thermostat's own levels
    p = zone_power(0.05, 20.0, 13.0, 23.0, 30.0)
    assert p.cooling == pytest.approx(0.05 * 1005.0 * 10.0) and p.reheat == pytest.approx(0.05 * 1005.0 * 7.0)


def test_runs_under_different_limits_or_days_cannot_be_compared(zm):
    a = closed_loop_test(VirtualPlant("summer", days=0.05, seed=4), "naive")
    b = closed_loop_test(VirtualPlant("summer", days=0.05, seed=4), "naive")
    check_comparable(a, b)
    low = {"target": {**a.setup["constraints"]["target"], "flow_min_occupied": 0.02}}
    cheat = replace(b, setup={**b.setup, "constraints": low, "controller": "mpc"})
    with pytest.raises(ParameterError, match="constraints differ"):
        check_comparable(a, cheat)
    with pytest.raises(ParameterError, match="seed"):
        check_comparable(a, replace(b, setup={**b.setup, "seed": 5}))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"season": "autumn"}, "autumn"),
        ({"days": 0}, "days"),
        ({"days": 1e-9}, "scored minute"),
        ({"days": 0.0001}, "scored minute"),
        ({"days": float("nan")}, "days"),
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
        ({"price": "hourly"}, "hourly"),
        ({"forecast": "psychic"}, "psychic"),
    ],
)
def test_bad_arguments_raise_one_line_errors(kwargs, match):
    season = kwargs.pop("season", "summer")
    with pytest.raises(ParameterError, match=match):
        VirtualPlant(season, **kwargs)


def test_an_unknown_controller_is_a_one_line_error_naming_the_close_ones(zm):
    with pytest.raises(ParameterError, match=r"'pid'.*mpc"):
        closed_loop_test(VirtualPlant("summer", days=0.05), "pid", model=zm)
    with pytest.raises(ParameterError, match="needs a model"):
        closed_loop_test(VirtualPlant("summer", days=0.05), "mpc")


def test_the_cost_weights_energy_by_the_price_signal(zm):
    flat = closed_loop_test(VirtualPlant("summer", days=1, seed=4), "naive")
    tou = closed_loop_test(VirtualPlant("summer", days=1, seed=4, price="tou"), "naive")
    assert flat.scores["cost"] == pytest.approx(flat.scores["energy_kWh"])
    assert tou.scores["energy_kWh"] == flat.scores["energy_kWh"]  # the thermostat ignores prices
    peak = price_signal("tou", tou.t) == PEAK_PRICE
    assert tou.scores["cost"] == pytest.approx(
        flat.scores["energy_kWh"] + (PEAK_PRICE - 1) * tou.series["power_W"][peak].sum() * 60 / 3.6e6
    )
    hours = np.array([17.0, 18.0, 23.99, 24.0]) * 3600.0  # 11 am, noon, 5:59 pm, 6 pm
    np.testing.assert_array_equal(price_signal("tou", hours), [1.0, PEAK_PRICE, PEAK_PRICE, 1.0])
