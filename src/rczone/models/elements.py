"""Construction values of the full-scale model: one 3R2C element per surface, the window, Cr.

The paper's full-scale model (Lin et al. 2012, section II, MRC(13, 8, 32)) has one 3R2C element per opaque
surface, a window resistor ``Rwin`` between ``Ti`` and ``To`` and the room capacity ``Cr``. Each
element comes from the surface's construction by a 3R2C split
(:func:`rczone.models.split.split_construction`), scaled by the surface's area.

The hallway door
----------------
The paper's model has no door element, while the zone has a door to the hallway. A massless
resistor ``Ti - Thw`` would add a 33rd parameter and change the model class, and leaving the
door out would change the steady state (for ``office_241`` the door carries about 24 % of the
hallway-side conductance). ``door="fold"`` (the default) therefore folds the door into the element
of the surface whose far side is the door's far side (the hallway wall): every resistance of
that element is multiplied by ``k = R_eff / R_wall`` where ``R_eff = 1 / (1/R_wall + 1/R_door)``
and ``R_wall = R1 + R2 + R3``. This keeps the DC conductance between ``Ti`` and ``Thw`` exact and
the element's split proportions; the element's capacities are unchanged. What it cannot keep
is the door's instantaneous (massless) path: at high frequency the folded element conducts
like its room-side resistance ``k R1`` rather than ``R1`` in parallel with the door.
``door="omit"`` leaves the door out (the literal paper model; DC gains then differ from a zone
with a door).

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from rczone.construction.room import ZoneGeometry
from rczone.errors import ParameterError, did_you_mean
from rczone.models.split import WallSplit, split_construction

#: How the door is treated.
DOOR_OPTIONS = ("fold", "omit")


@dataclass(frozen=True)
class SurfaceElement:
    """The 3R2C element of one surface, whole-surface values (K/W, J/K).

    Attributes
    ----------
    name : str
        Surface name (``"o"``, ``"f"``...), used in parameter names ``R{name}w1``...
    far_side : str
        Input name of the far-side temperature (``"To"``, ``"Tf"``...).
    split : WallSplit
        ``r1`` (room side), ``r2``, ``r3`` in K/W and ``c1`` (room side), ``c2`` in J/K.
    """

    name: str
    far_side: str
    split: WallSplit

    def parameter_values(self) -> dict[str, float]:
        """``{"R{s}w1": r1, "R{s}w2": r2, "R{s}w3": r3, "C{s}w1": c1, "C{s}w2": c2}``."""
        s, e = self.name, self.split
        return {f"R{s}w1": e.r1, f"R{s}w2": e.r2, f"R{s}w3": e.r3, f"C{s}w1": e.c1, f"C{s}w2": e.c2}


def _check_option(value: str, options: Sequence[str], what: str) -> None:
    if value not in options:
        raise ParameterError(
            f"unknown {what} {value!r}; expected one of {', '.join(options)}; " + did_you_mean(value, options)
        )


def surface_elements(
    geometry: ZoneGeometry, split: str = "matched", door: str = "fold"
) -> tuple[SurfaceElement, ...]:
    """The 3R2C element of every surface of ``geometry``, in the geometry's order.

    Parameters
    ----------
    geometry : ZoneGeometry
    split : {"matched", "symmetric"}
        The 3R2C split rule (:mod:`rczone.models.split`).
    door : {"fold", "omit"}
        What to do with ``geometry.door`` (see the module docstring).

    Returns
    -------
    tuple of SurfaceElement
    """
    _check_option(door, DOOR_OPTIONS, "door option")
    out = []
    for s in geometry.surfaces:
        e = split_construction(s.construction, split).scaled(s.area)
        out.append(SurfaceElement(s.name, s.far_side, e))
    if door == "fold" and geometry.door is not None:
        d = geometry.door
        hosts = [i for i, el in enumerate(out) if el.far_side == d.far_side]
        if len(hosts) != 1:
            raise ParameterError(
                f"door {d.name!r} leads to {d.far_side!r}, but {len(hosts)} surfaces have that far side;"
                " folding needs exactly one (use door='omit' or fix the geometry)"
            )
        i = hosts[0]
        el = out[i]
        r_wall = el.split.r_total
        r_eff = 1.0 / (1.0 / r_wall + 1.0 / d.resistance)
        out[i] = SurfaceElement(el.name, el.far_side, el.split.scaled_resistances(r_eff / r_wall))
    return tuple(out)


def full_scale_values(geometry: ZoneGeometry, split: str = "matched", door: str = "fold") -> dict[str, float]:
    """Construction values of the 32 full-scale parameters (``Cr``, ``Rwin``, ``R{s}w1``...).

    ``Cr`` is ``geometry.room_capacity`` (air + furnishings) and ``Rwin`` the window's
    air-to-air resistance.
    """
    vals = {"Cr": geometry.room_capacity, "Rwin": geometry.window.resistance}
    for el in surface_elements(geometry, split, door):
        vals.update(el.parameter_values())
    return vals


def elements_from_values(
    values: Mapping[str, float], surfaces: Sequence[tuple[str, str]]
) -> tuple[SurfaceElement, ...]:
    """Rebuild the surface elements from full-scale parameter values (e.g. a calibrated theta).

    Parameters
    ----------
    values : mapping of str to float
        Must hold ``R{s}w1, R{s}w2, R{s}w3, C{s}w1, C{s}w2`` for every surface ``s``.
    surfaces : sequence of (name, far_side)
    """
    out = []
    for name, far in surfaces:
        keys = [f"R{name}w1", f"R{name}w2", f"R{name}w3", f"C{name}w1", f"C{name}w2"]
        for k in keys:
            if k not in values:
                raise ParameterError(f"full-scale value {k!r} is missing; " + did_you_mean(k, values))
        out.append(SurfaceElement(name, far, WallSplit(*(float(values[k]) for k in keys))))
    return tuple(out)
