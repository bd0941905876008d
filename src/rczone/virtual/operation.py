"""How a closed-loop night is operated and logged: the features of real operation as options.

The paper (section IV) finds that a reduced model fitted to closed-loop night data returns a wall
resistance an order of magnitude below the forced-response fit while still matching the data.
Which features of real operation produce that is a question the virtual building can answer by
switching them on one at a time. :class:`Operation` collects them; its defaults are exactly the
operation of the shipped nights A, B, C (the data files do not change):

``loop``
    ``"staged"`` (default): the single-maximum VAV sequence of :mod:`rczone.virtual.control`
    (staged flow with a 20-40 min hold, reheat PI on the heating setpoint, a wide night band in
    which the room floats). ``"tight"``: every zone's box holds a constant flow
    (:data:`TIGHT_FLOW`) and a fast PI loop on the discharge temperature keeps the room at one
    setpoint (the middle of the mode's band): the room barely moves while ``Ts`` swings, as in
    a constant-volume reheat zone or a well-tuned dual-maximum box.
``deadband_K``
    Width of the night (unoccupied) band between heating and cooling setpoints, K, centred on
    the season's band; ``None`` keeps the season's (3.5-4 K). Staged loop only.
``gains``
    ``"constant"`` (default): the night gains of :data:`rczone.virtual.building.INTERNAL_GAIN`.
    ``"schedule"``: every zone also has :data:`SCHEDULE_GAIN` W more while its schedule is in
    occupied mode (lights, cleaning crew, equipment left on until the evening switch and back on
    before the morning start). The data still report the paper's ``Q = 50 W``: the extra gain is
    unmeasured, and it changes exactly when the setpoints change.
``sensor``
    ``"room"`` (default): the thermostat reads the room air. ``"diffuser"``: it hangs in the
    supply jet and reads ``Ti + diffuser_mix * (m / m_max) * (Ts - Ti)`` (``diffuser_mix``
    default :data:`DIFFUSER_MIX`; ``m_max`` = 0.12 kg/s). The target's logged
    ``Ti`` and every controller use that reading.
``trend_quantum_F``
    Resolution of the logged temperatures, F (default 0.1 F; BMS trend logs with 0.5 F or 1 F
    resolution are common).

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, IEEE CDC 2012, section IV-B.
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., 1999, section 13.4
   (identification in closed loop: an input correlated with the unmeasured disturbance biases
   the estimate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rczone.errors import ParameterError, did_you_mean
from rczone.virtual.control import FLOW_LEVELS
from rczone.virtual.sensors import TEMP_QUANT_F

#: Loop options.
LOOPS = ("staged", "tight")
#: Internal-gain options.
GAINS = ("constant", "schedule")
#: Sensor placement options.
SENSORS = ("room", "diffuser")
#: Constant flow of every box in the tight loop, kg/s.
TIGHT_FLOW = 0.08
#: Unmeasured gain added in occupied mode with ``gains="schedule"``, W per zone.
SCHEDULE_GAIN = 300.0
#: Share of supply air in the diffuser-mounted sensor's reading at full flow.
DIFFUSER_MIX = 0.15


def _check(value: str, options: tuple[str, ...], what: str) -> None:
    if value not in options:
        raise ParameterError(f"unknown {what} {value!r}; " + did_you_mean(value, options))


@dataclass(frozen=True)
class Operation:
    """Options of a closed-loop night (see the module docstring); defaults are today's nights."""

    loop: str = "staged"
    deadband_K: float | None = None
    gains: str = "constant"
    sensor: str = "room"
    trend_quantum_F: float = TEMP_QUANT_F
    diffuser_mix: float = DIFFUSER_MIX

    def __post_init__(self) -> None:
        _check(self.loop, LOOPS, "loop")
        _check(self.gains, GAINS, "gains option")
        _check(self.sensor, SENSORS, "sensor option")
        if self.deadband_K is not None and not (np.isfinite(self.deadband_K) and self.deadband_K > 0):
            raise ParameterError(f"deadband_K must be > 0 K or None, got {self.deadband_K!r}")
        if not (np.isfinite(self.diffuser_mix) and 0 <= self.diffuser_mix < 1):
            raise ParameterError(f"diffuser_mix must be in [0, 1), got {self.diffuser_mix!r}")
        if not (np.isfinite(self.trend_quantum_F) and self.trend_quantum_F > 0):
            raise ParameterError(f"trend_quantum_F must be > 0 F, got {self.trend_quantum_F!r}")

    @property
    def is_default(self) -> bool:
        """True for the operation of the shipped nights."""
        return self == Operation()

    def label(self) -> str:
        """Short text naming the options that differ from the default."""
        d = Operation()
        parts = [
            f"{k}={getattr(self, k)}"
            for k in ("loop", "deadband_K", "gains", "sensor", "trend_quantum_F", "diffuser_mix")
            if getattr(self, k) != getattr(d, k)
        ]
        return ", ".join(parts) or "as shipped"


def sensor_reading(
    t_air: np.ndarray, t_supply: np.ndarray, flow: np.ndarray, sensor: str, mix: float = DIFFUSER_MIX
) -> np.ndarray:
    """What a thermostat reads (before noise and quantization), degC.

    Parameters
    ----------
    t_air : ndarray
        Room air temperature, degC.
    t_supply, flow : ndarray
        Discharge temperature (degC) and flow (kg/s) of the box over the last interval.
    sensor : {"room", "diffuser"}
    mix : float
        Share of supply air in a diffuser-mounted sensor's reading at full flow.
    """
    if sensor == "room":
        return np.asarray(t_air, dtype=float)
    share = mix * np.asarray(flow, dtype=float) / FLOW_LEVELS[-1]
    return t_air + share * (np.asarray(t_supply, dtype=float) - t_air)
