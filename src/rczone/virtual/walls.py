"""Fine-resolution RC walls built from construction layers (the virtual building's "truth").

A wall of :class:`~rczone.construction.materials.Construction` between two temperature
nodes is discretized far finer than any model under test: every massive layer is cut into
``ceil(d / max_slice)`` equal slices (``max_slice = 2 cm`` by default), each slice a
capacitive node at its centre holding ``rho c (d/n) A`` J/K; between two neighbouring
slice centres sits the series resistance of the two half slices plus any massless
elements between them (air spaces, ``fixed_r``). The surface films are resistors
from the end nodes to the adjacent air nodes. So the wall's air-to-air DC resistance is
exactly ``r_total / A`` (the construction's value), while its dynamics are those of a
~10-node ladder rather than the 3R2C of the paper's models.

References
----------
.. [1] ASHRAE Handbook - Fundamentals, 2005, ch. 30 (layer data, film resistances).
.. [2] Y. Lin, T. Middelkoop, P. Barooah, IEEE CDC 2012: a wall is modelled there as
   3R2C; the ladder here is the standard finite-volume refinement of that model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rczone.construction.materials import Construction, Material
from rczone.errors import ParameterError
from rczone.network import Node, RCNetwork, Resistor

#: Largest slice of a massive layer, m (the task's "<= 2 cm" fine resolution).
MAX_SLICE = 0.02


@dataclass(frozen=True)
class WallLadder:
    """Nodes and resistors of one fine wall between ``a`` (far side) and ``b`` (room side).

    Attributes
    ----------
    nodes : tuple of Node
        Slice nodes, far side first (all capacitive).
    resistors : tuple of Resistor
        Series chain ``a - n1 - ... - nk - b``.
    """

    nodes: tuple[Node, ...]
    resistors: tuple[Resistor, ...]


def wall_ladder(
    prefix: str, construction: Construction, area: float, a: str, b: str, max_slice: float = MAX_SLICE
) -> WallLadder:
    """Discretize ``construction`` of ``area`` m2 between nodes ``a`` (far side) and ``b``.

    Parameters
    ----------
    prefix : str
        Node name prefix; nodes are ``f"{prefix}_{i}"``, i = 1..k from the far side.
    construction : Construction
        Layers far side first, with films.
    area : float
        m2.
    a, b : str
        Far-side and room-side node (or boundary) names.
    max_slice : float
        Largest slice thickness, m.

    Returns
    -------
    WallLadder
    """
    if not area > 0:
        raise ParameterError(f"wall {prefix!r}: area must be > 0 m2, got {area!r}")
    if not max_slice > 0:
        raise ParameterError(f"wall {prefix!r}: max_slice must be > 0 m, got {max_slice!r}")
    # Sequence of (per-area resistance before the node, per-area capacity of the node).
    pending_r = construction.film_out
    slices: list[tuple[float, float]] = []
    for mat in construction.layers:
        if mat.fixed_r is not None or mat.c == 0.0:
            pending_r += mat.r
            continue
        n = max(1, math.ceil(mat.thickness / max_slice - 1e-9))
        r_slice = mat.r / n
        c_slice = mat.c / n
        for _ in range(n):
            slices.append((pending_r + r_slice / 2, c_slice))
            pending_r = r_slice / 2
    pending_r += construction.film_in
    if not slices:
        raise ParameterError(f"wall {prefix!r}: construction {construction.name!r} has no massive layer")
    nodes = tuple(Node(f"{prefix}_{i + 1}", c * area) for i, (_, c) in enumerate(slices))
    names = [a, *(n.name for n in nodes), b]
    rs = [r for r, _ in slices] + [pending_r]
    resistors = tuple(Resistor(names[i], names[i + 1], r / area) for i, r in enumerate(rs))
    return WallLadder(nodes, resistors)


def wall_network(construction: Construction, area: float, max_slice: float = MAX_SLICE) -> RCNetwork:
    """A stand-alone fine wall between boundary temperatures ``"Ta"`` (far side) and ``"Tb"``."""
    lad = wall_ladder("w", construction, area, "Ta", "Tb", max_slice)
    return RCNetwork(
        f"fine wall {construction.name}", lad.nodes, ("Ta", "Tb"), lad.resistors, outputs=(lad.nodes[0].name,)
    )


def perturb_construction(construction: Construction, rng: np.random.Generator, spread: float) -> Construction:
    """A copy with every layer's conductivity (or air-space resistance) scaled by U(1-spread, 1+spread).

    Densities are scaled by U(1 - spread/3, 1 + spread/3): masses are better known than
    conductivities (moisture, ageing, workmanship affect conductivity most).
    """
    layers: list[Material] = []
    for m in construction.layers:
        f = float(rng.uniform(1 - spread, 1 + spread))
        if m.fixed_r is not None:
            layers.append(
                Material(m.name, m.thickness, m.conductivity, m.density, m.specific_heat, m.fixed_r / f)
            )
        else:
            g = float(rng.uniform(1 - spread / 3, 1 + spread / 3))
            layers.append(Material(m.name, m.thickness, m.conductivity * f, m.density * g, m.specific_heat))  # type: ignore[operator]
    return Construction(construction.name, tuple(layers), construction.film_out, construction.film_in)
