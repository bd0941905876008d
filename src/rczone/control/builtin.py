"""The factories of the built-in controllers (names in :mod:`rczone.control.registry`)."""

from __future__ import annotations

from rczone.control.controllers import (
    CommissionedThermostat,
    MPCController,
    OracleController,
    ThermostatController,
)
from rczone.control.disturbance import Disturbance
from rczone.control.heating import HeaterMPCController, HeaterThermostat, heat_limits
from rczone.control.mpc import MPC
from rczone.control.plant import Controller, Plant
from rczone.control.registry import ControllerOptions
from rczone.errors import ParameterError


def _configs(plant: Plant, name: str) -> dict:
    configs = getattr(plant, "configs", None)
    if configs is None:
        raise ParameterError(
            f"the {name} controller needs the plant's thermostat settings (a VirtualPlant's configs); "
            f"{type(plant).__name__} has none"
        )
    return configs


def naive(plant: Plant, options: ControllerOptions) -> Controller:
    """The zone's thermostat on its schedule's set points (the building's own, before issue 33)."""
    zone = plant.zones[0]
    cfg = _configs(plant, "naive")[zone]
    return ThermostatController(cfg, zone=zone, t_start=plant.measure()["time"], dt=plant.dt)


def _heated(plant: Plant) -> bool:
    """Whether the plant's zone is heated by a power it is told (``heat_max_<zone>`` among its limits)."""
    return f"heat_max_{plant.zones[0]}" in plant.constraints(plant.dt, interval=plant.dt)


def thermostat(plant: Plant, options: ControllerOptions) -> Controller:
    """The zone's thermostat as commissioned: set points inside the band, optimal start (the fair baseline).

    A heated zone's is a PI loop on its heater, held to the heater's limits
    (:class:`rczone.control.heating.HeaterThermostat`).
    """
    zone = plant.zones[0]
    if _heated(plant):
        return HeaterThermostat(zone=zone, limits=heat_limits(plant, zone), dt=plant.dt)
    cfg = _configs(plant, "thermostat")[zone]
    return CommissionedThermostat(cfg, zone=zone, t_start=plant.measure()["time"], dt=plant.dt)


def mpc(plant: Plant, options: ControllerOptions) -> Controller:
    """The reference MPC with ``options.model`` (an integrating heat disturbance unless told not to).

    In a heated zone it decides the model's heater input within the plant's heater limits
    (:class:`rczone.control.heating.HeaterMPCController`).
    """
    if options.model is None:
        raise ParameterError("the mpc controller needs a model (--model, or model= in the API)")
    dist = Disturbance("heat") if options.disturbance else None
    if _heated(plant):
        zone = plant.zones[0]
        return HeaterMPCController(
            options.model, options.settings, limits=heat_limits(plant, zone), zone=zone, disturbance=dist
        )
    return MPCController(MPC(options.model, options.settings, disturbance=dist), zone=plant.zones[0])


#: The oracle's model: the reduced 2-state model of the true construction (fast enough per step).
ORACLE_MODEL = "second-order"


def oracle(plant: Plant, options: ControllerOptions) -> Controller:
    """The MPC with the true construction's model, true temperature, forecast and gains."""
    from rczone.models.paper import paper_model

    bld = getattr(plant, "bld", None)
    if bld is None or not hasattr(plant, "true_forecast"):
        raise ParameterError(
            f"the oracle needs the plant's truth (a VirtualPlant); {type(plant).__name__} has none"
        )
    model = paper_model(ORACLE_MODEL, geometry=bld.target)
    dist = Disturbance("heat") if options.disturbance else None
    return OracleController(MPC(model, options.settings, disturbance=dist), plant, zone=plant.zones[0])


FACTORIES = {"naive": naive, "thermostat": thermostat, "mpc": mpc, "oracle": oracle}
