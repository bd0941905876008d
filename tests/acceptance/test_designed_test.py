"""Issue 5 acceptance: a designed forced-response test, played in the virtual building, then fitted.

It must keep the room inside its band and give smaller standard errors for Cr and Rw than the
scenario-C style forced test of the same length on the same night (paired seeds). Also checks the
playback itself: absolute supply-temperature commands are followed, and the relative-reheat
commands reproduce :func:`generate_night` exactly.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rczone.errors import DataError, ParameterError
from rczone.virtual.emulator import Command
from rczone.virtual.playback import play_schedule, schedule_commands
from rczone.virtual.scenarios import COLUMNS, forced_schedule, generate_night
from tests.acceptance.designed import FREE, LIMITS, designed, paired

FAST_SEEDS = (300, 301, 302)
SLOW_SEEDS = tuple(range(300, 310))


def test_design_respects_the_limits():
    res = designed()
    s = res.schedule
    assert res.within_band
    assert s["start_s"].iloc[0] == 0.0 and s["end_s"].iloc[-1] == pytest.approx(12 * 3600.0)
    assert (s["end_s"] - s["start_s"]).min() >= LIMITS.min_hold_s
    assert s["Ts"].between(*LIMITS.ranges["Ts"]).all() and s["m"].between(*LIMITS.ranges["m"]).all()
    assert LIMITS.band[0] <= res.predicted.min() and res.predicted.max() <= LIMITS.band[1]


# ---- playback ------------------------------------------------------------------------------------


def test_relative_commands_reproduce_generate_night():
    """The seeded schedule passed explicitly gives the very same night (same RNG streams)."""
    seed = 5
    g_sched = np.random.default_rng(seed).spawn(3)[2]
    again = generate_night("autumn", "forced", seed, warmup=3600.0, commands=forced_schedule(g_sched))
    pd.testing.assert_frame_equal(again, generate_night("autumn", "forced", seed, warmup=3600.0))


def test_playback_follows_absolute_supply_temperature():
    sched = pd.DataFrame(
        {"start_s": [0.0, 4 * 3600.0, 8 * 3600.0], "Ts": [30.0, 10.0, 24.0], "m": [0.1, 0.05, 0.12]}
    )
    df = play_schedule(sched, "autumn", seed=3, warmup=3600.0)
    ref = generate_night("autumn", "forced", 3, warmup=3600.0)
    assert list(df.columns) == list(COLUMNS) and df.shape == ref.shape
    np.testing.assert_array_equal(df["time"], ref["time"])
    t = df["time"].to_numpy()
    # after the coil's 3-min lag has settled (20 min in), Ts is the command within sensor noise
    settled = lambda a, b: (t >= a + 1200) & (t < b)  # noqa: E731
    assert np.abs(df.loc[settled(0, 4 * 3600), "Ts"] - 30.0).max() < 0.3
    assert np.abs(df.loc[settled(8 * 3600, 12 * 3600), "Ts"] - 24.0).max() < 0.3
    # 10 degC is below the AHU supply (13 degC + drift): the coil cannot cool, Ts stays at the AHU value
    low = df.loc[settled(4 * 3600, 8 * 3600), "Ts"]
    assert low.min() > 11.5 and abs(low.mean() - 13.0) < 1.0
    assert np.abs(df.loc[settled(0, 4 * 3600), "m"] - 0.1).max() < 0.01
    assert np.abs(df.loc[settled(4 * 3600, 8 * 3600), "m"] - 0.05).max() < 0.01
    # weather and neighbours are those of the same seed
    np.testing.assert_array_equal(df["To"], ref["To"])


@pytest.mark.parametrize(
    ("schedule", "match"),
    [
        (pd.DataFrame({"start_s": [0.0], "Ts": [20.0]}), "lacks column"),
        (pd.DataFrame({"start_s": [], "Ts": [], "m": []}), "empty"),
        (pd.DataFrame({"start_s": [60.0], "Ts": [20.0], "m": [0.1]}), "begin at 0 s"),
        (pd.DataFrame({"start_s": [0.0, 0.0], "Ts": [20.0, 21.0], "m": [0.1, 0.1]}), "increase strictly"),
        (pd.DataFrame({"start_s": [0.0, 50000.0], "Ts": [20.0, 21.0], "m": [0.1, 0.1]}), "after the"),
        (pd.DataFrame({"start_s": [0.0], "Ts": [np.nan], "m": [0.1]}), "non-finite"),
        (pd.DataFrame({"start_s": [0.0], "Ts": [20.0], "m": [-0.1]}), ">= 0 kg/s"),
    ],
)
def test_bad_schedules(schedule, match):
    with pytest.raises(DataError, match=match):
        schedule_commands(schedule)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: Command(0.0, -0.1), "m >= 0"),
        (lambda: Command(0.0, 0.1, reheat=-1.0), "reheat >= 0"),
        (lambda: Command(0.0, 0.1, ts=float("nan")), "finite"),
        (lambda: play_schedule({"start_s": [0.0]}), "pandas DataFrame"),
        (lambda: generate_night("autumn", "closed-loop", 0, commands=(Command(0.0, 0.1),)), "mode 'forced'"),
        (lambda: generate_night("autumn", "forced", 0, commands=()), "non-empty"),
    ],
)
def test_bad_commands(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def test_command_discharge_target():
    assert Command(0.0, 0.1, reheat=5.0).discharge_target(13.2) == pytest.approx(18.2)
    assert Command(0.0, 0.1, ts=30.0).discharge_target(13.2) == 30.0
    assert Command(0.0, 0.1, ts=12.0).discharge_target(13.2) == 13.2  # cannot cool below the AHU


# ---- designed vs scenario-C style ----------------------------------------------------------------


def _check_designed_beats_c_style(pairs) -> None:
    lo, hi = LIMITS.band
    for d, c in pairs:
        assert lo <= d.ti_min and d.ti_max <= hi, f"seed {d.seed}: room left its band"
        for k in FREE:
            # diagnose's Fisher prediction on the *played* data: the design's benefit survives playback
            assert d.predicted_se[k] < c.predicted_se[k], (k, d, c)
    for k in FREE:
        # fitted standard errors (ML, Kalman filter), averaged over the paired nights
        ml_d = np.mean([d.ml_se[k] for d, _ in pairs])
        ml_c = np.mean([c.ml_se[k] for _, c in pairs])
        assert ml_d < ml_c, f"{k}: ML standard error designed {ml_d:.3%} vs C-style {ml_c:.3%}"


@pytest.fixture(scope="module")
def fast_pairs():
    return [paired(s) for s in FAST_SEEDS]


def test_designed_test_beats_c_style(fast_pairs):
    _check_designed_beats_c_style(fast_pairs)


@pytest.mark.slow
def test_designed_test_beats_c_style_many_nights():
    pairs = [paired(s) for s in SLOW_SEEDS]
    _check_designed_beats_c_style(pairs)
    # and on most nights one by one
    for k in FREE:
        wins = sum(d.ml_se[k] < c.ml_se[k] for d, c in pairs)
        assert wins >= 0.6 * len(pairs), f"{k}: designed smaller ML se on {wins} of {len(pairs)} nights"
