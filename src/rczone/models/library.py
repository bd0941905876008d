"""The standard single-zone grey-box family (Bacher & Madsen 2011), as declared RC networks.

The models people fit to whole rooms and small buildings, named after their states:

========  ====================================================================================
name      network
========  ====================================================================================
Ti        room air ``Ti`` (``Ci``) to outdoors ``To`` through ``Ria``
TiTe      ``Ti`` (``Ci``) - ``Rie`` - envelope ``Te`` (``Ce``) - ``Rea`` - ``To``
TiTh      heater ``Th`` (``Ch``) - ``Rih`` - ``Ti`` (``Ci``) - ``Ria`` - ``To``; the heater's power
          enters ``Th``
TiTeTh    ``Th`` - ``Rih`` - ``Ti`` - ``Rie`` - ``Te`` - ``Rea`` - ``To``
TiTm      ``Ti`` - ``Ria`` - ``To``, and an internal thermal mass ``Tm`` (``Cm``) behind ``Rim``
========  ====================================================================================

Options are appended with ``+`` (``TiTe+heater+solar``):

* ``heater`` - heating power ``Ph`` (W) into ``Ti`` (into ``Th`` for the models with a heater
  node, where it is always present);
* ``solar`` - solar irradiance ``Ps`` (W/m2) through an effective aperture ``Aw`` (m2) into ``Ti``;
* ``air`` - supply air ``m cp (Ts - Ti)`` (flow ``m`` in kg/s, temperature ``Ts``);
* ``gain`` - another heat input ``Q`` (W) into ``Ti`` (internal gains, a constant if unmeasured).

The values are generic construction-scale starting points with wide bounds (a room to a small
house); the default fit searches the bounds globally, so they need not be close. Write a model file
(``rczone models show TiTe+solar > mine.toml``) to change anything.

References
----------
.. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522, section 3 (the model family and its notation).
"""

from __future__ import annotations

from rczone.errors import ParameterError, did_you_mean
from rczone.models.zone import ModelInputs, ZoneModel
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

#: Base structures of the family.
FAMILY = ("Ti", "TiTe", "TiTh", "TiTeTh", "TiTm")
#: Options, in the order they appear in a canonical name.
OPTIONS = ("heater", "solar", "air", "gain")

# value (SI), bounds (SI), description
_VALUES = {
    "Ci": (1.0e6, (1e4, 1e9), "room air and furniture"),
    "Ce": (1.0e7, (1e5, 1e10), "building envelope"),
    "Ch": (2.0e5, (1e3, 1e8), "heater"),
    "Cm": (1.0e7, (1e5, 1e10), "internal thermal mass"),
    "Ria": (1.0e-2, (1e-5, 10.0), "room air to outdoors"),
    "Rie": (2.0e-3, (1e-6, 1.0), "room air to envelope"),
    "Rea": (2.0e-2, (1e-5, 10.0), "envelope to outdoors"),
    "Rih": (1.0e-3, (1e-6, 1.0), "heater to room air"),
    "Rim": (1.0e-3, (1e-6, 1.0), "room air to internal mass"),
}


def _parameter(name: str) -> Parameter:
    value, bounds, text = _VALUES[name]
    kind = "capacitance" if name.startswith("C") else "resistance"
    return Parameter(name, kind, value, description=text, bounds=bounds)


def parse_name(name: str) -> tuple[str, tuple[str, ...]]:
    """``(base, options)`` of a family name such as ``"TiTe+solar+heater"``; raises for unknown parts."""
    parts = [p.strip() for p in name.split("+")]
    base, opts = parts[0], parts[1:]
    if base not in FAMILY:
        raise ParameterError(f"unknown model {base!r}; {did_you_mean(base, FAMILY)}")
    for o in opts:
        if o not in OPTIONS:
            raise ParameterError(f"unknown option {o!r} of model {base!r}; {did_you_mean(o, OPTIONS)}")
    if len(set(opts)) != len(opts):
        raise ParameterError(f"model {name!r} lists an option twice")
    return base, tuple(o for o in OPTIONS if o in opts)


def canonical_name(name: str) -> str:
    """The name with its options in the canonical order (``TiTe+solar+heater`` -> ``TiTe+heater+solar``)."""
    base, opts = parse_name(name)
    return "+".join((base, *opts))


def family_network(name: str) -> RCNetwork:
    """The network of a family model (see the module notes)."""
    base, opts = parse_name(name)
    nodes = [Node("Ti", "Ci", "room air and furniture")]
    resistors: list[Resistor] = []
    pnames = ["Ci"]
    if "Te" in base:
        nodes.append(Node("Te", "Ce", "building envelope"))
        resistors += [Resistor("Ti", "Te", "Rie"), Resistor("Te", "To", "Rea")]
        pnames += ["Ce", "Rie", "Rea"]
    else:
        resistors.append(Resistor("Ti", "To", "Ria"))
        pnames.append("Ria")
    if "Tm" in base:
        nodes.append(Node("Tm", "Cm", "internal thermal mass"))
        resistors.append(Resistor("Ti", "Tm", "Rim"))
        pnames += ["Cm", "Rim"]
    heater_node = "Ti"
    if "Th" in base:
        nodes.append(Node("Th", "Ch", "heater"))
        resistors.append(Resistor("Th", "Ti", "Rih"))
        pnames += ["Ch", "Rih"]
        heater_node = "Th"
    params = [_parameter(p) for p in pnames]
    heat = []
    if "heater" in opts or "Th" in base:
        heat.append(HeatInput("Ph", {heater_node: 1.0}))
    if "solar" in opts:
        heat.append(HeatInput("Ps", {"Ti": "Aw"}, unit="W/m2"))
        params.append(
            Parameter(
                "Aw", "gain", 2.0, unit="m2", description="effective solar aperture", bounds=(0.0, 100.0)
            )
        )
    if "gain" in opts:
        heat.append(HeatInput("Q", {"Ti": 1.0}))
    air = [SupplyAir("Ti", flow="m", temperature="Ts")] if "air" in opts else []
    full = "+".join((base, *opts))
    return RCNetwork(
        full,
        nodes,
        ["To"],
        resistors,
        params,
        heat_inputs=heat,
        supply_air=air,
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
