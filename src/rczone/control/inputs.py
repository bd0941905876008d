"""A model's inputs as a controller sees them: their roles, and a forecast in the model's own order.

Every input of a zone model plays one of three roles for a controller (the distinction of
Maciejowski [1]_, section 2.1: manipulated inputs, measured and unmeasured disturbances):

* ``actuator``: decided by the controller (the supply flow's temperature, a heater's power);
* ``measured``: a disturbance measured or forecast (outdoor temperature, irradiance, the
  temperatures of neighbouring spaces);
* ``unmeasured``: a disturbance nobody measures (internal gains): the model's default value is
  used, and an observer's disturbance state (:mod:`rczone.control.disturbance`) takes up the rest.

A model file may declare them (``inputs.roles`` of the JSON, :class:`rczone.models.zone.ModelInputs`);
:func:`input_roles` completes the declaration by the model's conventions, and :func:`model_inputs`
builds the forecast of every non-actuator input, in the model's input order, from named series
(a column of the input's name, the mean of the columns of its ``mean_of`` convention, or its
default).

References
----------
.. [1] J. M. Maciejowski, *Predictive Control with Constraints*, Prentice Hall, 2002.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import replace

import numpy as np

from rczone.errors import InputShapeError, ParameterError, did_you_mean
from rczone.models.zone import INPUT_ROLES, ZoneModel

__all__ = ["INPUT_ROLES", "input_roles", "model_inputs", "with_input_roles"]


def with_input_roles(model: ZoneModel, roles: Mapping[str, str]) -> ZoneModel:
    """A copy of ``model`` whose file declares ``roles`` (added to those it has); saved with it."""
    names = model.state_space().input_names
    for name, role in roles.items():
        if name not in names:
            raise ParameterError(
                f"input role for {name!r}: the model has no such input; " + did_you_mean(name, names)
            )
        if role not in INPUT_ROLES:
            raise ParameterError(
                f"input role of {name!r} must be one of {', '.join(INPUT_ROLES)}, got {role!r}"
            )
    return replace(model, inputs=replace(model.inputs, roles={**model.inputs.roles, **roles}))


def input_roles(model: ZoneModel, decided: Iterable[str] = ()) -> dict[str, str]:
    """The role of every input, in the model's order.

    Declared roles first; then ``decided`` inputs and supply-air temperatures are actuators,
    inputs with a default value unmeasured, the others measured.
    """
    net = model.network
    decided = set(decided) | {s.temperature for s in net.supply_air}
    roles = {}
    for name in model.state_space().input_names:
        declared = model.inputs.roles.get(name)
        if declared is not None:
            roles[name] = declared
        elif name in decided:
            roles[name] = "actuator"
        else:
            roles[name] = "unmeasured" if name in model.inputs.defaults else "measured"
    return roles


def model_inputs(
    model: ZoneModel, series: Mapping[str, np.ndarray], steps: int, *, decided: Iterable[str] = ()
) -> dict[str, np.ndarray]:
    """The forecast of every input that is not an actuator, ``steps`` values each, in the model's order.

    Parameters
    ----------
    model : ZoneModel
    series : mapping of str to array
        Named forecasts (SI), each of ``steps`` values or more, or one value (held).
    steps : int
    decided : iterable of str
        Inputs the controller decides besides those the model declares.

    Raises
    ------
    InputShapeError
        For a measured input with no series (naming what would do).
    """
    out = {}
    for name, role in input_roles(model, decided).items():
        if role == "actuator":
            continue
        cols = model.inputs.mean_of.get(name, ())
        if name in series:
            out[name] = _held(series[name], steps, name)
        elif cols and all(c in series for c in cols):
            out[name] = np.mean([_held(series[c], steps, c) for c in cols], axis=0)
        elif name in model.inputs.defaults:
            out[name] = np.full(steps, model.inputs.defaults[name])
        else:
            hint = (
                f"or the columns {', '.join(cols)} (their mean)"
                if cols
                else "or declare it unmeasured with a default"
            )
            raise InputShapeError(
                f"no forecast of the {role} input {name!r} of model {model.name!r}: give a series {name!r} {hint}"
            )
    return out


def _held(values: np.ndarray | float, steps: int, name: str) -> np.ndarray:
    v = np.atleast_1d(np.asarray(values, float))
    if v.size == 1:
        return np.full(steps, float(v[0]))
    if v.size < steps:
        raise InputShapeError(f"the forecast of {name!r} has {v.size} values, {steps} needed")
    return v[:steps]
