"""Networks to and from plain dictionaries (JSON), so a model travels as a small file.

A dictionary read from a file is untrusted: :func:`network_from_dict` checks every field's
type and says which one is wrong, and the network it builds is validated like any other
(names, topology, finite and positive element values, bounded tie expressions).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rczone.errors import NetworkError, ParameterError
from rczone.network.disturbance import LatentForce
from rczone.network.network import HeatInput, Node, RCNetwork, Resistor, SupplyAir
from rczone.network.parameters import Parameter
from rczone.network.prior import Prior

FORMAT = "rczone-network/1"

_PARAMETER_KEYS = ("name", "kind", "value", "expr", "unit", "description", "bounds", "fixed", "prior")


def network_to_dict(net: RCNetwork) -> dict[str, Any]:
    """A JSON-ready description of ``net`` (structure and declared parameters)."""
    return {
        "format": FORMAT,
        "name": net.name,
        "description": net.description,
        "nodes": [{"name": n.name, "capacity": n.capacity, "description": n.description} for n in net.nodes],
        "boundaries": list(net.boundaries),
        "resistors": [{"a": r.a, "b": r.b, "resistance": r.resistance} for r in net.resistors],
        "heat_inputs": [{"name": h.name, "split": dict(h.split), "unit": h.unit} for h in net.heat_inputs],
        "supply_air": [
            {"node": s.node, "flow": s.flow, "temperature": s.temperature, "cp": s.cp} for s in net.supply_air
        ],
        "outputs": list(net.outputs),
        "parameters": [
            {
                "name": p.name,
                "kind": p.kind,
                "value": p.value,
                "expr": p.expr,
                "unit": p.unit,
                "description": p.description,
                "bounds": list(p.bounds) if p.bounds is not None else None,
                "fixed": p.fixed,
                # written only when declared, so a model without priors keeps its JSON
                **({"prior": p.prior.to_dict()} if p.prior is not None else {}),
            }
            for p in net.parameters.values()
        ],
        # written only when declared, so a model without disturbances keeps its JSON
        **({"disturbances": [disturbance_to_dict(x) for x in net.disturbances]} if net.disturbances else {}),
    }


def disturbance_to_dict(d: LatentForce) -> dict[str, Any]:
    """A JSON-ready description of one disturbance (:mod:`rczone.network.disturbance`)."""
    out: dict[str, Any] = {
        "name": d.name,
        "kind": d.kind,
        "gains": dict(d.gains),
        "magnitude": d.magnitude,
        "length_scale": d.length_scale,
    }
    if d.period is not None:
        out["period"] = d.period
    return out


_DISTURBANCE_KEYS = ("name", "kind", "gains", "magnitude", "length_scale", "period")


def _disturbance(x: object, i: int) -> LatentForce:
    where = f"disturbances[{i}]"
    x = _known(x, _DISTURBANCE_KEYS, where)
    gains = _table(x.get("gains"), f"{where}.gains")
    values = {}
    for key in ("magnitude", "length_scale", "period"):
        values[key] = _value(x.get(key), f"{where}.{key}")
        if values[key] is None and key != "period":
            raise NetworkError(f"network description: {where} has no {key!r}")
    return LatentForce(
        _text(x, "name", where),
        _text(x, "kind", where),
        {str(k): _value(v, f"{where}.gains.{k}") for k, v in gains.items()},
        magnitude=values["magnitude"],
        length_scale=values["length_scale"],
        period=values["period"],
    )


def _table(d: object, where: str) -> Mapping[str, Any]:
    if not isinstance(d, Mapping):
        raise NetworkError(f"network description: {where} must be an object, got {type(d).__name__}")
    return d


def _known(d: object, keys: tuple[str, ...], where: str) -> Mapping[str, Any]:
    """``d`` as an object whose keys are all among ``keys``."""
    d = _table(d, where)
    unknown = [k for k in d if k not in keys]
    if unknown:
        raise NetworkError(f"network description: {where} has unknown key {unknown[0]!r}")
    return d


def _list(d: Mapping[str, Any], key: str, where: str, required: bool = True) -> list:
    if key not in d:
        if required:
            raise NetworkError(f"network description: {where} has no {key!r}")
        return []
    v = d[key]
    if not isinstance(v, list):
        raise NetworkError(f"network description: {where}.{key} must be a list, got {type(v).__name__}")
    return v


def _text(d: Mapping[str, Any], key: str, where: str, default: str | None = None) -> str:
    if key not in d or d[key] is None:
        if default is not None:
            return default
        raise NetworkError(f"network description: {where} has no {key!r}")
    v = d[key]
    if not isinstance(v, str):
        raise NetworkError(f"network description: {where}.{key} must be text, got {type(v).__name__}")
    return v


def _value(v: object, where: str) -> str | float | None:
    """An element value: a parameter name or a number (None where allowed, e.g. a massless node)."""
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise NetworkError(f"network description: {where} must be a number or a parameter name, got {v!r}")
    return float(v)


def _parameter(p: object, i: int) -> Parameter:
    where = f"parameters[{i}]"
    p = _known(p, _PARAMETER_KEYS, where)
    name = _text(p, "name", where)
    kw: dict[str, Any] = {"name": name, "kind": _text(p, "kind", where, "other")}
    for key in ("unit", "description", "expr"):
        if p.get(key) is not None:
            kw[key] = _text(p, key, where)
    if p.get("value") is not None:
        kw["value"] = _value(p["value"], f"{where}.value")
    if p.get("bounds") is not None:
        b = p["bounds"]
        if not isinstance(b, list) or len(b) != 2:
            raise NetworkError(f"network description: {where}.bounds must be [lower, upper], got {b!r}")
        kw["bounds"] = tuple(_value(x, f"{where}.bounds") for x in b)
    if p.get("fixed") is not None:
        kw["fixed"] = p["fixed"]
    if p.get("prior") is not None:
        kw["prior"] = Prior.from_dict(_table(p["prior"], f"{where}.prior"))
    return Parameter(**kw)


def network_from_dict(d: object) -> RCNetwork:
    """Rebuild a network written by :func:`network_to_dict` (validated like any network).

    Raises
    ------
    NetworkError, ParameterError
        Naming the field that is missing or malformed.
    """
    d = _table(d, "the network")
    if d.get("format") != FORMAT:
        raise NetworkError(
            f"not an rczone network description (format {d.get('format')!r}, expected {FORMAT!r})"
        )
    nodes = []
    for i, n in enumerate(_list(d, "nodes", "network")):
        n = _table(n, f"nodes[{i}]")
        nodes.append(
            Node(
                _text(n, "name", f"nodes[{i}]"),
                _value(n.get("capacity"), f"nodes[{i}].capacity"),
                _text(n, "description", f"nodes[{i}]", ""),
            )
        )
    boundaries = _list(d, "boundaries", "network")
    resistors = []
    for i, r in enumerate(_list(d, "resistors", "network")):
        r = _table(r, f"resistors[{i}]")
        res = _value(r.get("resistance"), f"resistors[{i}].resistance")
        if res is None:
            raise NetworkError(f"network description: resistors[{i}] has no 'resistance'")
        resistors.append(Resistor(_text(r, "a", f"resistors[{i}]"), _text(r, "b", f"resistors[{i}]"), res))
    heat = []
    for i, h in enumerate(_list(d, "heat_inputs", "network", required=False)):
        h = _table(h, f"heat_inputs[{i}]")
        split = _table(h.get("split"), f"heat_inputs[{i}].split")
        heat.append(
            HeatInput(
                _text(h, "name", f"heat_inputs[{i}]"),
                {str(k): _value(v, f"heat_inputs[{i}].split.{k}") for k, v in split.items()},
                _text(h, "unit", f"heat_inputs[{i}]", "W"),
            )
        )
    air = []
    for i, s in enumerate(_list(d, "supply_air", "network", required=False)):
        where = f"supply_air[{i}]"
        s = _table(s, where)
        air.append(
            SupplyAir(
                _text(s, "node", where),
                _text(s, "flow", where, "m"),
                _text(s, "temperature", where, "Ts"),
                _value(s.get("cp", 1005.0), f"{where}.cp"),
            )
        )
    params = [_parameter(p, i) for i, p in enumerate(_list(d, "parameters", "network"))]
    dists = [_disturbance(x, i) for i, x in enumerate(_list(d, "disturbances", "network", required=False))]
    outputs = d.get("outputs")
    if outputs is not None and (not isinstance(outputs, list) or not outputs):
        raise NetworkError("network description: outputs must be a non-empty list of node names")
    try:
        return RCNetwork(
            _text(d, "name", "network", "model"),
            nodes,
            boundaries,
            resistors,
            params,
            heat_inputs=heat,
            supply_air=air,
            outputs=outputs,
            description=_text(d, "description", "network", ""),
            disturbances=dists,
        )
    except (TypeError, AttributeError) as exc:
        raise NetworkError(f"network description is malformed: {exc}") from None
    except RecursionError:
        raise ParameterError("network description is nested too deeply") from None
