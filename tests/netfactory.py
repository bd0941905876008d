"""Networks used by several tests, declared with rczone's own network description.

These are test fixtures, not the product's paper models (those live in rczone.models and are
tested against these independent constructions where it matters).
"""

from __future__ import annotations

import numpy as np

from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

SURFACES = (("o", "To"), ("f", "Tf"), ("c", "Tc"), ("n1", "Tn1"), ("n2", "Tn2"), ("hw", "Thw"))


def thirteen_state(rng: np.random.Generator) -> RCNetwork:
    """A paper-like MRC(13, 8, 32) zone with random construction-like values."""
    nodes = [Node("Ti", "Cr")]
    res = [Resistor("Ti", "To", "Rwin")]
    params = [
        Parameter("Cr", "capacitance", rng.uniform(1e5, 8e5)),
        Parameter("Rwin", "resistance", rng.uniform(0.05, 0.3)),
    ]
    for s, far in SURFACES:
        nodes += [Node(f"T{s}w1", f"C{s}w1"), Node(f"T{s}w2", f"C{s}w2")]
        res += [
            Resistor("Ti", f"T{s}w1", f"R{s}w1"),
            Resistor(f"T{s}w1", f"T{s}w2", f"R{s}w2"),
            Resistor(f"T{s}w2", far, f"R{s}w3"),
        ]
        params += [Parameter(f"R{s}w{i}", "resistance", rng.uniform(0.005, 0.1)) for i in (1, 2, 3)]
        params += [Parameter(f"C{s}w{i}", "capacitance", rng.uniform(2e5, 3e6)) for i in (1, 2)]
    return RCNetwork(
        "13-state test zone",
        nodes,
        [far for _, far in SURFACES],
        res,
        params,
        heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
        supply_air=[SupplyAir("Ti", "m", "Ts")],
    )


def one_r_one_c(R: float = 0.01, C: float = 5e5) -> RCNetwork:
    """Ti with capacity C connected to To through R; Q on Ti."""
    return RCNetwork(
        "1R1C",
        [Node("Ti", "C")],
        ["To"],
        [Resistor("Ti", "To", "R")],
        [Parameter("R", "resistance", R), Parameter("C", "capacitance", C)],
        heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
    )
