from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rczone.errors import DataError, InputShapeError
from rczone.estimation import Dataset

from .nets import NET2, data2

NAMES = dict(input_names=("To", "Q"), flow_names=(), output_names=("Ti",))
T = np.arange(4) * 60.0
U = np.ones((4, 2))
Y = np.ones((4, 1))


@pytest.mark.parametrize(
    ("kwargs", "err", "match"),
    [
        ({"u": np.ones((3, 2))}, InputShapeError, r"u must have shape \(n_samples, 2\) = \(4, 2\)"),
        ({"u": np.ones((4, 3))}, InputShapeError, r"columns \['To', 'Q'\], got \(4, 3\)"),
        ({"y": np.ones((5, 1))}, InputShapeError, r"y must have shape .* got \(5, 1\)"),
        ({"y": np.full((4, 1), np.inf)}, InputShapeError, "infinite"),
        ({"y": np.full((4, 1), np.nan)}, DataError, "all NaN"),
        (
            {"u": np.where(np.eye(4, 2) > 0, np.nan, 1.0)},
            DataError,
            r"input 'To' is missing \(NaN or infinite\) at 1 of 4 samples, first at t = 0 s \(sample 0\);"
            " inputs must be complete",
        ),
        ({"t": np.array([0.0, 60.0, 60.0, 120.0])}, InputShapeError, "strictly increasing"),
        ({"m": np.ones((4, 1))}, InputShapeError, r"m must have shape \(n_samples, 0\)"),
    ],
)
def test_bad_datasets_raise(kwargs, err, match) -> None:
    args = {"t": T, "u": U, "m": np.zeros((4, 0)), "y": Y, **NAMES, **kwargs}
    with pytest.raises(err, match=match):
        Dataset(**args)


def test_dataset_is_read_only_and_from_frame_picks_columns() -> None:
    d = data2(n=10)
    with pytest.raises(ValueError, match="read-only"):
        d.y[0, 0] = 1.0
    df = pd.DataFrame(
        {"Ti": d.y[:, 0], "junk": 0.0, "m": d.m[:, 0], **{n: d.u[:, i] for i, n in enumerate(d.input_names)}}
    )
    df.index = pd.date_range("2011-10-24 18:00", periods=10, freq="10min")
    d2 = Dataset.from_frame(df, NET2)
    np.testing.assert_allclose(d2.t, d.t)
    np.testing.assert_array_equal(d2.u, d.u)
    with pytest.raises(DataError, match=r"no column 'Tsd'.*did you mean"):
        Dataset.from_frame(df.rename(columns={"Tsd": "Tsd_"}), NET2)


def test_check_against_names_mismatch() -> None:
    d = Dataset(T, U, np.zeros((4, 0)), Y, **NAMES)
    with pytest.raises(InputShapeError, match=r"data inputs \['To', 'Q'\] do not match network 'two'"):
        d.check_against(NET2)
