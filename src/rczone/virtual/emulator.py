"""Closed-loop simulation of the virtual building.

Every 60 s the BMS senses the zone temperatures, each zone's controller (or forced
command schedule) sets its flow and discharge temperature, and these are held over the
next interval. With the flows fixed the network is linear, so one interval is advanced
*exactly* with the zero-order-hold transition ``x+ = Phi x + Gamma u`` of
``ss.matrices(m)`` [1]_; the pair is cached per distinct flow vector. Because the flows
switch between a few discrete levels and are held for tens of minutes, a night needs a
few dozen matrix exponentials at most.

The run starts ``warmup`` seconds before 6 pm from the steady state in which every zone
sits at its occupied heating setpoint under minimum flow and the day's mean outdoor
temperature (supply temperatures solved for), so the slow wall modes start near their
daily mean; daytime gains (:data:`DAY_GAIN`) during the warm-up leave the rooms warm at
6 pm, and the night starts with the building cooling down, as in a real trend log.

References
----------
.. [1] G. F. Franklin, J. D. Powell, M. Workman, Digital Control of Dynamic Systems, 3rd
   ed., 1998, section 4.3.3 (zero-order-hold equivalent).
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from rczone.errors import ParameterError
from rczone.simulation import zoh
from rczone.virtual.building import VirtualBuilding
from rczone.virtual.control import (
    CONTROL_DT,
    FLOW_LEVELS,
    SEASONS,
    ControllerConfig,
    ObservingController,
    TightController,
    VAVController,
    ZoneController,
    controller_configs,
)
from rczone.virtual.operation import SCHEDULE_GAIN, TIGHT_FLOW, Operation, sensor_reading
from rczone.virtual.sensors import sense_temperature
from rczone.virtual.weather import DIURNAL, check_season, outdoor_temperature

#: Slow drift of the AHU supply temperature: standard deviation (K) and correlation time (s).
AHU_DRIFT_STD = 0.3
AHU_DRIFT_TAU = 1800.0
#: Daytime gains during the warm-up (occupants, lights, equipment, solar through the window), W;
#: they ramp down linearly over the hour before ``DAY_END`` (6 pm) as people
#: leave, and leave the walls and furniture warm at 6 pm.
DAY_GAIN = {"target": 700.0, "n1": 700.0, "n2": 700.0, "hw": 200.0, "f": 700.0, "c": 700.0}
DAY_END = 0.0
#: One day, s; with ``daily=True`` schedules and daytime gains repeat with this period.
DAY = 86400.0
#: Start of the daytime gains with ``daily=True``, s after 6 pm (8 am).
DAY_START = 14 * 3600.0


def day_gain_share(t: float, daily: bool) -> float:
    """Share of :data:`DAY_GAIN` present at ``t`` (s from 6 pm).

    One night (``daily=False``): full until an hour before 6 pm, ramping down to zero at 6 pm
    (only the warm-up sees them). Several days: the same ramp every day, on from 8 am.
    """
    if not daily:
        return min(max((DAY_END - t) / 3600.0, 0.0), 1.0)
    tm = t % DAY
    return min(max((DAY - tm) / 3600.0, 0.0), 1.0) if tm >= DAY_START else 0.0


@dataclass(frozen=True)
class Command:
    """One block of a forced-response schedule from ``start`` (s from 6 pm).

    ``reheat`` is the discharge temperature above the AHU supply temperature, K. When ``ts``
    (an absolute discharge-temperature setpoint, degC) is given it replaces ``reheat``: the
    reheat coil then aims at ``max(ts, T_ahu)``, because it can only heat the AHU's supply air
    (a setpoint below the AHU supply temperature is met only as far as the AHU allows).
    """

    start: float
    m: float
    reheat: float = 0.0
    ts: float | None = None

    def __post_init__(self) -> None:
        values = {"start": self.start, "m": self.m, "reheat": self.reheat}
        if self.ts is not None:
            values["ts"] = self.ts
        bad = {k: v for k, v in values.items() if not np.isfinite(v)}
        if bad:
            raise ParameterError(f"Command values must be finite, got {bad}; check the schedule")
        if self.m < 0 or self.reheat < 0:
            raise ParameterError(
                f"Command needs m >= 0 kg/s and reheat >= 0 K, got m={self.m!r}, reheat={self.reheat!r};"
                " a VAV box cannot extract air or cool below the AHU supply"
            )

    def discharge_target(self, t_ahu: float) -> float:
        """Discharge temperature the coil aims at when the AHU supplies ``t_ahu`` degC."""
        return t_ahu + self.reheat if self.ts is None else max(self.ts, t_ahu)


class ForcedController:
    """Follows a piecewise-constant command schedule, ignoring the zone temperature.

    Before the first command's start the zone's thermostat (``fallback``) is in charge.
    The discharge temperature still passes the reheat coil's first-order lag, towards
    :meth:`Command.discharge_target` (relative reheat or absolute setpoint).
    """

    def __init__(
        self, commands: tuple[Command, ...], fallback: VAVController, tau_coil: float = 180.0
    ) -> None:
        self.commands = commands
        self.fallback = fallback
        self.tau_coil = tau_coil
        self.ts: float | None = None

    def step(self, t: float, t_sensed: float, t_ahu: float) -> tuple[float, float]:
        if t < self.commands[0].start:
            m, self.ts = self.fallback.step(t, t_sensed, t_ahu)
            return m, self.ts
        cmd = self.commands[0]
        for c in self.commands:
            if c.start <= t:
                cmd = c
        target = cmd.discharge_target(t_ahu)
        if self.ts is None:
            self.ts = target
        else:
            self.ts += (1.0 - np.exp(-CONTROL_DT / self.tau_coil)) * (target - self.ts)
        return cmd.m, self.ts


@dataclass(frozen=True)
class EmulatorRun:
    """A simulated stretch of building operation.

    Attributes
    ----------
    t : ndarray, shape (N + 1,)
        Times of the states, s from 6 pm.
    x : ndarray, shape (N + 1, n)
        True states (network order).
    u : ndarray, shape (N, p)
        Inputs held over ``[t[k], t[k+1])`` (network input order).
    m : ndarray, shape (N, nf)
        Flows held over the same intervals, kg/s.
    sensed : dict of str to ndarray, shape (N + 1,)
        Zone air temperatures as the BMS sensed them (what the controllers used), degC.
    n_discretizations : int
        Distinct flow vectors met (size of the ZOH cache).
    t_ahu, t_out : ndarray, shape (N,), optional
        AHU supply and outdoor temperatures over the intervals, degC.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    m: np.ndarray
    sensed: dict[str, np.ndarray]
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    flow_names: tuple[str, ...]
    n_discretizations: int
    t_ahu: np.ndarray | None = None
    t_out: np.ndarray | None = None

    def state(self, name: str) -> np.ndarray:
        """True temperature trajectory of node ``name``, shape (N + 1,)."""
        return self.x[:, self.state_names.index(name)]

    def input(self, name: str) -> np.ndarray:
        """Input ``name`` over the intervals, shape (N,)."""
        return self.u[:, self.input_names.index(name)]

    def flow(self, name: str) -> np.ndarray:
        """Flow ``name`` over the intervals, shape (N,)."""
        return self.m[:, self.flow_names.index(name)]


def _initial_state(bld: VirtualBuilding, season: str, heat_sp: Mapping[str, float]) -> np.ndarray:
    ss = bld.network.state_space()
    m0 = np.full(len(bld.zones), FLOW_LEVELS[0])
    A, B = ss.matrices(m0)
    u = np.zeros(len(ss.input_names))
    u[ss.input_names.index("To")] = DIURNAL[season][0]
    for z in bld.zones:
        u[ss.input_names.index(bld.gain_name(z))] = bld.gains[z]
    # Zone air temperatures are affine in the supply temperatures: solve for setpoints.
    air_idx = [ss.state_names.index(bld.air_nodes[z]) for z in bld.zones]
    ts_idx = [ss.input_names.index(bld.supply_name(z)) for z in bld.zones]
    x_base = np.linalg.solve(A, -B @ u)
    G = np.linalg.solve(A, -B[:, ts_idx])
    target = np.array([heat_sp[z] for z in bld.zones])
    ts = np.linalg.solve(G[air_idx], target - x_base[air_idx])
    return x_base + G @ ts


def thermostat_configs(
    bld: VirtualBuilding,
    season: str,
    rng: np.random.Generator,
    *,
    warmup: float = 6 * 3600.0,
    operation: Operation | None = None,
    daily: bool = False,
) -> dict[str, ControllerConfig]:
    """The thermostat settings (setpoints, schedule) that :func:`run` will draw from ``rng``.

    ``rng`` is not advanced (a copy is used), so a controller can be given the zone's band
    before ``run(bld, season, rng, ...)`` is called with the same generator.
    """
    _, g_ctrl, _, _ = copy.deepcopy(rng).spawn(4)
    return _configs(bld, season, g_ctrl, warmup, operation or Operation(), daily)


def _configs(
    bld: VirtualBuilding, season: str, g_ctrl: np.random.Generator, warmup: float, op: Operation, daily: bool
) -> dict[str, ControllerConfig]:
    return {
        z: replace(_with_deadband(c, op.deadband_K), period=DAY if daily else None)
        for z, c in controller_configs(season, bld.zones, g_ctrl, -warmup).items()
    }


def run(
    bld: VirtualBuilding,
    season: str,
    rng: np.random.Generator,
    duration: float = 12 * 3600.0,
    warmup: float = 6 * 3600.0,
    forced: Mapping[str, tuple[Command, ...]] | None = None,
    sense: Callable[[np.ndarray, np.random.Generator], np.ndarray] = sense_temperature,
    operation: Operation | None = None,
    *,
    controllers: Mapping[str, ZoneController] | None = None,
    daily: bool = False,
) -> EmulatorRun:
    """Simulate the building in closed loop from ``-warmup`` to ``duration`` s after 6 pm.

    Parameters
    ----------
    bld : VirtualBuilding
    season : {"summer", "winter", "autumn"}
    rng : numpy.random.Generator
        Source of all randomness (weather, controller settings, AHU drift, sensors).
    duration, warmup : float
        s; multiples of 60 s.
    forced : mapping of zone to Command tuple, optional
        Zones that follow a command schedule instead of their thermostat.
    sense : callable
        Temperature sensor model used by the controllers.
    operation : Operation, optional
        Loop, night deadband, unmeasured scheduled gains and thermostat placement
        (:mod:`rczone.virtual.operation`); default: the operation of the shipped nights.
    controllers : mapping of zone to ZoneController, optional
        Zones run by a controller of the caller's (:class:`~rczone.virtual.control.ZoneController`;
        an :class:`~rczone.virtual.control.ObservingController` also reads every sensor first).
    daily : bool
        Runs of several days: the thermostats' schedules and the daytime gains repeat every day.

    Returns
    -------
    EmulatorRun
    """
    sim = Simulation(
        bld,
        season,
        rng,
        duration=duration,
        warmup=warmup,
        forced=forced,
        sense=sense,
        operation=operation,
        controllers=controllers,
        daily=daily,
    )
    while not sim.done:
        sim.advance()
    return sim.result()


class Simulation:
    """One run of the building, advanced one control interval at a time (what :func:`run` loops over).

    The arguments are those of :func:`run`. After construction the zone temperatures at
    ``-warmup`` are sensed; each :meth:`advance` lets every zone's controller act (or takes the
    caller's ``(m, Ts)`` for the zones in ``held``), advances the network exactly over
    :data:`CONTROL_DT` and senses again. The random streams are drawn in :func:`run`'s order, so a
    run advanced here with the zones' own thermostats is :func:`run`'s run.
    """

    def __init__(
        self,
        bld: VirtualBuilding,
        season: str,
        rng: np.random.Generator,
        *,
        duration: float,
        warmup: float,
        forced: Mapping[str, tuple[Command, ...]] | None = None,
        sense: Callable[[np.ndarray, np.random.Generator], np.ndarray] = sense_temperature,
        operation: Operation | None = None,
        controllers: Mapping[str, ZoneController] | None = None,
        daily: bool = False,
    ) -> None:
        check_season(season)
        g_weather, g_ctrl, g_ahu, self._g_sense = rng.spawn(4)
        self.bld, self.daily, self._sense = bld, daily, sense
        self.n_steps = round((duration + warmup) / CONTROL_DT)
        self.t = -warmup + CONTROL_DT * np.arange(self.n_steps + 1)
        self.t_out = outdoor_temperature(season, self.t, g_weather)
        self.t_ahu = SEASONS[season].t_ahu + _ahu_drift(g_ahu, self.n_steps + 1)
        self.op = operation or Operation()
        self.configs = _configs(bld, season, g_ctrl, warmup, self.op, daily)
        self.ctrls = self._controllers(forced, controllers, warmup)
        self.ss = ss = bld.network.state_space()
        idx = ss.input_names.index
        self._air = np.array([ss.state_names.index(bld.air_nodes[z]) for z in bld.zones])
        self._ts = np.array([idx(bld.supply_name(z)) for z in bld.zones])
        self._gain = np.array([idx(bld.gain_name(z)) for z in bld.zones])
        self._to = idx("To")
        self._u_base, self._u_day = np.zeros(len(ss.input_names)), np.zeros(len(ss.input_names))
        for z in bld.zones:
            self._u_base[idx(bld.gain_name(z))] = bld.gains[z]
            self._u_day[idx(bld.gain_name(z))] = DAY_GAIN.get(z, 0.0)
        n, p, nf = len(ss.state_names), len(ss.input_names), len(ss.flow_names)
        self.x = np.empty((self.n_steps + 1, n))
        self.u = np.empty((self.n_steps, p))
        self.m = np.empty((self.n_steps, nf))
        self.sensed = np.empty((self.n_steps + 1, len(bld.zones)))
        self.x[0] = _initial_state(bld, season, {z: self.configs[z].heat_occ for z in bld.zones})
        self._cache: dict[tuple[float, ...], tuple[np.ndarray, np.ndarray]] = {}
        self.k = 0
        self._sense_now()

    def _controllers(self, forced, controllers, warmup: float) -> dict[str, ZoneController]:
        cfgs, op = self.configs, self.op
        ctrls: dict[str, ZoneController] = {
            z: TightController(cfgs[z], TIGHT_FLOW) if op.loop == "tight" else VAVController(cfgs[z], -warmup)
            for z in self.bld.zones
        }
        for z, cmds in dict(forced or {}).items():
            ctrls[z] = ForcedController(cmds, VAVController(cfgs[z], -warmup))
        ctrls.update(dict(controllers or {}))
        return ctrls

    @property
    def done(self) -> bool:
        """Whether the run has reached its end."""
        return self.k >= self.n_steps

    def _sense_now(self) -> None:
        k = self.k
        reading = self.x[k, self._air]
        if self.op.sensor != "room" and k > 0:
            reading = sensor_reading(
                reading, self.u[k - 1, self._ts], self.m[k - 1], self.op.sensor, self.op.diffuser_mix
            )
        self.sensed[k] = self._sense(reading, self._g_sense)

    def readings(self) -> dict[str, float]:
        """``{"To": outdoor, <air node>: sensed temperature of every zone}`` now, degC."""
        k, bld = self.k, self.bld
        return {
            "To": float(self.t_out[k]),
            **{bld.air_nodes[z]: float(self.sensed[k, j]) for j, z in enumerate(bld.zones)},
        }

    def advance(self, held: Mapping[str, tuple[float, float]] | None = None) -> None:
        """Advance one control interval; zones in ``held`` get its ``(m, Ts)``, the others their controller."""
        k, bld, held = self.k, self.bld, held or {}
        tk = float(self.t[k])
        uk = self._u_base + day_gain_share(tk, self.daily) * self._u_day
        if self.op.gains == "schedule":
            occupied = np.array([not self.configs[z].unoccupied(tk) for z in bld.zones])
            uk[self._gain] += SCHEDULE_GAIN * occupied
        uk[self._to] = self.t_out[k]
        observers = [c for z, c in self.ctrls.items() if z not in held and isinstance(c, ObservingController)]
        if observers:
            readings = self.readings()
            for c in observers:
                c.observe(tk, readings)
        mk = np.empty(len(self.ss.flow_names))
        for j, z in enumerate(bld.zones):
            if z in held:
                mk[j], uk[self._ts[j]] = held[z]
            else:
                mk[j], uk[self._ts[j]] = self.ctrls[z].step(
                    tk, float(self.sensed[k, j]), float(self.t_ahu[k])
                )
        key = tuple(mk)
        if key not in self._cache:
            self._cache[key] = zoh(*self.ss.matrices(mk), CONTROL_DT)
        phi, gam = self._cache[key]
        self.x[k + 1] = phi @ self.x[k] + gam @ uk
        self.u[k], self.m[k] = uk, mk
        self.k = k + 1
        self._sense_now()

    def result(self) -> EmulatorRun:
        """The run so far (states up to now)."""
        k, ss = self.k, self.ss
        return EmulatorRun(
            t=self.t[: k + 1].copy(),
            x=self.x[: k + 1].copy(),
            u=self.u[:k].copy(),
            m=self.m[:k].copy(),
            sensed={z: self.sensed[: k + 1, j].copy() for j, z in enumerate(self.bld.zones)},
            state_names=ss.state_names,
            input_names=ss.input_names,
            flow_names=ss.flow_names,
            n_discretizations=len(self._cache),
            t_ahu=self.t_ahu[:k].copy(),
            t_out=self.t_out[:k].copy(),
        )


def _ahu_drift(g_ahu: np.random.Generator, n: int) -> np.ndarray:
    """The AHU supply temperature's slow drift (first order, :data:`AHU_DRIFT_STD`, :data:`AHU_DRIFT_TAU`), K."""
    a = np.exp(-CONTROL_DT / AHU_DRIFT_TAU)
    drift = np.empty(n)
    drift[0] = g_ahu.normal(0.0, AHU_DRIFT_STD)
    w = g_ahu.normal(0.0, AHU_DRIFT_STD * np.sqrt(1 - a * a), size=n)
    for k in range(1, n):
        drift[k] = a * drift[k - 1] + w[k]
    return drift


def _with_deadband(cfg: ControllerConfig, deadband: float | None) -> ControllerConfig:
    """``cfg`` with its night band narrowed or widened to ``deadband`` K about its centre."""
    if deadband is None:
        return cfg
    mid = 0.5 * (cfg.heat_unocc + cfg.cool_unocc)
    return replace(cfg, heat_unocc=mid - 0.5 * deadband, cool_unocc=mid + 0.5 * deadband)
