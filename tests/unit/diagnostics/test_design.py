import numpy as np
import pandas as pd
import pytest

from rczone.diagnostics.design import DesignLimits, design_test, schedule_fisher
from rczone.errors import ParameterError
from rczone.models import get_model
from rczone.simulation import simulate, steady_state

CONDITIONS = {"To": 18.0, "Tsd": 22.0, "Q": 50.0}


@pytest.fixture(scope="module")
def design():
    net = get_model("second-order-paper")
    limits = DesignLimits(band=(18.0, 27.0), min_hold_s=3600.0, ts_levels=3, m_levels=2)
    return net, design_test(
        net, ["Cr", "Rw"], duration_s=6 * 3600, limits=limits, conditions=CONDITIONS, max_sweeps=2
    )


def test_designed_schedule_respects_limits_and_band(design):
    net, res = design
    sch = res.schedule
    assert sch["Ts"].between(12.0, 35.0).all() and sch["m"].between(0.02, 0.12).all()
    assert ((sch["end_s"] - sch["start_s"]) >= 3600.0 - 1e-9).all()
    assert res.within_band
    # independent check of the band: simulate the played samples with the prior model
    s = res.samples(60.0)
    u = np.column_stack([np.full(len(s), 18.0), np.full(len(s), 22.0), s["Ts"], np.full(len(s), 50.0)])
    ss = net.state_space()
    x0 = steady_state(ss, u[0], s["m"].iloc[0])
    x0 += 22.5 - x0[0]  # the design starts mid-band with the walls in equilibrium
    ti = simulate(ss, s["time"].to_numpy(), u, s[["m"]].to_numpy(), x0=x0).y[:, 0]
    assert 18.0 <= ti.min() and ti.max() <= 27.0


def test_design_beats_a_constant_schedule(design):
    net, res = design
    t = np.arange(0, 6 * 3600 + 1, 60.0)
    u = np.column_stack(
        [np.full(t.size, 18.0), np.full(t.size, 22.0), np.full(t.size, 20.0), np.full(t.size, 50.0)]
    )
    ld_const, se_const = schedule_fisher(
        net, ["Cr", "Rw"], t, u, np.full((t.size, 1), 0.12), np.array([22.5, 22.5])
    )
    assert res.log_det > ld_const + 2.0
    assert all(res.expected_se[k] < se_const[k] for k in ("Cr", "Rw"))


def test_schedule_csv_is_playable(design, tmp_path):
    _, res = design
    res.to_csv(str(tmp_path / "s.csv"), start=pd.Timestamp("2026-10-24 18:00", tz="America/New_York"))
    df = pd.read_csv(tmp_path / "s.csv")
    assert list(df.columns) == ["time_s", "clock", "Ts_setpoint_degC", "m_setpoint_kg_s"]
    assert df["time_s"].iloc[0] == 0 and df["clock"].iloc[0].startswith("2026-10-24T18:00:00-04:00")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (
            {"limits": DesignLimits(band=(10.0, 10.5), min_hold_s=3600.0)},
            r"no schedule keeps the room inside",
        ),
        ({"free": ["Rq"]}, r"unknown free parameter 'Rq'"),
        ({"conditions": {"Tso": 1.0}}, r"unknown input 'Tso'"),
    ],
)
def test_bad_design_requests(kwargs, match):
    args = {"free": ["Rw"], "duration_s": 7200.0, "limits": DesignLimits(min_hold_s=3600.0), **kwargs}
    with pytest.raises(ParameterError, match=match):
        design_test(get_model("second-order-paper"), **args)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"band": (25.0, 20.0)}, "band must be"),
        ({"m_range": (-0.1, 0.1)}, ">= 0"),
        ({"min_hold_s": 0}, "min_hold_s"),
    ],
)
def test_bad_limits(kw, match):
    with pytest.raises(ParameterError, match=match):
        DesignLimits(**kw)
