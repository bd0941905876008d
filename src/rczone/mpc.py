"""Models ready for model-predictive control: save, load, and matrices for a sample time.

A :class:`ZoneModel` (:mod:`rczone.models.zone`) is a network with parameter values and the
provenance of those values. It writes to and reads from a small JSON file and gives the
continuous or exact discrete LTI matrices at a chosen mass flow (the bilinear model is LTI
for constant flow), as plain numpy arrays (:meth:`ZoneModel.arrays`, :meth:`ZoneModel.discrete`)
or as a python-control ``StateSpace`` (:meth:`ZoneModel.to_control`, optional extra
``rczone[control]``). This module is the MPC-facing entry point; it imports no plotting.

It also re-exports :mod:`rczone.control`: the noise model, the Kalman observer with an optional
disturbance state (:func:`estimate_state`) and the reference economic MPC (:class:`MPC`,
optional extra ``rczone[mpc]`` for its QP solver).

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

from rczone.control import MPC, Disturbance, Forecast, MPCSettings, estimate_state
from rczone.models.zone import FORMAT, DiscreteModel, ZoneModel

__all__ = [
    "FORMAT",
    "MPC",
    "DiscreteModel",
    "Disturbance",
    "Forecast",
    "MPCSettings",
    "ZoneModel",
    "estimate_state",
]
