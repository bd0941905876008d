"""The calibration workflow: data frame in, fitted model, its checks and its predictions out.

Three concepts, a module each: :mod:`~rczone.calibration.dataset` (a model's signals picked
from a frame by name, on the frame's time axis), :mod:`~rczone.calibration.calibration` (the
fit from the model's values and its open-loop and residual checks, :class:`Calibration`) and
:mod:`~rczone.calibration.prediction` (open-loop and k-step predictions with a band,
:class:`Prediction`). The network is never modified; fitted values live in a new
:class:`~rczone.models.zone.ZoneModel`.
"""

from rczone.calibration.calibration import Calibration, calibrate, parameter_covariance
from rczone.calibration.dataset import (
    ModelLike,
    PreparedData,
    as_model,
    complete_stretch,
    dataset,
    frame_from,
    prepare,
    time_index,
)
from rczone.calibration.prediction import (
    INITIAL_STATES,
    Prediction,
    noise_values,
    predict,
    prediction,
    saved_covariance,
)

__all__ = [
    "INITIAL_STATES",
    "Calibration",
    "ModelLike",
    "Prediction",
    "PreparedData",
    "as_model",
    "calibrate",
    "complete_stretch",
    "dataset",
    "frame_from",
    "noise_values",
    "parameter_covariance",
    "predict",
    "prediction",
    "prepare",
    "saved_covariance",
    "time_index",
]
