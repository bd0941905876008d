"""The MPC-facing entry point: fitted zone models, state and disturbance estimation, a reference MPC.

A :class:`ZoneModel` (:mod:`rczone.models.zone`, re-exported here) is a network with parameter values
and their provenance; it saves to and loads from a small JSON file and gives the continuous or exact
discrete LTI matrices at a chosen mass flow (the bilinear model is LTI for constant flow), as numpy
arrays or a python-control ``StateSpace``. Importing this package loads no plotting library.

Modules: :mod:`~rczone.control.noise` (the discrete noise model of a fit),
:mod:`~rczone.control.disturbance` (the appended disturbance state),
:mod:`~rczone.control.model` (the model as a controller sees it, its exact discretization and
derivatives in the flow), :mod:`~rczone.control.observer` (Kalman filter, steady-state gain,
:func:`estimate_state`), :mod:`~rczone.control.energy` (how a zone's fan, reheat and cooling
energy is counted), :mod:`~rczone.control.mpc` (the reference economic MPC, OSQP),
:mod:`~rczone.control.constraints` (a zone's limits), :mod:`~rczone.control.plant` (the plant and
controller protocols), :mod:`~rczone.control.virtualplant` (the virtual building as a plant),
:mod:`~rczone.control.controllers` and :mod:`~rczone.control.registry` (controllers by name,
plug-ins), :mod:`~rczone.control.closedloop` (closed-loop tests) and
:mod:`~rczone.control.export` (python-control and plain named arrays).

Examples
--------
The one-node family model ``Ti`` (room capacity ``Ci`` behind ``Ria`` to outdoors) at 10-min steps:
its discrete pole is ``exp(-dt / (Ria Ci))``, and a model with supply air needs its operating flow.

>>> import numpy as np
>>> from rczone.models import load_model
>>> zm = load_model("Ti")
>>> d = zm.discrete(600.0)
>>> bool(np.isclose(d.Ad[0, 0], np.exp(-600.0 / (zm.theta["Ria"] * zm.theta["Ci"]))))
True
>>> load_model("second-order-paper").discrete(600.0, m=0.1).Ad.shape
(2, 2)
"""

from rczone.control.constraints import ZoneConstraints
from rczone.control.disturbance import Disturbance
from rczone.control.energy import ZonePower, zone_power
from rczone.control.export import NamedArrays, named_arrays, to_control
from rczone.control.model import ControlModel, DiscreteMatrices, FlowDerivative
from rczone.control.mpc import MPC, ControlAction, Forecast, MPCSettings, Plan
from rczone.control.noise import NoiseModel
from rczone.control.observer import KalmanObserver, StateEstimate, StateMoments, estimate_state
from rczone.control.plant import Controller, Plant
from rczone.control.registry import ControllerOptions, controller_names, make_controller, register_controller
from rczone.models.zone import FORMAT, DiscreteModel, ZoneModel

__all__ = [
    "FORMAT",
    "MPC",
    "ControlAction",
    "ControlModel",
    "Controller",
    "ControllerOptions",
    "DiscreteMatrices",
    "DiscreteModel",
    "Disturbance",
    "FlowDerivative",
    "Forecast",
    "KalmanObserver",
    "MPCSettings",
    "NamedArrays",
    "NoiseModel",
    "Plan",
    "Plant",
    "StateEstimate",
    "StateMoments",
    "ZoneConstraints",
    "ZoneModel",
    "ZonePower",
    "controller_names",
    "estimate_state",
    "make_controller",
    "named_arrays",
    "register_controller",
    "to_control",
    "zone_power",
]
