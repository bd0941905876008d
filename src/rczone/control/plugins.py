"""Named factories of one kind: built in, registered at run time, or installed as plug-ins.

Controllers (:mod:`rczone.control.registry`) and emulators (:mod:`rczone.emulators.registry`) are
looked up by name the same way: a name registered in Python wins, then a built-in one, then an
entry point of the kind's group in an installed package (the mechanism of the Python packaging
specification [1]_), loaded only when its name is asked for, so that a plain command imports no
plug-in. A third party adds one without editing rczone::

    [project.entry-points."rczone.emulators"]
    mybuilding = "mypackage.plant:MyPlant"

References
----------
.. [1] Python Packaging Authority, "Entry points specification",
   packaging.python.org/en/latest/specifications/entry-points/ (the ``[project.entry-points]``
   table of ``pyproject.toml``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from importlib.metadata import entry_points
from typing import Any

from rczone.errors import ParameterError, did_you_mean


class Registry:
    """The factories of one kind by name.

    Parameters
    ----------
    kind : str
        What the factories make, in messages (``"controller"``, ``"emulator"``).
    group : str
        The entry-point group of plug-ins (``"rczone.controllers"``).
    builtins : callable
        Returns the built-in factories by name; called on the first look-up (the modules that
        define them are imported then, not when the registry is).
    """

    def __init__(self, kind: str, group: str, builtins: Callable[[], Mapping[str, Callable[..., Any]]]):
        self.kind = kind
        self.group = group
        self._builtins = builtins
        self._registered: dict[str, Callable[..., Any]] = {}

    def register(self, name: str, factory: Callable[..., Any]) -> None:
        """Make ``factory`` available under ``name`` (replacing a registration of that name)."""
        if not (isinstance(name, str) and name.strip() and name.isprintable()):
            raise ParameterError(f"a {self.kind} name must be a non-empty printable string, got {name!r}")
        if not callable(factory):
            raise ParameterError(f"the factory of {self.kind} {name!r} must be callable, got {factory!r}")
        self._registered[name] = factory

    def unregister(self, name: str) -> None:
        """Remove a registration made by :meth:`register` (a built-in name stays)."""
        self._registered.pop(name, None)

    def _plugins(self) -> dict[str, Any]:
        return {ep.name: ep for ep in entry_points(group=self.group)}

    def names(self) -> tuple[str, ...]:
        """Every name known: built in, registered and plug-ins, sorted."""
        return tuple(sorted({*self._builtins(), *self._registered, *self._plugins()}))

    def factory(self, name: str) -> Callable[..., Any]:
        """The factory called ``name``.

        Raises
        ------
        ParameterError
            For an unknown name (with the close ones) or a plug-in that fails to load.
        """
        found = self._registered.get(name) or self._builtins().get(name)
        if found is not None:
            return found
        ep = self._plugins().get(name)
        if ep is None:
            raise ParameterError(f"unknown {self.kind} {name!r}; " + did_you_mean(str(name), self.names()))
        try:
            return ep.load()
        except Exception as exc:  # a plug-in's import error is the user's to fix, in one line
            raise ParameterError(
                f"{self.kind} plug-in {name!r} ({ep.value}) failed to load: {type(exc).__name__}: {exc}"
            ) from None
