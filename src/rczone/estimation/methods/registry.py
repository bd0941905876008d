"""The estimation methods by name: the built-in ones, those registered in Python, and plug-ins.

Every module that behaves differently per method asks the :class:`~.base.Method` record for the
property it needs instead of comparing method strings. A third party adds a method without editing
rczone, either in Python (:func:`register_method`) or by declaring an entry point in the group
``rczone.methods`` of its package, whose object is a :class:`~.base.Method`::

    [project.entry-points."rczone.methods"]
    huber = "mypackage.huber:METHOD"

Entry points are read once, on the first look-up of a name that is not registered (or when
all names are listed), so a plain ``rczone fit`` imports no plug-in.
"""

from __future__ import annotations

from importlib.metadata import entry_points

from rczone.errors import ParameterError, did_you_mean
from rczone.estimation.methods import kstep, ls, map, mcmc, ml
from rczone.estimation.methods.base import Method

#: Entry-point group of third-party methods.
ENTRY_POINT_GROUP = "rczone.methods"

#: The registered methods by name, built-in ones first (the first is listed first in help texts).
REGISTRY: dict[str, Method] = {
    m.name: m for m in (ls.METHOD, ml.METHOD, map.METHOD, mcmc.METHOD, kstep.METHOD)
}

#: The default method of the command line, the API and the batch manifest.
DEFAULT_METHOD = "ml"

_BUILT_IN = frozenset(REGISTRY)
_plugins_loaded = False


def register_method(method: Method, *, replace: bool = False) -> Method:
    """Register ``method`` under its name, for ``--method NAME`` and ``method=NAME``.

    Parameters
    ----------
    method : Method
        The method record, with its options and ``run``.
    replace : bool
        Replace a method registered under the same name (never a built-in one).

    Returns
    -------
    Method
        ``method`` (so a module can write ``METHOD = register_method(Method(...))``).

    Raises
    ------
    ParameterError
        For an object that is not a :class:`Method`, a built-in name, or a name already taken
        without ``replace``.
    """
    if not isinstance(method, Method):
        raise ParameterError(f"register_method takes a rczone Method, got {type(method).__name__}")
    if method.name in _BUILT_IN:
        raise ParameterError(f"method {method.name!r} is built in; register yours under another name")
    if method.name in REGISTRY and not replace and REGISTRY[method.name] is not method:
        raise ParameterError(f"method {method.name!r} is registered already; pass replace=True to replace it")
    REGISTRY[method.name] = method
    return method


def unregister_method(name: str) -> None:
    """Remove a method registered by :func:`register_method` (never a built-in one)."""
    if name in _BUILT_IN:
        raise ParameterError(f"method {name!r} is built in and cannot be removed")
    REGISTRY.pop(name, None)


def load_plugins() -> None:
    """Register the methods of the entry-point group :data:`ENTRY_POINT_GROUP` (once).

    A plug-in that fails to load, or whose object is not a :class:`Method`, is one
    :class:`~rczone.errors.ParameterError` naming the entry point.
    """
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in REGISTRY:
            continue
        try:
            obj = ep.load()
        except Exception as exc:  # a third party's import error, reported as ours in one line
            raise ParameterError(
                f"the method plug-in {ep.name!r} ({ep.value}) failed to load: {type(exc).__name__}: {exc}"
            ) from None
        if not isinstance(obj, Method):
            raise ParameterError(
                f"the method plug-in {ep.name!r} ({ep.value}) is a {type(obj).__name__}, not a rczone Method"
            )
        if obj.name != ep.name:
            raise ParameterError(
                f"the method plug-in {ep.name!r} ({ep.value}) calls itself {obj.name!r}; the names must agree"
            )
        REGISTRY[obj.name] = obj


def method_names() -> tuple[str, ...]:
    """Every registered method's name (plug-ins included), in registry order."""
    load_plugins()
    return tuple(REGISTRY)


def method_of(name: str) -> Method:
    """The registered method called ``name``.

    Parameters
    ----------
    name : str
        A registered name (built in, :func:`register_method`, or an entry point).

    Returns
    -------
    Method

    Raises
    ------
    ParameterError
        For an unknown name, with the closest known one.
    """
    m = REGISTRY.get(name) if isinstance(name, str) else None
    if m is None and isinstance(name, str):
        load_plugins()
        m = REGISTRY.get(name)
    if m is None:
        known = method_names()
        raise ParameterError(
            f"unknown method {name!r}; {did_you_mean(str(name), known)} (method must be one of"
            f" {', '.join(known)})"
        )
    return m
