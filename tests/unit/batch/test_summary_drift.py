"""The run summary lists the calibrations flagged as drifted, whatever dtype the column came back with."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from rczone.batch.summary import _drifted


@pytest.mark.parametrize(
    ("column", "flagged"),
    [
        ([True, None, False], ["a"]),  # object column: None is "not tested"
        ([1.0, np.nan, 0.0], ["a"]),  # float column read back from Parquet
        ([None, None, None], []),
        ([np.nan, np.nan, np.nan], []),
        ([True, False, True], ["a", "c"]),
    ],
)
def test_drifted_rows_are_listed_without_a_pandas_warning(column, flagged):
    ok = pd.DataFrame(
        {"zone": list("abc"), "method": "ml", "drift": column, "drift_since_s": 1.0, "drift_tests": "cusum"}
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # fillna(False) on a float column warned (Pandas4Warning)
        assert [d["zone"] for d in _drifted(ok)] == flagged
