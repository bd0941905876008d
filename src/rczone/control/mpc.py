"""A reference economic MPC for one VAV zone: flow and reheat as decisions, a comfort band, OSQP.

Every ``dt`` (default 10 min) the controller

1. updates its Kalman observer (:mod:`rczone.control.observer`) with the measured room
   temperature, after predicting over the last interval with what it applied;
2. solves, over ``H`` steps (default 36, 6 h), the economic problem

   .. math::

       \\min \\sum_k \\pi_k \\Delta t\\,(P_k + \\dot Q_{cool,k} + P_{fan,k})
            + w_1 s_k + w_2 s_k^2 + \\text{small move penalties}

   subject to the model, ``T_low,k - s_k <= Ti_k <= T_high,k + s_k``, ``s_k >= 0``,
   ``m_min,k <= m_k <= m_max,k`` (per step: the settings' bounds and the plant's, e.g. a
   ventilation minimum that follows the schedule) and ``0 <= P_k <= m_k cp (Ts_max - T_ahu,k)`` (the discharge
   temperature limit, linear in ``(m, P)``). The energy terms are those of
   :mod:`rczone.control.energy`; ``pi`` a price (default 1 per kWh: energy);
3. applies the first flow and reheat power (discharge temperature ``T_ahu + P/(m cp)``).

**The bilinear term by sequential linearization.** With the reheat power ``P`` as a heat
input (:class:`~rczone.control.model.ControlModel`) the model is bilinear only in the flow.
Around a nominal trajectory ``(m_k, x_k, P_k)`` the exact discrete model is linearized in
the flow with its exact derivatives (:meth:`ControlModel.flow_derivative`),
``x+ = Ad(m_k) x + Bd(m_k) u + Ed(m_k) P + (dAd x_k + dBd u + dEd P_k)(m - m_k)``, and the
cooling load ``m cp (Ti - T_ahu)`` to first order. The QP is solved, the nominal trajectory
re-simulated with the exact model at the new flows, and the QP solved again
(``linearizations`` passes, default 2; Diehl et al. [2]_ call this a real-time iteration when
one pass is made per sample). The first nominal is the last plan shifted by one step, and
OSQP starts from the last solution shifted likewise (warm start).

**The QP's form.** By default the states are eliminated (:mod:`rczone.control.qp`, the
condensed form): the QP has the flows, reheat powers and slacks only, one sparsity pattern at
every step, so one OSQP problem is set up once and later only updated. For the paper's 13-state
model this takes OSQP from thousands of iterations to tens or hundreds, and a step (observer,
two linearizations, two QPs) from about 0.5 s to 0.04 s of CPU (``bench/mpc_step.py``, which
replays one run through both forms and checks that they act alike). ``formulation="uncondensed"``
keeps the earlier form (states as variables, the dynamics as equality constraints).

**Why OSQP.** An operator-splitting QP solver (Stellato et al. [1]_): maintained (Oxford and
Princeton, v1 2024), BSD-licensed, small binary wheels with only numpy and scipy as
dependencies, widely used (CVXPY's default QP solver, do-mpc's and acados' QP option), sparse
and warm-startable, and it reports infeasibility instead of failing silently. It is an
optional extra (``pip install 'rczone[mpc]'``); the rest of rczone does not need it.

References
----------
.. [1] B. Stellato, G. Banjac, P. Goulart, A. Bemporad, S. Boyd, "OSQP: an operator splitting
   solver for quadratic programs", Mathematical Programming Computation 12 (2020) 637-672.
.. [2] M. Diehl, H. G. Bock, J. P. Schlöder, "A real-time iteration scheme for nonlinear
   optimization in optimal feedback control", SIAM J. Control Optim. 43(5) (2005) 1714-1736.
.. [3] F. Oldewurtel et al., "Use of model predictive control and weather forecasts for energy
   efficient building climate control", Energy and Buildings 45 (2012) 15-27.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp

from rczone.control.disturbance import Disturbance
from rczone.control.energy import FAN_W_PER_KG_S
from rczone.control.model import ControlModel
from rczone.control.observer import KalmanObserver, StateMoments
from rczone.control.qp import (
    OSQP_SETTINGS,
    Band,
    CondensedSolver,
    Coupling,
    Decision,
    Prediction,
    QPMatrices,
    Weights,
    condensed_qp,
)
from rczone.data.units import to_si
from rczone.errors import InputShapeError, ParameterError, RczoneError, did_you_mean
from rczone.models.zone import ZoneModel
from rczone.network import CP_AIR

#: Joules per kWh.
J_PER_KWH = 3.6e6
#: The QP's forms (:class:`MPCSettings`).
FORMULATIONS = ("condensed", "uncondensed")


@dataclass(frozen=True)
class MPCSettings:
    """Settings of :class:`MPC`, bounds in the user's units (converted to SI once, by :class:`MPC`).

    Parameters
    ----------
    dt : float
        Control interval, s.
    horizon : int
        Prediction steps.
    flow_min, flow_max : float
        Supply-flow bounds in ``flow_unit`` (any flow unit of :mod:`rczone.data.units`).
    ts_max : float
        Highest discharge temperature in ``temperature_unit``.
    comfort_weight, comfort_weight_quadratic : float
        Cost per K and per K^2 outside the band, per step (price units; energy costs about 0.1
        to 0.3 per step).
    move_weight : float
        Cost per (kg/s)^2 of flow change and per kW^2 of reheat change between steps.
    linearizations : int
        Sequential-linearization passes per step.
    formulation : {"condensed", "uncondensed"}
        The QP's form: ``condensed`` (default) eliminates the states and keeps one OSQP problem,
        updated and warm-started from step to step (:mod:`rczone.control.qp`); ``uncondensed``
        keeps the states as variables and the dynamics as equality constraints, set up afresh
        for every pass (the form before issue 33, several times slower for a 13-state model).
    heat_limits : mapping of str to (float, float)
        Heat inputs of the model the MPC decides (actuators: an electric heater, a radiator
        circuit's power, ``Ph``), each with its lowest and highest power in W per step; the
        energy they use is costed at the price like the reheat. Default none.
    """

    dt: float = 600.0
    horizon: int = 36
    flow_min: float = 0.02
    flow_max: float = 0.12
    flow_unit: str = "kg/s"
    ts_max: float = 35.0
    temperature_unit: str = "degC"
    comfort_weight: float = 5.0
    comfort_weight_quadratic: float = 50.0
    move_weight: float = 1e-2
    linearizations: int = 2
    formulation: str = "condensed"
    heat_limits: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        limits = {}
        for name, pair in dict(self.heat_limits).items():
            lo, hi = pair if isinstance(pair, (tuple, list)) and len(pair) == 2 else (None, None)
            if (
                not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                    for v in (lo, hi)
                )
                or lo > hi
            ):
                raise ParameterError(
                    f"MPC heat limit of {name!r} must be two finite numbers (lowest, highest) in W with "
                    f"lowest <= highest, got {pair!r}"
                )
            limits[str(name)] = (float(lo), float(hi))
        object.__setattr__(self, "heat_limits", MappingProxyType(limits))
        if self.formulation not in FORMULATIONS:
            raise ParameterError(
                f"MPC setting formulation must be one of {', '.join(FORMULATIONS)}, got {self.formulation!r}"
            )
        for k in ("dt", "comfort_weight", "comfort_weight_quadratic", "move_weight"):
            v = getattr(self, k)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0) or (k == "dt" and v <= 0):
                raise ParameterError(f"MPC setting {k} must be a finite number >= 0 (dt > 0), got {v!r}")
        for k in ("horizon", "linearizations"):
            v = getattr(self, k)
            if not (isinstance(v, int) and v >= 1):
                raise ParameterError(f"MPC setting {k} must be an integer >= 1, got {v!r}")


def _osqp() -> Any:
    """The OSQP module, or a one-line error saying how to install it."""
    try:
        import osqp
    except ImportError:
        raise RczoneError(
            "the MPC needs the QP solver OSQP; install the extra: pip install 'rczone[mpc]'"
        ) from None
    return osqp


class Limits(NamedTuple):
    """Input bounds in SI: flow (kg/s) and highest discharge temperature (degC)."""

    m_min: float
    m_max: float
    ts_max: float


def si_limits(s: MPCSettings) -> Limits:
    """The bounds of ``s`` in SI units, checked."""
    m_min, m_max = to_si([s.flow_min, s.flow_max], s.flow_unit, "flow", "MPC flow bounds")
    ts_max = float(to_si([s.ts_max], s.temperature_unit, "temperature", "MPC ts_max")[0])
    if not (0 < m_min <= m_max and math.isfinite(m_max)):
        raise ParameterError(
            f"MPC flow bounds must satisfy 0 < flow_min <= flow_max, got {s.flow_min!r}, {s.flow_max!r} "
            f"{s.flow_unit} (the supply air needs a minimum flow to carry the reheat)"
        )
    return Limits(float(m_min), float(m_max), ts_max)


@dataclass(frozen=True, eq=False)
class Forecast:
    """What the controller is told about the next ``H`` steps, SI, time-first (length >= H + 1).

    Attributes
    ----------
    inputs : mapping of str to ndarray
        Every model input except the supply temperature, e.g. ``To``, ``Tsd``, ``Q`` (a missing
        input with a model default, such as ``Q = 50 W``, takes the default).
    t_ahu : ndarray or None
        AHU supply temperature before reheat, degC (None for a model without supply air).
    lower, upper : ndarray
        Comfort band, degC.
    price : ndarray, optional
        Price per kWh (default 1: energy).
    m_min, m_max : ndarray, optional
        The plant's flow limits per step (length >= H), kg/s, e.g. a ventilation minimum that
        follows the occupancy schedule (:class:`~rczone.control.constraints.ZoneConstraints`);
        step ``k``'s flow is held to ``max(flow_min, m_min[k]) <= m_k <= min(flow_max, m_max[k])``
        (the settings' bounds still apply).
    """

    inputs: Mapping[str, np.ndarray]
    t_ahu: np.ndarray | None
    lower: np.ndarray
    upper: np.ndarray
    price: np.ndarray | None = None
    m_min: np.ndarray | None = None
    m_max: np.ndarray | None = None

    def length(self) -> int:
        series = [self.lower, self.upper, *self.inputs.values()]
        return min(len(v) for v in ([self.t_ahu] if self.t_ahu is not None else []) + series)


class Plan(NamedTuple):
    """An optimal plan: flows (H,) kg/s, reheat (H,) W, states (H+1, n), predicted outputs (H+1,),
    slack (H,) K, QP status, solve time (s, all passes) and the decided heat inputs (H,) W by name
    (flows and reheat zero for a model without supply air)."""

    m: np.ndarray
    reheat: np.ndarray
    x: np.ndarray
    y: np.ndarray
    slack: np.ndarray
    status: str
    solve_time: float
    heat: Mapping[str, np.ndarray] = MappingProxyType({})


class ControlAction(NamedTuple):
    """What :meth:`MPC.step` applies: flow kg/s, reheat W, discharge temperature degC (NaN without
    supply air), the plan, and the decided heat inputs W by name."""

    m: float
    reheat: float
    ts: float
    plan: Plan
    heat: Mapping[str, float] = MappingProxyType({})


class QPData(NamedTuple):
    """The linearized problem over the horizon (SI): matrices per step and cost coefficients;
    ``Bh`` (H, n, r) the decided heat inputs' columns of ``Bd`` (per W)."""

    Ad: np.ndarray
    Ed: np.ndarray
    G: np.ndarray
    c: np.ndarray
    qm: np.ndarray
    qp: np.ndarray
    qx: np.ndarray
    Bh: np.ndarray | None = None


def _shifted(z: np.ndarray, n: int, H: int) -> np.ndarray:
    """A solution ``[x_1..x_H, d_1 (H), ..., s (H)]`` moved one step on (the last step repeated)."""
    x = z[: n * H].reshape(H, n)
    rest = z[n * H :].reshape(-1, H)
    return np.concatenate(
        [np.vstack([x[1:], x[-1:]]).ravel(), np.hstack([rest[:, 1:], rest[:, -1:]]).ravel()]
    )


class _Triplets:
    """A sparse matrix assembled block by block (rows grow as constraints are added)."""

    def __init__(self) -> None:
        self.rows = 0
        self.r: list[np.ndarray] = []
        self.c: list[np.ndarray] = []
        self.v: list[np.ndarray] = []

    def block(self, r0: int, c0: int, values: np.ndarray) -> None:
        rr, cc = np.indices(values.shape)
        self.r.append((rr + r0).ravel())
        self.c.append((cc + c0).ravel())
        self.v.append(np.asarray(values, float).ravel())

    def matrix(self, ncols: int) -> sp.csc_matrix:
        return sp.csc_matrix(
            (np.concatenate(self.v), (np.concatenate(self.r), np.concatenate(self.c))),
            shape=(self.rows, ncols),
        )


@dataclass
class _Memory:
    """What the controller keeps between steps (the observer estimate, the last plan and action)."""

    est: StateMoments | None = None
    time: float | None = None
    u: np.ndarray | None = None
    action: ControlAction | None = None
    solver: Any = None
    z: np.ndarray | None = None
    innovations: list[float] = field(default_factory=list)


class MPC:
    """Economic MPC of one zone (see the module notes).

    Parameters
    ----------
    model : ZoneModel or ControlModel
        With one supply flow (decided with its reheat), or heat inputs declared as decisions by
        ``settings.heat_limits`` (an electric heater, a radiator circuit), or both.
    settings : MPCSettings, optional
    disturbance : Disturbance or None, optional
        The disturbance state of the observer (default an integrating heat disturbance at the
        room node; ``None`` for none). Ignored when ``model`` is a ControlModel.
    """

    def __init__(
        self,
        model: ZoneModel | ControlModel,
        settings: MPCSettings | None = None,
        *,
        disturbance: Disturbance | None = Disturbance(),  # noqa: B008 (frozen, immutable default)
    ) -> None:
        self.cm = model if isinstance(model, ControlModel) else ControlModel(model, disturbance=disturbance)
        self.settings = settings or MPCSettings()
        self.heaters = self._heat_decisions()
        air = len(self.cm.flow_names) == 1 and bool(self.cm.model.network.supply_air)
        if len(self.cm.flow_names) > 1 or not (air or self.heaters):
            raise ParameterError(
                f"the MPC needs a model with one supply-air flow or heat inputs it decides "
                f"(MPCSettings(heat_limits={{name: (lowest W, highest W)}})); {self.cm.model.name!r} has "
                f"flows {list(self.cm.flow_names)} and inputs {list(self.cm.input_names)}"
            )
        if self.settings.formulation == "uncondensed" and not (air and not self.heaters):
            raise ParameterError(
                "the uncondensed QP decides a supply flow and its reheat only; use 'condensed'"
            )
        self.limits = si_limits(self.settings)
        self.observer = KalmanObserver(self.cm)
        self._ts = self.cm.input_names.index(self.cm.model.network.supply_air[0].temperature) if air else None
        self._heat_idx = [self.cm.input_names.index(h) for h in self.heaters]
        self._defaults = dict(self.cm.model.inputs.defaults)
        self._mem = _Memory()

    def _heat_decisions(self) -> tuple[str, ...]:
        """The heat inputs the MPC decides: those with limits; an input the model file calls an actuator needs them."""
        names = self.cm.input_names
        for name in self.settings.heat_limits:
            if name not in names:
                raise ParameterError(
                    f"MPC heat limit for {name!r}: the model has no such input; " + did_you_mean(name, names)
                )
        roles = getattr(self.cm.model.inputs, "roles", {})
        for name, role in roles.items():
            if role == "actuator" and name not in self.settings.heat_limits and name in names:
                sa = self.cm.model.network.supply_air
                if not (sa and name == sa[0].temperature):
                    raise ParameterError(
                        f"input {name!r} is an actuator of the model: give its limits, "
                        f"MPCSettings(heat_limits={{{name!r}: (lowest W, highest W)}})"
                    )
        return tuple(self.settings.heat_limits)

    @property
    def air(self) -> bool:
        """Whether the MPC decides a supply flow and its reheat."""
        return self._ts is not None

    # ------------------------------------------------------------ inputs
    def _input_matrix(self, fc: Forecast, H: int) -> np.ndarray:
        """Model inputs over the horizon, shape (H + 1, p); the supply temperature is ``t_ahu``, the
        decided heat inputs are zero (the QP adds them)."""
        decided = {self._ts, *self._heat_idx}
        known = [n for i, n in enumerate(self.cm.input_names) if i not in decided]
        for name in fc.inputs:
            if name not in known:
                hint = "it is a decision of the MPC" if name in self.heaters else did_you_mean(name, known)
                raise InputShapeError(f"the forecast has an input {name!r} the model does not use; {hint}")
        cols = []
        for i, name in enumerate(self.cm.input_names):
            if i == self._ts:
                cols.append(np.asarray(fc.t_ahu, float)[: H + 1])
            elif i in decided:
                cols.append(np.zeros(H + 1))
            elif name in fc.inputs:
                cols.append(np.asarray(fc.inputs[name], float)[: H + 1])
            elif name in self._defaults:
                cols.append(np.full(H + 1, self._defaults[name]))
            else:
                raise InputShapeError(f"the forecast has no input {name!r} (the model needs it)")
        u = np.column_stack(cols)
        if not np.all(np.isfinite(u)):
            raise InputShapeError("the forecast has non-finite inputs")
        return u

    def _with_heat(self, u: np.ndarray, heat: np.ndarray) -> np.ndarray:
        """``u`` (K, p) with the decided heat inputs' columns set to ``heat`` (K, r) W."""
        out = np.array(u, float)
        out[:, self._heat_idx] = heat
        return out

    def _check(self, fc: Forecast) -> int:
        H = self.settings.horizon
        if self.air and fc.t_ahu is None:
            raise InputShapeError(
                "the forecast needs t_ahu, the AHU supply temperature (the model has supply air)"
            )
        if fc.length() < H + 1:
            raise InputShapeError(
                f"the forecast must cover horizon + 1 = {H + 1} steps, it has {fc.length()}"
            )
        band = np.column_stack([fc.lower[: H + 1], fc.upper[: H + 1]])
        if not np.all(np.isfinite(band)) or np.any(band[:, 0] > band[:, 1]):
            raise InputShapeError("the comfort band must be finite with lower <= upper")
        for name in ("m_min", "m_max"):
            v = getattr(fc, name)
            if v is not None and (len(v) < H or not np.all(np.isfinite(np.asarray(v, float)[:H]))):
                raise InputShapeError(f"the forecast's {name} must have {H} finite values, one per step")
        return H

    def flow_bounds(self, fc: Forecast, H: int) -> tuple[np.ndarray, np.ndarray]:
        """Per-step flow bounds (H,) each, kg/s: the settings' bounds and the forecast's, the tighter
        (zero without supply air)."""
        if not self.air:
            return np.zeros(H), np.zeros(H)
        lim = self.limits
        lo = (
            np.full(H, lim.m_min)
            if fc.m_min is None
            else np.maximum(lim.m_min, np.asarray(fc.m_min, float)[:H])
        )
        hi = (
            np.full(H, lim.m_max)
            if fc.m_max is None
            else np.minimum(lim.m_max, np.asarray(fc.m_max, float)[:H])
        )
        if np.any(lo > hi):
            k = int(np.argmax(lo > hi))
            raise InputShapeError(
                f"the flow bounds of step {k} are empty ({lo[k]:.4g} > {hi[k]:.4g} kg/s); "
                "check the plant's limits against the MPC's flow_min and flow_max"
            )
        return lo, hi

    # ------------------------------------------------------------ the QP
    def simulate(self, x0: np.ndarray, u: np.ndarray, m: np.ndarray, reheat: np.ndarray) -> np.ndarray:
        """States (H+1, n) of the exact discrete model under flows ``m`` and reheat ``reheat`` (H,)
        (the decided heat inputs are columns of ``u``)."""
        x = [np.asarray(x0, float)]
        for k in range(len(m)):
            d = self.cm.discrete(self.settings.dt, m[k] if self.air else 0.0)
            x.append(d.Ad @ x[-1] + d.Bd @ u[k] + d.Ed[:, 0] * reheat[k])
        return np.array(x)

    def linearize(
        self,
        x0: np.ndarray,
        u: np.ndarray,
        fc: Forecast,
        m: np.ndarray,
        reheat: np.ndarray,
        heat: np.ndarray | None = None,
    ) -> QPData:
        """The problem linearized around the nominal flows ``m``, reheat ``reheat`` and heat inputs
        ``heat`` (H, r) W (the decided columns of ``u`` are zero; the QP adds them)."""
        dt, H = self.settings.dt, len(m)
        un = u if heat is None else self._with_heat(u, np.vstack([heat, heat[-1:]]))
        xn = self.simulate(x0, un, m, reheat)
        c = self.cm.matrices
        yn = xn @ c.C[0] + un @ c.D[0]
        Ad, Ed, G, const, Bh = [], [], [], [], []
        for k in range(H):
            d = self.cm.discrete(dt, m[k] if self.air else 0.0)
            gk = np.zeros(len(x0))
            if self.air:
                g = self.cm.flow_derivative(dt, m[k])
                gk = g.dAd[0] @ xn[k] + g.dBd[0] @ un[k] + g.dEd[0][:, 0] * reheat[k]
            Ad.append(d.Ad)
            Ed.append(d.Ed[:, 0])
            G.append(gk)
            const.append(d.Bd @ u[k] - gk * m[k])
            Bh.append(d.Bd[:, self._heat_idx])
        price = np.ones(H) if fc.price is None else np.asarray(fc.price, float)[:H]
        w = price * dt / J_PER_KWH
        qm, qx = np.zeros(H), np.zeros(H)
        if self.air:
            to = np.asarray(fc.inputs.get("To", np.full(H + 1, np.inf)), float)[:H]
            t_ahu = np.asarray(fc.t_ahu, float)[:H]
            cool_t = np.minimum(yn[:H], to) - t_ahu
            active = (cool_t > 0) & (yn[:H] < to)
            qm = w * (FAN_W_PER_KG_S + CP_AIR * np.maximum(cool_t, 0.0))
            qx = w * CP_AIR * m * active  # on the output at the start of each step (k >= 1 free)
        return QPData(np.array(Ad), np.array(Ed), np.array(G), np.array(const), qm, w, qx, np.array(Bh))

    def _qp(self, x0, u, fc, q: QPData, m_prev: float, p_prev: float) -> QPMatrices:
        """The sparse QP ``min 1/2 z'Pz + q'z, l <= Az <= u`` in z = [x_1..x_H, m, P (kW), s]."""
        s = self.settings
        H, n = len(q.qm), len(x0)
        c = self.cm.matrices
        Cy, Dy = c.C[0], c.D[0]
        im, ip, isl = n * H, n * H + H, n * H + 2 * H
        nz = n * H + 3 * H
        A = _Triplets()
        lo, hi = [], []
        eye = np.eye(n)
        for k in range(H):  # dynamics: x_{k+1} - Ad x_k - G m_k - Ed P_k = c_k (+ Ad x_0)
            r = A.rows
            A.block(r, n * k, eye)
            if k > 0:
                A.block(r, n * (k - 1), -q.Ad[k])
            A.block(r, im + k, -q.G[k][:, None])
            A.block(r, ip + k, -1e3 * q.Ed[k][:, None])
            A.rows += n
            rhs = q.c[k] + (q.Ad[0] @ x0 if k == 0 else 0.0)
            lo.extend(rhs)
            hi.extend(rhs)
        low, up = np.asarray(fc.lower, float), np.asarray(fc.upper, float)
        for k in range(1, H + 1):  # comfort band with slack: y + s >= low, y - s <= up
            for sign, bounds in ((1.0, (low[k] - Dy @ u[k], np.inf)), (-1.0, (-np.inf, up[k] - Dy @ u[k]))):
                A.block(A.rows, n * (k - 1), Cy[None, :])
                A.block(A.rows, isl + k - 1, np.array([[sign]]))
                A.rows += 1
                lo.append(bounds[0])
                hi.append(bounds[1])
        span = self._span(fc, H) / 1e3
        m_lo, m_hi = self.flow_bounds(fc, H)
        for k in range(H):  # input bounds, reheat limit P <= m cp (ts_max - T_ahu), slack >= 0
            r = A.rows
            A.block(r, im + k, np.array([[1.0]]))
            A.block(r + 1, ip + k, np.array([[1.0]]))
            A.block(r + 2, ip + k, np.array([[1.0]]))
            A.block(r + 2, im + k, np.array([[-span[k]]]))
            A.block(r + 3, isl + k, np.array([[1.0]]))
            A.rows += 4
            lo.extend([m_lo[k], 0.0, -np.inf, 0.0])
            hi.extend([m_hi[k], np.inf, 0.0, np.inf])
        qv = np.zeros(nz)
        qv[im : im + H] = q.qm
        qv[ip : ip + H] = q.qp * 1e3
        qv[isl:] = s.comfort_weight
        for k in range(1, H):  # the cooling load's dependence on the room temperature
            qv[n * (k - 1) : n * k] += q.qx[k] * Cy
        D = sp.diags([np.ones(H), -np.ones(H - 1)], [0, -1], shape=(H, H))  # moves
        M2 = 2 * s.move_weight * (D.T @ D)
        P = sp.block_diag(
            [sp.csc_matrix((n * H, n * H)), M2, M2, 2 * s.comfort_weight_quadratic * sp.eye(H)], format="csc"
        )
        qv[im] -= 2 * s.move_weight * m_prev
        qv[ip] -= 2 * s.move_weight * p_prev / 1e3
        return QPMatrices(sp.triu(P, format="csc"), qv, A.matrix(nz), np.array(lo), np.array(hi))

    def _condensed(
        self, x0, u, fc, q: QPData, bounds: tuple[np.ndarray, np.ndarray], prev: np.ndarray
    ) -> QPMatrices:
        """The QP without the states, in z = [m, P (kW) if supply air; heat inputs (kW); s] (:mod:`rczone.control.qp`).

        ``prev`` holds the values applied last, in that order (W for powers).
        """
        s = self.settings
        H = len(q.qm)
        c = self.cm.matrices
        Cy, Dy = c.C[0], c.D[0]
        decisions, couplings = [], []
        if self.air:
            decisions += [
                Decision(q.G, q.qm, bounds[0], bounds[1], prev[0]),
                Decision(1e3 * q.Ed, 1e3 * q.qp, np.zeros(H), np.full(H, np.inf), prev[1] / 1e3),
            ]
            couplings.append(Coupling(1, 0, self._span(fc, H) / 1e3))
        for j, name in enumerate(self.heaters):
            lo, hi = self.settings.heat_limits[name]
            decisions.append(
                Decision(
                    1e3 * q.Bh[:, :, j],
                    1e3 * q.qp,
                    np.full(H, lo / 1e3),
                    np.full(H, hi / 1e3),
                    prev[-len(self.heaters) + j] / 1e3,
                )
            )
        dy = u[1 : H + 1] @ Dy
        low, up = np.asarray(fc.lower, float)[1 : H + 1], np.asarray(fc.upper, float)[1 : H + 1]
        band = Band(low - dy, up - dy, np.r_[q.qx[1:H], 0.0])
        weights = Weights(s.comfort_weight, s.comfort_weight_quadratic, s.move_weight)
        return condensed_qp(Prediction(q.Ad, q.c, x0, Cy), decisions, band, weights, couplings)

    def _span(self, fc: Forecast, H: int) -> np.ndarray:
        """The reheat power per unit flow at the discharge limit, ``cp (ts_max - T_ahu)``, W per kg/s, (H,)."""
        return np.maximum(self.limits.ts_max - np.asarray(fc.t_ahu, float)[:H], 0.0) * CP_AIR

    def _solve(self, qp: QPMatrices, z: np.ndarray | None) -> Any:
        """OSQP's result: the kept, updated problem (condensed) or a fresh one (uncondensed)."""
        if self.settings.formulation == "condensed":
            if self._mem.solver is None:
                self._mem.solver = CondensedSolver(_osqp())
            return self._mem.solver.solve(qp, warm=z)
        solver = _osqp().OSQP()
        solver.setup(qp.P, qp.q, qp.A, qp.lower, qp.upper, **OSQP_SETTINGS)
        if z is not None:  # the last step's solution shifted, then the last pass's
            solver.warm_start(x=z)
        return solver.solve(raise_error=False)

    def _previous(self, m_lo: np.ndarray) -> np.ndarray:
        """The values applied last (flow, reheat W if supply air; heat inputs W), the first move's reference."""
        a = self._mem.action
        prev = [a.m, a.reheat] if a is not None else [m_lo[0], 0.0]
        heat = (
            [a.heat[h] for h in self.heaters]
            if a is not None
            else [max(self.settings.heat_limits[h][0], 0.0) for h in self.heaters]
        )
        return np.array((prev if self.air else []) + heat, float)

    def plan(
        self, x0: np.ndarray, forecast: Forecast, *, nominal: tuple[np.ndarray, ...] | None = None
    ) -> Plan:
        """Solve the problem from state ``x0`` (n,) (see the module notes).

        ``nominal``: the first linearization point, ``(m, reheat)`` or ``(m, reheat, heat)`` with
        ``heat`` (H, r) W (default the lowest flow, no reheat, the heat inputs' lowest power).
        """
        H = self._check(forecast)
        u = self._input_matrix(forecast, H)
        mem = self._mem
        bounds = self.flow_bounds(forecast, H)
        r = len(self.heaters)
        lims = np.array([self.settings.heat_limits[h] for h in self.heaters]).reshape(r, 2)
        m, reheat = nominal[:2] if nominal is not None else (bounds[0].copy(), np.zeros(H))
        heat = (
            nominal[2]
            if nominal is not None and len(nominal) > 2
            else np.tile(np.maximum(lims[:, 0], 0.0), (H, 1))
        )
        heat = np.clip(heat, lims[:, 0], lims[:, 1])
        m = np.clip(m, *bounds)
        prev = self._previous(bounds[0])
        elapsed, status = 0.0, ""
        n, nd = len(x0), (2 if self.air else 0) + r
        off = 0 if self.settings.formulation == "condensed" else n * H  # where the decisions start in z
        z = _shifted(mem.z, off // H, H) if mem.z is not None and len(mem.z) == off + (nd + 1) * H else None
        for _ in range(self.settings.linearizations):
            q = self.linearize(x0, u, forecast, m, reheat, heat if r else None)
            if off:
                qp = self._qp(x0, u, forecast, q, prev[0], prev[1])
            else:
                qp = self._condensed(x0, u, forecast, q, bounds, prev)
            t0 = _time.perf_counter()
            res = self._solve(qp, z)
            elapsed += _time.perf_counter() - t0
            status = str(res.info.status)
            if res.x is None or not np.all(np.isfinite(res.x)):
                raise RczoneError(
                    f"the MPC's QP could not be solved ({status}); check the band and the bounds"
                )
            z = res.x
            d = z[off : off + nd * H].reshape(nd, H)
            if self.air:
                m = np.clip(d[0], *bounds)
                reheat = np.clip(d[1] * 1e3, 0.0, m * self._span(forecast, H))
            if r:
                heat = np.clip(d[-r:].T * 1e3, lims[:, 0], lims[:, 1])
        mem.z = z
        un = self._with_heat(u, np.vstack([heat, heat[-1:]])) if r else u
        x = self.simulate(x0, un, m, reheat)
        c = self.cm.matrices
        planned = MappingProxyType({h: heat[:, j].copy() for j, h in enumerate(self.heaters)})
        y = x @ c.C[0] + un @ c.D[0]
        return Plan(m, reheat, x, y, z[off + nd * H :], status, elapsed, planned)

    # ------------------------------------------------------------ the loop
    def set_estimate(self, est: StateMoments, time: float) -> None:
        """Start (or reset) the observer from ``est`` at ``time`` (e.g. from :func:`estimate_state`)."""
        self._mem = _Memory(
            est=StateMoments(np.asarray(est.x, float), np.asarray(est.P, float)), time=float(time)
        )

    def step(self, time: float, measurements: Mapping[str, float], forecast: Forecast) -> ControlAction:
        """One control step: observe, plan, return the flow and reheat to hold for ``dt``.

        Parameters
        ----------
        time : float
            s.
        measurements : mapping
            The measured outputs (e.g. ``{"Ti": 22.4}``; NaN or missing = not measured).
        forecast : Forecast
            From ``time`` on, one value per ``dt``.
        """
        H = self._check(forecast)
        mem = self._mem
        u_now = self._input_matrix(forecast, H)[0]
        for name in measurements:
            if name not in self.cm.output_names:
                raise InputShapeError(
                    f"measurement {name!r}: the model measures {list(self.cm.output_names)}; "
                    + did_you_mean(name, self.cm.output_names)
                )
        y = np.array([float(measurements.get(o, np.nan)) for o in self.cm.output_names])
        if mem.est is None:
            mem.est = self.observer.prior(y)
        elif mem.time is not None and mem.action is not None and time > mem.time:
            mem.est = self.observer.predict(
                mem.est, mem.u, mem.action.m if self.air else 0.0, time - mem.time, heat=mem.action.reheat
            )
        mem.est, e = self.observer.update(mem.est, y, u_now)
        mem.innovations.append(float(e[0]))
        nominal = None
        if mem.action is not None:
            p = mem.action.plan
            ahead = [np.r_[p.m[1:], p.m[-1]], np.r_[p.reheat[1:], p.reheat[-1]]]
            if self.heaters:
                ahead.append(np.column_stack([np.r_[p.heat[h][1:], p.heat[h][-1]] for h in self.heaters]))
            nominal = tuple(ahead)
        plan = self.plan(mem.est.x, forecast, nominal=nominal)
        m0, r0 = float(plan.m[0]), float(plan.reheat[0])
        ts = float(forecast.t_ahu[0]) + r0 / (m0 * CP_AIR) if self.air else math.nan
        heat = MappingProxyType({h: float(v[0]) for h, v in plan.heat.items()})
        action = ControlAction(m0, r0, ts, plan, heat)
        if self.heaters:  # the observer's next prediction holds the heat inputs applied
            u_now = self._with_heat(u_now[None, :], np.array([[heat[h] for h in self.heaters]]))[0]
        mem.time, mem.u, mem.action = float(time), u_now, action
        return action

    @property
    def estimate(self) -> StateMoments | None:
        """The observer's current (filtered) estimate."""
        return self._mem.est

    @property
    def innovations(self) -> np.ndarray:
        """One-step prediction errors of the first output at every step so far, K."""
        return np.array(self._mem.innovations)
