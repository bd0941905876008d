"""Data indicators that tell, before any fit, whether a data set can separate parameters.

The paper's lesson (section IV): closed-loop building data look rich, yet when the room stays
close to its surroundings all night the heat flow through the walls is tiny and a model with a
grossly wrong wall resistance fits as well as the right one. These indicators measure that
directly: how far and how independently the room temperature moves from each surrounding
temperature, how much each input varies, where the flow is constant, and where data are missing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.errors import DataError, did_you_mean


@dataclass(frozen=True)
class SurroundingIndicator:
    """How the zone temperature relates to one surrounding temperature (K)."""

    name: str
    correlation: float
    max_abs_diff_K: float
    median_abs_diff_K: float
    std_diff_K: float


@dataclass(frozen=True)
class InputVariation:
    """Spread of one input over the data."""

    name: str
    std: float
    range: float


@dataclass(frozen=True)
class DataIndicators:
    """Indicators of one data set.

    Attributes
    ----------
    surroundings : tuple of SurroundingIndicator
    inputs : tuple of InputVariation
    constant_flow_stretches : tuple of (start_s, end_s, m_kg_s)
        Stretches of at least ``min_stretch_s`` where the flow is constant (the LTI case).
    gaps : tuple of (start_s, end_s)
        Stretches where the room temperature is missing.
    duration_s : float
    """

    surroundings: tuple[SurroundingIndicator, ...]
    inputs: tuple[InputVariation, ...]
    constant_flow_stretches: tuple[tuple[float, float, float], ...]
    gaps: tuple[tuple[float, float], ...]
    duration_s: float

    def surrounding(self, name: str) -> SurroundingIndicator:
        for s in self.surroundings:
            if s.name == name:
                return s
        raise DataError(
            f"no indicator for {name!r}; " + did_you_mean(name, [s.name for s in self.surroundings])
        )

    def to_dict(self) -> dict:
        return {
            "surroundings": {
                s.name: {k: v for k, v in vars(s).items() if k != "name"} for s in self.surroundings
            },
            "inputs": {i.name: {"std": i.std, "range": i.range} for i in self.inputs},
            "constant_flow_stretches": [
                {"start_s": a, "end_s": b, "m_kg_s": m} for a, b, m in self.constant_flow_stretches
            ],
            "gaps": [{"start_s": a, "end_s": b} for a, b in self.gaps],
            "duration_s": self.duration_s,
        }


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges [i, j) where ``mask`` is True."""
    edges = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True))


def data_indicators(
    frame: pd.DataFrame,
    output: str = "Ti",
    surroundings: Sequence[str] = (),
    inputs: Sequence[str] = (),
    flow: str | None = None,
    flow_tol: float = 1e-3,
    min_stretch_s: float = 1800.0,
) -> DataIndicators:
    """Compute :class:`DataIndicators` for a data frame with a ``time`` (s) and an ``output`` column.

    Parameters
    ----------
    frame : DataFrame
    output : str
        The zone temperature the surroundings are compared with.
    surroundings : sequence of str
        Temperatures around the zone (boundaries of the model: outdoors, neighbouring spaces).
    inputs : sequence of str
        Inputs whose spread is reported.
    flow : str, optional
        Supply flow whose constant stretches are reported.
    flow_tol : float
        Largest change between samples still counted as constant flow, kg/s.
    min_stretch_s : float
        Shortest constant-flow stretch reported, s.

    Columns that are absent are skipped. :func:`rczone.diagnostics.diagnose` passes the model's
    own signals.
    """
    for c in ("time", output):
        if c not in frame:
            raise DataError(f"data have no {c!r} column; " + did_you_mean(c, frame.columns))
    t = frame["time"].to_numpy(float)
    ti = frame[output].to_numpy(float)
    cols = {c: frame[c].to_numpy(float) for c in frame.columns}
    sur = []
    for name in surroundings:
        if name not in cols or name == output:
            continue
        d = cols[name] - ti
        ok = np.isfinite(d)
        if ok.sum() < 3:
            continue
        a, b = ti[ok], cols[name][ok]
        corr = float(np.corrcoef(a, b)[0, 1]) if a.std() > 0 and b.std() > 0 else float("nan")
        ad = np.abs(d[ok])
        sur.append(
            SurroundingIndicator(name, corr, float(ad.max()), float(np.median(ad)), float(d[ok].std()))
        )
    var = []
    for name in inputs:
        if name in cols and np.isfinite(cols[name]).any():
            v = cols[name][np.isfinite(cols[name])]
            var.append(InputVariation(name, float(v.std()), float(v.max() - v.min())))
    stretches = []
    if flow is not None and flow in cols:
        mv = cols[flow]
        same = np.r_[False, np.abs(np.diff(mv)) <= flow_tol]
        for i, j in _runs(same):
            start = i - 1
            if t[j - 1] - t[start] >= min_stretch_s:
                stretches.append((float(t[start]), float(t[j - 1]), float(np.median(mv[start:j]))))
    gaps = tuple((float(t[max(i - 1, 0)]), float(t[min(j, len(t) - 1)])) for i, j in _runs(~np.isfinite(ti)))
    return DataIndicators(tuple(sur), tuple(var), tuple(stretches), gaps, float(t[-1] - t[0]))
