"""VAV-box thermostats of the virtual building (night operation).

Each zone's VAV box follows a common single-maximum sequence, acting every 60 s on the
*sensed* (noisy, quantized) zone temperature:

* **Flow**: discrete levels ``FLOW_LEVELS`` = 0.02, 0.05, 0.08, 0.12 kg/s (0.12 kg/s is
  the largest flow in the paper's data). The minimum level depends on the schedule mode
  (occupied: 0.05 kg/s, unoccupied: 0.02 kg/s). In cooling the level steps up one when
  the sensed temperature exceeds the cooling setpoint by ``band_up`` and down when it is
  ``band_down`` below it, and never before ``hold`` seconds (20-40 min, seeded per zone)
  have passed since the last change. So ``m`` holds constant for long stretches, as the
  paper requires of its data ("m constant for long periods").
* **Discharge temperature**: the AHU supply temperature (summer ~13 degC, winter ~15
  degC, slow seeded drift) plus reheat from a PI loop on the heating-setpoint error
  (proportional gain ``kp`` K per K, integral time ``ti`` s, anti-windup by clamping),
  limited to ``ts_max`` (35 degC), passed through a first-order coil lag (``tau_coil``,
  3 min). In summer there is little reheat; in winter it reaches ~30-35 degC.
* **Schedule**: occupied mode until the evening switch (about 19:00) and again from the
  morning start (about 05:00), unoccupied in between; the setpoints (seasonal, seeded
  +-0.3 K per zone) change with the mode, which moves the temperatures during the night.

Every number is an assumption typical of US university office buildings (ASHRAE
Guideline 36 style single-maximum VAV sequence) unless it comes from the paper.

References
----------
.. [1] ASHRAE Guideline 36-2018, High-performance sequences of operation for HVAC
   systems, section 5.6 (VAV terminal unit with reheat).
.. [2] Y. Lin, T. Middelkoop, P. Barooah, IEEE CDC 2012, section III-A (m up to
   0.12 kg/s; data chosen with m constant for long periods).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

#: Discrete VAV flow levels, kg/s (max 0.12 kg/s from the paper).
FLOW_LEVELS = (0.02, 0.05, 0.08, 0.12)
#: Controller sample time, s.
CONTROL_DT = 60.0


@dataclass(frozen=True)
class SeasonSettings:
    """Seasonal setpoints and AHU settings, degC.

    ``heat_occ``/``cool_occ`` apply in occupied mode, ``heat_unocc``/``cool_unocc`` at night.
    """

    t_ahu: float
    heat_occ: float
    cool_occ: float
    heat_unocc: float
    cool_unocc: float


#: Per season: AHU supply temperature and setpoints, degC.
SEASONS = {
    "summer": SeasonSettings(t_ahu=13.0, heat_occ=21.7, cool_occ=23.5, heat_unocc=21.0, cool_unocc=25.0),
    "winter": SeasonSettings(t_ahu=15.0, heat_occ=23.9, cool_occ=25.0, heat_unocc=22.2, cool_unocc=26.0),
    "autumn": SeasonSettings(t_ahu=13.0, heat_occ=22.0, cool_occ=23.5, heat_unocc=21.5, cool_unocc=25.0),
}


@dataclass(frozen=True)
class ControllerConfig:
    """One VAV box's settings (SI, degC).

    Parameters
    ----------
    heat_occ, cool_occ, heat_unocc, cool_unocc : float
        Setpoints, degC.
    unocc_start, unocc_end : float
        Unoccupied mode from ``unocc_start`` to ``unocc_end``, s from the start of the night (6 pm).
    hold : float
        Minimum time between two flow-level changes, s.
    band_up, band_down : float
        Cooling-error thresholds for a level up / down, K.
    kp : float
        Reheat proportional gain, K of discharge temperature per K of error.
    ti : float
        Reheat integral time, s.
    ts_max : float
        Highest discharge temperature, degC.
    tau_coil : float
        Reheat coil time constant, s.
    period : float, optional
        Repeat the schedule every ``period`` s (one day for runs of several days); ``None``: one night.
    """

    heat_occ: float
    cool_occ: float
    heat_unocc: float
    cool_unocc: float
    unocc_start: float
    unocc_end: float
    hold: float = 1800.0
    band_up: float = 0.3
    band_down: float = 0.5
    kp: float = 6.0
    ti: float = 1200.0
    ts_max: float = 35.0
    tau_coil: float = 180.0
    period: float | None = None

    def unoccupied(self, t: float) -> bool:
        """Whether the schedule is in unoccupied mode at ``t`` (s from 6 pm)."""
        tm = t % self.period if self.period else t
        return self.unocc_start <= tm < self.unocc_end


@runtime_checkable
class ZoneController(Protocol):
    """What the virtual building asks of a zone's controller (thermostat, forced schedule, MPC).

    :meth:`step` is called once per control interval (:data:`CONTROL_DT`) with the time (s from
    6 pm), the zone's sensed air temperature and the AHU supply temperature (degC), and returns
    the flow (kg/s) and discharge temperature (degC) held over the next interval.
    """

    def step(self, t: float, t_sensed: float, t_ahu: float) -> tuple[float, float]: ...


@runtime_checkable
class ObservingController(ZoneController, Protocol):
    """A controller that also reads the building's other sensors before each :meth:`step`.

    :meth:`observe` gets ``{"To": outdoor temperature, <air node>: sensed temperature of every
    zone}``, degC (e.g. a model-predictive controller whose model needs the neighbours).
    """

    def observe(self, t: float, readings: Mapping[str, float]) -> None: ...


def controller_configs(
    season: str, zones: tuple[str, ...], rng: np.random.Generator, t0: float
) -> dict[str, ControllerConfig]:
    """Seeded per-zone controller settings for ``season``.

    Parameters
    ----------
    t0 : float
        Simulation start relative to 6 pm, s (negative for a warm-up before the night).
    """
    s = SEASONS[season]
    out = {}
    for z in zones:
        off = float(rng.uniform(-0.3, 0.3))
        out[z] = ControllerConfig(
            heat_occ=s.heat_occ + off,
            cool_occ=s.cool_occ + off,
            heat_unocc=s.heat_unocc + off,
            cool_unocc=s.cool_unocc + off,
            unocc_start=3600.0 + float(rng.uniform(-900.0, 900.0)),
            unocc_end=11 * 3600.0 + float(rng.uniform(-900.0, 900.0)),
            hold=float(rng.uniform(1200.0, 2400.0)),
        )
    return out


def pi_reheat(integral: float, error: float, kp: float, ti: float, span: float) -> tuple[float, float]:
    """One step of the reheat PI (positional form, clamping anti-windup); returns ``(reheat, integral)``.

    ``reheat`` (K above the AHU supply) is limited to ``[0, span]``; at a limit the integral is
    frozen while the error would drive it further into saturation.
    """
    integ = integral + CONTROL_DT / ti * error
    reheat = kp * (error + integ)
    if reheat > span:
        reheat = span
        integ = integral if error > 0 else integ
    elif reheat < 0.0:
        reheat = 0.0
        integ = integral if error < 0 else integ
    return reheat, integ


def coil_lag(ts: float | None, command: float, tau: float) -> float:
    """The reheat coil's first-order lag over one control interval (starts at ``command``)."""
    if ts is None:
        return command
    return ts + (1.0 - math.exp(-CONTROL_DT / tau)) * (command - ts)


class VAVController:
    """Run-time state of one VAV box (created per simulation, never shared).

    Call :meth:`step` once per control interval with the time (s from 6 pm), the sensed
    zone temperature and the current AHU supply temperature; it returns the flow and the
    discharge temperature held over the next interval.
    """

    def __init__(self, config: ControllerConfig, t_start: float) -> None:
        self.cfg = config
        self.level = 0
        self.last_change = t_start - config.hold
        self.integral = 0.0
        self.ts = None  # discharge temperature (coil output), degC
        self.command: float | None = None  # discharge set point (coil input), degC

    def _mode(self, t: float) -> bool:
        return self.cfg.unoccupied(t)

    def step(self, t: float, t_sensed: float, t_ahu: float) -> tuple[float, float]:
        """Advance one control interval; returns ``(m, Ts)`` in kg/s and degC."""
        c = self.cfg
        unocc = self._mode(t)
        heat_sp = c.heat_unocc if unocc else c.heat_occ
        cool_sp = c.cool_unocc if unocc else c.cool_occ
        min_level = 0 if unocc else 1
        # Flow staging with hysteresis and minimum hold.
        level = max(self.level, min_level)
        if t - self.last_change >= c.hold:
            e = t_sensed - cool_sp
            if e > c.band_up and level < len(FLOW_LEVELS) - 1:
                level += 1
            elif e < -c.band_down and level > min_level:
                level -= 1
        if level != self.level:
            self.level = level
            self.last_change = t
        reheat, self.integral = pi_reheat(self.integral, heat_sp - t_sensed, c.kp, c.ti, c.ts_max - t_ahu)
        self.command = t_ahu + reheat  # the coil's set point (what a plant with its own coil takes)
        self.ts = coil_lag(self.ts, self.command, c.tau_coil)
        return FLOW_LEVELS[self.level], self.ts


class TightController:
    """A constant-flow box whose fast PI loop on the discharge temperature pins the room to one setpoint.

    The setpoint is the middle of the mode's band (occupied or unoccupied, as
    :class:`VAVController`); the discharge temperature spans the AHU supply temperature to
    ``ts_max`` through the same coil lag. With ``kp`` = 10 K per K and ``ti`` = 10 min the room
    stays within about 0.1 K of the setpoint while ``Ts`` swings by several K.
    """

    def __init__(self, config: ControllerConfig, flow: float, kp: float = 10.0, ti: float = 600.0) -> None:
        self.cfg = config
        self.flow = flow
        self.kp = kp
        self.ti = ti
        self.integral: float | None = None
        self.ts: float | None = None

    def step(self, t: float, t_sensed: float, t_ahu: float) -> tuple[float, float]:
        """Advance one control interval; returns ``(m, Ts)`` in kg/s and degC."""
        c = self.cfg
        unocc = c.unoccupied(t)
        sp = 0.5 * (c.heat_unocc + c.cool_unocc) if unocc else 0.5 * (c.heat_occ + c.cool_occ)
        span = c.ts_max - t_ahu
        if self.integral is None:  # bumpless start at mid-span
            self.integral = 0.5 * span / self.kp
        reheat, self.integral = pi_reheat(self.integral, sp - t_sensed, self.kp, self.ti, span)
        self.ts = coil_lag(self.ts, t_ahu + reheat, c.tau_coil)
        return self.flow, self.ts
