"""Two coupled rooms: model files, exact simulation and a plain Kalman filter written from the physics.

Nothing here uses rczone's network builder, discretization or filter: the matrices are written
from the heat balances, discretized by matrix exponentials (Van Loan's method for the noise),
and filtered with the textbook vector-update Kalman filter.

Room 1 (``T1``, the target) and room 2 (``T2``, the neighbour) exchange heat through ``R12``;
both lose heat to outdoors (``To``) and have a heater (``P1``, ``P2``)::

    C1 dT1 = ((To - T1)/R1 + (T2 - T1)/R12 + P1) dt + C1 s1 dW1
    C2 dT2 = ((To - T2)/R2 + (T1 - T2)/R12 + P2) dt + C2 s2 dW2
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.linalg import expm
from scipy.stats import multivariate_normal

TRUE = {"C1": 4e6, "C2": 5e6, "R1": 8e-3, "R2": 6e-3, "R12": 2e-3}
#: Process noise, K/sqrt(s).
SIGMA_W = {"T1": 1e-3, "T2": 1e-3}

JOINT_TOML = """
name = "joint"
boundaries = ["To"]
outputs = ["T1", "T2"]
resistors = [["T1", "To", "R1"], ["T2", "To", "R2"], ["T1", "T2", "R12"]]
[nodes]
T1 = "C1"
T2 = "C2"
[heat_inputs]
P1 = "T1"
P2 = "T2"
[parameters]
C1 = { value = 1.5, unit = "kWh/K", bounds = [0.01, 100] }
C2 = { value = 1.5, unit = "kWh/K", bounds = [0.01, 100] }
R1 = { value = 5, unit = "K/kW", bounds = [0.05, 500] }
R2 = { value = 5, unit = "K/kW", bounds = [0.05, 500] }
R12 = { value = 3, unit = "K/kW", bounds = [0.05, 500] }
"""

SINGLE_TOML = """
name = "single"
boundaries = ["To", "T2"]
outputs = ["T1"]
resistors = [["T1", "To", "R1"], ["T1", "T2", "R12"]]
[nodes]
T1 = "C1"
[heat_inputs]
P1 = "T1"
[parameters]
C1 = { value = 1.5, unit = "kWh/K", bounds = [0.01, 100] }
R1 = { value = 5, unit = "K/kW", bounds = [0.05, 500] }
R12 = { value = 3, unit = "K/kW", bounds = [0.05, 500] }
"""

#: A model of room 1 that ignores room 2 altogether: not comparable with the joint model.
ALONE_TOML = """
name = "alone"
boundaries = ["To"]
outputs = ["T1"]
resistors = [["T1", "To", "R1"]]
[nodes]
T1 = "C1"
[heat_inputs]
P1 = "T1"
[parameters]
C1 = { value = 1.5, unit = "kWh/K" }
R1 = { value = 5, unit = "K/kW" }
"""


def write_models(folder) -> dict[str, str]:
    paths = {}
    for name, text in (("joint", JOINT_TOML), ("single", SINGLE_TOML), ("alone", ALONE_TOML)):
        p = folder / f"{name}.toml"
        p.write_text(text)
        paths[name] = str(p)
    return paths


def joint_matrices(v=TRUE) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (2, 2), ``B`` (2, 3) of the two rooms, inputs ``(To, P1, P2)``, states ``(T1, T2)``."""
    C1, C2, R1, R2, R12 = (v[k] for k in ("C1", "C2", "R1", "R2", "R12"))
    A = np.array([[-(1 / R1 + 1 / R12) / C1, 1 / (R12 * C1)], [1 / (R12 * C2), -(1 / R2 + 1 / R12) / C2]])
    B = np.array([[1 / (R1 * C1), 1 / C1, 0.0], [1 / (R2 * C2), 0.0, 1 / C2]])
    return A, B


def zoh(A: np.ndarray, B: np.ndarray, Qc: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    """``Phi, Gamma, Qd`` of a zero-order hold by matrix exponentials (Van Loan 1978 for ``Qd``)."""
    n, p = B.shape
    M = np.zeros((n + p, n + p))
    M[:n, :n], M[:n, n:] = A, B
    E = expm(M * dt)
    V = np.zeros((2 * n, 2 * n))
    V[:n, :n], V[:n, n:], V[n:, n:] = -A, Qc, A.T
    F = expm(V * dt)
    Phi = E[:n, :n]
    return Phi, E[:n, n:], Phi @ F[:n, n:]


def drive(n: int, dt: float, rng) -> pd.DataFrame:
    """Outdoor temperature with a daily cycle, two heaters switching at random."""
    t = np.arange(n) * dt
    h = t / 3600.0
    to = 3 + 4 * np.sin(2 * np.pi * (h - 9) / 24) + np.cumsum(rng.normal(0, 0.05, n))
    p1 = 400 + 1200 * (np.cumsum(rng.random(n) < dt / (4 * 3600)) % 2)
    p2 = 300 + 1500 * (np.cumsum(rng.random(n) < dt / (5 * 3600)) % 2)
    return pd.DataFrame({"time": t, "To": to, "P1": p1, "P2": p2})


def joint_data(n: int, dt: float, sigma_v: tuple[float, float], seed: int) -> pd.DataFrame:
    """Both rooms simulated exactly (process noise in both), ``T1`` and ``T2`` measured with ``sigma_v``."""
    rng = np.random.default_rng(seed)
    frame = drive(n, dt, rng)
    u = frame[["To", "P1", "P2"]].to_numpy()
    A, B = joint_matrices()
    Phi, G, Qd = zoh(A, B, np.diag([SIGMA_W["T1"] ** 2, SIGMA_W["T2"] ** 2]), dt)
    L = np.linalg.cholesky(Qd)
    x = np.linalg.solve(A, -B @ u[0])
    X = np.empty((n, 2))
    for k in range(n):
        X[k] = x
        x = Phi @ x + G @ u[k] + L @ rng.standard_normal(2)
    frame["T1"] = X[:, 0] + sigma_v[0] * rng.standard_normal(n)
    frame["T2"] = X[:, 1] + sigma_v[1] * rng.standard_normal(n)
    return frame


def controlled_neighbour_data(n: int, dt: float, seed: int) -> pd.DataFrame:
    """Room 2 held by its own controller (setpoint steps and small random moves, heat unmeasured).

    ``T2`` changes at the sample times and is measured to 0.01 K, so room 1 with the measured
    ``T2`` as a held input is the true model; ``P2`` is a heater that does not drive ``T2`` (its
    controller compensates), and the joint model's room-2 balance is wrong.
    """
    rng = np.random.default_rng(seed)
    frame = drive(n, dt, rng)
    h = frame["time"].to_numpy() / 3600.0
    t2 = np.where((h % 24 >= 7) & (h % 24 < 19), 22.0, 17.0) + np.cumsum(rng.normal(0, 0.05, n))
    C1, R1, R12 = TRUE["C1"], TRUE["R1"], TRUE["R12"]
    A = np.array([[-(1 / R1 + 1 / R12) / C1]])
    B = np.array([[1 / (R1 * C1), 1 / C1, 1 / (R12 * C1)]])
    Phi, G, Qd = zoh(A, B, np.array([[SIGMA_W["T1"] ** 2]]), dt)
    u = np.column_stack([frame["To"], frame["P1"], t2])
    x = np.linalg.solve(A, -B @ u[0])
    X = np.empty(n)
    for k in range(n):
        X[k] = x[0]
        x = Phi @ x + G @ u[k] + np.sqrt(Qd[0, 0]) * rng.standard_normal(1)
    frame["T1"] = X + 0.02 * rng.standard_normal(n)
    frame["T2"] = t2 + 0.01 * rng.standard_normal(n)
    return frame


def reference_conditional(frame: pd.DataFrame, sigma_v: tuple[float, float], x0_sd: float) -> np.ndarray:
    """``log p(y1_k | past, y2_k)`` of the true joint model by a textbook Kalman filter.

    Vector measurement update; the prior of the first state is ``N(x0, x0_sd^2 I)`` with ``x0`` the
    first measurements; the conditional density is ``N(y; yhat, S)`` divided by the marginal
    ``N(y2; yhat2, S22)``, both from scipy.stats.
    """
    dt = float(np.diff(frame["time"])[0])
    u = frame[["To", "P1", "P2"]].to_numpy()
    y = frame[["T1", "T2"]].to_numpy()
    A, B = joint_matrices()
    Phi, G, Qd = zoh(A, B, np.diag([SIGMA_W["T1"] ** 2, SIGMA_W["T2"] ** 2]), dt)
    R = np.diag(np.square(sigma_v))
    x, P = y[0].copy(), x0_sd**2 * np.eye(2)
    out = np.empty(len(frame))
    for k in range(len(frame)):
        S = P + R
        out[k] = multivariate_normal(x, S).logpdf(y[k]) - multivariate_normal(x[1], S[1, 1]).logpdf(y[k, 1])
        K = P @ np.linalg.inv(S)
        x, P = x + K @ (y[k] - x), P - K @ P
        x, P = Phi @ x + G @ u[k], Phi @ P @ Phi.T + Qd
    return out
