"""Where a zone's data come from: a trend-log file (with an optional column map) or a built-in name.

Shared by the command line, batch calibration and the Python API, so that every entry point
reads a user's data the same way.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from rczone import validation
from rczone.errors import DataError
from rczone.estimation.data import MIN_MEASURED


def read_frame(
    path: str | Path,
    column_map: str | Path | None = None,
    signals: Mapping[str, str] | None = None,
    required: Sequence[str] = (),
    outputs: Sequence[str] = ("Ti",),
) -> pd.DataFrame:
    """A zone's data as a frame in rczone's default columns (SI units, ``time`` in s).

    ``path`` is a CSV or Parquet file in the default columns (``time``, ``Ti``, ``To``, ``Ts``,
    ``m``, ``Q`` and ``Tsd`` or the five surroundings), or any trend log described by a TOML
    ``column_map``. Built-in data sets can be named directly (``A``, ``B``, ``C``). ``signals``
    (name -> quantity, :meth:`rczone.models.ZoneModel.signal_quantities`) are the model's: without a
    map, the columns named as them are read in SI units, and the ``required`` ones must exist. A
    record with fewer than :data:`~rczone.estimation.data.MIN_MEASURED` measured samples of one
    of the ``outputs`` is an error: it would fit anything.
    """
    from rczone.data import load_zone_data

    path = Path(path)
    if not os.path.lexists(path):  # a link that loops exists: its reader says what is wrong
        from rczone import datasets

        if str(path) in datasets.names():
            return datasets.load(str(path))
        raise DataError(
            f"data file {str(path)!r} does not exist (built-in data sets: {', '.join(datasets.names())})"
        )
    frame = load_zone_data(path, column_map, signals=signals, required=required).to_frame()
    validation.measured_outputs(frame, outputs, label=str(path), minimum=MIN_MEASURED)
    return frame


def read_model_frame(path: str | Path, column_map: str | Path | None, model) -> pd.DataFrame:
    """A zone's data for ``model`` (a :class:`~rczone.models.ZoneModel`): its signals, every output checked."""
    return read_frame(
        path, column_map, model.signal_quantities(), model.required_signals(), model.network.outputs
    )
