"""Where data are split: the start of a held-out part, the end of a warm-up.

``--holdout`` takes a time (``2009-02-09T12:00``, in the data's time zone) or the fraction of the
samples to hold out at the end (``0.25``); ``--warmup`` a duration from the start (``1d``, ``6h``,
``30min``) or a time. Both become a time on the data's own axis (UTC epoch seconds for a trend
log read through a column map, seconds from the start otherwise), so that the model's data set,
which may keep only a complete stretch of the frame, is split at the same instant.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from rczone.calibration.dataset import EPOCH_SECONDS
from rczone.errors import ParameterError


def _time(text: str, t: np.ndarray, timezone: str, option: str) -> float | None:
    """A date or date-time as a time on the axis ``t``; None when ``text`` is not one."""
    try:
        ts = pd.Timestamp(text)
    except (ValueError, OverflowError, TypeError):
        return None
    if ts is pd.NaT or not any(c in text for c in "-:T"):
        return None
    if not (t.size and t[0] > EPOCH_SECONDS):
        raise ParameterError(
            f"{option} {text!r} is a time, but the data have no clock time (seconds from the start);"
            " give a fraction or a duration instead"
        )
    try:
        if ts.tzinfo is None:
            ts = ts.tz_localize(timezone)
    except (ValueError, OverflowError):
        raise ParameterError(
            f"{option} {text!r} does not exist or is ambiguous in {timezone} (a daylight-saving change);"
            " give it with its UTC offset, e.g. 2014-11-02T01:30-05:00"
        ) from None
    return ts.timestamp()


def duration_seconds(text: str) -> float:
    """A positive duration with its unit (``1d``, ``6h``, ``30min``, ``2 days``) in seconds.

    A lower-case ``d`` means days and an upper-case ``H`` hours, as users write them (pandas
    deprecates both spellings).

    Raises
    ------
    ValueError
        Not a positive duration with a unit.
    """
    text = str(text).strip()
    if not any(c.isalpha() for c in text):
        raise ValueError(f"no unit in {text!r}")
    try:
        spelled = re.sub(r"(?<=[0-9\s])H$", "h", re.sub(r"(?<=[0-9\s])d$", "D", text))
        seconds = pd.Timedelta(spelled).total_seconds()
    except (TypeError, OverflowError) as exc:
        raise ValueError(str(exc)) from None
    if not seconds > 0:
        raise ValueError(f"{text!r} is not positive")
    return seconds


def _inside(value: float, t: np.ndarray, option: str, text: str) -> float:
    if not t[0] < value <= t[-1]:
        span = " to ".join(_stamp(v) for v in (t[0], t[-1]))
        raise ParameterError(
            f"{option} {text!r} leaves no data on one side: the data run from {span}; give a time inside"
        )
    return value


def _stamp(v: float) -> str:
    return pd.Timestamp(v, unit="s", tz="UTC").isoformat() if v > EPOCH_SECONDS else f"{v:g} s"


def holdout_start(t: np.ndarray, spec: str, *, timezone: str = "UTC") -> float:
    """The time the held-out part starts: ``spec`` a time or a fraction of the samples (held out at the end).

    Parameters
    ----------
    t : ndarray, shape (N,)
        The data's times, s.
    spec : str
        ``"2009-02-09T12:00"`` (local to ``timezone`` unless it has an offset) or ``"0.25"``.
    timezone : str
        IANA zone of a time without an offset (the column map's).

    Returns
    -------
    float
        The first held-out sample's time; every sample before it calibrates.
    """
    text = spec.strip()
    t = np.asarray(t, dtype=float)
    try:
        fraction = float(text)
    except ValueError:
        fraction = None
    if fraction is not None:
        if not 0 < fraction < 1:
            raise ParameterError(f"--holdout as a fraction must lie between 0 and 1, got {text!r}")
        i = round(len(t) * (1 - fraction))
        if not 0 < i < len(t):
            raise ParameterError(f"--holdout {text!r} leaves no sample on one side of {len(t)}")
        return float(t[i])
    value = _time(text, t, timezone, "--holdout")
    if value is None:
        raise ParameterError(
            f"--holdout must be a time (e.g. 2009-02-09T12:00) or a fraction of the samples (e.g. 0.25),"
            f" got {text!r}"
        )
    return _inside(value, t, "--holdout", text)


def warmup_end(t: np.ndarray, spec: str, *, timezone: str = "UTC") -> float:
    """The time the scored part starts: ``spec`` a duration from the first sample or a time.

    Parameters
    ----------
    t : ndarray, shape (N,)
        The data's times, s.
    spec : str
        ``"1d"``, ``"6h"``, ``"30min"`` (pandas' duration syntax) or ``"2009-02-09T12:00"``.
    timezone : str
        IANA zone of a time without an offset.

    Returns
    -------
    float
        The first scored sample's time; the samples before it warm the filter up.
    """
    text = spec.strip()
    t = np.asarray(t, dtype=float)
    value = _time(text, t, timezone, "--warmup")
    if value is None:
        try:
            seconds = duration_seconds(text)
        except ValueError:
            raise ParameterError(
                f"--warmup must be a duration with its unit (e.g. 1d, 6h, 30min) or a time (e.g."
                f" 2009-02-09T12:00), got {text!r}"
            ) from None
        value = float(t[0]) + seconds
    return _inside(value, t, "--warmup", text)


def split_frame(frame: pd.DataFrame, at: float) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The samples of ``frame`` (its ``time`` column, s) before ``at`` and from ``at`` on.

    Parameters
    ----------
    frame : DataFrame
        With a ``time`` column in seconds.
    at : float
        The split time, s.
    """
    before = frame["time"].to_numpy(float) < at
    return frame[before], frame[~before]
