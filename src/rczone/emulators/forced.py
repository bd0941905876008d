"""A forced-response test in EnergyPlus: zone thermostats driven by the schedule ``rczone design`` makes.

What EnergyPlus honours was measured on the medium office (VAV with reheat, docs/energyplus.md):
the ``Zone Temperature Control`` actuators (heating and cooling set points of a zone) are
followed by the terminal, which swings from its minimum flow with full reheat to its cooling
flow; the ``System Node Setpoint`` actuators on the terminal's nodes (flow limits, discharge
temperature) are not: the terminal sets its own flow and reheat every HVAC iteration. The test
therefore acts on the set points, as a supervisory BMS would.

The schedule is designed by :func:`rczone.diagnostics.design.design_test` (D-optimal, coordinate
exchange) on the paper's second-order zone model [1]_ closed by its thermostat: the HVAC is a
supply element ``Kt (Tset - Ti)`` (W) with the gain :data:`THERMOSTAT_GAIN` W/K, so that the set
point ``Tset`` is an input a test can drive, between :data:`SETPOINTS`, held at least
:data:`HOLD_S`, with the outdoor temperature at the weather file's mean over the test, the
surroundings at 21 degC and the paper's 50 W gain. Under a thermostat the outdoor resistance
``Rwin`` is not identifiable beside the walls' (the design says so), so the design aims at
:data:`FREE`. Several zones get the same schedule shifted in time
by a share of its length each, so that neighbours are not driven in step.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012, eq. (4).
.. [2] E. Walter, L. Pronzato, *Identification of Parametric Models from Experimental Data*,
   Springer, 1997, ch. 6 (D-optimal design).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rczone.emulators.catalog import outdoor_temperatures
from rczone.emulators.energyplus import Actuator, Emulation, EnergyPlusEmulator
from rczone.errors import ParameterError

#: Low and high set point, degC; the zone's allowed band during the test, degC.
SETPOINTS = (18.0, 25.0)
BAND = (15.0, 28.0)
#: Shortest hold of a set point, s; levels of the design's grid.
HOLD_S = 3600.0
LEVELS = 3
#: Thermostat gain of the design model, W/K; the parameters the design aims at.
THERMOSTAT_GAIN = 300.0
FREE = ("Cr", "Cw", "R1", "R2")
#: Cooling set point above the heating set point, K.
DEADBAND = 1.0
#: Longest forced test, days (rczone.diagnostics.design.MAX_DURATION_S).
MAX_DAYS = 7


def thermostat_model():
    """The paper's second-order zone closed by its thermostat (see the module notes)."""
    from rczone.models.paper import second_order
    from rczone.network import RCNetwork, SupplyAir

    net = second_order()
    return RCNetwork(
        f"{net.name}+thermostat",
        net.nodes,
        net.boundaries,
        net.resistors,
        net.parameters,
        heat_inputs=net.heat_inputs,
        supply_air=[SupplyAir(net.outputs[0], flow="Kt", temperature="Tset", cp=1.0)],
        outputs=net.outputs,
        description="second-order zone under a proportional thermostat Kt (Tset - Ti)",
    )


def design_setpoints(em: EnergyPlusEmulator) -> np.ndarray:
    """The designed set point at every zone time step of ``em``'s run (degC)."""
    from rczone.diagnostics.design import DesignLimits, design_test

    t0 = (em.start.timetuple().tm_yday - 1) * 86400.0
    duration = em.days * 86400.0
    tw, to = outdoor_temperatures(em._epw)
    inside = (tw > t0) & (tw <= t0 + duration)
    res = design_test(
        thermostat_model(),
        FREE,
        duration_s=duration,
        limits=DesignLimits({"Tset": SETPOINTS}, band=BAND, min_hold_s=HOLD_S, levels={"Tset": LEVELS}),
        conditions={"To": float(to[inside].mean()), "Tsd": 21.0, "Q": 50.0, "Kt": THERMOSTAT_GAIN},
    )
    t = em.step_s * np.arange(round(duration / em.step_s) + 1)
    k = np.searchsorted(res.schedule["start_s"].to_numpy(), t, side="right") - 1
    return res.schedule["Tset"].to_numpy()[np.clip(k, 0, len(res.schedule) - 1)]


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


def forced_run(em: EnergyPlusEmulator, zones: str | Sequence[str] | None, progress: Any = None) -> Emulation:
    """Run ``em`` with ``zones`` (default: the first conditioned zone) following the designed set points.

    The set points are in the run's frame as ``cmd:<zone> heating`` and ``cmd:<zone> cooling`` (degC).
    """
    driven = _zones(em, zones)
    if em.days > MAX_DAYS:
        raise ParameterError(
            f"a forced test lasts at most {MAX_DAYS} days (the design's limit); run fewer --days"
        )
    base = design_setpoints(em)
    n = len(base)
    shift = max(1, round(HOLD_S / em.step_s))
    schedules = {z: np.roll(base, i * max(shift, n // len(driven))) for i, z in enumerate(driven)}
    acts = {}
    for z in driven:
        acts[f"{z} heating"] = Actuator("Zone Temperature Control", "Heating Setpoint", z)
        acts[f"{z} cooling"] = Actuator("Zone Temperature Control", "Cooling Setpoint", z)
    t0 = (em.start.timetuple().tm_yday - 1) * 86400.0

    def controller(t: float, readings) -> dict[str, float]:
        k = min(round((t - t0) / em.step_s), n - 1)
        out = {}
        for z in driven:
            out[f"{z} heating"], out[f"{z} cooling"] = schedules[z][k], schedules[z][k] + DEADBAND
        return out

    return em.run(controller, acts, progress=progress)
