"""Built-in data sets: loading, errors, and exact regeneration of the shipped files."""

from __future__ import annotations

from importlib import resources

import numpy as np
import pandas as pd
import pytest

from rczone import datasets
from rczone.datasets.generate import main
from rczone.errors import DataError
from rczone.virtual.scenarios import COLUMNS


def test_names():
    assert datasets.names() == ("A", "B", "C")


@pytest.mark.parametrize("name", ["A", "B", "C"])
def test_load(name):
    df = datasets.load(name)
    assert tuple(df.columns) == COLUMNS
    assert df.shape == (720, 12)
    assert df.attrs["scenario"] == name
    assert df["time"].iloc[-1] == 43140
    assert np.isfinite(df.to_numpy(dtype=float)).all()
    assert datasets.describe(name) == df.attrs["description"]


def test_shipped_files_are_small():
    folder = resources.files("rczone.datasets").joinpath("data")
    for name in datasets.names():
        assert len(folder.joinpath(f"{name}.csv").read_bytes()) < 200_000
    assert "python -m rczone.datasets.generate" in folder.joinpath("README.md").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("name", "match"),
    [("a", "did you mean 'A'"), ("D", "unknown built-in data set 'D'"), ("summer", "rczone.datasets.names")],
)
def test_unknown_name(name, match):
    with pytest.raises(DataError, match=match):
        datasets.load(name)


def test_regeneration_reproduces_shipped_files(tmp_path, capsys):
    main(["--out", str(tmp_path)])
    assert "A.csv" in capsys.readouterr().out
    for name in datasets.names():
        shipped = datasets.load(name)
        fresh = pd.read_csv(tmp_path / f"{name}.csv")
        assert tuple(fresh.columns) == COLUMNS
        # to the printed precision (4 decimals)
        np.testing.assert_allclose(fresh.to_numpy(float), shipped.to_numpy(float), rtol=0, atol=1.01e-4)
