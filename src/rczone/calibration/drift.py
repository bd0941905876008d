"""Has the model drifted? CUSUM tests on the innovations and the widening of the online band.

A model calibrated on past data is used on new data; when the building changes (a window left
open, a retrofit, a sensor that slips) the model's errors change first. Two signals, both
calibrated on the same window as the conformal band (:mod:`rczone.calibration.conformal`):

* **a self-starting CUSUM on the innovations** [1]_ [2]_ [4]_: the filter's one-step innovations,
  standardized by their own variance, are averaged over blocks of :data:`BLOCK_S` (batch means, so
  that the autocorrelated innovations of a misspecified model are tested on nearly independent
  blocks [3]_). Each new block's mean, and the log of its mean square, is compared with the mean
  and spread of *every block before it* (the calibration window's, then each scored block as it
  arrives): the Student-t statistic of that comparison is mapped to a standard normal score
  through its own distribution (Hawkins' self-starting transformation [4]_ [5]_). For normal block
  statistics these scores are exactly independent N(0, 1) whatever the process's mean and spread,
  so the CUSUM's in-control run length no longer depends on how well a short calibration window
  estimated them (the log mean squares are nearly normal, with a lighter upper tail: the variance
  test errs on the quiet side). A reference held fixed from a few days of blocks errs by a tenth
  of a block standard deviation or so, for the whole prediction, which is what raised the false
  alarms of the fixed-reference design (2 in 60 undrifted ten-day records; docs/validation.md).
  Page's CUSUM
  ``S+ = max(0, S+ + x - k)`` (and ``S-`` for the mean) raises an alarm when it exceeds ``h``;
  ``k`` is :data:`CUSUM_K` and ``h`` (:data:`CUSUM_H`) is set by the in-control average run length
  :data:`CUSUM_ARL0` through Siegmund's approximation [6]_ (:func:`decision_interval`), not tuned
  on records. The change is dated at the start of the run that raised the alarm (the last block
  the statistic was zero), Page's estimate of the change point;
* **the online band's widening**: when the quantile (at the nominal level) of the recent
  standardized errors over which the online band is updated stays above :data:`WIDEN_FACTOR` times
  the calibration one for a whole :data:`WIDEN_WINDOW_S` (the median over that window), the errors
  at that horizon have grown beyond what the model was calibrated for; the drift is dated at the
  window's start. ACI's own level is not used: after a run of misses (k-step errors come in runs)
  it swings to an infinite band even when nothing changed.

The CUSUM starts from the warm-up after its first quarter (the filter's start), at least the
conformal window, and at least :data:`MIN_BLOCKS` blocks. A self-starting chart absorbs a change
it has not flagged: its blocks enter the running mean and spread, so a shift must be found within
a few dozen blocks or its score fades [5]_; on the virtual zone of docs/validation.md the hourly
blocks and the decision interval find the changes of issue 36 within a day.

``fit-many`` tests each zone's own record the same way (:func:`record_drift`): the fitted model's
innovations over the second half of the record against the first half's (after its first
quarter), so that nights whose errors leave the range of the earlier ones are flagged as drift,
with the time it started, instead of only being averaged into the stored error.

References
----------
.. [1] E. S. Page, "Continuous inspection schemes", Biometrika 41 (1954) 100-115.
.. [2] D. C. Montgomery, *Introduction to Statistical Quality Control*, 6th ed., Wiley 2009,
   section 9.1 (the tabular CUSUM, its ``k`` and ``h``, and the change-point estimate).
.. [3] G. C. Runger, T. R. Willemain, "Model-based and model-free control of autocorrelated
   processes", Journal of Quality Technology 27 (1995) 283-292 (batch means).
.. [4] D. M. Hawkins, "Self-starting cusum charts for location and scale", The Statistician 36
   (1987) 299-316.
.. [5] D. M. Hawkins, D. H. Olwell, *Cumulative Sum Charts and Charting for Quality Improvement*,
   Springer 1998 (self-starting charts and their loss of power after an undetected shift).
.. [6] D. Siegmund, *Sequential Analysis: Tests and Confidence Intervals*, Springer 1985 (the
   run length of Page's CUSUM of normal observations; the approximation as given in [2]_).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Length of the blocks the innovations are averaged over, s.
BLOCK_S = 3600.0
#: Reference value of the CUSUM, in standard deviations of the scores (half the shift it is tuned for).
CUSUM_K = 0.5
#: In-control average run length of each one-sided CUSUM, in blocks: with three one-sided tests
#: over ten days of hourly blocks, a false alarm in about one ten-day record in 1400 (one per zone
#: in some 38 years of hourly blocks).
CUSUM_ARL0 = 1.0e6
#: Fewest calibration blocks the CUSUM is calibrated from.
MIN_BLOCKS = 8
#: The online band has drifted when its quantile stays above this factor times the calibration one...
WIDEN_FACTOR = 2.0
#: ...for this long (the median over the window), s.
WIDEN_WINDOW_S = 6 * 3600.0


def siegmund_arl(h: float, k: float) -> float:
    """Average run length of Page's one-sided CUSUM of N(0, 1) observations (Siegmund's approximation).

    ``ARL = (exp(2 k b) - 2 k b - 1) / (2 k**2)`` with ``b = h + 1.166`` ([6]_; [2]_, section 9.1).

    Parameters
    ----------
    h : float
        Decision interval, in standard deviations.
    k : float
        Reference value, in standard deviations (> 0).

    Returns
    -------
    float
        The in-control average run length, in observations (blocks).
    """
    b = 2.0 * k * (h + 1.166)
    return (math.exp(b) - b - 1.0) / (2.0 * k * k)


def decision_interval(arl0: float, k: float) -> float:
    """The decision interval ``h`` whose in-control run length is ``arl0`` (:func:`siegmund_arl` inverted).

    Parameters
    ----------
    arl0 : float
        Target in-control average run length, blocks (> 1).
    k : float
        Reference value, in standard deviations (> 0).

    Raises
    ------
    ParameterError
        When ``arl0`` is not above 1 or ``k`` not positive.
    """
    from rczone.errors import ParameterError

    if not (arl0 > 1.0 and k > 0.0 and math.isfinite(arl0) and math.isfinite(k)):
        raise ParameterError(
            f"decision_interval: arl0 = {arl0!r} and k = {k!r}; expected a finite arl0 > 1 block"
            " and a finite k > 0 (e.g. arl0 = 1e6, k = 0.5)"
        )
    from scipy.optimize import brentq

    hi = 1.0
    while siegmund_arl(hi, k) < arl0:  # the run length grows with h: bracket the root
        hi *= 2.0
    return float(brentq(lambda h: siegmund_arl(h, k) - arl0, 0.0, hi, xtol=1e-12))


#: Decision interval of the CUSUM, in standard deviations: the one of :data:`CUSUM_ARL0` (about 12).
CUSUM_H = decision_interval(CUSUM_ARL0, CUSUM_K)
#: Largest self-starting score, in standard deviations (the normal quantile of the smallest double).
MAX_SCORE = 37.0
#: Share of a zone's record that :func:`record_drift` calibrates the CUSUM on (the rest is tested).
RECORD_REFERENCE = 0.5


@dataclass(frozen=True)
class DriftSignal:
    """One test that raised an alarm.

    Attributes
    ----------
    test : str
        ``"innovation mean"``, ``"innovation variance"`` or ``"band widening"``.
    output : str
    horizon : int or None
        Steps ahead of a widening signal (None for the innovation tests).
    since_s : float
        Estimated start of the drift (time on the data's axis, s).
    detected_s : float
        When the test raised its alarm, s.
    """

    test: str
    output: str
    horizon: int | None
    since_s: float
    detected_s: float

    def to_dict(self) -> dict:
        """JSON-ready."""
        return {
            "test": self.test,
            "output": self.output,
            "horizon": self.horizon,
            "since_s": self.since_s,
            "detected_s": self.detected_s,
        }


@dataclass(frozen=True, eq=False)
class CusumTrace:
    """A CUSUM statistic per block for one output, for the report's figure.

    Attributes
    ----------
    t : ndarray, shape (B,)
        End of each scored block, s.
    mean_up, mean_down, variance_up : ndarray, shape (B,)
        The statistics, in units of the blocks' self-starting scores (standard deviations).
    """

    t: np.ndarray
    mean_up: np.ndarray
    mean_down: np.ndarray
    variance_up: np.ndarray


@dataclass(frozen=True, eq=False)
class DriftCheck:
    """The drift tests of one prediction.

    Attributes
    ----------
    signals : tuple of DriftSignal
        Every test that raised an alarm (empty: no drift found).
    traces : dict
        Output name to its :class:`CusumTrace` (absent: too few calibration blocks).
    notes : tuple of str
        What could not be tested, in words.
    """

    signals: tuple[DriftSignal, ...]
    traces: dict
    notes: tuple[str, ...] = ()

    @property
    def drifted(self) -> bool:
        """Whether any test raised an alarm."""
        return bool(self.signals)

    @property
    def since_s(self) -> float | None:
        """The earliest estimated start of a drift, s (None: no drift)."""
        return min((s.since_s for s in self.signals), default=None)

    @property
    def detected_s(self) -> float | None:
        """The first alarm, s (None: no drift)."""
        return min((s.detected_s for s in self.signals), default=None)

    def describe(self) -> str:
        """One line: whether the model drifted, since when, and which tests say so."""
        if not self.drifted:
            tested = "CUSUM on the innovations" + (
                "" if any("online" in n for n in self.notes) else " and the online band's widening"
            )
            return f"no drift found ({tested})"
        tests = sorted(
            {
                f"{s.test} of {s.output}" + (f" at {s.horizon} steps" if s.horizon else "")
                for s in self.signals
            }
        )
        return (
            f"the model has DRIFTED since about {when(self.since_s)} (first alarm {when(self.detected_s)}):"
            f" {', '.join(tests)}"
        )

    def to_dict(self) -> dict:
        """JSON-ready: the verdict, when it started and every alarm, with the tests' settings."""
        return {
            "drifted": self.drifted,
            "since_s": self.since_s,
            "since": None if self.since_s is None else when(self.since_s),
            "detected_s": self.detected_s,
            "signals": [s.to_dict() for s in self.signals],
            "settings": {
                "block_s": BLOCK_S,
                "cusum_k": CUSUM_K,
                "cusum_h": CUSUM_H,
                "cusum_arl0": CUSUM_ARL0,
                "cusum_reference": "self-starting",
                "widen_factor": WIDEN_FACTOR,
                "widen_window_s": WIDEN_WINDOW_S,
            },
            "notes": list(self.notes),
        }


def when(t: float) -> str:
    """A time on the data's axis in words: an ISO UTC stamp for epoch seconds, else hours from zero.

    Parameters
    ----------
    t : float
        Time, s.
    """
    import pandas as pd

    from rczone.calibration.dataset import EPOCH_SECONDS

    if t > EPOCH_SECONDS:
        return pd.Timestamp(t, unit="s", tz="UTC").strftime("%Y-%m-%d %H:%M UTC")
    return f"{t / 3600:g} h"


def _blocks(
    z: np.ndarray, t: np.ndarray, lo: int, hi: int, size: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Block means, log mean squares and end times of ``z[lo:hi]`` in disjoint blocks of ``size`` samples.

    Blocks with fewer than half their samples are dropped.
    """
    means, logs, ends = [], [], []
    for a in range(lo, hi - size + 1, size):
        v = z[a : a + size]
        v = v[np.isfinite(v)]
        if v.size * 2 < size:
            continue
        means.append(float(np.mean(v)))
        logs.append(math.log(max(float(np.mean(v**2)), 1e-300)))
        ends.append(float(t[a + size - 1]))
    return np.array(means), np.array(logs), np.array(ends)


def _cusum(x: np.ndarray, sign: float) -> tuple[np.ndarray, int | None, int | None]:
    """Page's one-sided CUSUM of ``sign * x``: the statistic, the first alarm's index and the start of its run."""
    s = np.zeros(x.size)
    run_start = 0
    level = 0.0
    for i, v in enumerate(x):
        level = max(0.0, level + sign * v - CUSUM_K)
        if level == 0.0:
            run_start = i + 1
        s[i] = level
        if level > CUSUM_H:
            return np.concatenate([s[: i + 1], np.full(x.size - i - 1, np.nan)]), i, min(run_start, i)
    return s, None, None


def self_starting_scores(reference: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Hawkins' self-starting scores of ``x``: each against the mean and spread of every value before it.

    The ``n``-th value after ``n - 1`` earlier ones (``reference``, then ``x``'s own) gives
    ``T = (x_n - mean) / (s sqrt(1 + 1/(n - 1)))``, Student-t with ``n - 2`` degrees of freedom for
    independent normal values, and its score is the normal quantile of T's probability [4]_ [5]_.
    For independent normal values of any mean and spread the scores are independent N(0, 1).

    Parameters
    ----------
    reference : ndarray, shape (B,)
        The values before ``x`` (B >= 3).
    x : ndarray, shape (M,)
        The values scored, in order.

    Returns
    -------
    ndarray, shape (M,)
        The scores, clipped to ``+-``:data:`MAX_SCORE` (a value whose probability underflows).
    """
    from scipy.special import ndtri, stdtr

    every = np.concatenate([reference, x])
    centred = every - np.mean(reference)  # centred: the running sums lose no digits
    before = np.arange(reference.size, every.size)  # values before each scored one
    csum = np.concatenate([[0.0], np.cumsum(centred)])[before]
    csq = np.concatenate([[0.0], np.cumsum(centred**2)])[before]
    mean = csum / before
    spread = np.sqrt(np.maximum(csq - before * mean**2, 0.0) / (before - 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (centred[before] - mean) / (spread * np.sqrt(1.0 + 1.0 / before))
        # the tail the value is in, so that a far value keeps its digits
        score = np.where(t > 0, -ndtri(stdtr(before - 1, -t)), ndtri(stdtr(before - 1, t)))
    return np.clip(score, -MAX_SCORE, MAX_SCORE)


def innovation_cusum(
    z: np.ndarray, t: np.ndarray, first: int, window: int, output: str
) -> tuple[list[DriftSignal], CusumTrace | None]:
    """Self-starting CUSUM tests of one output's standardized innovations after ``first``, started on ``[first - window, first)``.

    Parameters
    ----------
    z : ndarray, shape (N,)
        Standardized one-step innovations (NaN where missing).
    t : ndarray, shape (N,)
        Times, s.
    first : int
        First scored sample.
    window : int
        Calibration samples before it.
    output : str
    """
    dt = float(np.median(np.diff(t)))
    size = max(1, round(BLOCK_S / dt))
    lo = max(0, first - window)
    m0, l0, _ = _blocks(z, t, lo, first, size)
    if m0.size < MIN_BLOCKS or np.std(m0, ddof=1) <= 0 or np.std(l0, ddof=1) <= 0:
        return [], None
    m, lg, ends = _blocks(z, t, first, z.size, size)
    xm = self_starting_scores(m0, m)
    xv = self_starting_scores(l0, lg)
    signals = []
    stats = {}
    for name, x, sign in (("mean_up", xm, 1.0), ("mean_down", xm, -1.0), ("variance_up", xv, 1.0)):
        s, alarm, start = _cusum(x, sign)
        stats[name] = s
        if alarm is not None:
            test = "innovation variance" if name == "variance_up" else "innovation mean"
            since = ends[start] - size * dt if start is not None else ends[alarm]
            signals.append(DriftSignal(test, output, None, float(since), float(ends[alarm])))
    return signals, CusumTrace(ends, stats["mean_up"], stats["mean_down"], stats["variance_up"])


def widening_signals(
    widening: np.ndarray, t: np.ndarray, first: int, horizons: tuple, outputs: tuple[str, ...]
) -> list[DriftSignal]:
    """Alarms where the online band's quantile stayed above :data:`WIDEN_FACTOR` times the calibration one.

    Parameters
    ----------
    widening : ndarray, shape (H, N, ny)
        Online over calibration quantile (:meth:`~rczone.calibration.conformal.ConformalBand.widening`).
    t : ndarray, shape (N,)
        Times, s.
    first : int
        First scored sample.
    horizons : tuple
        Steps ahead per horizon (None: open loop, never updated).
    outputs : tuple of str
    """
    dt = float(np.median(np.diff(t)))
    span = max(1, round(WIDEN_WINDOW_S / dt))
    out = []
    for h, steps in enumerate(horizons):
        for j, o in enumerate(outputs):
            w = widening[h, first:, j]
            if steps is None or w.size < span or not np.isfinite(w).any():
                continue
            high = np.where(np.isnan(w), 0.0, (w > WIDEN_FACTOR).astype(float))
            # the median over a window is above the factor when more than half its samples are
            share = np.convolve(high, np.ones(span) / span, mode="valid")
            hit = np.flatnonzero(share > 0.5)
            if hit.size:
                i = int(hit[0])
                out.append(
                    DriftSignal(
                        "band widening", o, steps, float(t[first + i]), float(t[first + i + span - 1])
                    )
                )
    return out


def check_drift(
    z: np.ndarray,
    t: np.ndarray,
    first: int,
    window: int,
    outputs: tuple[str, ...],
    *,
    widening: np.ndarray | None = None,
    horizons: tuple = (),
) -> DriftCheck:
    """Every drift test of a prediction (see the module notes).

    Parameters
    ----------
    z : ndarray, shape (N, ny)
        Standardized one-step innovations over the warm-up and the scored samples.
    t : ndarray, shape (N,)
        Times, s.
    first : int
        First scored sample.
    window : int
        Calibration samples before it (those of the conformal band).
    outputs : tuple of str
    widening : ndarray, shape (H, N, ny), optional
        The online band's widening; None without the online update.
    horizons : tuple
        Steps ahead of ``widening``'s horizons.
    """
    signals: list[DriftSignal] = []
    traces: dict = {}
    notes = []
    for j, o in enumerate(outputs):
        found, trace = innovation_cusum(z[:, j], t, first, window, o)
        signals += found
        if trace is None:
            notes.append(
                f"{o}: fewer than {MIN_BLOCKS} blocks of {BLOCK_S / 3600:g} h in the calibration window; no CUSUM"
            )
        else:
            traces[o] = trace
    if widening is not None:
        signals += widening_signals(widening, t, first, horizons, outputs)
    else:
        notes.append("no online update (--online): the band's widening is not watched")
    return DriftCheck(tuple(sorted(signals, key=lambda s: s.detected_s)), traces, tuple(notes))


def record_drift(model, data) -> DriftCheck | None:
    """The CUSUM tests of a zone's own record: its second half against its first (``fit-many``).

    The fitted model's Kalman filter runs over the whole record; its standardized one-step
    innovations after :data:`RECORD_REFERENCE` of the record are tested against those before it
    (after the filter's first quarter), as :func:`check_drift` does for ``predict``. A model fitted
    to a record whose building changed part-way is a compromise of before and after, so its
    errors shift at the change and the shift is dated. A record too short for
    :data:`MIN_BLOCKS` reference blocks is not filtered (a note says so).

    Parameters
    ----------
    model : ZoneModel
        The fitted model, with its noise levels.
    data : Dataset
        The zone's data (those of the fit; :func:`rczone.calibration.dataset.dataset`).

    Returns
    -------
    DriftCheck or None
        None when the model has no noise levels (a least-squares fit has no innovations to test).
    """
    from rczone.calibration.prediction import model_hold, noise_values
    from rczone.estimation.engines import run_filter
    from rczone.network.stochastic import is_noise_name

    if not any(is_noise_name(k) for k in model.noise):
        return None
    t = data.t
    first = int(np.searchsorted(t, t[0] + RECORD_REFERENCE * (t[-1] - t[0])))
    reference = first - first // 4
    if first < 2 or t[first - 1] - t[first - reference] < MIN_BLOCKS * BLOCK_S:
        need = MIN_BLOCKS * BLOCK_S / (RECORD_REFERENCE * 0.75) / 3600
        note = f"a record of {(t[-1] - t[0]) / 3600:.3g} h is too short to test for drift (about {need:.3g} h needed)"
        return DriftCheck((), {}, (note,))
    net = model.network
    out = run_filter(net, {**model.theta, **noise_values(model)}, data, model_hold(model))
    with np.errstate(invalid="ignore"):
        z = out.innovations / np.sqrt(np.einsum("kii->ki", out.S))
    check = check_drift(z, t, first, reference, net.outputs)
    notes = [n for n in check.notes if "online" not in n]
    notes.append("a fit has no online band: only the CUSUM on the innovations is tested")
    return DriftCheck(check.signals, check.traces, tuple(notes))
