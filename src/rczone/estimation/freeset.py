"""Which parameters a fit estimates: the default set, the names added to it and the names held.

One rule for ``rczone fit`` (:meth:`rczone.estimation.settings.FitSettings.free_for`) and for every
candidate of ``rczone select`` (:func:`rczone.selection.compare.candidate_settings`): the free
parameters are the ones given, else the method's default set
(:func:`rczone.estimation.fit.default_free`) plus the names written ``+NAME``, less the fixed
ones; every name must be a parameter, noise level or initial state of the network.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from rczone.errors import ParameterError
from rczone.network import RCNetwork

if TYPE_CHECKING:
    from rczone.estimation.settings import FitSettings

#: Start of a ``free`` entry that adds a parameter to the default free set (``"+sigma_w_Te"``).
ADD = "+"


def fixed_value(name: str, value: object) -> float | None:
    """A value to hold ``name`` at: None (the model's) or a finite number.

    Parameters
    ----------
    name : str
        The parameter, for the message.
    value : object
        None or a number.
    """
    if value is None:
        return None
    try:
        if isinstance(value, bool):
            raise TypeError
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"fixed value of {name!r} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ParameterError(f"fixed value of {name!r} must be finite, got {value!r}")
    return v


def check_free_and_fixed(free: Sequence[str] | None, fixed: Mapping[str, object]) -> None:
    """Raise when a name is both free (``NAME`` or ``+NAME``) and fixed.

    Parameters
    ----------
    free : sequence of str or None
    fixed : mapping
    """
    both = [n for n in fixed if n in (free or ()) or ADD + n in (free or ())]
    if both:
        raise ParameterError(f"parameter {both[0]!r} is both free and fixed; choose one")


def resolve_free(network: RCNetwork, settings: FitSettings) -> tuple[str, ...]:
    """The free parameters of a fit of ``network``: ``free`` (or the default, with the ``+`` entries), less ``fixed``.

    Parameters
    ----------
    network : RCNetwork
        The model's network.
    settings : FitSettings
        Its method (the default set: :func:`rczone.estimation.fit.default_free`), its noise
        placement, its ``free`` (the free parameters, or ``"+NAME"`` entries added to the default
        set), its ``fixed`` (names held; their values are not used here) and its ``bounds`` (names
        given search bounds: each must be free).

    Returns
    -------
    tuple of str

    Raises
    ------
    ParameterError
        For a name the network does not have (with the close names), nothing left free, or a
        bound of a parameter the fit does not estimate.
    """
    from rczone.estimation.fit import default_free
    from rczone.estimation.parameters import check_name

    free, fixed, bounds = settings.free, dict(settings.fixed), dict(settings.bounds)
    given = [n for n in (free or ()) if not n.startswith(ADD)]
    added = [n[len(ADD) :] for n in (free or ()) if n.startswith(ADD)]
    for name in (*added, *fixed, *bounds):
        check_name(network, name)
    base = list(given) if given else list(default_free(network, settings.method, noise=settings.noise))
    out = tuple(dict.fromkeys(n for n in (*base, *added) if n not in fixed))
    if not out:
        raise ParameterError("every parameter is fixed: leave at least one free")
    held = [n for n in bounds if n not in out]
    if held:
        raise ParameterError(
            f"bounds given for {held[0]!r}, which this fit does not estimate; free it too"
            f" (--free +{held[0]}, or free=['{ADD}{held[0]}']) or drop the bound"
        )
    return out
