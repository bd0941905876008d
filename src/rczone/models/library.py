"""The standard single-zone grey-box family (Bacher & Madsen 2011), as declared RC networks.

The models people fit to whole rooms and small buildings, named after their parts. A name is
``Ti`` followed by any of the parts below, in this order (``TiTmTeThTsnAeAsRia``):

========  ====================================================================================
part      what it adds
========  ====================================================================================
Ti        room air ``Ti`` (``Ci``); without ``Te`` joined to outdoors ``To`` through ``Ria``
Tm        an internal thermal medium ``Tm`` (``Cm``) behind ``Rim`` from the room air
Te        the envelope ``Te`` (``Ce``): room air - ``Rie`` - ``Te`` - ``Rea`` - ``To``
Th        the heater ``Th`` (``Ch``) behind ``Rih``; the heating power ``Ph`` enters ``Th``
Tsn       a sensor node (``Cs`` behind ``Ris``): the measured ``Ti`` becomes the sensor's
          temperature and the room air moves to node ``Tr`` (``Tsn``, not the paper's ``Ts``,
          which is the supply-air temperature channel here)
Ae        solar gains ``Ae Ps`` into the envelope (needs ``Te`` and ``+solar``)
As        solar gains ``As Ps`` into the sensor (needs ``Tsn`` and ``+solar``)
Ria       a resistance from the room air straight to outdoors, beside the envelope (needs ``Te``)
========  ====================================================================================

The five classic bases :data:`FAMILY` (``Ti``, ``TiTe``, ``TiTh``, ``TiTeTh``, ``TiTm``) are the
ones ``rczone models`` lists and ``rczone select`` compares by a criterion; forward selection
grows through :func:`family_bases`, every valid name, one part at a time.

Options are appended with ``+`` (``TiTe+heater+solar``):

* ``heater`` - heating power ``Ph`` (W) into the room air (into ``Th`` for the models with a
  heater node, where it is always present);
* ``solar`` - solar irradiance ``Ps`` (W/m2) through an effective aperture ``Aw`` (m2) into the
  room air (and ``Ae``, ``As`` where the name has them);
* ``air`` - supply air ``m cp (Ts - T)`` into the room air (flow ``m`` in kg/s, temperature ``Ts``);
* ``gain`` - another heat input ``Q`` (W) into the room air (internal gains, a constant if unmeasured).

The values are generic starting points; the default fit searches the bounds globally, so they need
not be close. The bounds reach from a single room to a large non-domestic building: effective heat
capacities per floor area are up to about 370 kJ/(m2 K) for very heavy construction (ISO 13790
table 12), so a 10 000 m2 office or school holds some 4e9 J/K in its structure; the room-air
node with furniture and inner linings goes to 1e10 J/K, the envelope and internal mass to 1e11
J/K, and the resistances down to 1e-6 K/W (a heat-loss coefficient of 1 MW/K) for the paths to
outdoors and 1e-7 K/W inside (surface conductances of some 8 W/(m2 K) over a million m2 of
surfaces at most). Write a model file (``rczone models show TiTe+solar > mine.toml``) to change
anything.

References
----------
.. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522, section 3 (the model family and its notation).
.. [2] ISO 13790:2008, "Energy performance of buildings - Calculation of energy use for space
   heating and cooling", section 12.3.1.2 and table 12 (effective internal heat capacity per
   floor area: 80 to 370 kJ/(m2 K)).
"""

from __future__ import annotations

import itertools
import re

from rczone.errors import ParameterError, did_you_mean
from rczone.models.zone import ModelInputs, ZoneModel
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

#: The classic bases of the family (listed by ``rczone models``, compared by ``rczone select``).
FAMILY = ("Ti", "TiTe", "TiTh", "TiTeTh", "TiTm")
#: The parts of a name after ``Ti``, in the order they appear in a canonical name.
PARTS = ("Tm", "Te", "Th", "Tsn", "Ae", "As", "Ria")
#: Parts that need another part (``Ae`` an envelope, ``As`` a sensor, ``Ria`` the envelope's path beside it).
_NEEDS = {"Ae": "Te", "As": "Tsn", "Ria": "Te"}
#: Options, in the order they appear in a canonical name.
OPTIONS = ("heater", "solar", "air", "gain")

# value (SI), bounds (SI), description; the bounds' reach is justified in the module notes
_VALUES = {
    "Ci": (1.0e6, (1e4, 1e10), "room air and furniture"),
    "Ce": (1.0e7, (1e5, 1e11), "building envelope"),
    "Ch": (2.0e5, (1e3, 1e9), "heater"),
    "Cm": (1.0e7, (1e5, 1e11), "internal thermal medium"),
    "Cs": (1.0e4, (1e1, 1e8), "temperature sensor"),
    "Ria": (1.0e-2, (1e-6, 10.0), "room air to outdoors"),
    "Rie": (2.0e-3, (1e-7, 1.0), "room air to envelope"),
    "Rea": (2.0e-2, (1e-6, 10.0), "envelope to outdoors"),
    "Rih": (1.0e-3, (1e-7, 1.0), "heater to room air"),
    "Rim": (1.0e-3, (1e-7, 1.0), "room air to internal medium"),
    "Ris": (1.0e-2, (1e-7, 10.0), "room air to sensor"),
}
# value, upper bound (m2), description of the solar apertures (lower bound 0)
_APERTURES = {
    "Aw": (2.0, 500.0, "effective solar aperture into the room air"),
    "Ae": (2.0, 500.0, "effective solar aperture into the envelope"),
    "As": (0.1, 50.0, "effective solar aperture into the sensor"),
}
_TOKEN = re.compile("|".join(sorted(("Ti", *PARTS), key=len, reverse=True)))


def _parameter(name: str) -> Parameter:
    if name in _APERTURES:
        value, hi, text = _APERTURES[name]
        return Parameter(name, "gain", value, unit="m2", description=text, bounds=(0.0, hi))
    value, bounds, text = _VALUES[name]
    kind = "capacitance" if name.startswith("C") else "resistance"
    return Parameter(name, kind, value, description=text, bounds=bounds)


def parse_base(base: str) -> tuple[str, ...]:
    """The parts of a base name after ``Ti`` (``"TiTeThRia"`` -> ``("Te", "Th", "Ria")``).

    Parameters
    ----------
    base : str
        A base name such as ``TiTmTeThAeRia``; the parts may come in any order.

    Returns
    -------
    tuple of str
        The parts in canonical order (:data:`PARTS`).

    Raises
    ------
    ParameterError
        For a name that is not ``Ti`` followed by known parts, a part twice, or a part without
        the part it needs.
    """
    tokens = _TOKEN.findall(base)
    if not base.startswith("Ti") or "".join(tokens) != base or tokens.count("Ti") != 1:
        raise ParameterError(
            f"unknown model {base!r}; {did_you_mean(base, FAMILY)} (a family name is Ti followed by"
            f" any of {', '.join(PARTS)})"
        )
    parts = tokens[1:]
    if len(set(parts)) != len(parts):
        raise ParameterError(f"model {base!r} names a part twice")
    for part, need in _NEEDS.items():
        if part in parts and need not in parts:
            raise ParameterError(
                f"model {base!r}: part {part} needs part {need} (e.g. {base.replace(part, need + part)})"
            )
    return tuple(p for p in PARTS if p in parts)


def family_bases() -> tuple[str, ...]:
    """Every valid base name of the family, the fewest parts first.

    Returns
    -------
    tuple of str
        ``Ti``, ``TiTm``, ``TiTe``, ... ``TiTmTeThTsnAeAsRia`` (canonical names).
    """
    out = []
    for k in range(len(PARTS) + 1):
        for parts in itertools.combinations(PARTS, k):
            if all(need in parts for part, need in _NEEDS.items() if part in parts):
                out.append("Ti" + "".join(parts))
    return tuple(out)


def parse_name(name: str) -> tuple[str, tuple[str, ...]]:
    """``(base, options)`` of a family name such as ``"TiTe+solar+heater"``; raises for unknown parts.

    Parameters
    ----------
    name : str
        A base (:func:`parse_base`) with options appended by ``+``.

    Returns
    -------
    (str, tuple of str)
        The canonical base and the options in canonical order.
    """
    parts = [p.strip() for p in name.split("+")]
    base, opts = parts[0], parts[1:]
    base = "Ti" + "".join(parse_base(base))
    for o in opts:
        if o not in OPTIONS:
            raise ParameterError(f"unknown option {o!r} of model {base!r}; {did_you_mean(o, OPTIONS)}")
    if len(set(opts)) != len(opts):
        raise ParameterError(f"model {name!r} lists an option twice")
    solar_parts = [p for p in ("Ae", "As") if p in parse_base(base)]
    if solar_parts and "solar" not in opts:
        raise ParameterError(
            f"model {name!r}: part {solar_parts[0]} is a solar gain; add the option +solar (the irradiance Ps)"
        )
    return base, tuple(o for o in OPTIONS if o in opts)


def is_family_name(name: str) -> bool:
    """Whether ``name`` starts like a family name (``Ti`` and known parts), valid or not.

    Parameters
    ----------
    name : str
        Any model name.

    Returns
    -------
    bool
    """
    base = name.split("+")[0].strip()
    return base.startswith("Ti") and "".join(_TOKEN.findall(base)) == base


def family_extensions(name: str) -> tuple[str, ...]:
    """The family models one part richer than ``name``, with the same options (forward selection's steps).

    Parameters
    ----------
    name : str
        A family name (``TiTeTh+heater+solar``).

    Returns
    -------
    tuple of str
        Canonical names, e.g. ``TiTmTeTh+heater+solar``, ``TiTeThAe+heater+solar``, ... (a part
        that needs another part, or a solar part without ``+solar``, is left out).
    """
    base, opts = parse_name(name)
    have = parse_base(base)
    out = []
    for part in PARTS:
        if part in have:
            continue
        richer = "Ti" + "".join(p for p in PARTS if p in have or p == part)
        try:
            out.append(canonical_name("+".join((richer, *opts))))
        except ParameterError:
            continue
    return tuple(out)


def canonical_name(name: str) -> str:
    """The name with its parts and options in the canonical order (``TiTe+solar+heater`` -> ``TiTe+heater+solar``).

    Parameters
    ----------
    name : str
        A family name.

    Returns
    -------
    str
    """
    base, opts = parse_name(name)
    return "+".join((base, *opts))


def family_network(name: str) -> RCNetwork:
    """The network of a family model (see the module notes).

    Parameters
    ----------
    name : str
        A family name (``TiTmTeThAeRia+solar``).

    Returns
    -------
    RCNetwork
    """
    base, opts = parse_name(name)
    parts = parse_base(base)
    air = "Tr" if "Tsn" in parts else "Ti"  # with a sensor, the measured Ti is the sensor's
    nodes = [Node(air, "Ci", "room air and furniture")]
    resistors: list[Resistor] = []
    pnames = ["Ci"]
    if "Tsn" in parts:
        nodes.insert(0, Node("Ti", "Cs", "temperature sensor (the measured indoor temperature)"))
        resistors.append(Resistor(air, "Ti", "Ris"))
        pnames += ["Cs", "Ris"]
    if "Te" in parts:
        nodes.append(Node("Te", "Ce", "building envelope"))
        resistors += [Resistor(air, "Te", "Rie"), Resistor("Te", "To", "Rea")]
        pnames += ["Ce", "Rie", "Rea"]
    if "Te" not in parts or "Ria" in parts:
        resistors.append(Resistor(air, "To", "Ria"))
        pnames.append("Ria")
    if "Tm" in parts:
        nodes.append(Node("Tm", "Cm", "internal thermal medium"))
        resistors.append(Resistor(air, "Tm", "Rim"))
        pnames += ["Cm", "Rim"]
    heater_node = air
    if "Th" in parts:
        nodes.append(Node("Th", "Ch", "heater"))
        resistors.append(Resistor("Th", air, "Rih"))
        pnames += ["Ch", "Rih"]
        heater_node = "Th"
    heat = []
    if "heater" in opts or "Th" in parts:
        heat.append(HeatInput("Ph", {heater_node: 1.0}))
    if "solar" in opts:
        split = {air: "Aw"}
        for part, node in (("Ae", "Te"), ("As", "Ti")):
            if part in parts:
                split[node] = part
        heat.append(HeatInput("Ps", split, unit="W/m2"))
        pnames += list(split.values())
    if "gain" in opts:
        heat.append(HeatInput("Q", {air: 1.0}))
    supply = [SupplyAir(air, flow="m", temperature="Ts")] if "air" in opts else []
    full = "+".join((base, *opts))
    return RCNetwork(
        full,
        nodes,
        ["To"],
        resistors,
        [_parameter(p) for p in pnames],
        heat_inputs=heat,
        supply_air=supply,
        outputs=["Ti"],
        description=f"{full}: the {base} model of Bacher & Madsen (2011)"
        + (f" with {', '.join(opts)}" if opts else ""),
    )


_DESCRIPTIONS = {
    "To": "outdoor air temperature, degC",
    "Ph": "heating power, W",
    "Ps": "solar irradiance, W/m2 (global horizontal or on the facade)",
    "Q": "internal heat gains, W",
    "m": "supply-air mass flow, kg/s",
    "Ts": "supply-air temperature, degC",
}


def family_model(name: str) -> ZoneModel:
    """A family model as a :class:`ZoneModel` (its inputs described for messages)."""
    net = family_network(name)
    desc = {k: v for k, v in _DESCRIPTIONS.items() if k in (*net.input_names, *net.flow_names)}
    return ZoneModel(net, inputs=ModelInputs(descriptions=desc), source=net.name)
