"""A centralized supervisory MPC of one floor: one joint model, one linear program for every zone.

:class:`FloorMPC` is :class:`~rczone.emulators.supervisory.SupervisoryMPC` written for a joint
model of several zones (:mod:`rczone.emulators.floor`), whose outputs are the controlled zones'
room temperatures. Every plant step it

1. **observes**: one Kalman filter on the joint model, each zone's supply air replaced by the heat
   it brought, ``P_z = m_z cp (Ts_z - Ti_z)`` (the model at zero flow with that heat at the zone's
   room node is the fitted model), with an integrating heat disturbance at every zone's room node
   (Pannocchia and Rawlings [1]_: one disturbance per measured output keeps the estimate
   offset-free in every zone);
2. **plans** over ``horizon`` steps every zone's heating and cooling with the coupling between the
   zones in the prediction: zone ``j``'s temperature responds to zone ``l``'s heat through the
   joint model's walls. The boundaries off the floor (plenum, attic, the next floor: measured
   ``Ti_<zone>`` of the building's other zones) and the zones' metered internal power are held at
   their last measurement, the outdoor temperature comes from the plant's forecast. Comfort is
   soft per zone, price, efficiency, COP and capacity are each zone's
   :class:`~rczone.emulators.supervisory.SupervisorySettings`: one linear program in condensed
   form, solved by HiGHS (centralized MPC, Scattolini [2]_, section 2);
3. **acts** per zone as the supervisory MPC of one zone does: the plan's temperature at the end of
   the step is the heating set point if the plan heats the zone in this step, the cooling set point
   if it cools it, the band's edge otherwise, clipped to the plant's set-point limits.

With no coupling between the zones the linear program separates and the plans are those of one
:class:`~rczone.emulators.supervisory.SupervisoryMPC` per zone (tested).

References
----------
.. [1] G. Pannocchia, J. B. Rawlings, "Disturbance models for offset-free model-predictive
   control", AIChE Journal 49(2) (2003) 426-437.
.. [2] R. Scattolini, "Architectures for distributed and hierarchical model predictive control -
   a review", Journal of Process Control 19(5) (2009) 723-731.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from scipy.optimize import linprog

from rczone.control.disturbance import Disturbance
from rczone.control.model import DiscreteMatrices
from rczone.control.noise import NoiseModel
from rczone.control.observer import DISTURBANCE_PRIOR_SD, NODE_PRIOR_SD, KalmanObserver
from rczone.emulators.floor import alias
from rczone.emulators.supervisory import HeatPlan, PlanStep, SupervisorySettings, set_points
from rczone.errors import ParameterError, RczoneError
from rczone.kernels.arrays import StateMoments
from rczone.models.zone import ZoneModel
from rczone.network import CP_AIR
from rczone.simulation.discretize import process_noise_covariance, zoh


class JointMatrices(NamedTuple):
    """The joint model as :class:`~rczone.control.observer.KalmanObserver` reads it: the zones'
    heats appended to the inputs (``B = [B | E]``, ``D = [D | 0]``), one disturbance per zone."""

    matrices: DiscreteMatrices
    noise: NoiseModel

    def discrete(self, dt: float, m: float) -> DiscreteMatrices:
        return self.matrices


def zone_outputs(model: ZoneModel, zones: Sequence[str]) -> list[str]:
    """Each zone's output of the joint model: ``T<letters and digits of the zone>`` or the zone's name."""
    outputs = list(model.network.outputs)
    found = []
    for z in zones:
        hits = [o for o in (f"T{alias(z)}", z) if o in outputs]
        if not hits:
            raise ParameterError(
                f"the floor MPC's model {model.name!r} has no output for zone {z!r} (T{alias(z)}); "
                f"its outputs are {outputs}"
            )
        found.append(hits[0])
    if len(outputs) != len(zones):
        extra = [o for o in outputs if o not in found]
        raise ParameterError(
            f"the floor MPC's model {model.name!r} has outputs {extra} for zones not controlled; "
            "control every zone of the model (--zones)"
        )
    return found


def supply_columns(model: ZoneModel, outputs: Sequence[str]) -> np.ndarray:
    """Heat input (per W) at each zone's supply-air node, (n, nz); one supply-air flow per zone."""
    net, ss = model.network, model.state_space()
    by_node = {s.node: s for s in net.supply_air}
    if len(net.supply_air) != len(outputs) or set(by_node) != set(outputs):
        raise ParameterError(
            f"the floor MPC needs one supply-air flow into each zone's room node {list(outputs)}; "
            f"{model.name!r} has supply air into {[s.node for s in net.supply_air]}"
        )
    values = net.values(model.theta)
    cols = []
    for o in outputs:
        s = by_node[o]
        cp = s.cp if isinstance(s.cp, (int, float)) else values[s.cp]
        f, ts = ss.flow_names.index(s.flow), ss.input_names.index(s.temperature)
        cols.append(ss.M[f][:, ts] / float(cp))
    return np.column_stack(cols)


def owners(model: ZoneModel, outputs: Sequence[str]) -> list[int | None]:
    """For each state, the zone whose room node reaches it through the network without crossing
    another zone's room node (None if no zone or several do): where the filter starts it."""
    net = model.network
    states = list(net.state_names)
    links: dict[str, set[str]] = {s: set() for s in states}
    for r in net.resistors:
        if r.a in links and r.b in links:
            links[r.a].add(r.b)
            links[r.b].add(r.a)
    reach: dict[str, set[int]] = {s: set() for s in states}
    for j, o in enumerate(outputs):
        todo, seen = [o], {o}
        while todo:
            s = todo.pop()
            reach[s].add(j)
            for t in links[s] - seen:
                if t not in outputs:
                    seen.add(t)
                    todo.append(t)
    return [next(iter(reach[s])) if len(reach[s]) == 1 else None for s in states]


def input_sources(
    model: ZoneModel, zones: Sequence[str], outputs: Sequence[str], measured: Sequence[str]
) -> list[tuple[str, object]]:
    """Where each input of the joint model comes from: ``("forecast", "To")``, ``("measured", (key,
    default))`` (a zone's supply temperature as its room's ``Ti_<zone>``, without effect at zero flow;
    its metered ``Q_<zone>``; a measured zone off the floor's ``Ti_<zone>``) or ``("default", value)``.

    Raises
    ------
    ParameterError
        For an input that is none of these and has no default.
    """
    net = model.network
    keys = {s.temperature: f"Ti_{z}" for z, o in zip(zones, outputs) for s in net.supply_air if s.node == o}
    keys |= {f"Q{alias(z)}": f"Q_{z}" for z in zones}
    keys |= {f"T{alias(n)}": f"Ti_{n}" for n in measured if n not in zones}
    defaults = dict(model.inputs.defaults)
    sources: list[tuple[str, object]] = []
    for name in model.state_space().input_names:
        if name == "To":
            sources.append(("forecast", "To"))
        elif name in keys:
            sources.append(("measured", (keys[name], defaults.get(name))))
        elif name in defaults:
            sources.append(("default", float(defaults[name])))
        else:
            raise ParameterError(
                f"the floor MPC cannot forecast the model input {name!r}: it is no zone's supply air,"
                " metered heat or measured temperature, and the model gives no default"
            )
    return sources


class FloorMPC:
    """The centralized supervisory MPC of several zones with their joint model (module notes).

    Parameters
    ----------
    model : ZoneModel
        A joint model whose outputs are the zones' room temperatures (``T<zone's letters and
        digits>``, as :func:`rczone.emulators.floor.floor_model` names them), with one supply-air
        flow into each zone's room node.
    zones : sequence of str
        The controlled zones, every output of the model.
    dt : float
        The plant's step, s.
    settings : SupervisorySettings or mapping of zone to it, optional
        Every zone's, or each zone's (the same horizon for all).
    measured : sequence of str
        Other zones of the building whose sensed temperature ``Ti_<zone>`` the plant measures: a
        model input ``T<zone's letters and digits>`` is that zone's (a boundary off the floor).
    """

    def __init__(
        self,
        model: ZoneModel,
        *,
        zones: Sequence[str],
        dt: float,
        settings: SupervisorySettings | Mapping[str, SupervisorySettings] | None = None,
        measured: Sequence[str] = (),
    ) -> None:
        self.zones = list(zones)
        if not self.zones or len(set(self.zones)) != len(self.zones):
            raise ParameterError(f"the floor MPC needs distinct zones, got {self.zones}")
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ParameterError(f"the floor MPC's step must be finite and > 0 s, got {dt!r}")
        self.model = model
        self.outputs = zone_outputs(model, self.zones)
        self.settings = self._per_zone(settings)
        self.dt = self.interval = float(dt)
        self.steps = self.settings[self.zones[0]].horizon
        self.horizon = self.steps * self.dt
        self._sources = input_sources(model, self.zones, self.outputs, measured)
        self._d, noise = self._discretize(supply_columns(model, self.outputs))
        self.observer = KalmanObserver(JointMatrices(self._d, noise))
        self._owner = owners(model, self.outputs)
        self.solve_times: list[float] = []
        self.innovations: list[np.ndarray] = []
        self._est: StateMoments | None = None
        self._u: np.ndarray | None = None
        self.plan: HeatPlan | None = None

    def _per_zone(self, settings) -> dict[str, SupervisorySettings]:
        if settings is None or isinstance(settings, SupervisorySettings):
            return dict.fromkeys(self.zones, settings or SupervisorySettings())
        missing = [z for z in self.zones if z not in settings]
        if missing:
            raise ParameterError(f"the floor MPC's settings name no settings for zones {missing}")
        out = {z: settings[z] for z in self.zones}
        if len({s.horizon for s in out.values()}) != 1:
            raise ParameterError(
                "the floor MPC plans every zone over one horizon; the zones' settings differ"
            )
        return out

    def _discretize(self, E: np.ndarray) -> tuple[DiscreteMatrices, NoiseModel]:
        """The joint model with a heat disturbance at each zone's room node, at zero flow, exact ZOH."""
        ss = self.model.state_space()
        n, nz, p = ss.n_states, len(self.zones), ss.n_inputs
        dist = Disturbance("heat")
        A = np.zeros((n + nz, n + nz))
        A[:n, :n] = ss.A
        for j, o in enumerate(self.outputs):
            i = ss.state_names.index(o)
            A[i, n + j] = 1.0 / float(ss.capacities[i])
        B = np.vstack([np.hstack([ss.B, E]), np.zeros((nz, p + nz))])
        noise = NoiseModel.from_model(self.model)
        Qc = np.zeros_like(A)
        Qc[:n, :n] = noise.Qc
        Qc[n:, n:] = np.eye(nz) * dist.intensity**2
        Ad, Bd = zoh(A, B, self.dt)
        C = np.hstack([ss.C, np.zeros((len(self.zones), nz))])
        C = C[[list(ss.output_names).index(o) for o in self.outputs]]
        D = np.hstack([ss.D, np.zeros((ss.D.shape[0], nz))])[
            [list(ss.output_names).index(o) for o in self.outputs]
        ]
        R = noise.R[np.ix_(*[[list(ss.output_names).index(o) for o in self.outputs]] * 2)]
        Qd = process_noise_covariance(A, Qc, self.dt)
        d = DiscreteMatrices(Ad, Bd, np.zeros((n + nz, 1)), C, D, Qd, R)
        return d, NoiseModel(Qc, R, noise.state_names, tuple(self.outputs), noise.source)

    def inputs(self, measurements: Mapping[str, float], to: np.ndarray) -> np.ndarray:
        """Model inputs over the forecast (len(to), p): ``To`` forecast, the rest held (module notes)."""
        cols = []
        for kind, what in self._sources:
            if kind == "forecast":
                cols.append(np.asarray(to, float))
                continue
            v = what
            if kind == "measured":
                key, default = what
                v = float(measurements.get(key, math.nan))
                if not math.isfinite(v):
                    v = math.nan if default is None else float(default)
                if not math.isfinite(v):
                    raise ParameterError(
                        f"the floor MPC has no measurement {key!r} to forecast its model's input"
                    )
            cols.append(np.full(len(to), float(v)))
        return np.column_stack(cols)

    def _prior(self, ti: np.ndarray) -> StateMoments:
        """Every node at its zone's measured temperature (the zones' mean if shared), disturbances 0."""
        nz = len(self.zones)
        mean = float(np.nanmean(ti))
        x = np.array(
            [mean if j is None or not math.isfinite(ti[j]) else ti[j] for j in self._owner] + [0.0] * nz
        )
        sd = np.r_[np.full(len(self._owner), NODE_PRIOR_SD), np.full(nz, DISTURBANCE_PRIOR_SD["heat"])]
        return StateMoments(x, np.diag(sd**2))

    def _observe(self, measurements: Mapping[str, float], u_now: np.ndarray) -> None:
        ti = np.array([float(measurements.get(f"Ti_{z}", math.nan)) for z in self.zones])
        heats = []
        for z, t in zip(self.zones, ti):
            m, ts = float(measurements.get(f"m_{z}", math.nan)), float(measurements.get(f"Ts_{z}", math.nan))
            ok = math.isfinite(m) and math.isfinite(ts) and math.isfinite(t)
            heats.append(m * CP_AIR * (ts - t) if ok else 0.0)
        if self._est is None:
            if not np.isfinite(ti).any():
                raise ParameterError("the floor MPC's first measurement has no zone temperature")
            self._est = self._prior(ti)
        else:
            self._est = self.observer.predict(self._est, np.r_[self._u, heats], 0.0, self.dt)
        self._est, e = self.observer.update(self._est, ti, np.r_[u_now, np.zeros(len(self.zones))])
        self.innovations.append(e)
        self._u = u_now

    def solve(
        self, x0: np.ndarray, u: np.ndarray, lower: np.ndarray, upper: np.ndarray, price: np.ndarray
    ) -> HeatPlan:
        """The plan from state ``x0`` with inputs ``u`` (H + 1, p), bands (nz, H + 1), price (H + 1,)."""
        d, H, nz = self._d, self.steps, len(self.zones)
        p = u.shape[1]
        A, B, E = d.Ad, d.Bd[:, :p], d.Bd[:, p:] * 1e3  # heat in kW
        C, D = d.C, d.D[:, :p]
        x, free, g, AE = np.asarray(x0, float), [], [], E
        for k in range(H):
            x = A @ x + B @ u[k]
            free.append(C @ x + D @ u[k + 1])
            g.append(C @ AE)  # every zone's response k steps after a kW in each zone
            AE = A @ AE
        free, g = np.array(free).T, np.array(g)
        G = np.zeros((nz, H, nz, H))
        for k in range(H):
            G[:, k, :, : k + 1] = np.transpose(g[k::-1], (1, 2, 0))
        G = G.reshape(nz * H, nz * H)
        st = [self.settings[z] for z in self.zones]

        def per_zone(f) -> np.ndarray:
            return np.concatenate([np.broadcast_to(f(s), (H,)) for s in st])

        margin = np.array([s.margin_K for s in st])[:, None]
        lo = np.asarray(lower, float)[:, 1 : H + 1] + margin
        hi = np.maximum(np.asarray(upper, float)[:, 1 : H + 1] - margin, lo)
        w = np.asarray(price, float)[:H] * self.dt / 3600.0  # per kW held a step: kWh x price
        cost = np.r_[
            per_zone(lambda s: w / s.heating_efficiency),
            per_zone(lambda s: w / s.cooling_cop),
            per_zone(lambda s: s.comfort_weight),
            per_zone(lambda s: s.comfort_weight + s.comfort_weight_steep),
        ]
        one = np.eye(nz * H)
        # G (h - c) + s1 + s2 >= lo - free;  G (h - c) - s1 - s2 <= hi - free
        A_ub = np.block([[-G, G, -one, -one], [G, -G, -one, -one]])
        b_ub = np.r_[(free - lo).ravel(), (hi - free).ravel()]
        bounds = (
            [(0.0, s.heating_capacity / 1e3) for s in st for _ in range(H)]
            + [(0.0, s.cooling_capacity / 1e3) for s in st for _ in range(H)]
            + [(0.0, s.slack_tier_K) for s in st for _ in range(H)]
            + [(0.0, None)] * (nz * H)
        )
        t0 = _time.perf_counter()
        res = linprog(cost, A_ub=A_ub, b_ub=b_ub, bounds=bounds, method="highs")
        elapsed = _time.perf_counter() - t0
        if res.status != 0 or res.x is None:
            raise RczoneError(f"the floor MPC's linear program could not be solved ({res.message})")
        h, c, s1, s2 = (np.clip(res.x[i * nz * H : (i + 1) * nz * H], 0.0, None) for i in range(4))
        y = np.column_stack([C @ x0 + D @ u[0], free + (G @ (h - c)).reshape(nz, H)])
        return HeatPlan(
            h.reshape(nz, H) * 1e3, c.reshape(nz, H) * 1e3, y, (s1 + s2).reshape(nz, H), "optimal", elapsed
        )

    def act(self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]) -> dict:
        """Observe, plan, and give every zone's thermostat its set points for the next step."""
        H = self.steps
        if len(forecast["time"]) < H + 1:
            raise ParameterError(f"the forecast must cover {H + 1} steps, it has {len(forecast['time'])}")
        u = self.inputs(measurements, forecast["To"][: H + 1])
        self._observe(measurements, u[0])
        lower = np.array([forecast[f"lower_{z}"][: H + 1] for z in self.zones])
        upper = np.array([forecast[f"upper_{z}"][: H + 1] for z in self.zones])
        plan = self.solve(self._est.x, u, lower, upper, forecast["price"])
        self.plan = plan
        self.solve_times.append(plan.solve_time)
        out: dict = {}
        for j, z in enumerate(self.zones):
            step = PlanStep(
                float(plan.y[j, 1]), plan.heating[j, 0], plan.cooling[j, 0], lower[j, 1], upper[j, 1]
            )
            out.update(set_points(z, self.settings[z], step, forecast))
        return out
