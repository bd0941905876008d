"""Synthetic nights from the paper's reduced 2nd-order model: closed-loop and forced response."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rczone.models import get_model
from rczone.simulation import steady_state, zoh


def night(mode: str, seed: int = 0, hours: float = 12.0, theta: dict | None = None) -> pd.DataFrame:
    """One night sampled every minute.

    ``closed-loop``: a thermostat (P control of Ts at constant flow) holds the room at 22 degC while
    the neighbours are held at 22 degC by their own controllers (small drift). ``forced``: Ts
    alternates between 12 and 35 degC every 2 h at the largest flow; neighbours at 22 degC.
    """
    rng = np.random.default_rng(seed)
    net = get_model("second-order-paper")
    ss = net.state_space(theta)
    t = np.arange(0, hours * 3600 + 1, 60.0)
    n = t.size
    To = 20 + 4 * np.cos(2 * np.pi * (t / 86400 + 0.25)) + 0.1 * rng.standard_normal(n)
    Tsd = 22 + 0.3 * np.sin(2 * np.pi * t / (5 * 3600) + rng.uniform(0, 6)) + 0.05 * rng.standard_normal(n)
    Q = np.full(n, 50.0)
    m = np.full(n, 0.05 if mode == "closed-loop" else 0.12)
    Ts = np.empty(n)
    x = np.array([22.0, 22.0])
    Phi, G = zoh(*ss.matrices(m[0]), 60.0)  # the flow is constant all night
    Ti = np.empty(n)
    for k in range(n):
        Ti[k] = x[0]
        if mode == "closed-loop":
            Ts[k] = np.clip(22 + 8.0 * (22.0 - x[0]) + (To[k] - 22) * 0.5, 12, 35)
        else:
            Ts[k] = 35.0 if (t[k] // 7200) % 2 == 0 else 12.0
        if k + 1 < n:
            x = Phi @ x + G @ np.array([To[k], Tsd[k], Ts[k], Q[k]])
    Ti_meas = Ti + 0.03 * rng.standard_normal(n)
    return pd.DataFrame({"time": t, "Ti": Ti_meas, "To": To, "Tsd": Tsd, "Ts": Ts, "m": m, "Q": Q})


def family(name: str = "TiTe+heater", outputs: tuple[str, ...] = ("Ti",), theta: dict | None = None):
    """A family model (Bacher & Madsen) as a ZoneModel, with other measured nodes if asked."""
    from rczone.models import ZoneModel, family_model
    from rczone.network import RCNetwork

    zm = family_model(name)
    n = zm.network
    net = RCNetwork(
        n.name, n.nodes, n.boundaries, n.resistors, n.parameters, n.heat_inputs, n.supply_air, outputs
    )
    return ZoneModel(net, {**zm.theta, **(theta or {})}, inputs=zm.inputs, source=name)


def heated(
    zm, mode: str = "prbs", seed: int = 0, hours: float = 48.0, dt: float = 300.0, noise: float = 0.02
) -> pd.DataFrame:
    """Data of a heated zone simulated exactly from ``zm`` (inputs ``To``, ``Ph``), sampled every ``dt`` s.

    ``prbs``: the heater switches between 0 and 2 kW in blocks of 1 to 4 h (a PRBS-like
    experiment, as in Bacher & Madsen's); ``idle``: it stays at 500 W. Outdoors 5 degC with a 4 K
    diurnal swing; the zone starts at rest. Every output gets ``noise`` K of white noise.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, hours * 3600.0 + 1.0, dt)
    cols = {"To": 5.0 + 4.0 * np.sin(2 * np.pi * t / 86400.0), "Ph": np.full(t.size, 500.0)}
    if mode == "prbs":
        level, k = 0.0, 0
        while k < t.size:
            n = int(rng.integers(round(3600 / dt), round(4 * 3600 / dt) + 1))
            cols["Ph"][k : k + n] = level
            level = 2000.0 - level
            k += n
    u = np.column_stack([cols[n] for n in zm.network.input_names])
    y = zm.simulate(t, u, x0=steady_state(zm.state_space(), u[0], 0.0)).y
    frame = pd.DataFrame({"time": t, **cols})
    for j, o in enumerate(zm.network.outputs):
        frame[o] = y[:, j] + noise * rng.standard_normal(t.size)
    return frame
