"""The benchmark problems beyond the paper's models: four coupled zones, and the 2-state peer task.

* :func:`four_zones` — four rooms in a row, each with an air node and an envelope node
  (8 states), the four room temperatures measured, neighbouring rooms coupled through a
  shared (party) wall; :func:`four_zone_data` simulates 1,000 hourly samples of the
  stochastic model with known parameters (process noise on the air nodes, a different
  measurement noise per sensor).
* :func:`peer_network` — the 2-state wall/room model of pySIP's Armadillo example
  (``TwTi_RoRi``: Tw to outdoor through Ro, Tw to Ti through Ri, heating on Ti), in SI units;
  :func:`peer_data` simulates it at the published estimates (720 half-hourly samples, FOH);
  :func:`armadillo_data` reads the Armadillo data (232 samples) from the shared folder when it
  is there (not redistributed with rczone).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.linalg import cholesky

from rczone.estimation import Dataset
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor
from rczone.simulation.discretize import interval_discretization

DAY = 86400.0
ROOMS = 4

#: The known parameters of the four-zone network (SI units).
FOUR_ZONE_TRUTH = {
    **{f"Ca{i}": c for i, c in zip(range(1, 5), (1.2e6, 0.8e6, 1.0e6, 1.5e6))},
    **{f"Cw{i}": c for i, c in zip(range(1, 5), (2.0e7, 1.5e7, 1.8e7, 2.5e7))},
    **{f"Rw{i}": r for i, r in zip(range(1, 5), (0.012, 0.016, 0.014, 0.010))},
    "Rwin": 0.03,
    "Rp": 0.008,
}
#: Noise of the simulated data: measurement noise per sensor (K), process noise per air node (K/sqrt(s)).
FOUR_ZONE_NOISE = {
    **{f"sigma_v_T{i}": s for i, s in zip(range(1, 5), (0.05, 0.08, 0.06, 0.1))},
    **{f"sigma_w_T{i}": 2e-3 for i in range(1, 5)},
    **{f"sigma_w_W{i}": 1e-4 for i in range(1, 5)},
    **{f"sigma_x0_{s}{i}": 0.5 for s in "TW" for i in range(1, 5)},
}
FOUR_ZONE_FREE = [
    *FOUR_ZONE_TRUTH,
    *(f"sigma_v_T{i}" for i in range(1, 5)),
    *(f"sigma_w_T{i}" for i in range(1, 5)),
]


def four_zones() -> RCNetwork:
    """Four rooms in a row: air node ``T<i>`` and envelope node ``W<i>`` each, party walls between neighbours."""
    nodes, res, heat = [], [], []
    for i in range(1, ROOMS + 1):
        nodes += [Node(f"T{i}", f"Ca{i}"), Node(f"W{i}", f"Cw{i}")]
        res += [
            Resistor(f"T{i}", "To", "Rwin"),
            Resistor(f"T{i}", f"W{i}", f"Rh{i}"),
            Resistor(f"W{i}", "To", f"Rh{i}"),
        ]
        heat.append(HeatInput(f"Q{i}", {f"T{i}": 1.0}))
        if i < ROOMS:
            res.append(Resistor(f"T{i}", f"T{i + 1}", "Rp"))
    params = [
        Parameter(n, "capacitance" if n.startswith("C") else "resistance", v)
        for n, v in FOUR_ZONE_TRUTH.items()
    ]
    params += [Parameter(f"Rh{i}", "resistance", expr=f"Rw{i}/2") for i in range(1, ROOMS + 1)]
    return RCNetwork(
        "four-zones",
        nodes,
        ["To"],
        res,
        params,
        heat_inputs=heat,
        outputs=[f"T{i}" for i in range(1, ROOMS + 1)],
        description="four rooms in a row coupled through party walls (benchmark)",
    )


def simulate_stochastic(
    net: RCNetwork,
    t: np.ndarray,
    u: np.ndarray,
    noise: dict[str, float],
    x0: np.ndarray,
    rng,
    hold: str = "zoh",
) -> np.ndarray:
    """Measurements of the exactly discretized stochastic model (process and measurement noise), shape (N, ny)."""
    ss = net.state_space()
    sw = np.array([noise[f"sigma_w_{s}"] for s in ss.state_names])
    keys = np.column_stack([np.diff(t)])
    Phi, G0, G1, Qd = interval_discretization(
        ss.A, ss.N, ss.B, ss.M, ss.capacities, keys, hold, np.diag(sw**2)
    )
    names = ["sigma_v"] if len(ss.output_names) == 1 else [f"sigma_v_{o}" for o in ss.output_names]
    sv = np.array([noise[n] for n in names])
    x = np.empty((t.size, ss.n_states))
    x[0] = x0
    for k in range(t.size - 1):
        w = cholesky(Qd[k] + 1e-30 * np.eye(ss.n_states), lower=True) @ rng.standard_normal(ss.n_states)
        x[k + 1] = Phi[k] @ x[k] + G0[k] @ u[k] + G1[k] @ u[k + 1] + w
    return x @ ss.C.T + u @ ss.D.T + sv * rng.standard_normal((t.size, sv.size))


def four_zone_data(n: int = 1000, seed: int = 12) -> Dataset:
    """``n`` hourly samples: outdoor temperature with a daily cycle, heating per room on a schedule."""
    rng = np.random.default_rng(seed)
    net = four_zones()
    t = np.arange(n) * 3600.0
    h = t / 3600.0
    cols = [5 + 6 * np.sin(2 * np.pi * (h - 9) / 24) + np.cumsum(0.1 * rng.standard_normal(n))]
    for i in range(ROOMS):
        on = ((h + 3 * i) % 24 >= 6) & ((h + 3 * i) % 24 < 20 - 2 * i)
        cols.append(np.where(on, 1500.0 + 300 * i, 200.0) + 100 * rng.standard_normal(n))
    u = np.column_stack(cols)
    ss = net.state_space()
    x0 = np.linalg.solve(ss.A, -ss.B @ u[0])
    y = simulate_stochastic(net, t, u, FOUR_ZONE_NOISE, x0, rng)
    return Dataset(t, u, np.zeros((n, 0)), y, net.input_names, (), net.outputs)


#: pySIP's published estimate on the Armadillo data, in SI units (Cw, Ci in J/K; sigw_w in K/sqrt(s)).
PEER_TRUTH = {"Ro": 0.017593, "Ri": 0.001984, "Cw": 169.597112 * DAY, "Ci": 18.94635 * DAY}
PEER_NOISE = {
    "sigma_w_Tw": 0.521344 / np.sqrt(DAY),
    "sigma_w_Ti": 0.0,
    "sigma_v": 0.034325,
    "sigma_x0_Tw": 0.1,
    "sigma_x0_Ti": 0.1,
}
#: The peer fit: 4 R and C, the wall's initial state, 3 noise levels.
PEER_FREE = ["Ro", "Ri", "Cw", "Ci", "x0_Tw", "sigma_w_Tw", "sigma_w_Ti", "sigma_v"]


def peer_network() -> RCNetwork:
    return RCNetwork(
        "TwTi_RoRi",
        nodes=[Node("Tw", "Cw"), Node("Ti", "Ci")],
        boundaries=["To"],
        resistors=[Resistor("Tw", "To", "Ro"), Resistor("Tw", "Ti", "Ri")],
        heat_inputs=[HeatInput("Qh", {"Ti": 1.0})],
        parameters=[
            Parameter("Ro", "resistance", 0.01),
            Parameter("Ri", "resistance", 0.01),
            Parameter("Cw", "capacitance", 1e7),
            Parameter("Ci", "capacitance", 1e6),
        ],
        outputs=["Ti"],
    )


def peer_data(n: int = 720, seed: int = 5) -> Dataset:
    """``n`` half-hourly samples of the peer model at the published estimates (FOH inputs)."""
    rng = np.random.default_rng(seed)
    net = peer_network().replace_parameters(
        [Parameter(k, ("resistance" if k[0] == "R" else "capacitance"), v) for k, v in PEER_TRUTH.items()]
    )
    t = np.arange(n) * 1800.0
    h = t / 3600.0
    To = 10 + 6 * np.sin(2 * np.pi * (h - 9) / 24) + np.cumsum(0.05 * rng.standard_normal(n))
    Qh = np.where((h % 24 > 6) & (h % 24 < 22), 1500.0, 0.0) * (rng.random(n) < 0.7)
    u = np.column_stack([To, Qh])
    y = simulate_stochastic(net, t, u, PEER_NOISE, np.array([26.6, 26.7]), rng, "foh")
    return Dataset(t, u, np.zeros((n, 0)), y, net.input_names, (), net.outputs)


def armadillo_data() -> Dataset | None:
    """The Armadillo data as pySIP fits it (232 samples), from ``$RCZONE_SHARED`` or ``../shared``; None if absent."""
    shared = Path(os.environ.get("RCZONE_SHARED", Path(__file__).resolve().parents[2] / "shared"))
    path = shared / "data" / "armadillo_pysip" / "armadillo_data_H2.csv"
    if not path.exists():
        return None
    import pandas as pd

    df = pd.read_csv(path).iloc[:-1]  # pySIP drops the last row
    df = df.rename(columns={"T_ext": "To", "P_hea": "Qh", "T_int": "Ti"}).set_index("Time")
    return Dataset.from_frame(df, peer_network())
