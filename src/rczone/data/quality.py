"""Data-quality findings that do not stop loading: gaps, flat sensors, and their warning class.

Suspicious but usable data are reported twice: as a Python warning of category
:class:`RczoneWarning` (so ``warnings.simplefilter("error", RczoneWarning)`` turns them
into errors in a strict pipeline) and as a line in ``ZoneData.warnings``.

Gaps
    A *gap* of a channel is a maximal stretch with no usable value: between two
    consecutive finite samples either there are missing (NaN) samples, or the time step
    is longer than ``max_gap``. A run of NaN at the start or end of the record is a gap
    too, bounded by the first or last time stamp. Gaps are never filled.

Flat sensors
    A temperature whose reading stays exactly equal for longer than ``flat_seconds``
    (default 6 h) is reported: real room and outdoor temperatures move by at least the
    sensor resolution over a few hours, so a frozen value usually is a stuck sensor or a
    BMS that repeats the last value after losing the point. Flows and heat inputs are
    exempt (commands are legitimately constant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FLAT_SECONDS = 6 * 3600.0
"""Default duration (s) of an exactly constant temperature that is reported as flat."""


class RczoneWarning(UserWarning):
    """Suspicious but usable data (gaps, flat sensors, irregular sampling...)."""


@dataclass(frozen=True)
class Gap:
    """A stretch without usable values in one channel.

    Attributes
    ----------
    channel : str
        Channel name (``"Ti"``...).
    start, end : float
        UTC epoch seconds of the last usable sample before the gap and the first one
        after it (or the record's first/last time stamp for a gap at an edge).
    n_missing : int
        Number of NaN samples inside the gap on the returned time axis.
    """

    channel: str
    start: float
    end: float
    n_missing: int

    @property
    def duration(self) -> float:
        """Length of the gap (s)."""
        return self.end - self.start


def find_gaps(t: np.ndarray, x: np.ndarray, channel: str, max_gap: float) -> list[Gap]:
    """Gaps of one channel sampled at times ``t``.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Strictly increasing times (s).
    x : ndarray, shape (N,)
        Values; NaN marks a missing sample.
    channel : str
        Name reported in each :class:`Gap`.
    max_gap : float
        Longest spacing (s) between consecutive finite samples that is not a gap.

    Returns
    -------
    list of Gap
        In time order.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    ok = np.flatnonzero(np.isfinite(x))
    if t.size == 0:
        return []
    if ok.size == 0:
        return [Gap(channel, float(t[0]), float(t[-1]), int(t.size))]
    gaps = []
    if ok[0] > 0:
        gaps.append(Gap(channel, float(t[0]), float(t[ok[0]]), int(ok[0])))
    a, b = ok[:-1], ok[1:]
    for i in np.flatnonzero((b - a > 1) | (t[b] - t[a] > max_gap)):
        gaps.append(Gap(channel, float(t[a[i]]), float(t[b[i]]), int(b[i] - a[i] - 1)))
    if ok[-1] < t.size - 1:
        gaps.append(Gap(channel, float(t[ok[-1]]), float(t[-1]), int(t.size - 1 - ok[-1])))
    return gaps


def longest_flat_run(t: np.ndarray, x: np.ndarray) -> tuple[float, float, float]:
    """Longest run of exactly equal consecutive finite values.

    Returns
    -------
    (duration, start, end) : tuple of float
        Seconds, and the run's first and last time stamps; ``(0, nan, nan)`` when no
        two consecutive finite samples are equal.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    best = (0.0, np.nan, np.nan)
    if x.size < 2:
        return best
    same = (x[1:] == x[:-1]) & np.isfinite(x[1:])
    edges = np.diff(np.concatenate([[0], same.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    if starts.size == 0:
        return best
    durations = t[stops] - t[starts]  # run of equal pairs k..j-1 covers samples k..j
    i = int(np.argmax(durations))
    return (float(durations[i]), float(t[starts[i]]), float(t[stops[i]]))
