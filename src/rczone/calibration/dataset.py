"""A model's data set: its signals picked from a frame by name, on the frame's time axis.

Shared by the fit, the prediction, diagnose and select: the model's own conventions for inputs the
data lack (:class:`~rczone.models.zone.ModelInputs`), the frame's DatetimeIndex kept, and the
longest complete stretch of a record. :func:`prepare` is the one place a frame becomes a data set:
what it returns (:class:`PreparedData`) is handed on unchanged, wherever a frame is accepted, so a
fit, its checks and its analyses read the data set the entry point built.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.data.quality import RczoneWarning
from rczone.errors import DataError, user_stacklevel
from rczone.estimation import Dataset
from rczone.models import ZoneModel, load_model
from rczone.models.zone import ModelInputs
from rczone.network import RCNetwork

ModelLike = ZoneModel | RCNetwork | str | os.PathLike


def as_model(model: ModelLike) -> ZoneModel:
    """A :class:`ZoneModel` from a model, a bare network, a built-in name or a model file."""
    return load_model(model)


def frame_from(data: pd.DataFrame) -> pd.DataFrame:
    """A frame with a ``time`` column in seconds; a DatetimeIndex (or datetime ``time``) is converted.

    Every API entry point accepts a frame indexed by time stamps: the time becomes seconds since
    the first sample (only differences of time enter the models).
    """
    if not isinstance(data, pd.DataFrame):
        raise DataError(f"data must be a pandas DataFrame, got {type(data).__name__}")
    if "time" in data:
        t = data["time"]
        if pd.api.types.is_datetime64_any_dtype(t):
            out = data.copy()
            out["time"] = (t - t.iloc[0]).dt.total_seconds()
            return out
        return data
    if isinstance(data.index, pd.DatetimeIndex):
        out = data.reset_index(drop=True)
        out.insert(0, "time", (data.index - data.index[0]).total_seconds().to_numpy())
        return out
    raise DataError(
        "the data have no 'time' column and no DatetimeIndex; give time in seconds or index the"
        " frame by time stamps"
    )


def ignored_channels(frame: pd.DataFrame) -> tuple[str, ...]:
    """The channels a column map mapped that the model (or every candidate) does not use, as loaded.

    A trend log read through a map lists them in ``frame.attrs["ignored_channels"]``
    (:meth:`rczone.data.zonedata.ZoneData.to_frame`); the results of a fit, a selection and a
    prediction repeat them in their JSON, so a script sees what the map carried that was not used.

    Parameters
    ----------
    frame : DataFrame
    """
    return tuple(str(n) for n in frame.attrs.get("ignored_channels") or ())


def time_index(frame: pd.DataFrame, t: np.ndarray) -> pd.DatetimeIndex | None:
    """The time stamps of the samples at ``t`` (as :func:`frame_from` made them), in the data's time zone.

    A frame indexed by time stamps (or with a datetime ``time`` column) gives them from its first
    stamp; UTC epoch seconds (a loaded trend log) give UTC stamps, converted to the zone of the
    frame's DatetimeIndex when it has one. None when the data have no clock time.
    """
    index = frame.index if isinstance(frame.index, pd.DatetimeIndex) else None
    t = np.asarray(t, dtype=float)
    if "time" in frame and pd.api.types.is_datetime64_any_dtype(frame["time"]):
        return pd.DatetimeIndex(frame["time"].iloc[0] + pd.to_timedelta(t, unit="s"), name="timestamp")
    if "time" in frame:
        if not (t.size and t[0] > EPOCH_SECONDS):
            return None
        stamps = pd.to_datetime(t, unit="s", utc=True)
        if index is not None and index.tz is not None:
            stamps = stamps.tz_convert(index.tz)
        return pd.DatetimeIndex(stamps, name="timestamp")
    if index is not None and len(index):
        return pd.DatetimeIndex(index[0] + pd.to_timedelta(t, unit="s"), name="timestamp")
    return None


#: Times above this (s) are UTC epoch seconds (after 1973), not seconds from the start of the data.
EPOCH_SECONDS = 1e8


def complete_stretch(u: np.ndarray, m: np.ndarray, y: np.ndarray) -> slice:
    """The longest run of samples where every input and flow is known and some output is measured.

    The model needs its inputs at every sample (an unknown input is not a missing measurement);
    outputs may be missing inside the run. Returns ``slice(start, stop)``.
    """
    ok = np.isfinite(u).all(axis=1) & np.isfinite(m).all(axis=1)
    best, start = (0, 0), None
    for i, good in enumerate(np.r_[ok, False]):
        if good and start is None:
            start = i
        elif not good and start is not None:
            if i - start > best[1] - best[0] and np.isfinite(y[start:i]).any():
                best = (start, i)
            start = None
    return slice(*best)


def missing_inputs(
    model: ModelLike, frame: pd.DataFrame, constants: Mapping[str, float] | None = None
) -> list[dict]:
    """Each input channel with missing or non-finite samples: its name, how many, and the first and last time.

    What a fit on the longest complete stretch (:func:`complete_stretch`) left out, said by channel
    so the user knows which sensor to repair (issue 39).

    Returns
    -------
    list of dict
        ``{"channel", "samples", "first_s", "last_s"}``, times on the data's axis (s).
    """
    zm = as_model(model)
    t, u, m, _ = zm.signals(frame_from(frame), constants)
    out = []
    for j, name in enumerate((*zm.network.input_names, *zm.network.flow_names)):
        bad = np.flatnonzero(~np.isfinite(np.column_stack([u, m])[:, j]))
        if bad.size:
            out.append(
                {
                    "channel": name,
                    "samples": int(bad.size),
                    "first_s": float(t[bad[0]]),
                    "last_s": float(t[bad[-1]]),
                }
            )
    return out


MIN_USED_FRACTION = 0.5
"""Where inputs have gaps, the longest complete stretch is used only if it holds at least this
fraction of the samples; below, the data are refused (exit code 2) rather than silently cut to a
small part. The fraction used is in the fitted model's provenance (``stretch``) and in fit's JSON."""


def dataset(
    model: ModelLike,
    frame: pd.DataFrame,
    constants: Mapping[str, float] | None = None,
    stretch: str = "longest",
) -> Dataset:
    """The model's signals from a frame (see :meth:`ZoneModel.signals`) as an estimation data set.

    Parameters
    ----------
    stretch : {"longest", "all"}
        ``"longest"``: where an input has gaps, the longest stretch without any
        (:func:`complete_stretch`; :func:`dataset_note` says which was used); ``"all"``: every
        sample (an input gap is then an error naming the sample).
    """
    zm = as_model(model)
    t, u, m, y = zm.signals(frame_from(frame), constants)
    implausible = zm.implausible_signals(u, m, y)  # every path's data pass here: frame, file, batch
    for line in implausible:
        warnings.warn(line, RczoneWarning, stacklevel=user_stacklevel())
    if stretch == "longest":
        sl = complete_stretch(u, m, y)
        if sl.stop - sl.start < 2:
            bad = [
                n
                for j, n in enumerate((*zm.network.input_names, *zm.network.flow_names))
                if not np.isfinite(np.column_stack([u, m])[:, j]).any()
            ]
            raise DataError(
                "no stretch of at least 2 samples where every input is known"
                + (f" ({', '.join(bad)} never are)" if bad else "")
                + "; check the column map and the data's gaps"
            )
        if (sl.stop - sl.start) < MIN_USED_FRACTION * len(t):
            raise DataError(
                f"only {sl.stop - sl.start} of {len(t)} samples ({(sl.stop - sl.start) / len(t):.0%}) form the"
                " longest stretch where every input is known, less than the"
                f" {MIN_USED_FRACTION:.0%} rczone uses without asking (rczone.calibration.dataset.MIN_USED_FRACTION):"
                " fill the inputs' gaps, hold a missing input constant (--const), or select the stretch"
                " with the column map's [time] start and end"
            )
        t, u, m, y = t[sl], u[sl], m[sl], y[sl]
    elif stretch != "all":
        raise DataError(f"stretch must be 'longest' or 'all', got {stretch!r}")
    net = zm.network
    return Dataset(
        t, u, m if m.shape[1] else None, y, net.input_names, net.flow_names, net.outputs, implausible
    )


@dataclass(frozen=True, eq=False)
class PreparedData:
    """A frame's data set for one model, built once by :func:`prepare` and then passed on unchanged.

    Every function that takes a frame for a model also takes this (the fit, its checks, diagnose,
    the profiles, the predictions, the smoother): given one prepared for the same signals and the
    same constants, it reads its :attr:`dataset` instead of building another.

    Attributes
    ----------
    frame : DataFrame
        The data as given (time stamps, indicators and the channels no signal reads are read from
        it).
    dataset : Dataset
        The model's signals (:func:`dataset`).
    constants : mapping or None
        The inputs held constant instead of read from ``frame``, as given.
    signals : tuple
        The input, flow and output names and input conventions the data set was built for.
    missing : tuple of dict
        The inputs with gaps, when the data set is a stretch of the frame (:func:`missing_inputs`).
    """

    frame: pd.DataFrame
    dataset: Dataset
    constants: Mapping[str, float] | None
    signals: tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...], ModelInputs]
    missing: tuple[dict, ...] = ()

    @property
    def ignored(self) -> tuple[str, ...]:
        """The channels of a column map no signal reads (:func:`ignored_channels`)."""
        return ignored_channels(self.frame)

    @property
    def stretch(self) -> dict[str, object]:
        """The samples used of the frame's (a record with gaps: the longest complete stretch)."""
        data, rows = self.dataset, len(self.frame)
        out: dict[str, object] = {
            "samples": int(data.n_samples),
            "of": rows,
            "fraction": data.n_samples / max(rows, 1),
            "start_s": float(data.t[0]),
            "end_s": float(data.t[-1]),
        }
        if data.n_samples < rows:
            out["missing"] = [dict(m) for m in self.missing]
        return out


def _signature(zm: ZoneModel) -> tuple:
    net = zm.network
    return (tuple(net.input_names), tuple(net.flow_names), tuple(net.outputs), zm.inputs)


def prepare(
    model: ModelLike,
    frame: pd.DataFrame | PreparedData,
    constants: Mapping[str, float] | None = None,
) -> PreparedData:
    """``frame``'s data set for ``model``: built here, or ``frame`` itself when it is already that.

    Parameters
    ----------
    model : ZoneModel, RCNetwork, str or path
    frame : DataFrame or PreparedData
        The data (``time`` in s or a DatetimeIndex, a column per signal), or data prepared before:
        returned as they are when prepared for the same signals and constants (None: the ones it
        was prepared with), else prepared again from their frame.
    constants : mapping, optional
        Inputs held constant (SI units).

    Returns
    -------
    PreparedData
    """
    zm = as_model(model)
    if isinstance(frame, PreparedData):
        constants = frame.constants if constants is None else constants
        if frame.signals == _signature(zm) and _same(frame.constants, constants):
            return frame
        frame = frame.frame
    data = dataset(zm, frame, constants)
    missing = tuple(missing_inputs(zm, frame, constants)) if data.n_samples < len(frame) else ()
    return PreparedData(frame, data, constants, _signature(zm), missing)


def _same(a: Mapping[str, float] | None, b: Mapping[str, float] | None) -> bool:
    return dict(a or {}) == dict(b or {})
