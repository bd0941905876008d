"""Closed-loop tests on EnergyPlus: a controller by name, run on zones of a prototype, scored.

:func:`energyplus_test` makes an :class:`~rczone.emulators.plant.EnergyPlusPlant`, the controller
(``baseline``: the building's own control, :class:`~rczone.emulators.supervisory.BuildingControl`;
``mpc``: :class:`~rczone.emulators.supervisory.SupervisoryMPC` with the given model, its heating
and cooling capacity :data:`CAPACITY_W_PER_M2` times the zone's floor area unless set, and for
several zones one per zone with that zone's model,
:class:`~rczone.emulators.supervisory.ZoneMPCs`, or with one joint model of them all the
centralized :class:`~rczone.emulators.floormpc.FloorMPC`, each zone's capacity its own floor
area's; any other name from
:mod:`rczone.control.registry`, e.g. a plug-in), runs
:func:`~rczone.control.closedloop.closed_loop_test` and closes EnergyPlus whatever happens.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

from rczone.control.closedloop import ClosedLoopResult, closed_loop_test
from rczone.control.prediction import SENSOR_RESOLUTION_K
from rczone.control.registry import ControllerOptions, make_controller
from rczone.emulators.floormpc import FloorMPC
from rczone.emulators.plant import EnergyPlusPlant
from rczone.emulators.supervisory import BuildingControl, SupervisoryMPC, SupervisorySettings, ZoneMPCs
from rczone.errors import ParameterError
from rczone.models.zone import ZoneModel

#: Heating and cooling capacity the supervisory MPC assumes, W per m2 of the zone's floor.
CAPACITY_W_PER_M2 = 60.0


def models_by_zone(model: ZoneModel | Mapping[str, ZoneModel] | None, zones: Sequence[str]):
    """``{zone: model}`` for the plant's zones: one model for one zone, or a mapping naming every zone."""
    if model is None:
        return None
    if isinstance(model, ZoneModel):
        if len(zones) != 1:
            raise ParameterError(
                f"{len(zones)} zones need a model each (--zones ZONE=MODEL,...), got one model for all"
            )
        return {zones[0]: model}
    missing = [z for z in zones if z not in model]
    extra = [z for z in model if z not in zones]
    if missing or extra:
        raise ParameterError(
            f"the models must name the controlled zones {list(zones)}: "
            + (f"no model for {missing}" if missing else f"models for zones not controlled: {extra}")
        )
    return {z: model[z] for z in zones}


def _settings_for(plant: EnergyPlusPlant, zone: str, settings: SupervisorySettings | None, margin_K):
    """The zone's MPC settings: ``settings`` or the defaults at its floor area's capacity; ``margin_K`` if given."""
    if settings is None:
        if zone not in plant.floor_area:
            plant.measure()  # starts EnergyPlus: the zones' floor areas are read from its eio
        cap = CAPACITY_W_PER_M2 * plant.floor_area[zone]
        settings = replace(SupervisorySettings(), heating_capacity=cap, cooling_capacity=cap)
    return settings if margin_K is None else replace(settings, margin_K=margin_K)


def joint(model: ZoneModel | Mapping[str, ZoneModel] | None, zones: Sequence[str]) -> bool:
    """Whether ``model`` is one joint model of several zones (``--zones A,B --model floor.json``)."""
    return isinstance(model, ZoneModel) and len(zones) > 1


def _floor_mpc(plant: EnergyPlusPlant, model: ZoneModel, settings, margin_K) -> FloorMPC:
    """The floor MPC of the plant's zones, each zone's settings as its own supervisory MPC's."""
    # the model checked before the zones' floor areas start EnergyPlus: a bad one is refused at once
    FloorMPC(model, zones=plant.zones, dt=plant.dt, measured=plant.zone_names)
    per_zone = {z: _settings_for(plant, z, settings, margin_K) for z in plant.zones}
    return FloorMPC(model, zones=plant.zones, dt=plant.dt, settings=per_zone, measured=plant.zone_names)


def make_controller_for(
    name: str,
    plant: EnergyPlusPlant,
    model: ZoneModel | Mapping[str, ZoneModel] | None,
    settings: SupervisorySettings | None,
    margin_K: float | None = None,
):  # settings None: the defaults with the capacity of each zone's floor area
    """The controller ``name`` for an EnergyPlus plant (see the module notes)."""
    if name == "baseline":
        return BuildingControl(plant.dt)
    if joint(model, plant.zones):
        if name != "mpc":
            raise ParameterError(
                f"a joint model of {len(plant.zones)} zones runs under --controller mpc or baseline, not {name!r}"
            )
        return _floor_mpc(plant, model, settings, margin_K)
    models = models_by_zone(model, plant.zones)
    if name == "mpc":
        if models is None:
            raise ParameterError("the mpc controller needs a model (--model zone.json)")
        mpcs = [
            SupervisoryMPC(
                models[z], zone=z, dt=plant.dt, settings=_settings_for(plant, z, settings, margin_K)
            )
            for z in plant.zones
        ]
        return mpcs[0] if len(mpcs) == 1 else ZoneMPCs(mpcs)
    if models is not None and len(models) > 1:
        raise ParameterError(f"the {name!r} controller runs one zone; give one --zone")
    return make_controller(name, plant, ControllerOptions(next(iter(models.values())) if models else None))


def energyplus_test(
    plant: EnergyPlusPlant,
    controller: str,
    *,
    model: ZoneModel | Mapping[str, ZoneModel] | None = None,
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
    model : ZoneModel or mapping of zone to ZoneModel, optional
        The MPC's model (one per zone when the plant has several, or one joint model of them all:
        the floor MPC); also the model whose prediction error is scored, per zone (a joint model
        predicting all its zones together, :func:`rczone.emulators.prediction.joint_prediction_scores`).
    settings : SupervisorySettings, optional
        The MPC's (every zone's); default :class:`SupervisorySettings` with the capacity of each
        zone's floor area (:data:`CAPACITY_W_PER_M2`).
    margin_K : float, optional
        How far inside the band the MPC aims, K.
    noise_floor : float
        The prediction score's lowest sensor noise, K.

    Returns
    -------
    ClosedLoopResult
    """
    shared = joint(model, plant.zones)
    models = model if shared else models_by_zone(model, plant.zones)
    try:
        ctl = make_controller_for(controller, plant, models, settings, margin_K)
        # a joint model is scored as it predicts, all its zones together, each zone on its output
        scored = dict.fromkeys(plant.zones, model) if shared else models
        res = closed_loop_test(plant, ctl, model=scored, noise_floor=noise_floor)
    finally:
        plant.close()
    setup = {**res.setup, "controller": controller} | ({"model": model.label} if shared else {})
    return ClosedLoopResult(res.scores, setup, res.t, res.series)
