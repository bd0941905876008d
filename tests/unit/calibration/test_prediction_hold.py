"""A prediction holds the inputs between samples as the model was fitted (issue 22, CLI parity)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lsim

from rczone.calibration import prediction
from rczone.errors import DataError
from rczone.models import load_model


@pytest.fixture(scope="module")
def ramp():
    """One node (Ti behind Ria to To), outdoor air ramping linearly between hourly samples.

    scipy's ``lsim`` interpolates the input linearly between samples: the exact response to a
    first-order hold, computed independently of rczone.
    """
    zm = load_model("Ti")
    tau = zm.theta["Ria"] * zm.theta["Ci"]
    t = np.arange(0.0, 12 * 3600.0 + 1, 3600.0)
    to = 5.0 + 10.0 * np.sin(2 * np.pi * t / 86400.0)
    _, y, _ = lsim(([1.0 / tau], [1.0, 1.0 / tau]), to, t, X0=[20.0 * tau])
    frame = pd.DataFrame({"time": t, "Ti": y, "To": to})
    return zm, frame, y


def test_the_model_s_recorded_hold_is_the_default(ramp) -> None:
    zm, frame, exact = ramp
    foh = dataclasses.replace(zm, provenance={**zm.provenance, "hold": "foh"})
    by_record = prediction(foh, frame, parameters=False)
    np.testing.assert_allclose(by_record.predicted[:, 0], exact, rtol=0, atol=1e-9)
    held = prediction(zm, frame, parameters=False)  # no record: inputs held over each interval
    assert np.max(np.abs(held.predicted[:, 0] - exact)) > 0.05
    forced = prediction(foh, frame, parameters=False, hold="zoh")
    np.testing.assert_allclose(forced.predicted, held.predicted, rtol=0, atol=1e-12)


def test_an_unknown_hold_is_one_clear_error(ramp) -> None:
    zm, frame, _ = ramp
    with pytest.raises(DataError, match="hold must be one of zoh, foh"):
        prediction(zm, frame, hold="cubic")
