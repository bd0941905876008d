import numpy as np
import pandas as pd
import pytest

from rczone.diagnostics import data_indicators
from rczone.errors import DataError


def frame():
    t = np.arange(0, 4 * 3600 + 1, 60.0)
    ti = 22 + np.sin(t / 3000)
    m = np.where(t < 7200, 0.05, 0.12)
    df = pd.DataFrame({"time": t, "Ti": ti, "Tn1": ti + 0.5, "Tc": 20.0 + 0 * t, "m": m, "Ts": 13 + 0 * t})
    df.loc[10:14, "Ti"] = np.nan
    return df


def test_indicators_measure_differences_correlation_and_flow_stretches():
    ind = data_indicators(frame(), "Ti", surroundings=("Tn1", "Tc", "Tf"), inputs=("m", "Ts", "Q"), flow="m")
    n1 = ind.surrounding("Tn1")
    assert n1.max_abs_diff_K == pytest.approx(0.5) and n1.median_abs_diff_K == pytest.approx(0.5)
    assert n1.correlation == pytest.approx(1.0) and n1.std_diff_K == pytest.approx(0.0, abs=1e-12)
    c = ind.surrounding("Tc")
    assert np.isnan(c.correlation)  # a constant surrounding has no correlation
    assert c.max_abs_diff_K == pytest.approx(3.0, abs=1e-3)
    assert [(a, b, mm) for a, b, mm in ind.constant_flow_stretches] == [
        (0.0, 7140.0, 0.05),
        (7200.0, 14400.0, 0.12),
    ]
    assert ind.gaps == ((540.0, 900.0),)
    assert {i.name for i in ind.inputs} == {"m", "Ts"}
    assert ind.to_dict()["surroundings"]["Tn1"]["max_abs_diff_K"] == pytest.approx(0.5)


def test_missing_required_column():
    with pytest.raises(DataError, match=r"no 'Ti' column; did you mean 'ti'"):
        data_indicators(pd.DataFrame({"time": [0.0, 1.0], "ti": [1.0, 2.0]}))
    with pytest.raises(DataError, match=r"no 'Tz' column"):
        data_indicators(frame(), output="Tz")


def test_any_output_and_no_flow():
    ind = data_indicators(frame().rename(columns={"Ti": "T_room"}), "T_room", surroundings=("Tn1",))
    assert ind.surrounding("Tn1").max_abs_diff_K == pytest.approx(0.5)
    assert ind.constant_flow_stretches == () and ind.inputs == ()
    with pytest.raises(DataError, match=r"no indicator for 'Tn2'"):
        data_indicators(frame(), surroundings=("Tn1",)).surrounding("Tn2")
