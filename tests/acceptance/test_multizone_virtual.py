"""Issue 12 (part 4): a multi-zone forced test of the virtual building, fitted jointly from the CLI.

The target and its side neighbour n1 follow independent forced-response schedules
(:func:`rczone.virtual.multizone.generate_multizone_night`); the joint model
``validation/models/virtual_two_zones.toml`` (starts from the nominal construction) is fitted by
``rczone fit`` with default settings and must recover, within 15 %, the truths that
:mod:`tests.acceptance.multizone_truth` reads off the true 152-state network before any fit.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rczone.construction import office_241
from rczone.construction.materials import ashrae_construction
from rczone.construction.room import AIR_CP, AIR_DENSITY
from rczone.errors import ParameterError
from rczone.models import load_model
from rczone.virtual.building import build_building, true_geometry
from rczone.virtual.multizone import column_names, generate_multizone_night
from rczone.virtual.scenarios import FORCED_LEVELS
from tests.acceptance.multizone_truth import (
    LIGHT_TAU,
    MATCH_PERIODS,
    RATIO,
    RMF_T,
    hour_scale_masses,
    hour_scale_partition_capacity,
    model_storage_admittance,
    partition_admittance_ratio,
    storage_admittance,
    true_values,
)

MODEL = Path(__file__).resolve().parents[2] / "validation" / "models" / "virtual_two_zones.toml"
SEED = 1
#: Parameters whose recovery within 15 % is claimed (see docs/multizone.md).
TOLERANCE = 0.15


def _values() -> dict[str, float]:
    zm = load_model(MODEL)
    return zm.network.values(zm.theta)


@pytest.fixture(scope="session")
def night() -> pd.DataFrame:
    return generate_multizone_night("autumn", SEED)


# ---- the scenario --------------------------------------------------------------------------------


def test_columns_and_metadata(night):
    assert list(night.columns) == [
        "time", "Ti", "Tn1", "Tn2", "Thw", "Tf", "Tc", "To", "Ts", "m", "Q", "Ts_n1", "m_n1", "Q_n1"
    ]  # fmt: skip
    assert len(night) == 720 and night["time"].iloc[-1] == 43140.0
    assert night.attrs["excited"] == ["target", "n1"]
    assert set(night.attrs["forced_schedules"]) == {"target", "n1"}
    assert night["Q"].eq(50.0).all() and night["Q_n1"].eq(50.0).all()


@pytest.mark.parametrize("zone", ["target", "n1"])
def test_forced_zones_follow_their_schedules(night, zone):
    ts_col, m_col, _ = column_names(zone)
    t = night["time"].to_numpy()
    sched = night.attrs["forced_schedules"][zone]
    ends = [s for s, _, _ in sched[1:]] + [t[-1] + 60.0]
    for (start, m, reheat), end in zip(sched, ends, strict=True):
        block = (t >= start) & (t < end)
        # the flow is the command within the sensor's noise and quantization
        assert np.abs(night.loc[block, m_col] - m).max() < 0.01
        settled = (t >= start + 900.0) & (t < end)  # after the reheat coil's 3-min lag
        level = night.loc[settled, ts_col]
        if not settled.any():
            continue
        if reheat > 0:
            assert level.min() > 30.0  # full reheat: ~13 degC AHU air + 22 K
        else:
            assert level.max() < 16.0  # AHU supply air (13 degC + drift)
    assert {(m, r) for _, m, r in sched} == set(FORCED_LEVELS.values())


def test_excitations_are_independent_and_the_others_stay_controlled(night):
    # the two zones' supply heat flows are far from collinear (the point of the test)
    q_t = night["m"] * (night["Ts"] - night["Ti"])
    q_n = night["m_n1"] * (night["Ts_n1"] - night["Tn1"])
    assert abs(np.corrcoef(q_t, q_n)[0, 1]) < 0.5
    assert abs(np.corrcoef(night["Ti"], night["Tn1"])[0, 1]) < 0.8
    # both forced rooms swing by several K; the thermostat-controlled ones do not
    for col in ("Ti", "Tn1"):
        assert night[col].max() - night[col].min() > 3.0
    for col in ("Tn2", "Thw", "Tf", "Tc"):
        assert night[col].max() - night[col].min() < 1.5


def test_deterministic_per_seed():
    kw = {"warmup": 0.0, "duration": 2 * 3600.0}
    a = generate_multizone_night("autumn", 7, ("target", "n2", "c"), **kw)
    pd.testing.assert_frame_equal(a, generate_multizone_night("autumn", 7, ("c", "target", "n2"), **kw))
    b = generate_multizone_night("autumn", 8, ("target", "n2", "c"), **kw)
    assert not np.array_equal(a["Ti"], b["Ti"])
    assert {"Ts_n2", "m_n2", "Q_n2", "Ts_c", "m_c", "Q_c"} <= set(a.columns) and "Ts_n1" not in a


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"excited": ()}, "non-empty"),
        ({"excited": ("target", "n3")}, "did you mean"),
        ({"excited": ("n1", "n1")}, "twice"),
        ({"warmup": 30.0}, "multiple of 60 s"),
        ({"duration": 0.0}, "multiple of 60 s"),
        ({"season": "spring"}, "season"),
    ],
)
def test_bad_arguments(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        generate_multizone_night(**kwargs)


# ---- the model file and the truth ------------------------------------------------------------------


def test_model_file_starts_from_the_nominal_construction():
    """The starts are nominal construction values (office_241), computed here independently."""
    v = _values()
    g = office_241()
    part = ashrae_construction("Medium Partitions")
    n1 = g.surface("n1")
    assert v["Rp"] == pytest.approx(n1.resistance, rel=1e-3)
    assert v["Cp"] == pytest.approx(n1.capacity, rel=2e-3)
    assert v["Ca_t"] == v["Ca_n1"] == pytest.approx(g.air_capacity, rel=1e-3)
    film_half = part.film_in + part.layers[0].r / 2  # air to the first board's centre
    assert RATIO[0] == pytest.approx(film_half / part.r_total, rel=1e-3)
    assert v["Rp1"] + v["Rp2"] + v["Rp3"] == pytest.approx(v["Rp"])
    # window in parallel with the external wall (DC)
    assert v["Rwin_t"] == pytest.approx(
        1 / (1 / g.window.resistance + 1 / g.surface("o").resistance), rel=1e-3
    )
    furn = g.furnishing.c_total * g.furnishing_area
    board = part.layers[-1].c
    tile = ashrae_construction("Medium Roof/Ceiling").layers[-1].c
    assert v["Cl_t"] == pytest.approx(furn + 34 * board + 20 * tile, rel=2e-3)
    assert v["Cl_n1"] == pytest.approx(furn + 49 * board + 40 * tile, rel=2e-3)
    # light-mass resistance tied to its capacity by the nominal time constant (films + half layers)
    tile_layer = ashrae_construction("Medium Roof/Ceiling").layers[-1]
    half = {"board": part.film_in + part.layers[-1].r / 2, "tile": part.film_in + tile_layer.r / 2}
    g_furn = 2 * g.furnishing_area / (part.film_in + g.furnishing.r_layers / 2)
    g_t = g_furn + 34 / half["board"] + 20 / half["tile"]
    g_n1 = g_furn + 49 / half["board"] + 40 / half["tile"]
    assert v["Rl_t"] * v["Cl_t"] == pytest.approx(v["Cl_t"] / g_t, rel=2e-3)
    assert v["Rl_n1"] * v["Cl_n1"] == pytest.approx(v["Cl_n1"] / g_n1, rel=2e-3)
    # the truth module's copy of the model's ties (its admittance match uses them)
    assert v["Rl_t"] * v["Cl_t"] == pytest.approx(LIGHT_TAU["t"])
    assert v["Rl_n1"] * v["Cl_n1"] == pytest.approx(LIGHT_TAU["n1"])
    assert v["Rmf_t"] == pytest.approx(RMF_T)
    assert g.air_capacity == pytest.approx(60 * AIR_DENSITY * AIR_CP)


def test_truth_is_the_true_construction():
    """The network-read truths agree with the true geometry (two independent paths)."""
    t = true_values()
    s = true_geometry().surface("n1")
    assert t["Rp"] == pytest.approx(s.resistance, rel=1e-9)
    assert t["Cp"] == pytest.approx(s.capacity, rel=1e-9)
    assert t["Ca_t"] == pytest.approx(true_geometry().air_capacity)
    # the light mass holds the target's true furniture (20 m2, not the nominal 15 m2)
    g = true_geometry()
    assert t["Cl_t"] > g.furnishing.c_total * g.furnishing_area
    # truth differs from the nominal starts, so a recovered value is not the start handed back
    v = _values()
    assert abs(v["Cl_t"] / t["Cl_t"] - 1) > 0.05 and abs(v["Rp"] / t["Rp"] - 1) > 0.02


def test_partition_truth_at_the_forced_periods():
    """With the construction Cp the element passes 10-21 % too little heat at 1-4 h; the hour-scale Cp fixes that."""
    periods = (3600.0, 7200.0, 14400.0)
    t = true_values()
    raw = partition_admittance_ratio(t["Cp"], periods)["transfer"]
    assert np.all((raw > 0.75) & (raw < 0.92))
    cp = hour_scale_partition_capacity()
    assert 0.8 < cp / t["Cp"] < 0.95
    matched = partition_admittance_ratio(cp, periods)["transfer"]
    np.testing.assert_allclose(matched, 1.0, atol=0.02)  # the whole 1-4 h band, not just 2 h
    # at DC the element is exact whatever Cp: its resistance is the true one
    dc = partition_admittance_ratio(cp, (1e9,))
    np.testing.assert_allclose([dc["room"][0], dc["transfer"][0]], 1.0, atol=1e-4)


def test_storage_admittance_of_the_zones():
    """The nodal analysis against closed forms; the model's dead-end branches match it over 1-4 h."""
    # the DC conduction is taken out: at a period of years only the pure storage j w C is left
    for z in ("t", "n1"):
        y = storage_admittance(z, (3e8,))[0]
        assert abs(y.real) < 1e-3 and 0 < y.imag < 2 * np.pi / 3e8 * 3e7
    # one node (the furniture) alone: the closed form 1/(R + 1/(j w C))
    net = build_building().network
    c = next(n.capacity for n in net.nodes if n.name == "target_furn")
    r = next(x.resistance for x in net.resistors if "target_furn" in (x.a, x.b))
    w = 2 * np.pi / 7200.0
    furn = 1.0 / (r + 1.0 / (1j * w * c))
    ladders = storage_admittance("t", (7200.0,))[0] - furn
    assert ladders.real > 0 and ladders.imag > 0  # the walls add conductance and storage
    t = true_values()
    for z in ("t", "n1"):
        h = hour_scale_masses(z)
        assert h["max_error"] < 0.05
        # the light layers are only partly reached at hour periods: below the construction sum
        assert 0.7 < h["Cl"] / t[f"Cl_{z}"] < 0.95
        fit = model_storage_admittance(z, h["Cl"], h["Rm"], h["Cm"], MATCH_PERIODS)
        np.testing.assert_allclose(fit, storage_admittance(z), rtol=0.05)
    # the target's slab is a sink without end at these periods: its capacity is not defined
    assert hour_scale_masses("t")["Cm"] > 100 * t["Cm_t"]


def claimed_truth() -> dict[str, float]:
    """The truths recovery within 15 % is claimed against (all computed without data)."""
    t = true_values()
    return {
        "Rp": t["Rp"],
        "Ca_t": t["Ca_t"],
        "Ca_n1": t["Ca_n1"],
        "Cl_t": hour_scale_masses("t")["Cl"],
        "Cl_n1": hour_scale_masses("n1")["Cl"],
    }


# ---- the joint fit from the CLI ------------------------------------------------------------------


@pytest.mark.slow
def test_cli_joint_fit_recovers_the_truth(night, tmp_path):
    from rczone.cli.main import main

    data, out = tmp_path / "night.csv", tmp_path / "fit.json"
    night.to_csv(data, index=False)
    rc = main(["fit", str(data), "--model", str(MODEL), "--json", str(out), "--no-profiles"])
    res = json.loads(out.read_text())
    assert rc == 0, rc  # a trustworthy fit: no estimate at a bound, starts agree
    est = {k: v["estimate"] for k, v in res["parameters"].items()}
    truth = claimed_truth()
    ratios = {k: est[k] / v for k, v in truth.items()}
    assert all(abs(r - 1) <= TOLERANCE for r in ratios.values()), ratios
    # the partition's capacity: one night pins it to ~15 % (its standard error), so it is checked
    # against the hour-scale truth within its own uncertainty, not claimed within 15 %
    cp = res["parameters"]["Cp"]
    assert abs(cp["estimate"] - hour_scale_partition_capacity()) < 2.5 * cp["std_error"]
    assert 0.08 < cp["std_error"] / cp["estimate"] < 0.25
