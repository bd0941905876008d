"""A supervisory MPC for EnergyPlus: it plans the zone's HVAC heat and gives the thermostat set points.

EnergyPlus's VAV terminals and packaged units ignore flow and discharge set points; they honour the
zone thermostat (measured, docs/energyplus.md). A supervisory MPC therefore decides what the
thermostat should hold, as supervisory MPCs of commercial buildings do (Sturzenegger et al. [1]_
act on the building's existing loops; Blum et al. [2]_ write zone set points in BOPTEST's
multi-zone test cases). :class:`SupervisoryMPC`, every plant step:

1. **observes**: a Kalman filter (:class:`~rczone.control.observer.KalmanObserver`) on the fitted
   zone model with an integrating heat disturbance, the supply air replaced by the heat it brought,
   ``P = m cp (Ts - Ti)`` from the BMS's metered flow and discharge temperature (the model at zero
   flow with that heat at the room node is the fitted model: its supply-air term is that heat);
2. **plans** over ``horizon`` steps the heating ``h_k >= 0`` and cooling ``c_k >= 0`` (W) that keep
   the predicted room temperature inside the comfort band narrowed by ``margin_K`` (soft, slack
   penalised by a convex piecewise-linear cost) at the least price-weighted energy, heating at
   ``heating_efficiency``, cooling at ``cooling_cop``, each at most its capacity: a linear model and
   a linear program in condensed form, solved by HiGHS's dual simplex [3]_ (scipy's ``linprog``;
   an ADMM QP solver needed thousands of iterations on this nearly linear problem);
3. **acts**: the plan's room temperature at the end of the step becomes the heating set point if
   the plan heats in this step and the cooling set point if it cools; the other set point is the
   band's edge, so the building's thermostat still guards the band. Both are held to the plant's
   set-point limits of the step (``heating_min_<zone>``...).

The forecast holds the zone's metered internal power ``Q`` and its neighbours' ``Tsd`` at their
last measurement and takes the outdoor temperature from the plant's forecast (with its error).

References
----------
.. [1] D. Sturzenegger, D. Gyalistras, M. Morari, R. S. Smith, "Model predictive climate control of
   a Swiss office building: implementation, results, and cost-benefit analysis", IEEE Trans.
   Control Systems Technology 24(1) (2016) 1-12.
.. [2] D. Blum et al., "Building optimization testing framework (BOPTEST) for simulation-based
   benchmarking of control strategies in buildings", J. Building Performance Simulation 14(5)
   (2021) 586-610.
.. [3] Q. Huangfu, J. A. J. Hall, "Parallelizing the dual revised simplex method", Mathematical
   Programming Computation 10 (2018) 119-142 (HiGHS).
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.optimize import linprog

from rczone.control.disturbance import Disturbance
from rczone.control.model import ControlModel
from rczone.control.observer import KalmanObserver
from rczone.errors import ParameterError, RczoneError
from rczone.kernels.arrays import StateMoments
from rczone.models.zone import ZoneModel
from rczone.network import CP_AIR


@dataclass(frozen=True)
class SupervisorySettings:
    """Settings of :class:`SupervisoryMPC` (SI).

    Parameters
    ----------
    horizon : int
        Prediction steps (of the plant's step).
    heating_capacity, cooling_capacity : float
        Largest heat the zone's HVAC can add or remove, W.
    heating_efficiency, cooling_cop : float
        Energy per heat: heating at ``1/heating_efficiency``, cooling at ``1/cooling_cop``.
    comfort_weight, comfort_weight_steep : float
        Cost per K outside the (narrowed) band per step, and the cost added per K beyond
        ``slack_tier_K`` (a convex piecewise-linear penalty: a linear program).
    slack_tier_K : float
    margin_K : float
        The band the plan aims at is narrowed by this much on either side, K.
    """

    horizon: int = 48
    heating_capacity: float = 10e3
    cooling_capacity: float = 10e3
    heating_efficiency: float = 1.0
    cooling_cop: float = 3.0
    comfort_weight: float = 5.0
    comfort_weight_steep: float = 50.0
    slack_tier_K: float = 0.3
    margin_K: float = 0.1

    def __post_init__(self) -> None:
        if not (isinstance(self.horizon, int) and self.horizon >= 1):
            raise ParameterError(f"supervisory MPC horizon must be an integer >= 1, got {self.horizon!r}")
        for k in ("heating_capacity", "cooling_capacity", "heating_efficiency", "cooling_cop"):
            v = getattr(self, k)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"supervisory MPC setting {k} must be a finite number > 0, got {v!r}")
        for k in ("comfort_weight", "comfort_weight_steep", "slack_tier_K", "margin_K"):
            v = getattr(self, k)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ParameterError(f"supervisory MPC setting {k} must be a finite number >= 0, got {v!r}")


class HeatPlan(NamedTuple):
    """A plan: heating and cooling (H,) W, predicted room temperature (H + 1,) degC, slack (H,) K,
    solver status and solve time (s); of several zones (the floor MPC's), one row per zone:
    (nz, H) and (nz, H + 1)."""

    heating: np.ndarray
    cooling: np.ndarray
    y: np.ndarray
    slack: np.ndarray
    status: str
    solve_time: float


class PlanStep(NamedTuple):
    """A plan's first step for one zone: room temperature at its end (degC), heating and cooling
    (W), and the band's edges at its end (degC)."""

    y1: float
    heating: float
    cooling: float
    lower: float
    upper: float


def set_points(
    zone: str, settings: SupervisorySettings, step: PlanStep, forecast: Mapping[str, np.ndarray]
) -> dict[str, float]:
    """The thermostat's set points from a plan's first step (module notes, 3), within the plant's limits."""
    z, s = zone, settings
    heat = step.y1 if step.heating > 0.02 * s.heating_capacity else float(step.lower)
    cool = step.y1 if step.cooling > 0.02 * s.cooling_capacity else float(step.upper)
    cool = min(max(cool, forecast[f"cooling_min_{z}"][0]), forecast[f"cooling_max_{z}"][0])
    heat = min(max(heat, forecast[f"heating_min_{z}"][0]), forecast[f"heating_max_{z}"][0], cool - 0.5)
    return {f"heating_{z}": heat, f"cooling_{z}": cool}


class SupervisoryMPC:
    """The supervisory MPC of one zone as a :class:`~rczone.control.plant.Controller` (module notes).

    Parameters
    ----------
    model : ZoneModel
        With one supply-air element entering the room node (the paper's models).
    zone : str
    dt : float
        The plant's step, s (the MPC decides every step).
    settings : SupervisorySettings, optional
    """

    def __init__(
        self, model: ZoneModel, *, zone: str, dt: float, settings: SupervisorySettings | None = None
    ) -> None:
        self.cm = ControlModel(model, disturbance=Disturbance("heat"))
        if len(self.cm.flow_names) != 1 or not model.network.supply_air:
            raise ParameterError(
                f"the supervisory MPC needs a model with one supply-air flow; {model.name!r} has flows "
                f"{list(self.cm.flow_names)}"
            )
        self.model = model
        self.zone = zone
        self.settings = settings or SupervisorySettings()
        self.dt = float(dt)
        self.interval = self.dt
        self.horizon = self.settings.horizon * self.dt
        self.observer = KalmanObserver(self.cm)
        self.solve_times: list[float] = []
        self.innovations: list[float] = []
        self._est: StateMoments | None = None
        self._u: np.ndarray | None = None
        self._d = self.cm.discrete(self.dt, 0.0)
        self.plan: HeatPlan | None = None

    def inputs(self, measurements: Mapping[str, float], to: np.ndarray) -> np.ndarray:
        """Model inputs over the forecast (len(to), p): ``To`` forecast, the rest held at the measurement."""
        z = self.zone
        held = {
            "Tsd": measurements[f"Tsd_{z}"],
            "Q": measurements.get(f"Q_{z}", math.nan),
            "Ts": measurements[f"Ti_{z}"],  # no effect at zero flow
        }
        defaults = dict(self.model.inputs.defaults)
        cols = []
        for name in self.cm.input_names:
            if name == "To":
                cols.append(np.asarray(to, float))
                continue
            v = held.get(name, defaults.get(name, math.nan))
            if not math.isfinite(v):
                v = defaults.get(name, math.nan)
            if not math.isfinite(v):
                raise ParameterError(f"the supervisory MPC cannot forecast the model input {name!r}")
            cols.append(np.full(len(to), float(v)))
        return np.column_stack(cols)

    def _observe(self, measurements: Mapping[str, float], u_now: np.ndarray) -> None:
        z = self.zone
        ti = float(measurements[f"Ti_{z}"])
        m, ts = float(measurements.get(f"m_{z}", math.nan)), float(measurements.get(f"Ts_{z}", math.nan))
        heat = m * CP_AIR * (ts - ti) if math.isfinite(m) and math.isfinite(ts) else 0.0
        if self._est is None:
            self._est = self.observer.prior(np.array([ti]))
        else:
            self._est = self.observer.predict(self._est, self._u, 0.0, self.dt, heat=heat)
        self._est, e = self.observer.update(self._est, np.array([ti]), u_now)
        self.innovations.append(float(e[0]))
        self._u = u_now

    def solve(
        self, x0: np.ndarray, u: np.ndarray, lower: np.ndarray, upper: np.ndarray, price: np.ndarray
    ) -> HeatPlan:
        """The plan from state ``x0`` with inputs ``u`` (H + 1, p), band and price (H + 1,) (module notes)."""
        s, d = self.settings, self._d
        H = s.horizon
        C, D = d.C[0], d.D[0]
        A, B, E = d.Ad, d.Bd, d.Ed[:, 0] * 1e3  # heat in kW
        free, x = [], np.asarray(x0, float)
        powers = [np.eye(len(x))]
        for k in range(H):
            x = A @ x + B @ u[k]
            free.append(C @ x + D @ u[k + 1])
            powers.append(A @ powers[-1])
        g = np.array([C @ powers[i] @ E for i in range(H)])  # response k steps after a kW
        G = np.zeros((H, H))
        for k in range(H):
            G[k, : k + 1] = g[k::-1]
        lo = np.asarray(lower, float)[1 : H + 1] + s.margin_K
        hi = np.asarray(upper, float)[1 : H + 1] - s.margin_K
        hi = np.maximum(hi, lo)
        free = np.array(free)
        w = np.asarray(price, float)[:H] * self.dt / 3600.0  # per kW held a step: kWh x price
        cost = np.r_[
            w / s.heating_efficiency,
            w / s.cooling_cop,
            np.full(H, s.comfort_weight),
            np.full(H, s.comfort_weight + s.comfort_weight_steep),
        ]
        one = np.eye(H)
        # G (h - c) + s1 + s2 >= lo - free;  G (h - c) - s1 - s2 <= hi - free
        A_ub = np.block([[-G, G, -one, -one], [G, -G, -one, -one]])
        b_ub = np.r_[free - lo, hi - free]
        bounds = (
            [(0.0, s.heating_capacity / 1e3)] * H
            + [(0.0, s.cooling_capacity / 1e3)] * H
            + [(0.0, s.slack_tier_K)] * H
            + [(0.0, None)] * H
        )
        t0 = _time.perf_counter()
        res = linprog(cost, A_ub=A_ub, b_ub=b_ub, bounds=bounds, method="highs")
        elapsed = _time.perf_counter() - t0
        if res.status != 0 or res.x is None:
            raise RczoneError(f"the supervisory MPC's linear program could not be solved ({res.message})")
        h, c, s1, s2 = (np.clip(res.x[i * H : (i + 1) * H], 0.0, None) for i in range(4))
        y = np.r_[C @ x0 + D @ u[0], free + G @ (h - c)]
        return HeatPlan(h * 1e3, c * 1e3, y, s1 + s2, "optimal", elapsed)

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """Observe, plan, and give the thermostat its set points for the next step (module notes)."""
        z, s = self.zone, self.settings
        H = s.horizon
        if len(forecast["time"]) < H + 1:
            raise ParameterError(f"the forecast must cover {H + 1} steps, it has {len(forecast['time'])}")
        u = self.inputs(measurements, forecast["To"][: H + 1])
        self._observe(measurements, u[0])
        lower, upper = forecast[f"lower_{z}"], forecast[f"upper_{z}"]
        plan = self.solve(self._est.x, u, lower, upper, forecast["price"])
        self.plan = plan
        self.solve_times.append(plan.solve_time)
        step = PlanStep(float(plan.y[1]), plan.heating[0], plan.cooling[0], lower[1], upper[1])
        return set_points(z, s, step, forecast)


class ZoneMPCs:
    """Several zones' supervisory MPCs, decentralized: each zone plans with its own model.

    A zone's neighbours enter its model as the measured temperature ``Tsd`` (the column map's
    conductance-weighted mean of the neighbouring zones, held at its last measurement over the
    horizon), so the plans are made independently, one linear program per zone and step; the
    set points of all zones are given at once. This is the multi-zone arrangement of a supervisory
    MPC written zone by zone (distributed MPC without coordination; Scattolini [1]_, section 3,
    "decentralized"): it neglects what a neighbour will do, which the centralized
    :class:`~rczone.emulators.floormpc.FloorMPC` plans for with a joint model of the floor.

    Parameters
    ----------
    controllers : sequence of SupervisoryMPC
        One per zone, all with the plant's step.

    References
    ----------
    .. [1] R. Scattolini, "Architectures for distributed and hierarchical model predictive
       control - a review", Journal of Process Control 19(5) (2009) 723-731.
    """

    def __init__(self, controllers: list[SupervisoryMPC]) -> None:
        if not controllers:
            raise ParameterError("a multi-zone MPC needs at least one zone")
        zones = [c.zone for c in controllers]
        if len(set(zones)) != len(zones):
            raise ParameterError(f"each zone has one MPC; given {zones}")
        steps = {c.interval for c in controllers}
        if len(steps) != 1:
            raise ParameterError(f"the zones' MPCs must share the plant's step, got {sorted(steps)} s")
        self.controllers = list(controllers)
        self.interval = controllers[0].interval
        self.horizon = max(c.horizon for c in controllers)
        self.solve_times: list[float] = []

    @property
    def zones(self) -> list[str]:
        """The zones, in the order given."""
        return [c.zone for c in self.controllers]

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """Every zone's set points for the next step; the step's solve time is the sum of the zones'."""
        out: dict = {}
        spent = 0.0
        for c in self.controllers:
            out.update(c.act(t, measurements, forecast))
            spent += c.solve_times[-1]
        self.solve_times.append(spent)
        return out


class BuildingControl:
    """The baseline: the building's own control (its thermostat schedules), no action.

    Parameters
    ----------
    dt : float
        The plant's step, s.
    """

    horizon = 0.0

    def __init__(self, dt: float) -> None:
        self.interval = float(dt)

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """Nothing: every zone runs on the building's schedules."""
        return {}
