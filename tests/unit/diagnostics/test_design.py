import dataclasses
import datetime

import numpy as np
import pandas as pd
import pytest

from rczone.diagnostics.design import DesignLimits, design_test, from_si, schedule_fisher
from rczone.errors import ParameterError
from rczone.models import get_model
from rczone.simulation import simulate, steady_state
from tests.unit.diagnostics.synthetic import family

CONDITIONS = {"To": 18.0, "Tsd": 22.0}  # Q: the paper model's default, 50 W
AIR = {"Ts": (12.0, 35.0), "m": (0.02, 0.12)}


@pytest.fixture(scope="module")
def design():
    net = get_model("second-order-paper")
    limits = DesignLimits(AIR, band=(18.0, 27.0), min_hold_s=3600.0, levels={"Ts": 3, "m": 2})
    return net, design_test(
        "second-order-paper",
        ["Cr", "Rw"],
        duration_s=6 * 3600,
        limits=limits,
        conditions=CONDITIONS,
        max_sweeps=2,
    )


def _start_state(ss, u0, m0, ti0):
    """The design's start: the zone at ti0, the wall in equilibrium with it and the first inputs."""
    A, B = ss.matrices(m0)
    x = np.array([ti0, 0.0])
    x[1] = -(A[1, 0] * ti0 + B[1] @ u0) / A[1, 1]
    return x


def test_designed_schedule_respects_limits_and_band(design):
    net, res = design
    sch = res.schedule
    assert list(sch.columns) == ["start_s", "end_s", "Ts", "m"]
    assert sch["Ts"].between(12.0, 35.0).all() and sch["m"].between(0.02, 0.12).all()
    assert ((sch["end_s"] - sch["start_s"]) >= 3600.0 - 1e-9).all()
    assert res.within_band and res.output == "Ti"
    # independent check of the band: simulate the played samples with the prior model
    s = res.samples(60.0)
    u = np.column_stack([np.full(len(s), 18.0), np.full(len(s), 22.0), s["Ts"], np.full(len(s), 50.0)])
    ss = net.state_space()
    x0 = _start_state(ss, u[0], s["m"].iloc[0], 22.5)
    ti = simulate(ss, s["time"].to_numpy(), u, s[["m"]].to_numpy(), x0=x0).y[:, 0]
    np.testing.assert_allclose(ti, res.predicted, atol=1e-9)
    assert 18.0 <= ti.min() and ti.max() <= 27.0


def test_design_beats_a_constant_schedule(design):
    net, res = design
    t = np.arange(0, 6 * 3600 + 1, 60.0)
    u = np.column_stack(
        [np.full(t.size, 18.0), np.full(t.size, 22.0), np.full(t.size, 20.0), np.full(t.size, 50.0)]
    )
    m = np.full((t.size, 1), 0.12)
    x0 = _start_state(net.state_space(), u[0], 0.12, 22.5)
    ld_const, se_const = schedule_fisher(net, ["Cr", "Rw"], t, u, m, x0, heat_offsets=["Q"])
    assert res.log_det > ld_const + 2.0
    assert all(res.expected_se[k] < se_const[k] for k in ("Cr", "Rw"))
    # the design's own criterion, recomputed on its schedule, is what it reports
    s = res.samples(60.0)
    u_d = np.column_stack([np.full(len(s), 18.0), np.full(len(s), 22.0), s["Ts"], np.full(len(s), 50.0)])
    x0_d = _start_state(net.state_space(), u_d[0], s["m"].iloc[0], 22.5)
    ld, se = schedule_fisher(
        net, ["Cr", "Rw"], s["time"].to_numpy(), u_d, s[["m"]].to_numpy(), x0_d, heat_offsets=["Q"]
    )
    assert ld == pytest.approx(res.log_det, rel=1e-9) and se == pytest.approx(res.expected_se, rel=1e-9)


def test_schedule_table_clock_times_and_units(design, tmp_path):
    _, res = design
    res.to_csv(tmp_path / "s.csv", start=pd.Timestamp("2026-10-24 18:00", tz="America/New_York"))
    df = pd.read_csv(tmp_path / "s.csv")
    assert list(df.columns) == ["time_s", "clock", "Ts_setpoint_degC", "m_setpoint_kg_s"]
    assert df["time_s"].iloc[0] == 0 and df["clock"].iloc[0].startswith("2026-10-24T18:00:00-04:00")
    night = res.table(datetime.time(22, 30), {"Ts": "degF", "m": "cfm"})
    assert list(night.columns) == ["time_s", "day", "clock", "Ts_setpoint_degF", "m_setpoint_cfm"]
    assert night["clock"].iloc[0] == "22:30"
    for _, row in night.iterrows():
        k = res.schedule["start_s"].searchsorted(row["time_s"])
        minutes = 22 * 60 + 30 + row["time_s"] / 60
        assert (
            row["day"] == minutes // 1440
            and row["clock"] == f"{int(minutes // 60) % 24:02d}:{int(minutes % 60):02d}"
        )
        assert row["Ts_setpoint_degF"] == pytest.approx(res.schedule["Ts"].iloc[k] * 9 / 5 + 32, rel=1e-5)
        # cfm: kg/s over the density 1.2 kg/m3, in cubic feet (0.3048 m) per minute
        assert row["m_setpoint_cfm"] == pytest.approx(
            res.schedule["m"].iloc[k] / 1.2 / 0.3048**3 * 60, rel=1e-5
        )


@pytest.mark.parametrize(
    ("unit", "quantity", "si"),
    [
        ("degF", "temperature", 20.0),
        ("K", "temperature", 20.0),
        ("kW", "power", 1500.0),
        ("L/s", "flow", 0.06),
    ],
)
def test_from_si_inverts_to_si(unit, quantity, si):
    from rczone.data.units import to_si

    assert to_si(from_si(np.array([si]), unit, quantity), unit, quantity)[0] == pytest.approx(si)


def test_a_heated_zone_gets_a_prbs_like_power_schedule():
    zm = family("TiTe+heater")
    limits = DesignLimits({"Ph": (0.0, 2000.0)}, band=(15.0, 30.0), min_hold_s=3600.0)
    res = design_test(zm, ["Ci", "Ce", "Rie", "Rea"], 24 * 3600, limits, conditions={"To": 5.0}, ti0=20.0)
    assert list(res.schedule.columns) == ["start_s", "end_s", "Ph"] and res.quantities == {"Ph": "power"}
    ph = res.schedule["Ph"].to_numpy()
    assert np.all(np.isin(ph, np.linspace(0, 2000, 5))) and {0.0, 2000.0} <= set(ph) and len(ph) >= 4
    # independent check: play the schedule on the model from the stated start
    s = res.samples(60.0)
    u = np.column_stack([np.full(len(s), 5.0), s["Ph"]])
    ss = zm.state_space()
    A, B = ss.matrices(0.0)
    te0 = -(A[1, 0] * 20.0 + B[1] @ u[0]) / A[1, 1]
    ti = simulate(ss, s["time"].to_numpy(), u, None, x0=np.array([20.0, te0])).y[:, 0]
    np.testing.assert_allclose(ti, res.predicted, atol=1e-9)
    assert 15.0 <= ti.min() and ti.max() <= 30.0 and res.within_band
    assert all(v < 0.1 for v in res.expected_se.values())


def test_every_output_counts_in_the_design():
    both = family("TiTe+heater", ("Ti", "Te"))
    limits = DesignLimits({"Ph": (0.0, 2000.0)}, band=(15.0, 30.0), min_hold_s=3 * 3600.0)
    one = design_test(
        family("TiTe+heater"), ["Ci", "Ce", "Rie", "Rea"], 24 * 3600, limits, conditions={"To": 5.0}
    )
    two = design_test(both, ["Ci", "Ce", "Rie", "Rea"], 24 * 3600, limits, conditions={"To": 5.0})
    assert two.log_det > one.log_det


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (
            {"limits": DesignLimits(AIR, band=(10.0, 10.5), min_hold_s=3600.0)},
            r"cannot stay inside the band 10..10.5 degC: with Ts 12..35 degC, m 0.02..0.12 kg/s and To 18"
            r" degC, Tsd 22 degC, Q 50 W its steady temperature is .* entirely above it",
        ),
        ({"ti0": 30.0}, r"starts at 30 degC, outside the band 17..28"),
        ({"free": ["Rq"]}, r"unknown free parameter 'Rq'"),
        ({"free": ["R1"]}, r"'R1' is tied"),
        ({"conditions": {**CONDITIONS, "Tso": 1.0}}, r"unknown input 'Tso'"),
        ({"conditions": {"To": 18.0}}, r"conditions lack Tsd"),
        ({"conditions": {**CONDITIONS, "Ts": 20.0}}, r"'Ts' is driven by the test"),
        (
            {"limits": DesignLimits({"To": (10.0, 20.0)}, min_hold_s=3600.0)},
            r"'To' is a boundary temperature",
        ),
        ({"limits": DesignLimits({"Tz": (10.0, 20.0)}, min_hold_s=3600.0)}, r"unknown input 'Tz' to drive"),
        ({"limits": DesignLimits({"m": (-0.1, 0.1)}, min_hold_s=3600.0)}, r"flow 'm' must be >= 0"),
        ({"limits": None}, r"needs limits"),
        ({"duration_s": 600.0}, r"at least one minimum hold"),
    ],
)
def test_bad_design_requests(kwargs, match):
    args = {
        "free": ["Rw"],
        "duration_s": 7200.0,
        "limits": DesignLimits(AIR, min_hold_s=3600.0),
        "conditions": CONDITIONS,
        **kwargs,
    }
    with pytest.raises(ParameterError, match=match):
        design_test("second-order-paper", **args)


def test_a_parameter_the_test_cannot_see_is_named():
    zm = family("TiTe+heater+solar")  # at night (Ps = 0) the solar aperture Aw shows nowhere
    limits = DesignLimits({"Ph": (0.0, 2000.0)}, band=(15.0, 30.0), min_hold_s=3 * 3600.0)
    with pytest.raises(ParameterError, match=r"Aw do\(es\) not affect the outputs"):
        design_test(zm, ["Ci", "Rie", "Aw"], 12 * 3600, limits, conditions={"To": 5.0, "Ps": 0.0})


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"band": (25.0, 20.0)}, "band must be"),
        ({"ranges": {"Ts": (30.0, 30.0)}}, "Ts must be"),
        ({"ranges": {"Ts": (10.0, float("inf"))}}, "Ts must be"),
        ({"ranges": {}}, "at least one input"),
        ({"min_hold_s": 0}, "min_hold_s"),
        ({"levels": {"Ts": 1}}, "integer >= 2"),
        ({"levels": {"Tq": 3}}, "has no range"),
    ],
)
def test_bad_limits(kw, match):
    with pytest.raises(ParameterError, match=match):
        DesignLimits(**{"ranges": AIR, **kw})


def test_steady_state_check_is_exact_for_a_first_order_zone():
    """Ti alone: steady temperature (To/Ria + Ph) * Ria; a band just above the largest is infeasible."""
    zm = family("Ti+heater")
    ria = zm.theta["Ria"]
    top = 5.0 + 1000.0 * ria
    with pytest.raises(ParameterError, match=rf"steady temperature is 5.0..{top:.1f} degC, entirely below"):
        design_test(
            zm,
            ["Ci"],
            7200.0,
            DesignLimits({"Ph": (0.0, 1000.0)}, band=(top + 0.1, top + 5), min_hold_s=3600.0),
            conditions={"To": 5.0},
        )
    assert steady_state(zm.state_space(), np.array([5.0, 1000.0]), 0.0)[0] == pytest.approx(top)


def test_a_design_prints_and_serializes_as_the_command(tmp_path, capsys, monkeypatch):
    """The schedule the command prints and writes is the result's summary() and to_dict()."""
    import json

    from rczone.cli.main import main
    from rczone.files.atomic import _jsonable

    monkeypatch.setenv("COLUMNS", "100")
    args = ["design", "--actuate", "Ts=13,35", "--actuate", "m=0.02,0.12", "--condition", "To=16"]
    args += [
        "--condition",
        "Tsd=22",
        "--hours",
        "2",
        "-o",
        str(tmp_path / "s.csv"),
        "--json",
        str(tmp_path / "d.json"),
    ]
    assert main(args) == 0
    printed = capsys.readouterr().out
    written = json.loads((tmp_path / "d.json").read_text())
    limits = DesignLimits(
        {"Ts": (13.0, 35.0), "m": (0.02, 0.12)}, (17.0, 28.0), 30 * 60.0
    )  # the CLI defaults
    res = design_test(
        "second-order-paper", ["Cr", "Rw"], 2 * 3600.0, limits, conditions={"To": 16.0, "Tsd": 22.0}
    )
    res = dataclasses.replace(
        res,
        model_label="second-order-paper",
        start=datetime.time(18, 0),  # the command's default start
        display_units={"Ts": "degC", "m": "kg/s", "Ti": "degC"},
    )
    assert json.loads(json.dumps(_jsonable(res.to_dict()))) == written
    assert printed == res.summary(width=100) + f"schedule written to {tmp_path / 's.csv'}\n"
    assert "commands of Ts, m" in repr(res) and len(repr(res)) < 200


def test_the_design_reports_whether_it_drives_its_inputs_apart(design):
    _, res = design
    exc = res.excitation
    s = res.samples()
    varying = [a for a in res.actuated if s[a].std() > 1e-9]  # a constant column's std is rounding
    assert exc.inputs == tuple(varying)
    if len(varying) == 2:  # the statistic is numpy's correlation of the played samples
        r = np.corrcoef(s[varying[0]], s[varying[1]])[0, 1]
        assert exc.correlation[0, 1] == pytest.approx(r, abs=1e-12)
        assert exc.collinear == (abs(r) >= 0.95)
    assert res.to_dict()["excitation"]["inputs"] == list(varying)


def test_an_information_with_two_negative_eigenvalues_scores_no_design(monkeypatch):
    """Its determinant is positive, but it is no information: -inf, and no negative variances."""
    import rczone.diagnostics.design as design

    indefinite = np.diag([4.0, -1.0, -2.0])  # det 8 > 0
    monkeypatch.setattr(design, "marginal_fisher", lambda S, nuis, w: indefinite)
    ld, cov = design._fisher_logdet(None, None, 1.0)
    assert ld == -np.inf and np.all(cov == np.inf)
    good = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]])
    monkeypatch.setattr(design, "marginal_fisher", lambda S, nuis, w: good)
    ld, cov = design._fisher_logdet(None, None, 1.0)
    assert ld == pytest.approx(np.log(np.linalg.det(good))) and np.allclose(cov, np.linalg.inv(good))
