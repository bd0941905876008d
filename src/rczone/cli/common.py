"""Helpers shared by CLI commands: reading a zone's data and choosing a model."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from rczone.errors import DataError
from rczone.models import get_model
from rczone.network import RCNetwork


def read_frame(path: Path, column_map: Path | None = None) -> pd.DataFrame:
    """A zone's data as a frame in rczone's default columns (SI units, ``time`` in s).

    ``path`` is a CSV or Parquet file in the default columns (``time``, ``Ti``, ``To``, ``Ts``,
    ``m``, ``Q`` and ``Tsd`` or the five surroundings), or any trend log described by a TOML
    ``column_map``. Built-in data sets can be named directly (``A``, ``B``, ``C``).
    """
    from rczone.data import load_zone_data

    if not path.exists():
        from rczone import datasets

        if str(path) in datasets.names():
            return datasets.load(str(path))
        raise DataError(
            f"data file {str(path)!r} does not exist (built-in data sets: {', '.join(datasets.names())})"
        )
    return load_zone_data(path, column_map).to_frame()


def model(name: str) -> RCNetwork:
    """A model by registry name (``second-order-paper``, ``second-order``, ``first-order``, ``full-scale``)."""
    return get_model(name)
