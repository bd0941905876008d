"""The limits a zone's controller is held to: a ventilation minimum that follows the schedule, and caps.

A VAV zone must get its ventilation air whenever it is occupied: ASHRAE Guideline 36 [1]_
(section 5.6.3) sets the terminal unit's occupied minimum flow from the ventilation rate
(ASHRAE Standard 62.1 [2]_) and lets it fall to a lower (here: the box's lowest) flow when the
zone is unoccupied. These limits belong to the zone, not to a controller: every controller
that runs the zone (its thermostat, an MPC, a user's) gets the same :class:`ZoneConstraints`
and is held to them, so that energy figures of two controllers compare like with like.

For the virtual building's zones (:func:`ZoneConstraints.from_config`) the occupied minimum is
the thermostat's second flow level ``FLOW_LEVELS[1]`` (0.05 kg/s), the unoccupied one its first
(0.02 kg/s), the maximum its top level (0.12 kg/s) and the discharge-temperature cap its
``ts_max`` (35 degC), on the thermostat's own occupancy schedule.

:meth:`ZoneConstraints.steps` gives the bounds per control step of a controller acting every
``dt`` s: the tightest value over each step's interval at the plant's own sample times, so a
controller that holds its action over the step meets the constraint at every plant step.

References
----------
.. [1] ASHRAE Guideline 36-2018, *High-performance sequences of operation for HVAC systems*,
   section 5.6 (VAV terminal unit with reheat: occupied and unoccupied minimum flows).
.. [2] ANSI/ASHRAE Standard 62.1-2019, *Ventilation for acceptable indoor air quality*,
   section 6.2 (ventilation rate procedure).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

import numpy as np

from rczone.errors import ParameterError
from rczone.virtual.control import CONTROL_DT, FLOW_LEVELS, ControllerConfig


class StepBounds(NamedTuple):
    """Bounds per control step (each of shape (n,)): flow ``m_min``, ``m_max`` (kg/s) and the
    highest discharge temperature ``ts_max`` (degC)."""

    m_min: np.ndarray
    m_max: np.ndarray
    ts_max: np.ndarray


@dataclass(frozen=True)
class ZoneConstraints:
    """A zone's time-varying limits (SI; times in s from 6 pm, see the module notes).

    Parameters
    ----------
    flow_min_occupied, flow_min_unoccupied : float
        Ventilation minimum of the supply flow in occupied and unoccupied mode, kg/s.
    flow_max : float
        Largest supply flow, kg/s.
    ts_max : float
        Highest discharge temperature, degC.
    unocc_start, unocc_end : float
        Unoccupied mode from ``unocc_start`` to ``unocc_end``, s from 6 pm (within each period).
    period : float or None
        The schedule repeats every ``period`` s; ``None``: once.
    """

    flow_min_occupied: float
    flow_min_unoccupied: float
    flow_max: float
    ts_max: float
    unocc_start: float
    unocc_end: float
    period: float | None = None

    def __post_init__(self) -> None:
        for k, v in asdict(self).items():
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ParameterError(f"zone constraint {k} must be a finite number, got {v!r}")
        if (
            not 0 < self.flow_min_unoccupied <= self.flow_max
            or not 0 < self.flow_min_occupied <= self.flow_max
        ):
            raise ParameterError(
                "zone constraints need 0 < flow minimum <= flow_max, got "
                f"{self.flow_min_occupied!r} / {self.flow_min_unoccupied!r} and {self.flow_max!r} kg/s"
            )

    @classmethod
    def from_config(cls, cfg: ControllerConfig) -> ZoneConstraints:
        """The constraints of a virtual-building zone run by thermostat settings ``cfg``."""
        return cls(
            flow_min_occupied=FLOW_LEVELS[1],
            flow_min_unoccupied=FLOW_LEVELS[0],
            flow_max=FLOW_LEVELS[-1],
            ts_max=cfg.ts_max,
            unocc_start=cfg.unocc_start,
            unocc_end=cfg.unocc_end,
            period=cfg.period,
        )

    def occupied(self, t: np.ndarray) -> np.ndarray:
        """Whether the zone is in occupied mode at ``t`` (s from 6 pm), boolean of ``t``'s shape."""
        t = np.asarray(t, float)
        tm = np.mod(t, self.period) if self.period else t
        return ~((tm >= self.unocc_start) & (tm < self.unocc_end))

    def flow_min(self, t: np.ndarray) -> np.ndarray:
        """The ventilation minimum at ``t`` (s from 6 pm), kg/s."""
        return np.where(self.occupied(t), self.flow_min_occupied, self.flow_min_unoccupied)

    def steps(self, t0: float, dt: float, n: int, *, sample: float = CONTROL_DT) -> StepBounds:
        """Bounds of ``n`` control steps of ``dt`` s from ``t0``: the tightest over each interval.

        ``sample`` is the plant's own step (s): the ventilation minimum is taken at every plant
        step inside ``[t0 + k dt, t0 + (k + 1) dt)``, and the largest of them bounds step ``k``.
        """
        per = max(1, round(dt / sample))
        t = t0 + dt * np.arange(n)[:, None] + sample * np.arange(per)[None, :]
        return StepBounds(self.flow_min(t).max(axis=1), np.full(n, self.flow_max), np.full(n, self.ts_max))

    def violations(self, t: np.ndarray, m: np.ndarray, ts: np.ndarray, *, tol: float = 1e-9) -> int:
        """The number of samples (flow ``m`` and discharge ``ts`` held from ``t``) outside the limits."""
        t, m, ts = (np.asarray(v, float) for v in (t, m, ts))
        bad = (m < self.flow_min(t) - tol) | (m > self.flow_max + tol) | (ts > self.ts_max + 1e-6)
        return int(bad.sum())

    def to_dict(self) -> dict[str, Any]:
        """The constraints as plain values (what a result's JSON records)."""
        return asdict(self)
