"""Built-in data sets: nights of the rczone virtual building standing in for the paper's data.

The paper's measurements (Pugh Hall room 241, University of Florida) are not public.
rczone ships three nights of its virtual building (:mod:`rczone.virtual`) that reproduce
the situations the paper studies:

* ``"A"``: summer night, normal closed-loop control (the room follows its surroundings);
* ``"B"``: winter night, normal closed-loop control;
* ``"C"``: autumn night, forced-response test (the room is driven several K away from its
  surroundings).

Each is 6 pm to 6 am at 1-minute samples (720 rows) in rczone's default columns
``time, Ti, To, Ts, m, Q, Tf, Tc, Tn1, Tn2, Thw, Tsd`` (s, degC, kg/s, W). The files in
``data/`` are regenerated exactly by ``python -m rczone.datasets.generate --out DIR``.

Examples
--------
>>> from rczone import datasets
>>> datasets.names()
('A', 'B', 'C')
>>> datasets.load("A").shape
(720, 12)
"""

from __future__ import annotations

from importlib import resources

import pandas as pd

from rczone.errors import DataError, did_you_mean
from rczone.virtual.scenarios import COLUMNS, SCENARIOS

__all__ = ["describe", "load", "names"]


def names() -> tuple[str, ...]:
    """Names of the built-in data sets."""
    return tuple(SCENARIOS)


def describe(name: str) -> str:
    """One-line description of data set ``name``."""
    return SCENARIOS[_check(name)].description


def _check(name: str) -> str:
    if name not in SCENARIOS:
        raise DataError(
            f"unknown built-in data set {name!r}; "
            + did_you_mean(name, SCENARIOS)
            + " (see rczone.datasets.names())"
        )
    return name


def load(name: str) -> pd.DataFrame:
    """Load built-in data set ``name`` (``"A"``, ``"B"`` or ``"C"``).

    Parameters
    ----------
    name : str

    Returns
    -------
    pandas.DataFrame
        720 rows, columns ``time, Ti, To, Ts, m, Q, Tf, Tc, Tn1, Tn2, Thw, Tsd``; ``df.attrs``
        holds the name (the data's label in results), the scenario, season, mode, seed and description.

    Raises
    ------
    DataError
        Unknown name (with the closest names).
    """
    s = SCENARIOS[_check(name)]
    with resources.files("rczone.datasets").joinpath("data", f"{name}.csv").open(encoding="utf-8") as fh:
        df = pd.read_csv(fh)
    if tuple(df.columns) != COLUMNS:
        raise DataError(
            f"built-in data set {name!r} has columns {list(df.columns)}, expected {list(COLUMNS)};"
            " the package data is damaged, reinstall rczone or regenerate with"
            " 'python -m rczone.datasets.generate'"
        )
    df.attrs.update(
        {
            "name": name,  # the data's name in titles and the JSON, and the hints' `rczone fit C`
            "scenario": name,
            "description": s.description,
            "season": s.season,
            "mode": s.mode,
            "seed": s.seed,
            "source": "rczone virtual building",
        }
    )
    return df
