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


def random_network(
    rng: np.random.Generator, n_cap: int, n_massless: int, n_bound: int, n_outputs: int = 1, n_flows: int = 1
) -> RCNetwork:
    """A connected RC network: random tree plus random extra edges, log-uniform R and C.

    ``n_outputs`` measured nodes: the first capacitive node, then random other nodes (a
    massless one gives an output with a ``D`` term); ``n_flows`` supply-air elements on random
    capacitive nodes, each with its own flow and supply temperature.
    """
    cap = [f"T{i}" for i in range(n_cap)]
    mass0 = [f"Z{i}" for i in range(n_massless)]
    bounds = [f"B{i}" for i in range(n_bound)]
    names = cap + mass0
    order = rng.permutation(len(names))
    edges = {(names[order[i]], names[order[rng.integers(0, i)]]) for i in range(1, len(names))}
    for _ in range(rng.integers(0, len(names) + 1) if len(names) > 1 else 0):
        a, b = rng.choice(len(names), 2, replace=False)
        edges.add((names[a], names[b]))
    for bnd in bounds:
        edges.add((names[rng.integers(0, len(names))], bnd))
    for z in mass0:  # a massless node needs two connections to be more than a dead end
        edges.add((z, bounds[rng.integers(0, n_bound)]))
    res, params = [], []
    for k, (a, b) in enumerate(sorted(edges)):
        res.append(Resistor(a, b, f"R{k}"))
        params.append(Parameter(f"R{k}", "resistance", float(10 ** rng.uniform(-3, 0))))
    nodes = [Node(c, f"C{i}") for i, c in enumerate(cap)] + [Node(z, None) for z in mass0]
    params += [Parameter(f"C{i}", "capacitance", float(10 ** rng.uniform(4, 7))) for i in range(n_cap)]
    return RCNetwork(
        "random",
        nodes,
        bounds,
        res,
        params,
        heat_inputs=[HeatInput("Q", {cap[rng.integers(0, n_cap)]: 1.0})],
        supply_air=[
            SupplyAir(cap[rng.integers(0, n_cap)], "m" if f == 0 else f"m{f}", "Ts" if f == 0 else f"Ts{f}")
            for f in range(n_flows)
        ],
        outputs=[cap[0], *rng.permutation(names[1:])[: n_outputs - 1].tolist()],
    )
