"""A forced-response test in EnergyPlus: the zone thermostat driven by a pseudo-random sequence.

What EnergyPlus honours was measured on the medium office (VAV with reheat, docs/energyplus.md):
the ``Zone Temperature Control`` actuators (heating and cooling set points of a zone) are
followed by the terminal, which swings from its minimum flow with full reheat to its cooling
flow at the AHU's supply temperature; the ``System Node Setpoint`` actuators on the terminal's
outlet node (``Mass Flow Rate Maximum/Minimum Available Setpoint``) are not: the terminal sets
its own outlet flow every iteration, and the flow stayed at its minimum whatever was asked. The
test therefore acts on the set points, as a supervisory BMS would: each driven zone follows a
pseudo-random binary sequence between a low and a high set point (Bacher & Madsen's PRBS
experiments [1]_), each level held a whole number of :data:`HOLD_S` periods, drawn from the seed,
with a dead band of :data:`DEADBAND` K between the heating and cooling set points. The supply
flow and temperature that result are what the BMS logs, and what a fit uses.

References
----------
.. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522, section 2 (PRBS heat inputs).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rczone.emulators.energyplus import Actuator, Emulation, EnergyPlusEmulator
from rczone.errors import ParameterError

#: Low and high set points of the sequence, degC.
LEVELS = (18.0, 25.0)
#: Shortest hold, s, and the most holds a level keeps.
HOLD_S = 3600.0
MAX_HOLDS = 3
#: Cooling set point above the heating set point, K.
DEADBAND = 1.0


def prbs(n_steps: int, step_s: float, rng: np.random.Generator) -> np.ndarray:
    """Levels (0 or 1) of a random binary sequence with holds of 1 to :data:`MAX_HOLDS` hours."""
    per_hold = max(1, round(HOLD_S / step_s))
    out = np.empty(n_steps, dtype=int)
    i, level = 0, int(rng.integers(2))
    while i < n_steps:
        k = per_hold * int(rng.integers(1, MAX_HOLDS + 1))
        out[i : i + k] = level
        i += k
        level = 1 - level
    return out


def _zones(em: EnergyPlusEmulator, zones: str | Sequence[str] | None) -> list[str]:
    conditioned = [z.name for z in em.hvac if z.inlets]
    if zones is None or zones == "":
        return conditioned[:1]
    names = zones.split(",") if isinstance(zones, str) else list(zones)
    out = [em.zone(n.strip()) for n in names]
    for z in out:
        if z not in conditioned:
            raise ParameterError(
                f"zone {z} of {em.building} has no air terminal: a forced test cannot drive it"
            )
    return out


def forced_run(em: EnergyPlusEmulator, zones: str | Sequence[str] | None, *, seed: int) -> Emulation:
    """Run ``em`` with ``zones`` (default: the first conditioned zone) driven by the sequence.

    Each zone draws its own sequence from ``seed``; the set points are in the run's frame as
    ``cmd:<zone> heating`` and ``cmd:<zone> cooling`` (degC).
    """
    driven = _zones(em, zones)
    rng = np.random.default_rng(seed)
    n = round(em.days * 86400.0 / em.step_s) + 1
    levels = {z: prbs(n, em.step_s, rng) for z in driven}
    acts = {}
    for z in driven:
        acts[f"{z} heating"] = Actuator("Zone Temperature Control", "Heating Setpoint", z)
        acts[f"{z} cooling"] = Actuator("Zone Temperature Control", "Cooling Setpoint", z)
    t0 = (em.start.timetuple().tm_yday - 1) * 86400.0

    def controller(t: float, readings) -> dict[str, float]:
        k = min(round((t - t0) / em.step_s), n - 1)
        out = {}
        for z in driven:
            sp = LEVELS[levels[z][k]]
            out[f"{z} heating"], out[f"{z} cooling"] = sp, sp + DEADBAND
        return out

    return em.run(controller, acts)
