"""Model files: an RC network written by a person, in TOML, with the words of :class:`RCNetwork`.

A model file declares the zone's nodes, boundaries, resistors, heat inputs, supply air,
outputs and parameters (value, unit, bounds, fixed or free), and how its inputs are found in
data. It is read by :func:`read_model_file` into a :class:`~rczone.models.zone.ZoneModel`
and written by :func:`model_to_toml` (``rczone models show NAME`` prints one to start from).

Format
------
Every key is optional except ``nodes``, ``resistors`` and ``parameters``; unknown keys are
errors with a suggestion, so a typo never drops a setting silently::

    name = "office 3.12"               # default: the file name
    description = "air and envelope"
    boundaries = ["To"]                # prescribed temperatures (inputs), degC
    outputs = ["Ti"]                   # measured nodes; default: the first node

    [nodes]                            # in state order; a node without capacity is massless
    Ti = { capacity = "Ci", description = "room air and furniture" }
    Te = "Ce"                          # short form: the capacity parameter
    # Ts = {}                          # a massless node (eliminated exactly)

    resistors = [                      # [node, node or boundary, resistance]
        ["Ti", "Te", "Rie"],
        ["Te", "To", "Rea"],
    ]

    [heat_inputs]                      # heat-flow inputs and where they go
    Ph = "Ti"                          # heater power, W, all into Ti
    Ps = { to = { Ti = "Aw" }, unit = "W/m2" }   # solar irradiance times aperture Aw (m2)

    [[supply_air]]                     # m cp (Ts - T_node), W
    node = "Ti"
    flow = "m"                         # kg/s
    temperature = "Ts"                 # degC
    # cp = 1005                        # J/(kg K)

    [[disturbance]]                    # an unmeasured heat input with a GP prior (docs/disturbances.md)
    name = "Qx"                        # its latent states: Qx, Qx_d1 (matern32)
    kind = "matern32"                  # or "matern52", "periodic" (then also period = "Pd")
    to = { Ti = 1.0 }                  # nodes and dimensionless gains; or to = "Ti"
    magnitude = "sx"                   # standard deviation of the heat flow, a parameter (W)
    length_scale = "lx"                # a parameter (s)

    [parameters]                       # values in the given unit, converted to SI on reading
    Ci  = { value = 1.2, unit = "MJ/K", bounds = [0.01, 100] }
    Ce  = { value = 15, unit = "MJ/K" }
    Rie = { value = 2, unit = "K/kW" }
    Rea = { value = 20, unit = "K/kW", fixed = true }   # held unless a fit frees it
    Aw  = { value = 2, unit = "m2", bounds = [0, 50] }
    sx  = { value = 200, unit = "W" }
    lx  = { value = 3, unit = "h" }
    # R1 = { expr = "Rw/2" }           # a tie: follows other parameters, never estimated
    # Rie = { value = 2, unit = "K/kW", prior = { dist = "lognormal", median = 2, sigma = 0.7 } }

    [inputs]                           # how inputs are found in data besides by name
    # Q = { default = 50, description = "internal gain, W" }  # constant when the data lack Q
    # Tsd = { mean_of = ["Tf", "Tc"] }                         # mean of columns when no Tsd

A parameter's kind (resistance, capacitance, gain) follows from where it is used; a
parameter used only in ties takes the kind of the ties that use it. Units: resistances
``K/W``, ``K/kW``; capacities ``J/K``, ``kJ/K``, ``MJ/K``, ``Wh/K``, ``kWh/K``; gains ``1`` or
``m2`` (an aperture for an irradiance input); heat inputs ``W`` or ``W/m2``; a disturbance's
magnitude ``W`` or ``kW``, its length scale and period ``s``, ``min``, ``h`` or ``d``. Bounds are in the
parameter's unit. The free parameters of a fit are, by default, every resistance, capacitance and
gain not marked ``fixed`` (and the noise levels for ML). A parameter's ``prior`` table declares
its prior distribution (:mod:`rczone.network.prior`: ``lognormal`` with ``median``, ``sigma``;
``normal`` with ``mean``, ``sigma``; ``uniform`` with ``lower``, ``upper``), numbers in the
parameter's unit except a log-normal's dimensionless ``sigma``.

Model files are untrusted input: size, encoding (UTF-8), nesting (:mod:`rczone.files.text`), names, numbers (finite),
units and tie expressions (bounded arithmetic, evaluated by rczone, never executed) are checked,
and every problem is one :class:`~rczone.errors.ModelFileError` naming the file and the key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rczone.errors import ModelFileError, RczoneError, did_you_mean
from rczone.models.zone import ModelInputs, ZoneModel, read_model_document
from rczone.network import CP_AIR, HeatInput, Node, Parameter, Prior, RCNetwork, Resistor, SupplyAir
from rczone.network.disturbance import ROLE_KINDS, LatentForce
from rczone.network.network import HEAT_INPUT_UNITS
from rczone.network.parameters import expression_names

TOP_KEYS = (
    "name",
    "description",
    "boundaries",
    "outputs",
    "nodes",
    "resistors",
    "heat_inputs",
    "supply_air",
    "disturbance",
    "parameters",
    "inputs",
)
NODE_KEYS = ("capacity", "description")
HEAT_KEYS = ("to", "unit", "description")
AIR_KEYS = ("node", "flow", "temperature", "cp")
DISTURBANCE_KEYS = ("name", "kind", "to", "magnitude", "length_scale", "period")
PARAMETER_KEYS = ("value", "unit", "bounds", "fixed", "expr", "kind", "description", "prior")
INPUT_KEYS = ("default", "mean_of", "description")

#: Units accepted for parameter values, per kind: factor to the SI unit (first entry).
PARAMETER_UNITS: dict[str, dict[str, float]] = {
    "resistance": {"K/W": 1.0, "K/kW": 1e-3, "mK/W": 1e-3},
    "capacitance": {"J/K": 1.0, "kJ/K": 1e3, "MJ/K": 1e6, "Wh/K": 3600.0, "kWh/K": 3.6e6},
    "gain": {"1": 1.0, "m2": 1.0, "%": 0.01},
    "magnitude": {"W": 1.0, "kW": 1e3},
    "time": {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0},
    "other": {"": 1.0, "J/(kg K)": 1.0},
}
_SI_GAIN_UNIT = {"1": "1", "m2": "m2", "%": "1"}
#: Most elements (nodes, resistors, parameters...) one model file may declare.
MAX_ELEMENTS = 2000


class _Reader:
    """Validation helpers that prefix every message with the file and the key."""

    def __init__(self, source: str) -> None:
        self.source = source

    def err(self, where: str, msg: str) -> ModelFileError:
        return ModelFileError(f"model file {self.source}: {where}: {msg}")

    def table(self, v: object, where: str) -> Mapping[str, Any]:
        if not isinstance(v, Mapping):
            raise self.err(where, f"must be a table, got {_type(v)}")
        if len(v) > MAX_ELEMENTS:
            raise self.err(where, f"has {len(v)} entries, more than the limit of {MAX_ELEMENTS}")
        return v

    def keys(self, t: Mapping[str, Any], allowed: Sequence[str], where: str) -> None:
        for k in t:
            if k not in allowed:
                raise self.err(
                    where, f"unknown key {k!r}; {did_you_mean(k, allowed)} (allowed: {', '.join(allowed)})"
                )

    def text(self, v: object, where: str) -> str:
        if not isinstance(v, str) or not v.strip():
            raise self.err(where, f"must be a non-empty string, got {_type(v)}")
        return v

    def names(self, v: object, where: str) -> list[str]:
        if not isinstance(v, list):
            raise self.err(where, f"must be a list of names, got {_type(v)}")
        if len(v) > MAX_ELEMENTS:
            raise self.err(where, f"has {len(v)} entries, more than the limit of {MAX_ELEMENTS}")
        return [self.text(x, f"{where}[{i}]") for i, x in enumerate(v)]

    def number(self, v: object, where: str) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.err(where, f"must be a number, got {_type(v)}")
        try:
            x = float(v)
        except OverflowError:
            raise self.err(where, "is too large") from None
        if not math.isfinite(x):
            raise self.err(where, f"must be finite, got {v!r}")
        return x

    def gains(self, to: object, where: str) -> dict[str, str | float]:
        """Where a heat flow goes: a node name (all of it), or a table of node -> gain."""
        if isinstance(to, str):
            return {self.text(to, where): 1.0}
        to = self.table(to, where)
        if not to:
            raise self.err(where, "names no node")
        return {k: self.element(v, f"{where}.{k}") for k, v in to.items()}

    def element(self, v: object, where: str) -> str | float:
        """An element value: a parameter name or a number."""
        if isinstance(v, str):
            return self.text(v, where)
        return self.number(v, where)


def _type(v: object) -> str:
    return {dict: "a table", list: "a list", str: "text", bool: "true/false"}.get(type(v), type(v).__name__)


def read_model_file(path: str | Path) -> ZoneModel:
    """Read a TOML model file (see the module notes) into a :class:`ZoneModel`.

    Raises
    ------
    ModelFileError
        One line naming the file and the key, for anything that is not a valid model.
    """
    p = Path(path)
    doc = read_model_document(p, "TOML")
    return model_from_document(doc, source=str(p), default_name=p.stem)


def model_from_document(
    doc: Mapping[str, Any], source: str = "<model>", default_name: str = "model"
) -> ZoneModel:
    """Build a :class:`ZoneModel` from a parsed model-file document (a dict)."""
    r = _Reader(source)
    doc = r.table(doc, "the top level")
    r.keys(doc, TOP_KEYS, "the top level")
    for key in ("nodes", "resistors", "parameters"):
        if key not in doc:
            raise r.err("the top level", f"missing {key!r} (a model needs nodes, resistors and parameters)")
    name = r.text(doc.get("name", default_name), "name")
    description = doc.get("description", "")
    if not isinstance(description, str):
        raise r.err("description", f"must be text, got {_type(description)}")

    nodes: list[Node] = []
    for n, spec in r.table(doc["nodes"], "[nodes]").items():
        where = f"[nodes].{n}"
        if isinstance(spec, str) or (not isinstance(spec, Mapping) and spec is not None):
            spec = {"capacity": spec}
        spec = r.table(spec, where)
        r.keys(spec, NODE_KEYS, where)
        cap = r.element(spec["capacity"], f"{where}.capacity") if "capacity" in spec else None
        desc = spec.get("description", "")
        if not isinstance(desc, str):
            raise r.err(f"{where}.description", "must be text")
        nodes.append(Node(n, cap, desc))
    if not nodes:
        raise r.err("[nodes]", "is empty; declare at least the room air node")

    resistors = []
    res_list = doc["resistors"]
    if not isinstance(res_list, list):
        raise r.err("resistors", f"must be a list of [node, node, resistance], got {_type(res_list)}")
    if len(res_list) > MAX_ELEMENTS:
        raise r.err("resistors", f"has {len(res_list)} entries, more than the limit of {MAX_ELEMENTS}")
    for i, spec in enumerate(res_list):
        where = f"resistors[{i}]"
        if isinstance(spec, list):
            if len(spec) != 3:
                raise r.err(where, f"must be [node, node, resistance], got {len(spec)} entries")
            a, b, val = spec
        elif isinstance(spec, Mapping):
            r.keys(spec, ("between", "resistance"), where)
            between = r.names(spec.get("between"), f"{where}.between")
            if len(between) != 2 or "resistance" not in spec:
                raise r.err(where, "needs between = [node, node] and resistance")
            (a, b), val = between, spec["resistance"]
        else:
            raise r.err(where, f"must be [node, node, resistance], got {_type(spec)}")
        resistors.append(
            Resistor(r.text(a, f"{where}[0]"), r.text(b, f"{where}[1]"), r.element(val, f"{where}[2]"))
        )

    heat = []
    for h, spec in r.table(doc.get("heat_inputs", {}), "[heat_inputs]").items():
        where = f"[heat_inputs].{h}"
        if isinstance(spec, str):
            spec = {"to": spec}
        spec = r.table(spec, where)
        r.keys(spec, HEAT_KEYS, where)
        split = r.gains(spec.get("to"), f"{where}.to")
        unit = spec.get("unit", "W")
        if unit not in HEAT_INPUT_UNITS:
            raise r.err(f"{where}.unit", f"{unit!r} is not one of {', '.join(HEAT_INPUT_UNITS)}")
        heat.append(HeatInput(h, split, unit))

    air = []
    air_list = doc.get("supply_air", [])
    if isinstance(air_list, Mapping):
        air_list = [air_list]
    if not isinstance(air_list, list):
        raise r.err("supply_air", f"must be [[supply_air]] tables, got {_type(air_list)}")
    for i, spec in enumerate(air_list):
        where = f"supply_air[{i}]"
        spec = r.table(spec, where)
        r.keys(spec, AIR_KEYS, where)
        if "node" not in spec:
            raise r.err(where, "needs node = the capacitive node the air enters")
        air.append(
            SupplyAir(
                r.text(spec["node"], f"{where}.node"),
                r.text(spec.get("flow", "m"), f"{where}.flow"),
                r.text(spec.get("temperature", "Ts"), f"{where}.temperature"),
                r.element(spec.get("cp", CP_AIR), f"{where}.cp"),
            )
        )

    dists = _disturbances(r, doc.get("disturbance", []))
    params = _parameters(r, r.table(doc["parameters"], "[parameters]"), nodes, resistors, heat, air, dists)
    inputs = _inputs(r, r.table(doc.get("inputs", {}), "[inputs]"))
    boundaries = r.names(doc.get("boundaries", []), "boundaries")
    outputs = r.names(doc["outputs"], "outputs") if "outputs" in doc else None
    try:
        net = RCNetwork(
            name, nodes, boundaries, resistors, params, heat, air, outputs, description, disturbances=dists
        )
        return ZoneModel(net, inputs=inputs, source=source)
    except ModelFileError as exc:
        raise ModelFileError(f"model file {source}: {str(exc).removeprefix('model: ')}") from None
    except RczoneError as exc:
        raise ModelFileError(f"model file {source}: {exc}") from None


def _disturbances(r: _Reader, items: object) -> list[LatentForce]:
    """The ``[[disturbance]]`` tables (see the module notes)."""
    if isinstance(items, Mapping):
        items = [items]
    if not isinstance(items, list):
        raise r.err("disturbance", f"must be [[disturbance]] tables, got {_type(items)}")
    if len(items) > MAX_ELEMENTS:
        raise r.err("disturbance", f"has {len(items)} entries, more than the limit of {MAX_ELEMENTS}")
    out = []
    for i, spec in enumerate(items):
        where = f"disturbance[{i}]"
        spec = r.table(spec, where)
        r.keys(spec, DISTURBANCE_KEYS, where)
        for key in ("name", "kind", "to", "magnitude", "length_scale"):
            if key not in spec:
                raise r.err(where, f"needs {key} (see docs/disturbances.md)")
        gains = r.gains(spec["to"], f"{where}.to")
        kw = {
            k: r.element(spec[k], f"{where}.{k}")
            for k in ("magnitude", "length_scale", "period")
            if k in spec
        }
        try:
            out.append(
                LatentForce(
                    r.text(spec["name"], f"{where}.name"), r.text(spec["kind"], f"{where}.kind"), gains, **kw
                )
            )
        except RczoneError as exc:
            raise r.err(where, str(exc)) from None
    return out


def _usage_kinds(
    nodes: list[Node],
    resistors: list[Resistor],
    heat: list[HeatInput],
    air: list[SupplyAir],
    dists: Sequence[LatentForce] = (),
) -> dict[str, set[str]]:
    """Kinds implied by where each parameter name is used."""
    used: dict[str, set[str]] = {}
    for n in nodes:
        if isinstance(n.capacity, str):
            used.setdefault(n.capacity, set()).add("capacitance")
    for res in resistors:
        if isinstance(res.resistance, str):
            used.setdefault(res.resistance, set()).add("resistance")
    for h in heat:
        for _, g in h.split:
            if isinstance(g, str):
                used.setdefault(g, set()).add("gain")
    for s in air:
        if isinstance(s.cp, str):
            used.setdefault(s.cp, set()).add("other")
    for d in dists:
        for _, g in d.gains:
            if isinstance(g, str):
                used.setdefault(g, set()).add("gain")
        for role, v in d.hyperparameters:
            if isinstance(v, str):
                used.setdefault(v, set()).add(ROLE_KINDS[role])
    return used


def _parameters(
    r: _Reader,
    table: Mapping[str, Any],
    nodes: list[Node],
    resistors: list[Resistor],
    heat: list[HeatInput],
    air: list[SupplyAir],
    dists: Sequence[LatentForce] = (),
) -> list[Parameter]:
    specs: dict[str, Mapping[str, Any]] = {}
    for p, spec in table.items():
        where = f"[parameters].{p}"
        if not isinstance(spec, Mapping):
            spec = {"value": spec}
        r.keys(spec, PARAMETER_KEYS, where)
        specs[p] = spec
    used = _usage_kinds(nodes, resistors, heat, air, dists)
    for p, kinds in used.items():
        if len(kinds) > 1:
            raise r.err(
                f"[parameters].{p}",
                f"is used as {' and as '.join(sorted(kinds))}; use one parameter per role",
            )
    kinds = {p: next(iter(used[p])) for p in used}
    # parameters used only in ties take the kind of the ties that use them
    for _ in range(len(specs)):
        changed = False
        for p, spec in specs.items():
            if p in kinds or "expr" in spec:
                continue
            users = {
                kinds[q]
                for q, s in specs.items()
                if "expr" in s and q in kinds and isinstance(s["expr"], str) and p in _names(r, q, s["expr"])
            }
            if len(users) == 1:
                kinds[p] = users.pop()
                changed = True
        if not changed:
            break
    out = []
    for p, spec in specs.items():
        where = f"[parameters].{p}"
        kind = spec.get("kind", kinds.get(p, "other"))
        if kind not in PARAMETER_UNITS:
            raise r.err(f"{where}.kind", f"{kind!r} is not one of {', '.join(PARAMETER_UNITS)}")
        if p in kinds and kinds[p] != kind and kinds[p] != "other":
            raise r.err(f"{where}.kind", f"is declared {kind!r} but used as a {kinds[p]}")
        units = PARAMETER_UNITS[kind]
        default_unit = next(iter(units))
        unit = spec.get("unit", default_unit)
        if kind == "other":
            factor, si_unit = 1.0, unit
            if not isinstance(unit, str):
                raise r.err(f"{where}.unit", "must be text")
        else:
            if unit not in units:
                hint = did_you_mean(str(unit), units)
                raise r.err(
                    f"{where}.unit", f"{unit!r} is not a unit of a {kind} ({', '.join(units)}); {hint}"
                )
            factor = units[unit]
            si_unit = _SI_GAIN_UNIT.get(unit, "1") if kind == "gain" else default_unit
        kw: dict[str, Any] = {"name": p, "kind": kind, "unit": si_unit}
        if "expr" in spec:
            if "unit" in spec and factor != 1.0:
                raise r.err(where, "a tie's expression is in SI units; drop its unit")
            kw["expr"] = r.text(spec["expr"], f"{where}.expr")
        if "value" in spec:
            kw["value"] = r.number(spec["value"], f"{where}.value") * factor
        if "bounds" in spec:
            b = spec["bounds"]
            if not isinstance(b, list) or len(b) != 2:
                raise r.err(f"{where}.bounds", f"must be [lower, upper], got {b!r}")
            kw["bounds"] = tuple(r.number(x, f"{where}.bounds") * factor for x in b)
        if "fixed" in spec:
            if not isinstance(spec["fixed"], bool):
                raise r.err(f"{where}.fixed", f"must be true or false, got {spec['fixed']!r}")
            kw["fixed"] = spec["fixed"]
        if "description" in spec:
            if not isinstance(spec["description"], str):
                raise r.err(f"{where}.description", "must be text")
            kw["description"] = spec["description"]
        if "prior" in spec:
            try:
                kw["prior"] = Prior.from_dict(r.table(spec["prior"], f"{where}.prior"), scale=factor)
            except RczoneError as exc:
                raise r.err(f"{where}.prior", str(exc)) from None
        if "value" not in spec and "expr" not in spec:
            raise r.err(where, "needs a value (or an expr for a tie)")
        try:
            out.append(Parameter(**kw))
        except RczoneError as exc:
            raise r.err(where, str(exc)) from None
    return out


def _names(r: _Reader, name: str, expr: str) -> tuple[str, ...]:
    try:
        return expression_names(expr)
    except RczoneError as exc:
        raise r.err(f"[parameters].{name}.expr", str(exc)) from None


def _inputs(r: _Reader, table: Mapping[str, Any]) -> ModelInputs:
    defaults, mean_of, desc = {}, {}, {}
    for name, spec in table.items():
        where = f"[inputs].{name}"
        spec = r.table(spec, where)
        r.keys(spec, INPUT_KEYS, where)
        if "default" in spec:
            defaults[name] = r.number(spec["default"], f"{where}.default")
        if "mean_of" in spec:
            cols = r.names(spec["mean_of"], f"{where}.mean_of")
            if not cols:
                raise r.err(f"{where}.mean_of", "lists no column")
            mean_of[name] = tuple(cols)
        if "description" in spec:
            desc[name] = r.text(spec["description"], f"{where}.description")
    return ModelInputs(defaults, mean_of, desc)


# --------------------------------------------------------------------------- writing
def _toml_value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(float(v))
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() and k.isascii() else _toml_value(k)


def model_to_toml(model: ZoneModel | RCNetwork, header: str = "") -> str:
    """A model file (see the module notes) for ``model``; values are written in SI units.

    With a :class:`ZoneModel`, its ``theta`` values are written as the parameters' values.
    :func:`read_model_file` of the result gives the same network (tested round trip).

    Parameters
    ----------
    model : ZoneModel or RCNetwork
        The model to write.
    header : str
        Comment lines at the top of the file (each prefixed with ``#``).

    Returns
    -------
    str
        The TOML text.
    """
    zm = model if isinstance(model, ZoneModel) else ZoneModel(model)
    net = zm.network
    lines = [f"# {line}".rstrip() for line in header.splitlines()] if header else []
    lines += [f"name = {_toml_value(net.name)}"]
    if net.description:
        lines.append(f"description = {_toml_value(net.description)}")
    lines.append(f"boundaries = {_toml_value(list(net.boundaries))}")
    lines.append(f"outputs = {_toml_value(list(net.outputs))}")
    lines.append("resistors = [")
    lines += [f"    {_toml_value([res.a, res.b, res.resistance])}," for res in net.resistors]
    lines += ["]", "", "[nodes]"]
    for n in net.nodes:
        spec: dict[str, object] = {}
        if n.capacity is not None:
            spec["capacity"] = n.capacity
        if n.description:
            spec["description"] = n.description
        lines.append(f"{_key(n.name)} = {_toml_value(spec)}")
    if net.heat_inputs:
        lines += ["", "[heat_inputs]"]
        for h in net.heat_inputs:
            hs: dict[str, object] = {"to": dict(h.split)}
            if h.unit != "W":
                hs["unit"] = h.unit
            lines.append(f"{_key(h.name)} = {_toml_value(hs)}")
    for s in net.supply_air:
        lines += ["", "[[supply_air]]"]
        lines += [
            f"{k} = {_toml_value(v)}"
            for k, v in (("node", s.node), ("flow", s.flow), ("temperature", s.temperature), ("cp", s.cp))
        ]
    for d in net.disturbances:
        lines += ["", "[[disturbance]]"]
        lines += [
            f"{k} = {_toml_value(v)}" for k, v in (("name", d.name), ("kind", d.kind), ("to", dict(d.gains)))
        ]
        lines += [f"{role} = {_toml_value(v)}" for role, v in d.hyperparameters]
    lines += ["", "[parameters]"]
    for p in net.parameters.values():
        ps: dict[str, object] = {}
        if p.is_tied:
            ps["expr"] = p.expr
        else:
            ps["value"] = zm.theta.get(p.name, p.value)
            ps["unit"] = p.unit
        if p.kind == "other":
            ps["kind"] = "other"
        if p.bounds is not None:
            ps["bounds"] = list(p.bounds)
        if p.fixed:
            ps["fixed"] = True
        if p.description:
            ps["description"] = p.description
        if p.prior is not None:
            ps["prior"] = p.prior.to_dict()
        if p.kind == "gain" and p.unit == "1":
            ps.pop("unit", None)
        lines.append(f"{_key(p.name)} = {_toml_value(ps)}")
    ins = zm.inputs
    names = list(dict.fromkeys([*ins.defaults, *ins.mean_of, *ins.descriptions]))
    if names:
        lines += ["", "[inputs]"]
        for k in names:
            spec = {}
            if k in ins.defaults:
                spec["default"] = ins.defaults[k]
            if k in ins.mean_of:
                spec["mean_of"] = list(ins.mean_of[k])
            if k in ins.descriptions:
                spec["description"] = ins.descriptions[k]
            lines.append(f"{_key(k)} = {_toml_value(spec)}")
    return "\n".join(lines) + "\n"
