"""A designed forced-response test, played in the virtual building, against the scenario-C style test.

Run ``python -m tests.acceptance.designed [n_seeds]`` from the repository root to print the
comparison table of ``docs/identifiability.md``.

The two tests of each pair share the seed, hence the weather, the neighbours' controllers, the AHU
drift and the sensor noise; they differ only in the target's supply-air commands: the D-optimal
schedule of :func:`rczone.diagnostics.design.design_test`, or the scenario generator's own forced
schedule (blocks of 60-150 min cycling cold / hot / minimum flow).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from functools import cache

import numpy as np
import pandas as pd

from rczone.calibration import calibrate
from rczone.diagnostics import diagnose
from rczone.diagnostics.design import DesignLimits, DesignResult, design_test
from rczone.models import get_model
from rczone.virtual.playback import play_schedule
from rczone.virtual.scenarios import NIGHT, generate_night

FREE = ("Cr", "Rw")
#: The limits of the issue: Ts 13-35 degC, m 0.01-0.12 kg/s, room 17-28 degC, holds >= 30 min.
LIMITS = DesignLimits({"Ts": (13.0, 35.0), "m": (0.01, 0.12)}, band=(17.0, 28.0), min_hold_s=1800.0)
#: Expected conditions of an autumn night of the virtual building (weather.DIURNAL: mean 16 degC;
#: neighbours under their thermostats near 22 degC; Q: the model's default, the paper's 50 W), and
#: the room at 6 pm.
CONDITIONS = {"To": 16.0, "Tsd": 22.0}
TI0 = 22.5


@cache
def designed() -> DesignResult:
    """The D-optimal 12 h schedule for Cr and Rw of the reduced model (cached: deterministic)."""
    return design_test("second-order-paper", list(FREE), NIGHT, LIMITS, conditions=CONDITIONS, ti0=TI0)


@dataclass(frozen=True)
class PlayedTest:
    """One played test: room range, diagnose's predicted and the fits' standard errors (relative)."""

    kind: str
    seed: int
    ti_min: float
    ti_max: float
    predicted_se: dict[str, float]
    ls_estimate: dict[str, float]
    ls_se: dict[str, float]
    ml_estimate: dict[str, float]
    ml_se: dict[str, float]
    ls_rmse_K: float


def outcome(kind: str, frame: pd.DataFrame, seed: int) -> PlayedTest:
    """Diagnose ``frame`` at the model's values and fit it by LS and ML."""
    net = get_model("second-order-paper")
    # both tests analysed at the same values, the design's prior, so that only the schedules differ
    rep = diagnose(net, frame, free=list(FREE), operating_point="model")
    ls = calibrate(net, frame, method="ls").result
    ml = calibrate(net, frame, method="ml").result
    return PlayedTest(
        kind=kind,
        seed=seed,
        ti_min=float(frame["Ti"].min()),
        ti_max=float(frame["Ti"].max()),
        predicted_se={k: rep.parameters[k].expected_rel_se for k in FREE},
        ls_estimate={k: float(ls.estimates[k]) for k in FREE},
        ls_se={k: float(ls.std_errors[k] / ls.estimates[k]) for k in FREE},
        ml_estimate={k: float(ml.estimates[k]) for k in FREE},
        ml_se={k: float(ml.std_errors[k] / ml.estimates[k]) for k in FREE},
        ls_rmse_K=float(ls.rmse_K),
    )


def paired(seed: int) -> tuple[PlayedTest, PlayedTest]:
    """(designed, C-style) on the same autumn night ``seed``."""
    d = outcome("designed", play_schedule(designed().schedule, "autumn", seed), seed)
    c = outcome("C-style", generate_night("autumn", "forced", seed), seed)
    return d, c


def markdown(pairs: list[tuple[PlayedTest, PlayedTest]]) -> str:
    """Per-seed comparison table and the means."""
    lines = [
        "| seed | test | Ti range (degC) | predicted se Cr / Rw | LS se Cr / Rw | ML se Cr / Rw"
        " | LS Cr, Rw | ML Cr, Rw | LS RMSE (K) |",
        "|" + "---|" * 9,
    ]
    for pair in pairs:
        for o in pair:
            lines.append(
                f"| {o.seed} | {o.kind} | {o.ti_min:.1f}..{o.ti_max:.1f}"
                f" | {o.predicted_se['Cr']:.1%} / {o.predicted_se['Rw']:.1%}"
                f" | {o.ls_se['Cr']:.1%} / {o.ls_se['Rw']:.1%} | {o.ml_se['Cr']:.1%} / {o.ml_se['Rw']:.1%}"
                f" | {o.ls_estimate['Cr']:.3g}, {o.ls_estimate['Rw']:.3g}"
                f" | {o.ml_estimate['Cr']:.3g}, {o.ml_estimate['Rw']:.3g} | {o.ls_rmse_K:.2f} |"
            )
    for i, kind in enumerate(("designed", "C-style")):
        outs = [p[i] for p in pairs]

        def mean(attr: str, k: str, outs=outs) -> float:
            return float(np.mean([getattr(o, attr)[k] for o in outs]))

        def spread(attr: str, k: str, outs=outs) -> float:
            return float(np.std(np.log([getattr(o, attr)[k] for o in outs]), ddof=1))

        lines.append(
            f"| mean | {kind} | | {mean('predicted_se', 'Cr'):.1%} / {mean('predicted_se', 'Rw'):.1%}"
            f" | {mean('ls_se', 'Cr'):.1%} / {mean('ls_se', 'Rw'):.1%}"
            f" | {mean('ml_se', 'Cr'):.1%} / {mean('ml_se', 'Rw'):.1%}"
            f" | scatter {spread('ls_estimate', 'Cr'):.1%}, {spread('ls_estimate', 'Rw'):.1%}"
            f" | scatter {spread('ml_estimate', 'Cr'):.1%}, {spread('ml_estimate', 'Rw'):.1%} | |"
        )
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover - documentation helper
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    res = designed()
    print(res.schedule.to_string())
    print("design expected se", res.expected_se, "predicted Ti", res.predicted.min(), res.predicted.max())
    print(markdown([paired(s) for s in range(300, 300 + n)]))
