"""Parallel aggregation of the full-scale construction values into the low-order parameters.

Lin et al. 2012, section III: "the surfaces that are aggregated to form the
integrated wall are parallel components, so that the total capacitance is the sum of the
capacitances of each surface and the total conductance the sum of their conductances". The
paper does not say more; rczone's exact rule is below. ``R*`` is a surface element's series
resistance ``R*w1 + R*w2 + R*w3`` (K/W, the hallway door already folded in, see
:mod:`rczone.models.elements`), ``C*`` its capacity ``C*w1 + C*w2`` (J/K).

Which surfaces form the wall
    Every surface whose far side is *not* the outdoor temperature ``To``: for the paper's zone
    the floor, ceiling, both side walls and the hallway wall (``f, c, n1, n2, hw``). Their far
    sides are the five surroundings that the low-order models replace by one ``Tsd``.

The external wall
    Its far side is ``To``, not ``Tsd``, so its conductance cannot join the wall path without
    changing the steady state. Its conductance joins the window path::

        Rwin_low = 1 / (1/Rwin + sum_ext 1/R*)

    and its capacity is *not* added to ``Cw`` (``external_capacity="none"``, the default): that
    mass exchanges heat with ``To`` and the room, never with the surroundings, and hanging it on
    the wall node (tied to ``Tsd``) adds a slow mode that the full model does not have in the
    ``Tsd`` path. The options ``"room-side"`` (its room-side capacity ``C*w1`` joins ``Cw``) and
    ``"all"`` (all of ``C*`` joins ``Cw``, the paper's "sum of the capacitances of each surface"
    read literally) exist for comparison. All three keep every steady-state gain (capacities do
    not enter the DC gain). ``"none"`` has the smallest frequency-domain error; for
    ``office_241`` the largest weighted error over the band (Lin et al. 2012, eq. (7): ``du`` = 45 F = 25 K for
    ``Ts`` and ``To``, 10 F = 5.6 K for ``Tsd``; 1e-5..1e-3 Hz; m = 0.12 kg/s; matched split) of
    the 2nd-order model is, in K:

    ===============  ======  ======  ======  =====
    option           Ts      Tsd     To      sum
    ===============  ======  ======  ======  =====
    ``none``         2.038   0.375   0.390   2.803
    ``room-side``    2.039   0.382   0.390   2.811
    ``all``          2.048   0.441   0.391   2.880
    ===============  ======  ======  ======  =====

    (sums with the symmetric split: 1.857, 1.881 and 1.913; ``tests/properties/test_models_paper.py``
    checks that ``none`` is smallest).

Second-order model (M(2,5,5), Lin et al. 2012, eq. (4))
    ``Cr`` = the full model's ``Cr``; ``Cw`` as above; ``Rwin`` = ``Rwin_low``;
    ``Rw = 1 / sum_wall 1/R*`` (parallel conductances), split into ``R1`` (room side) and
    ``R2`` (far side) with ``R1 + R2 = Rw`` exactly (so the DC gain is kept) in the ratio of the
    parallel combinations of the surfaces' room-side and far-side parts::

        a* = resistance from the room to the capacity centroid of the element
             = (C*w1 R*w1 + C*w2 (R*w1 + R*w2)) / (C*w1 + C*w2),   b* = R* - a*
        Pa = 1 / sum 1/a*,  Pb = 1 / sum 1/b*,
        R1 = Rw Pa / (Pa + Pb),  R2 = Rw Pb / (Pa + Pb).

    (``Pa + Pb`` itself is not ``Rw`` unless every surface has the same ratio ``a*/b*``, so the
    two parallel combinations are used only for the ratio.)

Reduced second-order model (the paper's section IV)
    ``R1 = R2 = Rw/2`` by definition, ``Rw``, ``Cw``, ``Rwin`` and ``Cr`` as above.

First-order model (M(1,5,3), Lin et al. 2012, eq. (3))
    ``Rwin`` = ``Rwin_low``, ``Rw`` as above. Its one capacity ``Cr``: the paper says "all the
    capacitive elements of a zone (walls, air, furniture) are aggregated into a single
    capacitor", so ``capacity="all"`` (the default) is ``Cr + sum of every C*`` (external wall
    included); ``capacity="room"`` keeps the room capacity alone. Both keep the DC gains. With
    the matched split the paper's reading also has the smaller summed eq.-7 error for
    ``office_241`` (``all``: Ts 5.31, Tsd 0.55, To 0.33 K; ``room``: Ts 4.81, Tsd 1.74,
    To 0.71 K); neither is good for ``Ts`` at the top of the band, the limitation of one state.

The Tsd caveat
    The low-order models have one input ``Tsd``, the *mean* of the five surroundings
    (:func:`rczone.models.paper.surroundings_to_tsd`), while in the full model each surrounding
    acts through its own surface's conductance. The low-order models therefore reproduce the
    full model exactly at DC only when the surroundings are equal; what is preserved in general
    is the DC gain of the *sum* ``H_sd = sum_i H_sd,i`` (Lin et al. 2012, eq. (6)), i.e. the response to a
    common change of all five surroundings. For unequal surroundings the low-order steady
    state weights them equally instead of by conductance.

The DC gains kept (from ``To``, from the surroundings summed, from ``Ts`` and from ``Q``, at
any constant flow ``m``): with ``G_o = 1/Rwin + sum_ext 1/R*``, ``G_w = sum_wall 1/R*`` and
``G = G_o + G_w + m cp``, the gains are ``G_o/G``, ``G_w/G``, ``m cp/G`` and ``1/G`` in every
model.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

from collections.abc import Sequence

from rczone.errors import ParameterError
from rczone.models.elements import SurfaceElement, _check_option

#: Name of the outdoor temperature; surfaces with this far side are external.
OUTDOOR = "To"
#: What happens to the external wall's capacity in the 2nd-order models.
EXTERNAL_CAPACITY_OPTIONS = ("room-side", "all", "none")
#: Rules for the reduced 2nd-order model's values (:func:`reduced_values`).
REDUCTION_RULES = ("parallel", "band")
#: The rule behind the reduced model's construction values (priors, starts, diagnose).
REDUCED_RULE = "parallel"
#: Which capacities form the first-order model's capacity.
FIRST_ORDER_CAPACITY_OPTIONS = ("room", "all")


def _partition(elements: Sequence[SurfaceElement]) -> tuple[list[SurfaceElement], list[SurfaceElement]]:
    wall = [e for e in elements if e.far_side != OUTDOOR]
    ext = [e for e in elements if e.far_side == OUTDOOR]
    if not wall:
        raise ParameterError(
            "no internal surface to aggregate into the wall: every surface faces 'To'; the low-order"
            " models need at least one surface whose far side is a surrounding space"
        )
    return wall, ext


def outdoor_resistance(rwin: float, elements: Sequence[SurfaceElement]) -> float:
    """``Rwin_low = 1 / (1/Rwin + sum_ext 1/R*)``, K/W: window and external walls in parallel."""
    _, ext = _partition(elements)
    return 1.0 / (1.0 / rwin + sum(1.0 / e.split.r_total for e in ext))


def wall_resistance(elements: Sequence[SurfaceElement]) -> float:
    """``Rw = 1 / sum_wall 1/R*``, K/W: the internal surfaces in parallel."""
    wall, _ = _partition(elements)
    return 1.0 / sum(1.0 / e.split.r_total for e in wall)


def wall_capacity(elements: Sequence[SurfaceElement], external_capacity: str = "none") -> float:
    """``Cw``, J/K: the internal surfaces' capacities plus the external share (module docstring)."""
    _check_option(external_capacity, EXTERNAL_CAPACITY_OPTIONS, "external_capacity")
    wall, ext = _partition(elements)
    cw = sum(e.split.c_total for e in wall)
    if external_capacity == "all":
        cw += sum(e.split.c_total for e in ext)
    elif external_capacity == "room-side":
        cw += sum(e.split.c1 for e in ext)
    return cw


def wall_split_ratio(elements: Sequence[SurfaceElement]) -> float:
    """``Pa / (Pa + Pb)``: the room-side share ``R1 / Rw`` of the 2nd-order wall (module docstring)."""
    wall, _ = _partition(elements)
    pa = 1.0 / sum(1.0 / e.split.r_centroid for e in wall)
    pb = 1.0 / sum(1.0 / (e.split.r_total - e.split.r_centroid) for e in wall)
    return pa / (pa + pb)


def second_order_values(
    cr: float, rwin: float, elements: Sequence[SurfaceElement], external_capacity: str = "none"
) -> dict[str, float]:
    """Parameter values of the 2nd-order model: ``Cr, Cw, Rwin, R1, R2``.

    Parameters
    ----------
    cr : float
        Room capacity of the full model, J/K.
    rwin : float
        Window resistance of the full model, K/W.
    elements : sequence of SurfaceElement
        The full model's surface elements.
    external_capacity : {"room-side", "all", "none"}
    """
    rw = wall_resistance(elements)
    alpha = wall_split_ratio(elements)
    return {
        "Cr": float(cr),
        "Cw": wall_capacity(elements, external_capacity),
        "Rwin": outdoor_resistance(rwin, elements),
        "R1": rw * alpha,
        "R2": rw * (1.0 - alpha),
    }


def reduced_values(
    cr: float,
    rwin: float,
    elements: Sequence[SurfaceElement],
    external_capacity: str = "none",
    rule: str = REDUCED_RULE,
) -> dict[str, float]:
    """Base parameter values of the reduced 2nd-order model: ``Cr, Rw, Cw, Rwin`` (R1 = R2 = Rw/2).

    Parameters
    ----------
    rule : {"parallel", "band"}
        ``"parallel"``: this module's aggregation (every DC gain kept). ``"band"``: the values
        matched to the full model's response over the paper's band
        (:func:`rczone.models.reduction.band_matched`; ``external_capacity`` does not apply).
    """
    _check_option(rule, REDUCTION_RULES, "reduction rule")
    if rule == "band":
        from rczone.models.reduction import band_matched  # reduction builds on this module

        return band_matched(cr, rwin, elements, "second-order-paper").values
    return {
        "Cr": float(cr),
        "Rw": wall_resistance(elements),
        "Cw": wall_capacity(elements, external_capacity),
        "Rwin": outdoor_resistance(rwin, elements),
    }


def first_order_values(
    cr: float, rwin: float, elements: Sequence[SurfaceElement], capacity: str = "all"
) -> dict[str, float]:
    """Parameter values of the 1st-order model: ``Cr, Rwin, Rw``.

    ``capacity="room"`` keeps ``cr``; ``"all"`` adds every surface's capacity (module docstring).
    """
    _check_option(capacity, FIRST_ORDER_CAPACITY_OPTIONS, "first-order capacity option")
    c = float(cr)
    if capacity == "all":
        c += sum(e.split.c_total for e in elements)
    return {"Cr": c, "Rwin": outdoor_resistance(rwin, elements), "Rw": wall_resistance(elements)}
