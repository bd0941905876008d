"""Small networks shared by the estimation unit tests."""

from __future__ import annotations

import numpy as np

from rczone.estimation import Dataset
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from rczone.simulation import simulate

NET2 = RCNetwork(
    "two",
    nodes=[Node("Ti", "Cr"), Node("Tw", "Cw")],
    boundaries=["To", "Tsd"],
    resistors=[Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"), Resistor("Tw", "Tsd", "R2")],
    heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
    supply_air=[SupplyAir("Ti", "m", "Ts")],
    parameters=[
        Parameter("Cr", "capacitance", 8e5),
        Parameter("Cw", "capacitance", 6e6),
        Parameter("Rwin", "resistance", 0.05),
        Parameter("Rw", "resistance", 0.01),
        Parameter("R1", "resistance", expr="Rw/2"),
        Parameter("R2", "resistance", expr="Rw/2"),
        Parameter("g", "gain", 1.0),
    ],
)

NET1 = RCNetwork(
    "one",
    nodes=[Node("Ti", "Cr")],
    boundaries=["To"],
    resistors=[Resistor("Ti", "To", "R")],
    heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
    parameters=[Parameter("Cr", "capacitance", 1e6), Parameter("R", "resistance", 0.01)],
)


def data2(n: int = 145, noise: float = 0.0, rng: np.random.Generator | None = None) -> Dataset:
    """One day at 10 min from NET2 at its declared values, optional white measurement noise."""
    t = np.arange(n) * 600.0
    h = t / 3600.0
    u = np.column_stack(
        [
            25 + 5 * np.sin(2 * np.pi * h / 24),
            22 + np.sin(2 * np.pi * h / 7),
            np.where(h % 6 < 3, 13.0, 18.0),
            50 + 40 * (h % 5 < 2),
        ]
    )
    m = np.where(h % 8 < 4, 0.1, 0.03)[:, None]
    y = simulate(NET2.state_space(), t, u, m).y
    if noise:
        y = y + noise * rng.standard_normal(y.shape)
    return Dataset(t, u, m, y, NET2.input_names, NET2.flow_names, NET2.outputs)


def data1(n: int = 97) -> Dataset:
    t = np.arange(n) * 900.0
    h = t / 3600.0
    u = np.column_stack([10 + 5 * np.sin(2 * np.pi * h / 24), 500.0 * (h % 6 < 3)])
    y = simulate(NET1.state_space(), t, u).y
    return Dataset(t, u, np.zeros((n, 0)), y, NET1.input_names, (), NET1.outputs)
