"""State and disturbance estimation, a reference MPC and closed-loop tests for fitted zone models.

Modules: :mod:`~rczone.control.noise` (the discrete noise model of a fit),
:mod:`~rczone.control.disturbance` (the appended disturbance state),
:mod:`~rczone.control.model` (the model as a controller sees it, its exact discretization and
derivatives in the flow), :mod:`~rczone.control.observer` (Kalman filter, steady-state gain,
:func:`estimate_state`), :mod:`~rczone.control.energy` (how a zone's fan, reheat and cooling
energy is counted), :mod:`~rczone.control.mpc` (the reference economic MPC, OSQP),
:mod:`~rczone.control.closedloop` (closed-loop tests on the virtual building) and
:mod:`~rczone.control.export` (python-control and plain named arrays).
"""

from rczone.control.disturbance import Disturbance
from rczone.control.energy import ZonePower, zone_power
from rczone.control.export import NamedArrays, named_arrays, to_control
from rczone.control.model import ControlModel, DiscreteMatrices, FlowDerivative
from rczone.control.mpc import MPC, ControlAction, Forecast, MPCSettings, Plan
from rczone.control.noise import NoiseModel
from rczone.control.observer import Estimate, KalmanObserver, StateEstimate, estimate_state

__all__ = [
    "MPC",
    "ControlAction",
    "ControlModel",
    "DiscreteMatrices",
    "Disturbance",
    "Estimate",
    "FlowDerivative",
    "Forecast",
    "KalmanObserver",
    "MPCSettings",
    "NamedArrays",
    "NoiseModel",
    "Plan",
    "StateEstimate",
    "ZonePower",
    "estimate_state",
    "named_arrays",
    "to_control",
    "zone_power",
]
