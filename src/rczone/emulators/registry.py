"""Emulators by name: the buildings a controller can be tested on (issue 34, item 3).

An emulator is a factory ``factory(**options) -> Plant`` (:class:`rczone.control.plant.Plant`):
the emulator owns its options, as a method does. Built in: ``virtual`` (the 152-state virtual
building, :class:`rczone.control.virtualplant.VirtualPlant`: ``season``, ``days``, ``seed``,
``price``, ``comfort_band``, ``forecast``) and ``energyplus`` (an ASHRAE prototype run by
EnergyPlus, :class:`rczone.emulators.plant.EnergyPlusPlant`: ``building``, ``weather``, ``zones``,
``start``, ``days``, ``step_minutes``, ``seed``; the optional extra ``rczone[energyplus]``) and
``house`` (a room heated by an electric heater, :class:`rczone.control.house.HousePlant`:
``days``, ``seed``, ``price``, ``heat_limit``).
:func:`register_emulator` adds one in Python; a package adds one with an entry point of the group
``rczone.emulators`` (:mod:`rczone.control.plugins`).
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from typing import Any

from rczone.control.plant import Plant
from rczone.control.plugins import Registry
from rczone.errors import ParameterError

#: The entry-point group of emulator plug-ins.
ENTRY_POINT_GROUP = "rczone.emulators"


def _lazy(target: str) -> Callable[..., Plant]:
    """A built-in emulator's factory: the class ``"module:Class"``, imported on the first run."""

    def factory(**options: Any) -> Plant:
        return _load(target)(**options)

    factory.target = target  # type: ignore[attr-defined]  (whose constructor takes the options)
    return factory


def _load(target: str) -> Callable[..., Plant]:
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


_BUILTINS = {
    "virtual": _lazy("rczone.control.virtualplant:VirtualPlant"),
    "energyplus": _lazy("rczone.emulators.plant:EnergyPlusPlant"),
    "house": _lazy("rczone.control.house:HousePlant"),
}


def _builtins() -> dict[str, Callable[..., Plant]]:
    return _BUILTINS


#: The emulators by name (:class:`rczone.control.plugins.Registry`).
EMULATORS = Registry("emulator", ENTRY_POINT_GROUP, _builtins)


def register_emulator(name: str, factory: Callable[..., Plant]) -> None:
    """Make ``factory`` available as emulator ``name`` (replacing a registration of that name).

    Parameters
    ----------
    name : str
    factory : callable
        ``factory(**options) -> Plant``.
    """
    EMULATORS.register(name, factory)


def unregister_emulator(name: str) -> None:
    """Remove an emulator registered by :func:`register_emulator`."""
    EMULATORS.unregister(name)


def emulator_names() -> tuple[str, ...]:
    """Every emulator name known: built in, registered and plug-ins, sorted."""
    return EMULATORS.names()


def make_plant(name: str, **options: Any) -> Plant:
    """The plant of emulator ``name`` with its own ``options``.

    Raises
    ------
    ParameterError
        For an unknown name, an option the emulator does not take (naming those it does), or a
        factory that returns no plant.
    """
    factory = EMULATORS.factory(name)
    target = _load(factory.target) if hasattr(factory, "target") else factory
    try:
        params = inspect.signature(target).parameters
    except (TypeError, ValueError):  # a builtin or C callable: let the call decide
        params = {}
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    unknown = sorted(set(options) - set(params)) if params and not takes_any else []
    if unknown:
        allowed = [
            n for n, p in params.items() if p.kind is not inspect.Parameter.VAR_POSITIONAL and n != "self"
        ]
        raise ParameterError(
            f"emulator {name!r} has no option {', '.join(map(repr, unknown))}; it takes {', '.join(allowed)}"
        )
    plant = factory(**options)
    if not isinstance(plant, Plant):
        raise ParameterError(
            f"emulator {name!r}: its factory returned {type(plant).__name__}, which lacks the plant interface"
            " (rczone.control.plant.Plant: measure, step, forecast, constraints, kpis)"
        )
    return plant
