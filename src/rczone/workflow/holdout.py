"""Fit on the data before a split, score on the rest: ``--holdout`` of ``fit`` and ``select``, in one place.

The split is a time on the data's own axis (:func:`rczone.calibration.holdout.holdout_start`: a
time stamp in the column map's time zone, or the fraction of the samples held out at the end);
the model is fitted on the part before it and scored on the part after it at one step, 1 h, 6 h,
24 h and open loop next to persistence and ARX (:func:`rczone.calibration.horizons.holdout_scores`),
the warm-up of every horizon taken from the data before the split. The command line and the
Python API call the same two functions, so ``rczone.fit(..., holdout=0.25)`` returns the scores
``rczone fit --holdout 0.25`` prints.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import pandas as pd

from rczone.models import ZoneModel


def split_time(
    frame: pd.DataFrame,
    spec: str | float | None,
    *,
    model: ZoneModel,
    columns: str | os.PathLike | None = None,
    warmup: bool = False,
) -> float | None:
    """The time a held-out part starts (or a warm-up ends), on the frame's time axis; None without ``spec``.

    Parameters
    ----------
    frame : DataFrame
        The data, as :func:`rczone.load_data` reads them (``time`` in s).
    spec : str or float, optional
        ``--holdout``: a time (``"2009-02-09T12:00"``) or a fraction of the samples (``0.25``);
        with ``warmup`` a ``--warmup`` duration (``"1d"``) or time.
    model : ZoneModel
        The model the data are for (the column map's quantities).
    columns : str or path, optional
        The column map the data were read with: its time zone reads a time stamp.
    warmup : bool
        Read ``spec`` as the end of a warm-up instead of the start of a held-out part.

    Returns
    -------
    float or None
    """
    if spec is None:
        return None
    from rczone.calibration.holdout import holdout_start, warmup_end

    timezone = "UTC"
    if columns is not None:
        from rczone.data.columnmap import read_column_map

        timezone = read_column_map(columns, model.signal_quantities()).timezone
    t = frame["time"].to_numpy(float)
    return (warmup_end if warmup else holdout_start)(t, str(spec), timezone=timezone)


def before(frame: pd.DataFrame, at: float | None) -> pd.DataFrame:
    """The part of ``frame`` a held-out fit is fitted on (all of it without a split)."""
    if at is None:
        return frame
    from rczone.calibration.holdout import split_frame

    return split_frame(frame, at)[0]


def score_held_out(
    fitted: ZoneModel, full: pd.DataFrame, at: float, constants: Mapping[str, float] | None, label: str
):
    """The fitted model's scores on the held-out part of ``full`` (from ``at``), per horizon, with baselines.

    Parameters
    ----------
    fitted : ZoneModel
        The model fitted on the data before ``at``.
    full : DataFrame
        All the data (the part before ``at`` warms the filter up).
    at : float
        Where the held-out part starts (:func:`split_time`).
    constants : mapping, optional
        Inputs held constant, SI units.
    label : str
        The data's name; the scores are titled ``"<label> (held out)"``.

    Returns
    -------
    HorizonScores
    """
    from rczone.calibration.horizons import holdout_scores

    return holdout_scores(fitted, full, at, dict(constants or {}) or None, label=f"{label} (held out)")


def conformal_settings(window: str | None, online: bool, start: float | None):
    """``--conformal WINDOW`` and ``--online`` as :class:`~rczone.calibration.conformal.ConformalSettings`.

    Parameters
    ----------
    window : str, optional
        The calibration window at the end of the warm-up, a duration with its unit (``"1d"``);
        None: no conformal band.
    online : bool
        Update the bands while predicting (adaptive conformal inference).
    start : float, optional
        Where the warm-up ends (:func:`split_time`); a conformal band needs one.

    Returns
    -------
    ConformalSettings or None
    """

    from rczone.calibration.conformal import ConformalSettings
    from rczone.errors import ParameterError

    if window is None:
        if online:
            raise ParameterError("--online updates a conformal band: give --conformal WINDOW too (e.g. 1d)")
        return None
    if start is None:
        raise ParameterError("--conformal calibrates on the end of the warm-up: give --warmup too")
    from rczone.calibration.holdout import duration_seconds

    try:
        seconds = duration_seconds(window)
    except ValueError:
        raise ParameterError(
            f"--conformal must be a duration with its unit (e.g. 1d, 12h), got {window!r}"
        ) from None
    return ConformalSettings(seconds, online=online)
