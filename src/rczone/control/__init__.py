"""State and disturbance estimation, a reference MPC and closed-loop tests for fitted zone models.

Modules: :mod:`~rczone.control.noise` (the discrete noise model of a fit),
:mod:`~rczone.control.disturbance` (the appended disturbance state),
:mod:`~rczone.control.model` (the model as a controller sees it, its exact discretization and
derivatives in the flow), :mod:`~rczone.control.observer` (Kalman filter, steady-state gain,
:func:`estimate_state`).
"""

from rczone.control.disturbance import Disturbance
from rczone.control.model import ControlModel, DiscreteMatrices, FlowDerivative
from rczone.control.noise import NoiseModel
from rczone.control.observer import Estimate, KalmanObserver, StateEstimate, estimate_state

__all__ = [
    "ControlModel",
    "DiscreteMatrices",
    "Disturbance",
    "Estimate",
    "FlowDerivative",
    "KalmanObserver",
    "NoiseModel",
    "StateEstimate",
    "estimate_state",
]
