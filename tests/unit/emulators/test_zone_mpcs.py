"""Several zones under the supervisory MPC (``--zones``): one MPC per zone with its own model, the
set points of all zones at once, the models matched to the zones, each zone's prediction scored."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from rczone.cli.main import main
from rczone.control.closedloop import MeasurementLog, _prediction_scores
from rczone.emulators.control import models_by_zone
from rczone.emulators.supervisory import SupervisoryMPC, SupervisorySettings, ZoneMPCs
from rczone.errors import ParameterError
from rczone.models import load_model

DT = 900.0
H = 8


def _mpc(zone: str, model: str = "second-order", dt: float = DT) -> SupervisoryMPC:
    return SupervisoryMPC(load_model(model), zone=zone, dt=dt, settings=SupervisorySettings(horizon=H))


def _inputs(zones):
    t = DT * np.arange(H + 1)
    measurements = {"time": 0.0, "To": -5.0}
    forecast = {"time": t, "To": np.full(H + 1, -5.0), "price": np.ones(H + 1)}
    for i, z in enumerate(zones):
        measurements |= {
            f"Ti_{z}": 19.0 + i,
            f"Tsd_{z}": 20.0,
            f"Q_{z}": 300.0,
            f"m_{z}": 0.1,
            f"Ts_{z}": 25.0,
        }
        forecast |= {
            f"lower_{z}": np.full(H + 1, 21.0),
            f"upper_{z}": np.full(H + 1, 24.0),
            f"heating_min_{z}": np.full(H + 1, 18.0),
            f"heating_max_{z}": np.full(H + 1, 24.0),
            f"cooling_min_{z}": np.full(H + 1, 21.0),
            f"cooling_max_{z}": np.full(H + 1, 27.0),
        }
    return measurements, forecast


def test_each_zone_gets_what_its_own_mpc_would_give_it_alone():
    zones = ["a", "b"]
    measurements, forecast = _inputs(zones)
    together = ZoneMPCs([_mpc("a"), _mpc("b", "first-order")]).act(0.0, measurements, forecast)
    alone = {}
    for z, m in zip(zones, ["second-order", "first-order"], strict=True):
        alone |= _mpc(z, m).act(0.0, measurements, forecast)
    assert together == pytest.approx(alone) and set(together) == {
        "heating_a",
        "cooling_a",
        "heating_b",
        "cooling_b",
    }
    # below the band with room to heat: both plan heat, the cold zone (19 degC) a set point above 21
    assert together["heating_a"] > 21.0 and together["cooling_a"] - together["heating_a"] >= 0.5


def test_the_steps_solve_time_is_the_sum_of_the_zones():
    mpcs = ZoneMPCs([_mpc("a"), _mpc("b")])
    mpcs.act(0.0, *_inputs(["a", "b"]))
    a, b = (c.solve_times[-1] for c in mpcs.controllers)
    assert mpcs.solve_times == [pytest.approx(a + b)] and mpcs.zones == ["a", "b"]
    assert mpcs.interval == DT and mpcs.horizon == H * DT


@pytest.mark.parametrize(
    ("controllers", "match"),
    [([], "at least one zone"), (["a", "a"], "one MPC"), (["a", ("b", 1800.0)], "share the plant's step")],
)
def test_a_bad_set_of_zone_mpcs_is_refused(controllers, match):
    made = [_mpc(c) if isinstance(c, str) else _mpc(c[0], dt=c[1]) for c in controllers]
    with pytest.raises(ParameterError, match=match):
        ZoneMPCs(made)


def test_models_are_matched_to_the_controlled_zones():
    m = load_model("second-order")
    assert models_by_zone(m, ["a"]) == {"a": m} and models_by_zone(None, ["a", "b"]) is None
    assert list(models_by_zone({"b": m, "a": m}, ["a", "b"])) == ["a", "b"]
    with pytest.raises(ParameterError, match="need a model each"):
        models_by_zone(m, ["a", "b"])
    with pytest.raises(ParameterError, match=r"no model for \['b'\]"):
        models_by_zone({"a": m}, ["a", "b"])
    with pytest.raises(ParameterError, match=r"not controlled: \['c'\]"):
        models_by_zone({"a": m, "b": m, "c": m}, ["a", "b"])


class _Scored:
    """A plant whose prediction scores per zone are given."""

    def __init__(self, per):
        self.per = per

    def prediction_scores(self, values, t, model, *, zone, noise_floor):
        return self.per[zone]


def test_several_zones_are_scored_each_and_together_by_their_root_mean_square():
    log = MeasurementLog(np.zeros(1), {})
    m = load_model("second-order")
    per = {
        "a": {"prediction_rmse_K": 0.3, "open_loop_rmse_K": 1.0},
        "b": {"prediction_rmse_K": 0.4, "open_loop_rmse_K": None},
    }
    out = _prediction_scores(_Scored(per), log, {"a": m, "b": m}, 0.05)
    assert out["prediction_rmse_K_a"] == 0.3 and out["open_loop_rmse_K_b"] is None
    assert out["prediction_rmse_K"] == pytest.approx(math.sqrt((0.09 + 0.16) / 2))
    assert out["open_loop_rmse_K"] is None  # one zone has none: no total
    one = _prediction_scores(_Scored(per), log, {"a": m}, 0.05)
    assert one == per["a"]
    assert _prediction_scores(_Scored(per), log, {}, 0.05) == {"prediction_rmse_K": None}


@pytest.mark.parametrize(
    ("zones", "extra", "match"),
    [
        ("Perimeter_ZN_1=second-order,Perimeter_ZN_1=first-order", [], "names 'Perimeter_ZN_1' twice"),
        ("Perimeter_ZN_1=second-order,Perimeter_ZN_2", [], r"no model for \['Perimeter_ZN_2'\]"),
        ("Perimeter_ZN_1=", [], "takes ZONE=MODEL"),
        ("Perimeter_ZN_1,Perimeter_ZN_2", ["--zone", "Core_ZN"], "--zone or --zones"),
        ("Perimeter_ZN_1=no-such-model", [], "no-such-model"),
    ],
)
def test_bad_zones_are_one_line_and_exit_2_before_energyplus_starts(zones, extra, match, capsys):
    args = [
        "control-test",
        "--emulator",
        "energyplus",
        "--building",
        "office_small",
        "--zones",
        zones,
        *extra,
    ]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error:") and re.search(match, err)


def test_zones_are_refused_off_energyplus(capsys):
    assert main(["control-test", "--zones", "a=second-order,b=second-order"]) == 2
    assert "--zones is read by --emulator energyplus only" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--zones", "Core_ZN,Perimeter_ZN_1", "--model", "second-order"], "no output for zone 'Core_ZN'"),
        (["--zones", "Core_ZN=second-order,Perimeter_ZN_1", "--model", "first-order"], "or one joint model"),
    ],
)
def test_a_joint_model_that_does_not_name_the_zones_is_one_line(extra, match, capsys):
    pytest.importorskip("pyenergyplus")
    args = ["control-test", "--emulator", "energyplus", "--building", "office_small", "--days", "1"]
    assert main([*args, "--controller", "mpc", *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error:") and re.search(match, err), err
