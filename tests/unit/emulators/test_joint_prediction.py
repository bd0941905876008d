"""A joint floor model's prediction errors in the loop: without coupling between its zones they are
each zone's own model's (scored by the one-zone code, an observer of its own); with coupling every
zone's prediction feeds its neighbours'."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.emulators.prediction import KEYS, joint_prediction_scores, prediction_scores
from rczone.models import load_model

from .test_floor_mpc import VALUES, ZONES, _floor

DT = 900.0


def _log(n: int = 40, seed: int = 3) -> tuple[dict, np.ndarray]:
    """What the plant measured: two zones, their off-floor neighbours, supply air, metered heat."""
    rng = np.random.default_rng(seed)
    t = DT * np.arange(n)
    v = {"To": -4.0 + 3.0 * np.sin(t / 2e4), "Ti_na": 18.0 + 0.2 * rng.standard_normal(n)}
    v["Ti_nb"] = 21.0 + 0.2 * rng.standard_normal(n)
    for k, z in enumerate(ZONES):
        v[f"Ti_{z}"] = 20.0 + k + 0.5 * np.sin(t / 1e4 + k) + 0.05 * rng.standard_normal(n)
        v[f"Q_{z}"] = 200.0 + 100.0 * rng.random(n)
        v[f"m_{z}"] = 0.05 + 0.1 * rng.random(n)
        v[f"Ts_{z}"] = 24.0 + 4.0 * rng.random(n)
    v["Tsd_a"], v["Tsd_b"] = v["Ti_na"], v["Ti_nb"]  # the one-zone models' neighbour
    return v, t


def test_without_coupling_each_zone_scores_as_its_own_model():
    values, t = _log()
    joint = joint_prediction_scores(values, t, _floor(None))
    assert set(joint) == set(ZONES)
    for z in ZONES:
        alone = prediction_scores(values, t, load_model("second-order").with_values(VALUES[z]), zone=z)
        for k in KEYS:
            assert joint[z][k] == pytest.approx(alone[k], rel=1e-9), (z, k)
    # the joint model through the scorer the plant calls, zone by zone
    assert prediction_scores(values, t, _floor(None), zone="b") == joint["b"]


def test_coupled_zones_predict_together():
    values, t = _log()
    apart, together = (
        joint_prediction_scores(values, t, _floor(None)),
        joint_prediction_scores(values, t, _floor(0.002)),
    )
    for z in ZONES:  # the wall between the rooms changes every horizon's prediction of both
        assert all(abs(together[z][k] - apart[z][k]) > 1e-4 for k in KEYS[1:])


def test_a_log_without_the_models_zones_or_too_short_gives_nothing():
    values, t = _log()
    assert joint_prediction_scores({k: v for k, v in values.items() if k != "Ti_b"}, t, _floor(None)) == {}
    short = joint_prediction_scores({k: v[:6] for k, v in values.items()}, t[:6], _floor(None))
    assert short == {z: dict.fromkeys(KEYS) for z in ZONES}
    assert prediction_scores(values, t, _floor(None), zone="elsewhere") == dict.fromkeys(KEYS)
