"""Design of a forced-response test: a D-optimal schedule of the inputs a building can drive.

The inputs the test may drive are the *actuated* ones, each within a range: the supply-air
temperature and flow of a ventilated zone (the paper's experiment), the power of a heater (a
PRBS-like experiment as in Bacher & Madsen's), or any mix of a model's supply temperatures, flows
and heat inputs. Every other input is held at an expected constant (the test's *conditions*: the
outdoor temperature, the surroundings, a gain).

The schedule is piecewise constant: the test is cut into segments of the minimum hold time, and
each segment gets a value of every actuated input from a grid inside its range. The criterion is
``log det`` of the Fisher information of the free log-parameters over every output of the model,
with the nuisances a fit must also absorb (initial state, the unknown offset of every constant heat
input) marginalized, exactly as in :func:`rczone.diagnostics.identifiability.diagnose`. The search
is a coordinate exchange: each segment in turn takes the grid point that most increases the
criterion while the predicted zone temperature (the model's first output) stays inside the allowed
band; sweeps repeat until nothing improves.

Before searching, the request is checked for feasibility: the zone must start inside the band, and
the steady temperatures the actuated inputs can hold (at the conditions) must reach into the band;
otherwise no schedule can keep the zone inside it and the error says why.

References
----------
.. [1] E. Walter, L. Pronzato, *Identification of Parametric Models from Experimental Data*,
   Springer, 1997, ch. 6 (D-optimal design).
.. [2] R. K. Meyer, C. J. Nachtsheim, "The coordinate-exchange algorithm for constructing exact
   optimal experimental designs", Technometrics 37(1), 1995.
.. [3] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522 (PRBS heating experiments).
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import time as clock_time
from types import MappingProxyType

import numpy as np
import pandas as pd

from rczone.data.units import to_si
from rczone.diagnostics.fisher import check_free, marginal_fisher, nuisance_responses, sample_weight
from rczone.errors import ParameterError, did_you_mean
from rczone.estimation.costs import auto_initial_state
from rczone.files.atomic import write_text_atomic
from rczone.models import ZoneModel
from rczone.network import RCNetwork
from rczone.results import Result
from rczone.simulation import steady_state
from rczone.simulation.sensitivity import output_sensitivities

#: Grid points per range unless given: temperatures and powers, flows.
DEFAULT_LEVELS = 5
DEFAULT_FLOW_LEVELS = 3


MIN_HOLD_S = 60.0
"""Shortest hold of a command (s): a BMS holds a set point at least a minute."""
MAX_SEGMENTS = 400
"""Most held commands in one test (duration / hold), a week at 30-minute holds; each is chosen by
searching the grid, so the search time grows with their number (a few seconds per hundred)."""
MAX_DURATION_S = 7 * 24 * 3600.0
"""Longest test (s): a week."""


@dataclass(frozen=True)
class DesignLimits:
    """What the test may do.

    Parameters
    ----------
    ranges : mapping of str to (float, float)
        The actuated inputs and their ranges, SI units (degC, kg/s, W), e.g.
        ``{"Ts": (12, 35), "m": (0.02, 0.12)}`` or ``{"Ph": (0, 2000)}``.
    band : (float, float)
        Allowed zone temperature (the model's first output), degC.
    min_hold_s : float
        Shortest time a command is held, s.
    levels : mapping of str to int, optional
        Grid points per range (at least 2); default 5, and 3 for flows.
    """

    ranges: Mapping[str, tuple[float, float]]
    band: tuple[float, float] = (17.0, 28.0)
    min_hold_s: float = 1800.0
    levels: Mapping[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.ranges, Mapping) or not self.ranges:
            raise ParameterError(
                "ranges must name at least one input the test may drive, with its range, e.g."
                " {'Ts': (12, 35), 'm': (0.02, 0.12)}"
            )
        ranges = {}
        for label, pair in (*self.ranges.items(), ("band", self.band)):
            try:
                lo, hi = (float(v) for v in pair)
            except (TypeError, ValueError):
                raise ParameterError(f"{label} must be (low, high), got {pair!r}") from None
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ParameterError(f"{label} must be (low, high) with low < high, got ({lo:g}, {hi:g})")
            ranges[str(label)] = (lo, hi)
        band = ranges.pop("band")
        if not (
            isinstance(self.min_hold_s, (int, float))
            and math.isfinite(self.min_hold_s)
            and self.min_hold_s >= MIN_HOLD_S
        ):
            raise ParameterError(
                f"min_hold_s (the shortest hold) must be at least {MIN_HOLD_S:g} s (one minute,"
                f" rczone.diagnostics.design.MIN_HOLD_S) and finite, got {self.min_hold_s!r} s"
            )
        for k, n in dict(self.levels).items():
            if k not in ranges:
                raise ParameterError(
                    f"levels given for {k!r}, which has no range; " + did_you_mean(k, ranges)
                )
            if isinstance(n, bool) or not isinstance(n, int) or n < 2:
                raise ParameterError(f"levels of {k!r} must be an integer >= 2, got {n!r}")
        object.__setattr__(self, "ranges", MappingProxyType(ranges))
        object.__setattr__(self, "band", band)
        object.__setattr__(self, "levels", MappingProxyType(dict(self.levels)))

    def to_dict(self) -> dict:
        return {
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "band": list(self.band),
            "min_hold_s": self.min_hold_s,
            "levels": dict(self.levels),
        }


@dataclass(frozen=True, eq=False, repr=False)
class DesignResult(Result):
    """A designed schedule and what it is predicted to give.

    Attributes
    ----------
    schedule : DataFrame
        One row per command: ``start_s``, ``end_s``, then one column per actuated input (SI units).
    t : ndarray
        Sample times of the prediction, s.
    predicted : ndarray
        Predicted zone temperature (the model's first output, ``output``) with the prior values, degC.
    expected_se : dict of name to float
        Expected relative standard errors of the free parameters.
    log_det : float
    within_band : bool
    limits : DesignLimits
    output : str
    quantities : dict of str to str
        Quantity of each actuated input (``temperature``, ``flow``, ``power``, ``irradiance``).
    model_label : str
        The model's name, for titles.
    start : Timestamp or datetime.time, optional
        When the test starts (the schedule's clock column).
    display_units : dict of str to str
        Units the schedule and the predicted temperature are shown in (default SI).
    """

    schedule: pd.DataFrame
    t: np.ndarray
    predicted: np.ndarray
    expected_se: dict[str, float]
    log_det: float
    within_band: bool
    limits: DesignLimits
    output: str = "Ti"
    quantities: dict[str, str] = field(default_factory=dict)
    model_label: str = "model"
    start: pd.Timestamp | clock_time | None = None
    display_units: Mapping[str, str] = field(default_factory=dict)

    @property
    def actuated(self) -> tuple[str, ...]:
        """The inputs the test drives."""
        return tuple(self.limits.ranges)

    @property
    def excitation(self):
        """Whether the schedule drives the actuated inputs apart (:mod:`rczone.data.excitation`)."""
        from rczone.data.excitation import input_excitation

        frame = self.samples()
        return input_excitation(frame[list(self.actuated)].to_numpy(float), self.actuated)

    def _setpoint_units(self) -> dict[str, str]:
        return {a: self.display_units[a] for a in self.actuated if a in self.display_units}

    def to_frame(self) -> pd.DataFrame:
        """The schedule as a building management system takes it (:meth:`table` in the display units)."""
        return self.table(self.start, self._setpoint_units())

    def _repr_line(self) -> str:
        return f"{len(self.schedule)} commands of {', '.join(self.actuated)} for {self.model_label}"

    def summary_lines(self) -> list:
        """What ``rczone design`` prints (before the file it writes)."""
        from rich.table import Table

        from rczone.results.fit_text import esc

        frame = self.to_frame()
        table = Table(title=f"Forced-response schedule for {esc(self.model_label)}")
        for c in frame.columns:
            table.add_column(esc(c))
        for row in frame.itertuples(index=False):
            table.add_row(*(esc(f"{v:g}" if isinstance(v, float) else v) for v in row))
        t_unit = self.display_units.get(self.output, "degC")
        lo, hi = from_si(
            self.predicted[[self.predicted.argmin(), self.predicted.argmax()]], t_unit, "temperature"
        )
        se = ", ".join(f"{esc(k)} ±{v:.0%}" for k, v in self.expected_se.items())
        lines = [table, f"predicted {esc(self.output)} {lo:.1f}..{hi:.1f} {esc(t_unit)}; expected {se}"]
        return lines + self.excitation.summary_lines()

    def samples(self, dt: float = 60.0) -> pd.DataFrame:
        """The commands sampled every ``dt`` seconds (what a BMS plays), SI units."""
        t = np.arange(0.0, float(self.schedule["end_s"].iloc[-1]) + 1e-9, dt)
        k = np.clip(
            np.searchsorted(self.schedule["start_s"].to_numpy(), t, side="right") - 1,
            0,
            len(self.schedule) - 1,
        )
        return pd.DataFrame({"time": t, **{a: self.schedule[a].to_numpy()[k] for a in self.actuated}})

    def table(
        self, start: pd.Timestamp | clock_time | None = None, units: Mapping[str, str] | None = None
    ) -> pd.DataFrame:
        """The schedule for a building management system: one row per command change.

        Parameters
        ----------
        start : Timestamp or datetime.time, optional
            When the test starts: a date and time (``clock`` is then an ISO 8601 time stamp, with
            its UTC offset when ``start`` has a time zone), or a time of day (``day`` counts the
            midnights passed and ``clock`` is ``HH:MM``).
        units : mapping of input name to unit, optional
            Units of the setpoints (any spelling of :mod:`rczone.data.units`); default SI.

        Returns
        -------
        DataFrame
            ``time_s`` (from the start), the clock columns, and ``<input>_setpoint_<unit>``.
        """
        units = dict(units or {})
        starts = self.schedule["start_s"].to_numpy(float)
        df = pd.DataFrame({"time_s": starts})
        if isinstance(start, pd.Timestamp):
            df["clock"] = [(start + pd.Timedelta(seconds=float(s))).isoformat() for s in starts]
        elif isinstance(start, clock_time):
            minutes = start.hour * 60 + start.minute + starts / 60.0
            df["day"] = (minutes // 1440).astype(int)
            df["clock"] = [f"{int(m // 60) % 24:02d}:{int(m % 60):02d}" for m in minutes]
        for a in self.actuated:
            quantity = self.quantities.get(a, "temperature")
            unit = units.get(a) or SI_UNIT[quantity]
            values = from_si(self.schedule[a].to_numpy(float), unit, quantity)
            token = unit.replace("/", "_").replace("^", "").replace(" ", "")
            df[f"{a}_setpoint_{token}"] = [float(f"{v:.6g}") for v in values]
        return df

    def to_csv(
        self,
        path: str | os.PathLike,
        start: pd.Timestamp | clock_time | None = None,
        units: Mapping[str, str] | None = None,
    ) -> None:
        """Write :meth:`table` as CSV (atomically)."""
        write_text_atomic(path, self.table(start, units).to_csv(index=False))

    def to_dict(self) -> dict:
        """What ``rczone design --json`` writes."""
        return {
            "schedule": self.schedule.to_dict(orient="list"),
            "expected_rel_se": self.expected_se,
            "log_det_fisher": self.log_det,
            "within_band": self.within_band,
            "output": self.output,
            "predicted_min_degC": float(np.min(self.predicted)),
            "predicted_max_degC": float(np.max(self.predicted)),
            "limits": self.limits.to_dict(),
            "model": self.model_label,
            "units": dict(self.display_units),
            "start": str(self.start),
            "setpoints": self.to_frame().to_dict(orient="list"),
            "excitation": self.excitation.to_dict(),
        }


#: SI unit of each quantity (as in :mod:`rczone.data.units`).
SI_UNIT = {"temperature": "degC", "flow": "kg/s", "power": "W", "irradiance": "W/m2"}


def from_si(values: np.ndarray, unit: str, quantity: str) -> np.ndarray:
    """Values in SI units converted to ``unit`` (the inverse of :func:`rczone.data.units.to_si`).

    Every conversion to SI is affine (a scale, and an offset for temperatures), so the inverse
    follows from the images of 0 and 1.
    """
    zero, one = to_si(np.array([0.0, 1.0]), unit, quantity, column=unit)
    return (np.asarray(values, float) - zero) / (one - zero)


def _fisher_logdet(S: np.ndarray, nuis: np.ndarray, weight: float) -> tuple[float, np.ndarray]:
    """log det of the marginal Fisher matrix and the free covariance; ``-inf`` unless it is positive definite.

    By its Cholesky factor: a positive determinant alone (``slogdet``'s sign) also passes a matrix
    with an even number of negative eigenvalues, which rounding can give a nearly singular
    information, and its inverse then has negative variances.
    """
    Fr = marginal_fisher(S, nuis, weight)
    try:
        L = np.linalg.cholesky(Fr)
    except np.linalg.LinAlgError:
        return -np.inf, np.full(Fr.shape, np.inf)
    inv_L = np.linalg.inv(L)
    return 2.0 * float(np.sum(np.log(np.diag(L)))), inv_L.T @ inv_L


def actuatable(network: RCNetwork) -> tuple[str, ...]:
    """Inputs a test can drive: supply-air temperatures (not boundaries), flows and heat inputs."""
    supply = [s.temperature for s in network.supply_air if s.temperature not in network.boundaries]
    return (*dict.fromkeys(supply), *network.flow_names, *(h.name for h in network.heat_inputs))


def _check_request(
    zm: ZoneModel, free: Sequence[str], limits: DesignLimits, conditions: Mapping[str, float]
) -> dict[str, float]:
    """Validate the free set, the actuated inputs and the conditions; the full conditions (defaults added)."""
    net = zm.network
    check_free(net, free, zm.theta)
    can = actuatable(net)
    signals = (*net.input_names, *net.flow_names)
    for a, (lo, _) in limits.ranges.items():
        if a in net.boundaries:
            raise ParameterError(
                f"{a!r} is a boundary temperature (outdoors or a neighbouring space), which a test cannot"
                f" drive; the model's drivable inputs are {', '.join(can) or 'none'}"
            )
        if a not in signals:
            raise ParameterError(f"unknown input {a!r} to drive; " + did_you_mean(a, can))
        if a in net.flow_names and lo < 0:
            raise ParameterError(f"the range of flow {a!r} must be >= 0 kg/s, got {lo:g}")
    full = {}
    for k, v in conditions.items():
        if k not in signals:
            raise ParameterError(f"unknown input {k!r} in conditions; " + did_you_mean(k, signals))
        if k in limits.ranges:
            raise ParameterError(f"{k!r} is driven by the test (it has a range); it takes no condition")
        if not math.isfinite(v):
            raise ParameterError(f"condition {k!r} must be a finite number, got {v!r}")
        if k in net.flow_names and v < 0:
            raise ParameterError(f"condition {k!r} is a flow and must be >= 0 kg/s, got {v:g}")
        full[k] = float(v)
    for k in signals:
        if k not in full and k not in limits.ranges and k in zm.inputs.defaults:
            full[k] = zm.inputs.defaults[k]
    missing = [k for k in signals if k not in full and k not in limits.ranges]
    if missing:
        raise ParameterError(
            f"the test's conditions lack {', '.join(missing)}: give the value each is expected to have"
            f" during the test (rczone design --condition {missing[0]}=...; conditions={{{missing[0]!r}: ...}}"
            " in Python), or drive it with a range"
        )
    return full


def _steady_output(ss, u: np.ndarray, m: np.ndarray) -> float:
    """The first output in equilibrium with constant inputs ``u`` and flows ``m``."""
    return float((ss.C @ steady_state(ss, u, m) + ss.D @ u)[0])


def _describe(zm: ZoneModel, limits: DesignLimits, conditions: Mapping[str, float]) -> str:
    """The request in words, SI units: "with Ts 12..35 degC, m 0.02..0.12 kg/s and To 18 degC"."""
    unit = {k: SI_UNIT[q] for k, q in zm.signal_quantities().items()}
    ranges = ", ".join(f"{k} {lo:.4g}..{hi:.4g} {unit.get(k, '')}" for k, (lo, hi) in limits.ranges.items())
    held = ", ".join(f"{k} {v:.4g} {unit.get(k, '')}" for k, v in conditions.items())
    return f"with {ranges}" + (f" and {held}" if held else "")


def design_test(
    model: ZoneModel | RCNetwork | str,
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
    """D-optimal forced-response schedule of the actuated inputs of a zone.

    Parameters
    ----------
    model : ZoneModel, RCNetwork or str
        The zone's model (:func:`rczone.models.load_model`); its values are the prior.
    free : sequence of str
        Parameters the test should identify.
    duration_s : float
        Length of the test (e.g. one night, 12 h).
    limits : DesignLimits
        The actuated inputs and their ranges, the zone's band, the shortest hold.
    theta : mapping, optional
        Values replacing the model's own (the prior).
    conditions : mapping, optional
        Constant values of the other inputs and flows during the test (SI units), e.g.
        ``{"To": 18, "Tsd": 22}``; an input the model gives a default (such as the paper's
        ``Q = 50 W``) takes it unless given. Every other input must be given.
    ti0 : float, optional
        Zone temperature at the start (default: the middle of the band); the other nodes start in
        equilibrium with it and the first inputs.
    dt : float
        Sample time of the schedule and of the final check, s.
    sigma_K, correlation_time_s : float
        As in :func:`~rczone.diagnostics.identifiability.diagnose`.
    max_sweeps : int
        Most passes of the coordinate search over the segments (it stops earlier when a pass
        improves nothing).
    progress : callable, optional
        Called as ``progress(done, total)`` after each segment of a pass.

    Returns
    -------
    DesignResult

    Raises
    ------
    ParameterError
        An unknown or undrivable input, a missing condition, or an infeasible request (the zone
        starts outside the band, or no combination of the actuated inputs holds it inside).
    """
    from rczone.models import load_model

    if limits is None:
        raise ParameterError("design_test needs limits: the inputs the test may drive and their ranges")
    zm = load_model(model)
    if theta:
        zm = zm.with_values(theta)
    net = zm.network
    conditions = _check_request(zm, free, limits, dict(conditions or {}))
    if not (math.isfinite(duration_s) and duration_s >= limits.min_hold_s):
        raise ParameterError("the test must last at least one minimum hold time")
    if duration_s > MAX_DURATION_S:
        raise ParameterError(
            f"the test would last {duration_s / 3600:.4g} h, more than the limit of {MAX_DURATION_S / 3600:g} h"
            " (rczone.diagnostics.design.MAX_DURATION_S); design a shorter test and repeat it"
        )
    if duration_s // limits.min_hold_s > MAX_SEGMENTS:
        raise ParameterError(
            f"the test would hold {duration_s // limits.min_hold_s:,.0f} commands, more than the limit of"
            f" {MAX_SEGMENTS} (rczone.diagnostics.design.MAX_SEGMENTS); use a longer minimum hold or a"
            " shorter test"
        )
    lo, hi = limits.band
    ti0 = 0.5 * (lo + hi) if ti0 is None else float(ti0)
    if not lo <= ti0 <= hi:
        raise ParameterError(f"the zone starts at {ti0:g} degC, outside the band {lo:g}..{hi:g} degC")
    n_seg = int(duration_s // limits.min_hold_s)
    seg_len = duration_s / n_seg
    acts = list(limits.ranges)
    flows = [a for a in acts if a in net.flow_names]
    lin = [a for a in acts if a not in net.flow_names]  # supply temperatures and powers: y is affine in them
    grid = {
        a: np.linspace(
            *limits.ranges[a], limits.levels.get(a, DEFAULT_FLOW_LEVELS if a in flows else DEFAULT_LEVELS)
        )
        for a in acts
    }
    iu = {a: net.input_names.index(a) for a in lin}
    im = {a: net.flow_names.index(a) for a in flows}
    base_u = np.array([conditions.get(n, 0.0) for n in net.input_names])
    base_m = np.array([conditions.get(n, 0.0) for n in net.flow_names])
    heat_offsets = [h.name for h in net.heat_inputs if h.unit == "W" and h.name not in limits.ranges]
    ss = net.state_space(zm.theta)
    theta0 = dict(zm.theta)

    def inputs_at(values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        u, m = base_u.copy(), base_m.copy()
        for a, v in values.items():
            if a in iu:
                u[iu[a]] = v
            else:
                m[im[a]] = v
        return u, m

    # feasibility: the steady zone temperatures the actuated inputs can hold must reach the band
    steady = {
        combo: _steady_output(ss, *inputs_at(dict(zip(acts, combo, strict=True))))
        for combo in itertools.product(*(grid[a] for a in acts))
    }
    low, high = min(steady.values()), max(steady.values())
    if high < lo or low > hi:
        side, hint = (
            ("below", "allow warmer supply air, more heating or a lower band")
            if high < lo
            else ("above", "allow cooler supply air, less heating or a higher band")
        )
        raise ParameterError(
            f"the zone cannot stay inside the band {lo:g}..{hi:g} degC: {_describe(zm, limits, conditions)}"
            f" its steady temperature is {low:.1f}..{high:.1f} degC, entirely {side} it; {hint}"
        )
    start_combo = min(steady, key=lambda c: abs(steady[c] - ti0))
    y0 = np.full(len(net.outputs), np.nan)
    y0[0] = ti0

    def responses(values: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Zone temperature, stacked sensitivities and nuisance responses on a grid of ``step`` s."""
        tg = np.arange(0.0, duration_s + 1e-9, step)
        seg = np.minimum((tg // seg_len).astype(int), n_seg - 1)
        u = np.tile(base_u, (tg.size, 1))
        m = np.tile(base_m, (tg.size, 1))
        for k, a in enumerate(acts):
            if a in iu:
                u[:, iu[a]] = values[seg, k]
            else:
                m[:, im[a]] = values[seg, k]
        mm = m if m.shape[1] else None
        x0 = auto_initial_state(ss, u[0], m[0], y0)
        sens = output_sensitivities(net, theta0, free, tg, u, mm, x0=x0)
        nuis, _ = nuisance_responses(ss, tg, u, m, heat_offsets)
        P = len(free)
        return sens.y[:, 0], sens.dy.reshape(-1, P), nuis.reshape(-1, nuis.shape[-1])

    def score(y: np.ndarray, S: np.ndarray, nuis: np.ndarray, step: float) -> tuple[float, np.ndarray]:
        if y.min() < lo or y.max() > hi:
            return -np.inf, np.empty(0)
        ld, cov = _fisher_logdet(S, nuis, sample_weight(step, sigma_K, correlation_time_s))
        return ld, np.sqrt(np.diag(cov))

    # Search on a coarse grid. For fixed flows, the zone temperature and its sensitivities are
    # affine in each segment's supply temperatures and powers (the model is linear in u for given
    # m), so 1 + (number of those) simulations per flow combination give every candidate exactly.
    step = min(300.0, limits.min_hold_s / 6, dt * 5)
    values = np.tile(np.array(start_combo, float), (n_seg, 1))
    best, _ = score(*responses(values, step), step)
    kl = [acts.index(a) for a in lin]
    kf = [acts.index(a) for a in flows]
    lin_low = np.array([grid[a][0] for a in lin])
    lin_span = np.array([grid[a][-1] - grid[a][0] for a in lin])
    total = max_sweeps * n_seg
    done = 0
    for _sweep in range(max_sweeps):
        improved = False
        for s in range(n_seg):
            for f_combo in itertools.product(*(grid[a] for a in flows)):
                base = values.copy()
                base[s, kf] = f_combo
                base[s, kl] = lin_low
                y_b, S_b, nuis = responses(base, step)
                ends = []
                for j, k in enumerate(kl):
                    c = base.copy()
                    c[s, k] = grid[lin[j]][-1]
                    y_k, S_k, _ = responses(c, step)
                    ends.append((y_k - y_b, S_k - S_b))
                for lin_combo in itertools.product(*(grid[a] for a in lin)):
                    cand = np.empty(len(acts))
                    cand[kf], cand[kl] = f_combo, lin_combo
                    if np.array_equal(cand, values[s]):
                        continue
                    frac = (np.array(lin_combo) - lin_low) / lin_span if lin else np.empty(0)
                    y = y_b + sum(f * dy for f, (dy, _) in zip(frac, ends, strict=True))
                    S = S_b + sum(f * dS for f, (_, dS) in zip(frac, ends, strict=True))
                    val, _ = score(y, S, nuis, step)
                    if val > best + 1e-9:
                        best, improved = val, True
                        values = values.copy()
                        values[s] = cand
            done += 1
            if progress:
                progress(done, total)
        if not improved:
            break
    # final prediction and check on the fine grid
    y, S, nuis = responses(values, dt)
    best, se = score(y, S, nuis, dt)
    if y.min() < lo or y.max() > hi:
        raise ParameterError(
            f"no schedule keeps the zone inside the band {lo:g}..{hi:g} degC ({_describe(zm, limits, conditions)},"
            f" starting at {ti0:g} degC); widen the band or narrow the ranges"
        )
    if not np.isfinite(best):
        blind = [n for j, n in enumerate(free) if not np.any(np.abs(S[:, j]) > 1e-12)]
        raise ParameterError(
            f"no schedule of {', '.join(acts)} identifies every free parameter (the information is singular"
            + (f": {', '.join(blind)} do(es) not affect the outputs at these conditions" if blind else "")
            + "); leave such parameters out of free"
        )
    t = np.arange(0.0, duration_s + 1e-9, dt)
    sched = pd.DataFrame(
        {"start_s": np.arange(n_seg) * seg_len, "end_s": (np.arange(n_seg) + 1) * seg_len}
        | {a: values[:, k] for k, a in enumerate(acts)}
    )
    # merge consecutive equal commands
    keep = np.r_[True, np.any(np.diff(values, axis=0) != 0, axis=1)]
    grp = np.cumsum(keep) - 1
    agg = {"start_s": ("start_s", "first"), "end_s": ("end_s", "last")} | {a: (a, "first") for a in acts}
    sched = sched.groupby(grp).agg(**agg).reset_index(drop=True)
    quantities = zm.signal_quantities()
    return DesignResult(
        sched,
        t,
        y,
        dict(zip(free, se.tolist(), strict=True)),
        best,
        bool(y.min() >= lo and y.max() <= hi),
        limits,
        net.outputs[0],
        {a: quantities.get(a, "temperature") for a in acts},
    )


def schedule_fisher(
    model: ZoneModel | RCNetwork | str,
    free: Sequence[str],
    t: np.ndarray,
    u: np.ndarray,
    m: np.ndarray | None,
    x0: np.ndarray,
    theta: Mapping[str, float] | None = None,
    sigma_K: float = 0.1,
    correlation_time_s: float = 1800.0,
    heat_offsets: Sequence[str] = (),
) -> tuple[float, dict[str, float]]:
    """log det and expected relative standard errors for given input trajectories.

    Used to compare a designed schedule with another test (e.g. the scenario-C style test)
    on the same footing: every output, the initial state and the ``heat_offsets`` marginalized.
    """
    from rczone.models import load_model

    zm = load_model(model)
    if theta:
        zm = zm.with_values(theta)
    net = zm.network
    ss = net.state_space(zm.theta)
    mm = m if m is not None and np.size(m) else None
    sens = output_sensitivities(net, dict(zm.theta), free, t, u, mm, x0=x0)
    nuis, _ = nuisance_responses(ss, t, u, mm, heat_offsets)
    dt = float(np.median(np.diff(t)))
    P = len(free)
    ld, cov = _fisher_logdet(
        sens.dy.reshape(-1, P),
        nuis.reshape(-1, nuis.shape[-1]),
        sample_weight(dt, sigma_K, correlation_time_s),
    )
    return ld, dict(zip(free, np.sqrt(np.diag(cov)).tolist(), strict=True))
