"""rczone.simulate: a model on data, every node over the data's own time stamps."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import rczone
from rczone.errors import ParameterError


def _frame(n: int = 61, dt_s: float = 600.0, tz: str = "Europe/Copenhagen") -> pd.DataFrame:
    index = pd.date_range("2026-01-10 18:00", periods=n, freq=pd.Timedelta(seconds=dt_s), tz=tz)
    # a step in outdoor temperature halfway: the analytic solution is piecewise exponential
    to = np.where(np.arange(n) < n // 2, 5.0, -3.0)
    return pd.DataFrame({"To": to}, index=index)


def test_one_node_matches_the_analytic_exponential_on_the_data_time_stamps() -> None:
    model = rczone.load_model("Ti")
    tau = model.theta["Ria"] * model.theta["Ci"]  # s
    frame = _frame()
    out = rczone.simulate(model, frame, x0={"Ti": 30.0})
    assert list(out.columns) == ["Ti"]
    assert out.index.equals(frame.index.rename(out.index.name))  # same stamps, same time zone
    assert str(out.index.tz) == "Europe/Copenhagen"
    t = (frame.index - frame.index[0]).total_seconds().to_numpy()
    k = len(t) // 2
    first = 5.0 + (30.0 - 5.0) * np.exp(-t[: k + 1] / tau)
    second = -3.0 + (first[-1] + 3.0) * np.exp(-(t[k:] - t[k]) / tau)
    expected = np.concatenate([first, second[1:]])
    np.testing.assert_allclose(out["Ti"].to_numpy(), expected, rtol=1e-9, atol=1e-9)


def test_without_x0_the_model_starts_at_its_steady_state() -> None:
    out = rczone.simulate("Ti", _frame())
    assert out["Ti"].iloc[0] == pytest.approx(5.0)


def test_options_are_keyword_only_and_a_bad_node_is_one_clear_error() -> None:
    with pytest.raises(TypeError):
        rczone.simulate("Ti", _frame(), {"Ti": 30.0})  # type: ignore[misc]
    with pytest.raises(ParameterError, match="not a node of model"):
        rczone.simulate("Ti", _frame(), x0={"Tw": 30.0})


def test_a_measured_node_starts_at_its_first_measurement() -> None:
    """The analytic one-node decay from the measured start (x0 still wins where given)."""
    model = rczone.load_model("Ti")
    tau = model.theta["Ria"] * model.theta["Ci"]
    frame = _frame().assign(Ti=21.0)
    out = rczone.simulate(model, frame)
    assert out["Ti"].iloc[0] == 21.0
    t = (frame.index[1] - frame.index[0]).total_seconds()
    assert out["Ti"].iloc[1] == pytest.approx(5.0 + 16.0 * np.exp(-t / tau), rel=1e-9)
    assert rczone.simulate(model, frame, x0={"Ti": 30.0})["Ti"].iloc[0] == 30.0
    assert rczone.simulate(model, frame.assign(Ti=np.nan))["Ti"].iloc[0] == pytest.approx(5.0)


def test_a_built_in_data_set_is_named_by_its_name() -> None:
    from rczone.workflow.datasource import frame_and_label

    zm = rczone.load_model("second-order-paper")
    assert frame_and_label(rczone.load_data("C"), None, zm)[1] == "C"
