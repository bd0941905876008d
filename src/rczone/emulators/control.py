"""Closed-loop tests on EnergyPlus: a controller by name, run on one zone of a prototype, scored.

:func:`energyplus_test` makes an :class:`~rczone.emulators.plant.EnergyPlusPlant`, the controller
(``baseline``: the building's own control, :class:`~rczone.emulators.supervisory.BuildingControl`;
``mpc``: :class:`~rczone.emulators.supervisory.SupervisoryMPC` with the given model, its heating
and cooling capacity :data:`CAPACITY_W_PER_M2` times the zone's floor area unless set; any other
name from :mod:`rczone.control.registry`, e.g. a plug-in), runs
:func:`~rczone.control.closedloop.closed_loop_test` and closes EnergyPlus whatever happens.
"""

from __future__ import annotations

from dataclasses import replace

from rczone.control.closedloop import ClosedLoopResult, closed_loop_test
from rczone.control.prediction import SENSOR_RESOLUTION_K
from rczone.control.registry import ControllerOptions, make_controller
from rczone.emulators.plant import EnergyPlusPlant
from rczone.emulators.supervisory import BuildingControl, SupervisoryMPC, SupervisorySettings
from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel

#: Heating and cooling capacity the supervisory MPC assumes, W per m2 of the zone's floor.
CAPACITY_W_PER_M2 = 60.0


def make_controller_for(
    name: str, plant: EnergyPlusPlant, model: ZoneModel | None, settings: SupervisorySettings | None
):  # settings None: the defaults with the capacity of the zone's floor area
    """The controller ``name`` for an EnergyPlus plant (see the module notes)."""
    if name == "baseline":
        return BuildingControl(plant.dt)
    if name == "mpc":
        if model is None:
            raise ParameterError("the mpc controller needs a model (--model zone.json)")
        zone = plant.zones[0]
        if settings is None:
            plant.measure()  # starts EnergyPlus: the zone's floor area is read from its eio
            cap = CAPACITY_W_PER_M2 * plant.floor_area[zone]
            settings = replace(SupervisorySettings(), heating_capacity=cap, cooling_capacity=cap)
        return SupervisoryMPC(model, zone=zone, dt=plant.dt, settings=settings)
    return make_controller(name, plant, ControllerOptions(model))


def energyplus_test(
    plant: EnergyPlusPlant,
    controller: str,
    *,
    model: ZoneModel | None = None,
    settings: SupervisorySettings | None = None,
    margin_K: float | None = None,
    noise_floor: float = SENSOR_RESOLUTION_K,
) -> ClosedLoopResult:
    """Run ``controller`` on ``plant`` (fresh) to its end and score it; EnergyPlus is closed after.

    Parameters
    ----------
    plant : EnergyPlusPlant
    controller : str
        ``baseline``, ``mpc`` or a registered controller's name.
    model : ZoneModel, optional
        The MPC's model; also the model whose prediction error is scored.
    settings : SupervisorySettings, optional
        The MPC's; default :class:`SupervisorySettings` with the capacity of the zone's floor
        area (:data:`CAPACITY_W_PER_M2`) and ``margin_K`` if given.
    margin_K : float, optional
        How far inside the band the MPC aims, K.
    noise_floor : float
        The prediction score's lowest sensor noise, K.

    Returns
    -------
    ClosedLoopResult
    """
    try:
        if margin_K is not None and controller == "mpc":
            plant.measure()  # starts EnergyPlus: the zone's floor area is read from its eio
            cap = CAPACITY_W_PER_M2 * plant.floor_area[plant.zones[0]]
            base = settings or SupervisorySettings(heating_capacity=cap, cooling_capacity=cap)
            settings = replace(base, margin_K=margin_K)
        ctl = make_controller_for(controller, plant, model, settings)
        res = closed_loop_test(plant, ctl, model=model, noise_floor=noise_floor)
    finally:
        plant.close()
    setup = {**res.setup, "controller": controller}
    return ClosedLoopResult(res.scores, setup, res.t, res.series)
