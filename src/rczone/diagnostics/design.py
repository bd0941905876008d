"""Design of a forced-response test: a D-optimal schedule of supply-air commands.

The schedule is piecewise constant: the night is cut into segments of the minimum hold time,
and each segment gets a supply temperature and a flow from a grid inside the allowed ranges.
The criterion is ``log det`` of the Fisher information of the free log-parameters, with the
nuisances a fit must also absorb (initial state, unknown heat-gain offset) marginalized, exactly
as in :func:`rczone.diagnostics.identifiability.diagnose`. The search is a coordinate exchange:
each segment in turn takes the grid point that most increases the criterion while the
predicted room temperature stays inside the allowed band; sweeps repeat until nothing
improves.

References
----------
.. [1] E. Walter, L. Pronzato, *Identification of Parametric Models from Experimental Data*,
   Springer, 1997, ch. 6 (D-optimal design).
.. [2] R. K. Meyer, C. J. Nachtsheim, "The coordinate-exchange algorithm for constructing exact
   optimal experimental designs", Technometrics 37(1), 1995.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.atomic import write_text_atomic
from rczone.errors import ParameterError, did_you_mean
from rczone.network import RCNetwork
from rczone.simulation import simulate, steady_state
from rczone.simulation.sensitivity import output_sensitivities


@dataclass(frozen=True)
class DesignLimits:
    """What the test may do.

    Parameters
    ----------
    ts_range : (float, float)
        Supply-air temperature range, degC.
    m_range : (float, float)
        Supply mass-flow range, kg/s.
    band : (float, float)
        Allowed room temperature, degC.
    min_hold_s : float
        Shortest time a command is held, s.
    ts_levels, m_levels : int
        Grid points per range.
    """

    ts_range: tuple[float, float] = (12.0, 35.0)
    m_range: tuple[float, float] = (0.02, 0.12)
    band: tuple[float, float] = (17.0, 28.0)
    min_hold_s: float = 1800.0
    ts_levels: int = 5
    m_levels: int = 3

    def __post_init__(self) -> None:
        for label, (lo, hi) in (("ts_range", self.ts_range), ("m_range", self.m_range), ("band", self.band)):
            if not lo < hi:
                raise ParameterError(f"{label} must be (low, high) with low < high, got ({lo}, {hi})")
        if self.m_range[0] < 0:
            raise ParameterError("m_range must be >= 0 kg/s")
        if not self.min_hold_s > 0:
            raise ParameterError("min_hold_s must be > 0")
        if self.ts_levels < 2 or self.m_levels < 1:
            raise ParameterError("need at least 2 supply-temperature levels and 1 flow level")


@dataclass(frozen=True, eq=False)
class DesignResult:
    """A designed schedule and what it is predicted to give.

    Attributes
    ----------
    schedule : DataFrame
        One row per segment: ``start_s``, ``end_s``, ``Ts`` (degC), ``m`` (kg/s).
    t : ndarray
        Sample times of the prediction, s.
    ti_predicted : ndarray
        Predicted room temperature with the prior parameters, degC.
    expected_se : dict of name to float
        Expected relative standard errors of the free parameters.
    log_det : float
    within_band : bool
    """

    schedule: pd.DataFrame
    t: np.ndarray
    ti_predicted: np.ndarray
    expected_se: dict[str, float]
    log_det: float
    within_band: bool
    limits: DesignLimits

    def samples(self, dt: float = 60.0) -> pd.DataFrame:
        """The commands sampled every ``dt`` seconds (what a BMS plays)."""
        t = np.arange(0.0, float(self.schedule["end_s"].iloc[-1]) + 1e-9, dt)
        k = np.clip(
            np.searchsorted(self.schedule["start_s"].to_numpy(), t, side="right") - 1,
            0,
            len(self.schedule) - 1,
        )
        return pd.DataFrame(
            {"time": t, "Ts": self.schedule["Ts"].to_numpy()[k], "m": self.schedule["m"].to_numpy()[k]}
        )

    def to_csv(self, path: str, start: pd.Timestamp | None = None) -> None:
        """Write the schedule as a CSV a building management system can play (atomically).

        Columns: ``time_s`` (from the test start), ``clock`` (when ``start`` is given),
        ``Ts_setpoint_degC``, ``m_setpoint_kg_s``; one row per command change.
        """
        df = pd.DataFrame(
            {
                "time_s": self.schedule["start_s"].to_numpy(),
                "Ts_setpoint_degC": self.schedule["Ts"].round(2).to_numpy(),
                "m_setpoint_kg_s": self.schedule["m"].round(4).to_numpy(),
            }
        )
        if start is not None:
            df.insert(
                1, "clock", [(start + pd.Timedelta(seconds=float(s))).isoformat() for s in df["time_s"]]
            )
        write_text_atomic(path, df.to_csv(index=False))

    def to_dict(self) -> dict:
        return {
            "schedule": self.schedule.to_dict(orient="list"),
            "expected_rel_se": self.expected_se,
            "log_det_fisher": self.log_det,
            "within_band": self.within_band,
            "ti_min_degC": float(np.min(self.ti_predicted)),
            "ti_max_degC": float(np.max(self.ti_predicted)),
            "limits": vars(self.limits),
        }


def _fisher_logdet(S: np.ndarray, nuis: np.ndarray) -> tuple[float, np.ndarray]:
    """log det of the Schur complement of the nuisance block, and the free covariance."""
    J = np.column_stack([S, nuis])
    F = J.T @ J
    P = S.shape[1]
    Fr = F[:P, :P] - F[:P, P:] @ np.linalg.pinv(F[P:, P:], rcond=1e-13) @ F[P:, :P]
    sign, ld = np.linalg.slogdet(Fr)
    if sign <= 0:
        return -np.inf, np.full((P, P), np.inf)
    return float(ld), np.linalg.inv(Fr)


def design_test(
    network: RCNetwork,
    free: Sequence[str],
    duration_s: float = 12 * 3600.0,
    limits: DesignLimits | None = None,
    theta: Mapping[str, float] | None = None,
    conditions: Mapping[str, float] | None = None,
    ti0: float | None = None,
    dt: float = 60.0,
    sigma_K: float = 0.1,
    correlation_time_s: float = 1800.0,
    max_sweeps: int = 4,
    progress: Callable[[int, int], None] | None = None,
) -> DesignResult:
    """D-optimal forced-response schedule for the target room's supply air.

    Parameters
    ----------
    network : RCNetwork
        With one flow input and a supply temperature input ``Ts``.
    free : sequence of str
        Parameters the test should identify.
    duration_s : float
        Length of the test (e.g. one night, 12 h).
    limits : DesignLimits
    theta : mapping, optional
        Prior parameter values (default: construction values).
    conditions : mapping, optional
        Constant values of the other inputs during the test, e.g. ``{"To": 18, "Tsd": 22, "Q": 50}``
        (defaults: 22 degC for temperatures, 0 for heat inputs).
    ti0 : float, optional
        Room temperature at the start (default: middle of the band).
    sigma_K, correlation_time_s : as in :func:`~rczone.diagnostics.identifiability.diagnose`.

    Returns
    -------
    DesignResult
    """
    limits = limits or DesignLimits()
    if len(network.flow_names) != 1 or "Ts" not in network.input_names:
        raise ParameterError("design_test needs a model with one supply-air flow and a 'Ts' input")
    for n in free:
        if n not in network.parameters:
            raise ParameterError(f"unknown free parameter {n!r}; " + did_you_mean(n, network.parameters))
    if duration_s < limits.min_hold_s:
        raise ParameterError("the test must last at least one minimum hold time")
    conditions = dict(conditions or {})
    for k in conditions:
        if k not in network.input_names:
            raise ParameterError(
                f"unknown input {k!r} in conditions; " + did_you_mean(k, network.input_names)
            )
    n_seg = int(duration_s // limits.min_hold_s)
    seg_len = duration_s / n_seg
    heat = [h.name for h in network.heat_inputs]
    base_u = np.array([conditions.get(n, 0.0 if n in heat else 22.0) for n in network.input_names])
    its = network.input_names.index("Ts")
    ts_grid = np.linspace(*limits.ts_range, limits.ts_levels)
    m_grid = (
        np.linspace(*limits.m_range, limits.m_levels)
        if limits.m_levels > 1
        else np.array([limits.m_range[1]])
    )
    ss = network.state_space(theta)
    lo, hi = limits.band
    ti0 = 0.5 * (lo + hi) if ti0 is None else float(ti0)

    def responses(
        ts_seq: np.ndarray, m_seq: np.ndarray, step: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Room temperature, its sensitivities and the nuisance responses on a grid of ``step`` s."""
        tg = np.arange(0.0, duration_s + 1e-9, step)
        seg = np.minimum((tg // seg_len).astype(int), n_seg - 1)
        u = np.tile(base_u, (tg.size, 1))
        u[:, its] = ts_seq[seg]
        m = m_seq[seg][:, None]
        x0 = steady_state(ss, u[0], m[0])
        x0 = x0 + (ti0 - x0[0])  # walls in equilibrium with the room at ti0
        sens = output_sensitivities(network, theta, free, tg, u, m, x0=x0)
        nuis = [
            simulate(ss, tg, np.zeros_like(u), m, x0=np.eye(ss.n_states)[i]).y[:, 0]
            for i in range(ss.n_states)
        ]
        if heat:
            uq = np.zeros_like(u)
            uq[:, [network.input_names.index(h) for h in heat]] = 1.0
            nuis.append(simulate(ss, tg, uq, m, x0=np.zeros(ss.n_states)).y[:, 0])
        return sens.y[:, 0], sens.dy[:, 0, :], np.column_stack(nuis)

    def score(ti: np.ndarray, S: np.ndarray, nuis: np.ndarray, step: float) -> tuple[float, np.ndarray]:
        if ti.min() < lo or ti.max() > hi:
            return -np.inf, np.empty(0)
        ww = np.sqrt(min(1.0, step / correlation_time_s)) / sigma_K
        ld, cov = _fisher_logdet(S * ww, nuis * ww)
        return ld, np.sqrt(np.diag(cov))

    # Search on a coarse grid. For fixed flows, the room temperature and its sensitivities are
    # affine in each segment's supply temperature (the model is linear in u for given m), so
    # two simulations per flow level give every supply-temperature candidate exactly.
    step = min(300.0, limits.min_hold_s / 6, dt * 5)
    mid = 0.5 * (lo + hi)
    ts_seq = np.full(n_seg, ts_grid[np.argmin(np.abs(ts_grid - mid))])
    m_seq = np.full(n_seg, m_grid[0])
    best, _ = score(*responses(ts_seq, m_seq, step), step)
    total = max_sweeps * n_seg
    done = 0
    for _sweep in range(max_sweeps):
        improved = False
        for s in range(n_seg):
            for m_c in m_grid:
                cand_m = m_seq.copy()
                cand_m[s] = m_c
                a_ts, b_ts = ts_seq.copy(), ts_seq.copy()
                a_ts[s], b_ts[s] = ts_grid[0], ts_grid[-1]
                ya, Sa, nuis = responses(a_ts, cand_m, step)
                yb, Sb, _ = responses(b_ts, cand_m, step)
                for ts_c in ts_grid:
                    if ts_c == ts_seq[s] and m_c == m_seq[s]:
                        continue
                    f = (ts_c - ts_grid[0]) / (ts_grid[-1] - ts_grid[0])
                    val, _ = score(ya + f * (yb - ya), Sa + f * (Sb - Sa), nuis, step)
                    if val > best + 1e-9:
                        best, improved = val, True
                        ts_seq, m_seq = ts_seq.copy(), cand_m
                        ts_seq[s] = ts_c
            done += 1
            if progress:
                progress(done, total)
        if not improved:
            break
    # final prediction and check on the fine grid
    ti, S, nuis = responses(ts_seq, m_seq, dt)
    best, se = score(ti, S, nuis, dt)
    t = np.arange(0.0, duration_s + 1e-9, dt)
    if not np.isfinite(best):
        raise ParameterError(
            "no schedule keeps the room inside the band with these limits (even the starting one leaves it);"
            " widen the band, narrow the supply-temperature range or lower the maximum flow"
        )
    sched = pd.DataFrame(
        {
            "start_s": np.arange(n_seg) * seg_len,
            "end_s": (np.arange(n_seg) + 1) * seg_len,
            "Ts": ts_seq,
            "m": m_seq,
        }
    )
    # merge consecutive equal commands
    keep = np.r_[True, (np.diff(ts_seq) != 0) | (np.diff(m_seq) != 0)]
    grp = np.cumsum(keep) - 1
    sched = sched.groupby(grp).agg(
        start_s=("start_s", "first"), end_s=("end_s", "last"), Ts=("Ts", "first"), m=("m", "first")
    )
    return DesignResult(
        sched.reset_index(drop=True),
        t,
        ti,
        dict(zip(free, se.tolist(), strict=True)),
        best,
        bool(ti.min() >= lo and ti.max() <= hi),
        limits,
    )


def schedule_fisher(
    network: RCNetwork,
    free: Sequence[str],
    t: np.ndarray,
    u: np.ndarray,
    m: np.ndarray,
    x0: np.ndarray,
    theta: Mapping[str, float] | None = None,
    sigma_K: float = 0.1,
    correlation_time_s: float = 1800.0,
    heat_input: str | None = "Q",
) -> tuple[float, dict[str, float]]:
    """log det and expected relative standard errors for given input trajectories.

    Used to compare a designed schedule with another test (e.g. the scenario-C style test)
    on the same footing.
    """
    ss = network.state_space(theta)
    sens = output_sensitivities(network, theta, free, t, u, m, x0=x0)
    nuis = [
        simulate(ss, t, np.zeros_like(u), m, x0=np.eye(ss.n_states)[i]).y[:, 0] for i in range(ss.n_states)
    ]
    if heat_input in network.input_names:
        uq = np.zeros_like(u)
        uq[:, network.input_names.index(heat_input)] = 1.0
        nuis.append(simulate(ss, t, uq, m, x0=np.zeros(ss.n_states)).y[:, 0])
    dt = float(np.median(np.diff(t)))
    w = np.sqrt(min(1.0, dt / correlation_time_s)) / sigma_K
    ld, cov = _fisher_logdet(sens.dy[:, 0, :] * w, np.column_stack(nuis) * w)
    return ld, dict(zip(free, np.sqrt(np.diag(cov)).tolist(), strict=True))
