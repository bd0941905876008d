"""Controllers by name: the built-in ones, those registered at run time, and plug-ins.

A controller is made by a *factory* ``factory(plant, options) -> Controller`` from the plant
(:class:`~rczone.control.plant.Plant`) and :class:`ControllerOptions` (the model and the MPC's
settings, for controllers that use them). :func:`register_controller` adds a factory under a
name; a package adds one without being imported by declaring an entry point in the group
``rczone.controllers`` (the name is the entry point's, its object the factory), the mechanism
of the Python packaging specification [1]_. ``rczone control-test --controller NAME`` and
:func:`~rczone.control.closedloop.closed_loop_test` find either.

Built in: ``thermostat`` (the commissioned baseline), ``naive`` (the schedule's set points, no
early start), ``mpc`` (the reference MPC with the given model), ``oracle`` (the MPC with the
plant's own model and state).

References
----------
.. [1] Python Packaging Authority, "Entry points specification",
   packaging.python.org/en/latest/specifications/entry-points/ (the ``[project.entry-points]``
   table of ``pyproject.toml``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rczone.control.mpc import MPCSettings
from rczone.control.plant import Controller, Plant
from rczone.control.plugins import Registry
from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel

#: The entry-point group of controller plug-ins.
ENTRY_POINT_GROUP = "rczone.controllers"


@dataclass(frozen=True)
class ControllerOptions:
    """What a factory may use besides the plant.

    Parameters
    ----------
    model : ZoneModel, optional
        The controller's model (the MPC's).
    settings : MPCSettings, optional
    disturbance : bool
        The MPC's observer estimates an unmeasured heat input (offset-free).
    """

    model: ZoneModel | None = None
    settings: MPCSettings | None = None
    disturbance: bool = True


Factory = Callable[[Plant, ControllerOptions], Controller]


def _builtins() -> dict[str, Factory]:
    """The built-in controllers (imported on the first look-up)."""
    from rczone.control import builtin

    return builtin.FACTORIES


#: The controllers by name (:class:`rczone.control.plugins.Registry`).
CONTROLLERS = Registry("controller", ENTRY_POINT_GROUP, _builtins)


def register_controller(name: str, factory: Factory) -> None:
    """Make ``factory`` available as controller ``name`` (replacing a registration of that name).

    Parameters
    ----------
    name : str
    factory : callable
        ``factory(plant, options) -> Controller``.
    """
    CONTROLLERS.register(name, factory)


def unregister_controller(name: str) -> None:
    """Remove a controller registered by :func:`register_controller`."""
    CONTROLLERS.unregister(name)


def controller_names() -> tuple[str, ...]:
    """Every controller name known: built in, registered and plug-ins, sorted."""
    return CONTROLLERS.names()


def make_controller(name: str, plant: Plant, options: ControllerOptions | None = None) -> Controller:
    """The controller ``name`` for ``plant``.

    Raises
    ------
    ParameterError
        For an unknown name (with the close ones), a plug-in that fails to load, or a factory
        that returns no controller.
    """
    controller = CONTROLLERS.factory(name)(plant, options or ControllerOptions())
    if not isinstance(controller, Controller):
        raise ParameterError(
            f"controller {name!r}: its factory returned {type(controller).__name__}, which lacks act(), "
            "horizon or interval (rczone.control.plant.Controller)"
        )
    return controller
