"""Networks to and from plain dictionaries (JSON), so a model travels as a small file."""

from __future__ import annotations

from typing import Any

from rczone.errors import NetworkError
from rczone.network.network import HeatInput, Node, RCNetwork, Resistor, SupplyAir
from rczone.network.parameters import Parameter

FORMAT = "rczone-network/1"


def network_to_dict(net: RCNetwork) -> dict[str, Any]:
    """A JSON-ready description of ``net`` (structure and declared parameter values)."""
    return {
        "format": FORMAT,
        "name": net.name,
        "description": net.description,
        "nodes": [{"name": n.name, "capacity": n.capacity, "description": n.description} for n in net.nodes],
        "boundaries": list(net.boundaries),
        "resistors": [{"a": r.a, "b": r.b, "resistance": r.resistance} for r in net.resistors],
        "heat_inputs": [{"name": h.name, "split": dict(h.split)} for h in net.heat_inputs],
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
            }
            for p in net.parameters.values()
        ],
    }


def network_from_dict(d: dict[str, Any]) -> RCNetwork:
    """Rebuild a network written by :func:`network_to_dict` (validated like any network)."""
    if d.get("format") != FORMAT:
        raise NetworkError(
            f"not an rczone network description (format {d.get('format')!r}, expected {FORMAT!r})"
        )
    try:
        return RCNetwork(
            d["name"],
            [Node(n["name"], n["capacity"], n.get("description", "")) for n in d["nodes"]],
            d["boundaries"],
            [Resistor(r["a"], r["b"], r["resistance"]) for r in d["resistors"]],
            [Parameter(**p) for p in d["parameters"]],
            heat_inputs=[HeatInput(h["name"], h["split"]) for h in d.get("heat_inputs", [])],
            supply_air=[SupplyAir(**s) for s in d.get("supply_air", [])],
            outputs=d.get("outputs"),
            description=d.get("description", ""),
        )
    except (KeyError, TypeError) as exc:
        raise NetworkError(f"network description is incomplete or malformed: {exc}") from None
