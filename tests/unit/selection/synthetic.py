"""Data simulated from a known stochastic RC model (Euler-Maruyama, independent of rczone's filter)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rczone.models import load_model

#: The structure the data come from, and its values (away from the model's declared start values).
TRUE_MODEL = "TiTe+heater"
TRUE_VALUES = {"Ci": 2e6, "Ce": 8e6, "Rie": 2e-3, "Rea": 4e-3}
#: Process noise (K/sqrt(s)) on each state and measurement noise (K); sigma_w_Te is the fits' default.
TRUE_NOISE = {"Ti": 2e-3, "Te": 1e-3}
TRUE_SIGMA_V = 0.02


def simulate_sde(
    model, theta, t, u, sigma_w, sigma_v, rng, substeps: int = 60, x0=None
) -> tuple[np.ndarray, np.ndarray]:
    """Euler-Maruyama on ``substeps`` steps per sample, inputs held; returns (states, outputs)."""
    zm = load_model(model).with_values(theta)
    ss = zm.state_space()
    A, B, C, D = ss.A, ss.B, ss.C, ss.D
    sw = np.array([sigma_w.get(s, 0.0) for s in ss.state_names])
    x = -np.linalg.solve(A, B @ u[0]) if x0 is None else np.asarray(x0, float)
    X = np.empty((t.size, x.size))
    for k in range(t.size):
        X[k] = x
        if k == t.size - 1:
            break
        h = (t[k + 1] - t[k]) / substeps
        drive = B @ u[k]
        noise = rng.standard_normal((substeps, x.size)) * (sw * np.sqrt(h))
        for i in range(substeps):
            x = x + h * (A @ x + drive) + noise[i]
    y = X @ C.T + u @ D.T + sigma_v * rng.standard_normal((t.size, C.shape[0]))
    return X, y


def inputs(n: int, dt: float, rng: np.random.Generator) -> pd.DataFrame:
    """Outdoor temperature (daily cycle and a random walk), a PRBS-like heater, a solar-like signal."""
    t = np.arange(n) * dt
    h = t / 3600.0
    to = 2 + 3 * np.sin(2 * np.pi * (h - 9) / 24) + np.cumsum(rng.normal(0, 0.05, n))
    heater = 300 + 900 * (np.cumsum(rng.random(n) < dt / (3 * 3600)) % 2)
    sun = np.clip(np.sin(2 * np.pi * (h - 6) / 24), 0, None) * 300 * rng.uniform(0.3, 1.0, n)
    return pd.DataFrame({"time": t, "To": to, "Ph": heater, "Ps": sun})


def prbs_zone(days: float = 3.0, dt: float = 300.0, seed: int = 1) -> pd.DataFrame:
    """A zone from :data:`TRUE_MODEL` driven by outdoor air and a switching heater (``Ps`` does nothing)."""
    rng = np.random.default_rng(seed)
    n = int(days * 86400 / dt) + 1
    frame = inputs(n, dt, rng)
    u = frame[["To", "Ph"]].to_numpy()
    _, y = simulate_sde(TRUE_MODEL, TRUE_VALUES, frame["time"].to_numpy(), u, TRUE_NOISE, TRUE_SIGMA_V, rng)
    frame["Ti"] = y[:, 0]
    return frame
