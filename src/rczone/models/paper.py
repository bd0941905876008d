"""The paper's zone models as declared RC networks, with construction (ASHRAE) values.

Lin, Middelkoop & Barooah [1]_, section II:

* :func:`full_scale` - MRC(13, 8, 32): room node ``Ti`` (``Cr``), one 3R2C element per surface
  (nodes ``T{s}w1`` room side, ``T{s}w2``; parameters ``R{s}w1, R{s}w2, R{s}w3, C{s}w1, C{s}w2``),
  window ``Rwin`` between ``Ti`` and ``To``. Inputs ``To, Tf, Tc, Tn1, Tn2, Thw, Ts, Q`` and
  the flow ``m``.
* :func:`second_order` - M(2, 5, 5), eq. (4): ``Ti`` (``Cr``), ``Tw`` (``Cw``), ``Rwin``
  ``Ti - To``, ``R1`` ``Ti - Tw``, ``R2`` ``Tw - Tsd``. Inputs ``To, Tsd, Ts, Q`` and ``m``.
* :func:`first_order` - M(1, 5, 3), eq. (3): ``Cr``; ``Rwin`` ``Ti - To``; ``Rw`` ``Ti - Tsd``.
* :func:`second_order_reduced` - the paper's section IV parameterization: base parameters
  ``Cr``, ``Rw`` (to be estimated) and ``Cw``, ``Rwin`` (held at construction values by the
  estimation setup), with ``R1 = R2 = Rw/2`` tied.

Every model has the supply air ``m cp (Ts - Ti)`` on ``Ti`` and the heat input ``Q`` on ``Ti``.
Parameter defaults are construction values of a :class:`~rczone.construction.ZoneGeometry`
(default :func:`~rczone.construction.office_241`): the full model's from the surfaces'
3R2C splits (:mod:`rczone.models.elements`), the low-order ones by parallel aggregation
(:mod:`rczone.models.aggregation`, where the exact rule is written down).

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented
   thermal models of zones in multi-zone buildings", IEEE CDC 2012, eqs. (1)-(4), section IV.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from rczone.construction.room import AIR_CP, ZoneGeometry, office_241
from rczone.errors import InputShapeError, ParameterError, did_you_mean
from rczone.models.aggregation import first_order_values, reduced_values, second_order_values
from rczone.models.elements import full_scale_values, surface_elements
from rczone.models.zone import ModelInputs, ZoneModel
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

#: The five surrounding temperatures of the paper's zone, in the full model's input order.
SURROUNDINGS = ("Tf", "Tc", "Tn1", "Tn2", "Thw")
#: Inputs of the low-order models (besides the flow ``m``), in network order.
LOW_ORDER_INPUTS = ("To", "Tsd", "Ts", "Q")

_SURFACE_TEXT = {
    "o": "external wall",
    "f": "floor",
    "c": "ceiling",
    "n1": "side wall to neighbour 1",
    "n2": "side wall to neighbour 2",
    "hw": "hallway wall (door folded in)",
}


def _common(node: str = "Ti") -> tuple[list[HeatInput], list[SupplyAir]]:
    return [HeatInput("Q", {node: 1.0})], [SupplyAir(node, flow="m", temperature="Ts", cp=AIR_CP)]


def _geometry(geometry: ZoneGeometry | None) -> ZoneGeometry:
    return office_241() if geometry is None else geometry


def full_scale(geometry: ZoneGeometry | None = None, split: str = "matched", door: str = "fold") -> RCNetwork:
    """The full-scale model MRC(13, 8, 32) with construction values of ``geometry``.

    Parameters
    ----------
    geometry : ZoneGeometry, optional
        Default :func:`~rczone.construction.office_241`.
    split : {"matched", "symmetric"}
        3R2C split of each construction (:mod:`rczone.models.split`).
    door : {"fold", "omit"}
        The hallway door: folded into the hallway surface keeping the DC conductance (default),
        or left out (:mod:`rczone.models.elements`).

    Returns
    -------
    RCNetwork
        States ``Ti`` then ``T{s}w1, T{s}w2`` per surface; 1 + 2 x (number of surfaces) states
        and 2 + 5 x (number of surfaces) base parameters (13 and 32 for the paper's six surfaces).
    """
    g = _geometry(geometry)
    vals = full_scale_values(g, split, door)
    nodes = [Node("Ti", "Cr", "room air and furnishings")]
    resistors = [Resistor("Ti", "To", "Rwin")]
    params = [
        Parameter("Cr", "capacitance", vals["Cr"], description="room air and furnishings"),
        Parameter("Rwin", "resistance", vals["Rwin"], description="window, air to air"),
    ]
    boundaries = ["To"]
    for el in surface_elements(g, split, door):
        s, far = el.name, el.far_side
        text = _SURFACE_TEXT.get(s, f"surface {s}")
        if far not in boundaries:
            boundaries.append(far)
        nodes += [
            Node(f"T{s}w1", f"C{s}w1", f"{text}, room side"),
            Node(f"T{s}w2", f"C{s}w2", f"{text}, far side"),
        ]
        resistors += [
            Resistor("Ti", f"T{s}w1", f"R{s}w1"),
            Resistor(f"T{s}w1", f"T{s}w2", f"R{s}w2"),
            Resistor(f"T{s}w2", far, f"R{s}w3"),
        ]
        for k, side in ((1, "room side"), (2, "middle"), (3, f"far side, to {far}")):
            params.append(
                Parameter(f"R{s}w{k}", "resistance", vals[f"R{s}w{k}"], description=f"{text}, {side}")
            )
        for k, side in ((1, "room side"), (2, "far side")):
            params.append(
                Parameter(f"C{s}w{k}", "capacitance", vals[f"C{s}w{k}"], description=f"{text}, {side}")
            )
    heat, air = _common()
    return RCNetwork(
        "full-scale",
        nodes,
        boundaries,
        resistors,
        params,
        heat_inputs=heat,
        supply_air=air,
        description=f"MRC({len(nodes)}, {len(boundaries) + 2}, {len(params)}) full-scale model of {g.name}"
        f" ({split} 3R2C split, door {door})",
    )


def _low_order_boundaries() -> list[str]:
    return ["To", "Tsd"]


def second_order(
    geometry: ZoneGeometry | None = None,
    split: str = "matched",
    door: str = "fold",
    external_capacity: str = "none",
) -> RCNetwork:
    """The 2nd-order model M(2, 5, 5) (Lin et al. 2012, eq. (4)) with aggregated construction values.

    Parameters
    ----------
    geometry, split, door
        As for :func:`full_scale`; the values are aggregated from that model's elements.
    external_capacity : {"room-side", "all", "none"}
        Share of the external wall's capacity that joins ``Cw`` (:mod:`rczone.models.aggregation`).
    """
    g = _geometry(geometry)
    v = second_order_values(
        g.room_capacity, g.window.resistance, surface_elements(g, split, door), external_capacity
    )
    heat, air = _common()
    return RCNetwork(
        "second-order",
        [Node("Ti", "Cr", "room air and furnishings"), Node("Tw", "Cw", "all walls lumped")],
        _low_order_boundaries(),
        [Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"), Resistor("Tw", "Tsd", "R2")],
        [
            Parameter("Cr", "capacitance", v["Cr"], description="room air and furnishings"),
            Parameter("Cw", "capacitance", v["Cw"], description="walls (aggregated)"),
            Parameter("Rwin", "resistance", v["Rwin"], description="window and external wall to To"),
            Parameter("R1", "resistance", v["R1"], description="room to wall node"),
            Parameter("R2", "resistance", v["R2"], description="wall node to surroundings Tsd"),
        ],
        heat_inputs=heat,
        supply_air=air,
        description=f"M(2, 5, 5) second-order model of {g.name}, aggregated from the full-scale model",
    )


def second_order_reduced(
    geometry: ZoneGeometry | None = None,
    split: str = "matched",
    door: str = "fold",
    external_capacity: str = "none",
) -> RCNetwork:
    """The paper's reduced 2nd-order model (section IV): ``R1 = R2 = Rw/2``.

    Base parameters ``Cr``, ``Rw`` (the unknowns of the paper's calibration) and ``Cw``,
    ``Rwin`` (held at their construction values in the paper); ``R1`` and ``R2`` are tied
    (``expr="Rw/2"``). Arguments as for :func:`second_order`.
    """
    g = _geometry(geometry)
    v = reduced_values(
        g.room_capacity, g.window.resistance, surface_elements(g, split, door), external_capacity
    )
    heat, air = _common()
    return RCNetwork(
        "second-order-paper",
        [Node("Ti", "Cr", "room air and furnishings"), Node("Tw", "Cw", "all walls lumped")],
        _low_order_boundaries(),
        [Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"), Resistor("Tw", "Tsd", "R2")],
        [
            Parameter("Cr", "capacitance", v["Cr"], description="room air and furnishings (estimated)"),
            Parameter("Rw", "resistance", v["Rw"], description="wall, room to surroundings (estimated)"),
            Parameter(
                "Cw", "capacitance", v["Cw"], description="walls, fixed at the construction value", fixed=True
            ),
            Parameter(
                "Rwin", "resistance", v["Rwin"], description="window and external wall, fixed", fixed=True
            ),
            Parameter("R1", "resistance", expr="Rw/2", description="room half of the wall"),
            Parameter("R2", "resistance", expr="Rw/2", description="far half of the wall"),
        ],
        heat_inputs=heat,
        supply_air=air,
        description=f"the paper's reduced second-order model of {g.name} (R1 = R2 = Rw/2)",
    )


def first_order(
    geometry: ZoneGeometry | None = None, split: str = "matched", door: str = "fold", capacity: str = "all"
) -> RCNetwork:
    """The 1st-order model M(1, 5, 3) (Lin et al. 2012, eq. (3)) with aggregated construction values.

    Parameters
    ----------
    geometry, split, door
        As for :func:`full_scale`.
    capacity : {"room", "all"}
        ``Cr`` alone, or ``Cr`` plus every wall capacity (:mod:`rczone.models.aggregation`).
    """
    g = _geometry(geometry)
    v = first_order_values(g.room_capacity, g.window.resistance, surface_elements(g, split, door), capacity)
    heat, air = _common()
    return RCNetwork(
        "first-order",
        [Node("Ti", "Cr", "room air and furnishings")],
        _low_order_boundaries(),
        [Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tsd", "Rw")],
        [
            Parameter("Cr", "capacitance", v["Cr"], description="zone capacity"),
            Parameter("Rwin", "resistance", v["Rwin"], description="window and external wall to To"),
            Parameter("Rw", "resistance", v["Rw"], description="walls, room to surroundings Tsd"),
        ],
        heat_inputs=heat,
        supply_air=air,
        description=f"M(1, 5, 3) first-order model of {g.name}, aggregated from the full-scale model",
    )


_REGISTRY: dict[str, Callable[..., RCNetwork]] = {
    "full-scale": full_scale,
    "second-order": second_order,
    "first-order": first_order,
    "second-order-paper": second_order_reduced,
}


def model_names() -> tuple[str, ...]:
    """Names accepted by :func:`get_model`."""
    return tuple(_REGISTRY)


def get_model(name: str, geometry: ZoneGeometry | None = None, **options: str) -> RCNetwork:
    """One of the paper's models by name, with construction values of ``geometry``.

    Parameters
    ----------
    name : {"full-scale", "second-order", "first-order", "second-order-paper"}
        ``"second-order-paper"`` is the reduced model of the paper's section IV.
    geometry : ZoneGeometry, optional
        Default :func:`~rczone.construction.office_241`.
    **options
        Passed to the model's function (``split``, ``door``, ``external_capacity``, ``capacity``).

    Returns
    -------
    RCNetwork
    """
    if name not in _REGISTRY:
        raise ParameterError(
            f"unknown model {name!r}; expected one of {', '.join(_REGISTRY)}; "
            + did_you_mean(name, _REGISTRY)
        )
    return _REGISTRY[name](geometry, **options)


def surroundings_to_tsd(
    u_full: np.ndarray, input_names: Sequence[str], surroundings: Sequence[str] = SURROUNDINGS
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Map the full model's inputs to the low-order models' inputs ``(To, Tsd, Ts, Q)``.

    ``Tsd`` is the plain mean of the surrounding temperatures (the paper's section IV choice;
    see the Tsd caveat in :mod:`rczone.models.aggregation`).

    Parameters
    ----------
    u_full : ndarray, shape (n_samples, len(input_names))
        Time-first inputs of the full model (the flow ``m`` is a separate array and unchanged).
    input_names : sequence of str
        Column names, e.g. ``full_scale().input_names``; must include ``To``, ``Ts``, ``Q`` and
        every name in ``surroundings``.
    surroundings : sequence of str
        The columns averaged into ``Tsd``.

    Returns
    -------
    u_low : ndarray, shape (n_samples, 4)
    names : tuple of str
        ``("To", "Tsd", "Ts", "Q")``, the input order of the low-order networks.
    """
    u = np.asarray(u_full, dtype=float)
    names = tuple(input_names)
    if u.ndim != 2 or u.shape[1] != len(names):
        raise InputShapeError(
            f"u_full must have shape (n_samples, {len(names)}) to match input_names, got {u.shape};"
            " inputs are time-first (n_samples, n_channels)"
        )
    if not surroundings:
        raise InputShapeError("surroundings is empty; Tsd needs at least one surrounding temperature")
    for n in (*surroundings, "To", "Ts", "Q"):
        if n not in names:
            raise InputShapeError(f"input {n!r} is missing from input_names; " + did_you_mean(n, names))
    col = {n: i for i, n in enumerate(names)}
    tsd = u[:, [col[n] for n in surroundings]].mean(axis=1)
    out = np.column_stack([u[:, col["To"]], tsd, u[:, col["Ts"]], u[:, col["Q"]]])
    return out, LOW_ORDER_INPUTS


#: The paper's constant internal gain (idle PC and printer), W, used when data carry no ``Q``.
Q_PAPER = 50.0


def paper_inputs(network: RCNetwork) -> ModelInputs:
    """How the paper's models find their inputs: ``Q`` = 50 W unless measured, ``Tsd`` = mean of the surroundings."""
    desc = {
        "To": "outdoor air temperature, degC",
        "Tsd": "mean temperature of the surrounding spaces (floor, ceiling, neighbours, hallway), degC",
        "Ts": "supply-air temperature, degC",
        "m": "supply-air mass flow, kg/s",
        "Q": "internal heat gain, W (the paper: a constant 50 W)",
    }
    desc.update({s: "temperature of a surrounding space, degC" for s in SURROUNDINGS})
    names = (*network.input_names, *network.flow_names)
    return ModelInputs(
        defaults={"Q": Q_PAPER} if "Q" in names else {},
        mean_of={"Tsd": SURROUNDINGS} if "Tsd" in names else {},
        descriptions={k: v for k, v in desc.items() if k in names},
    )


def paper_model(name: str, geometry: ZoneGeometry | None = None, **options: str) -> ZoneModel:
    """One of the paper's models (:func:`get_model`) as a :class:`ZoneModel` with its input conventions."""
    net = get_model(name, geometry, **options)
    return ZoneModel(net, inputs=paper_inputs(net), source=name)
