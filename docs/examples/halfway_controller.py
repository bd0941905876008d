"""A controller in one file: the ventilation minimum the plant states, reheat towards the band's middle.

Install it as a package that declares the entry point::

    [project.entry-points."rczone.controllers"]
    halfway = "halfway_controller:factory"

and run ``rczone control-test --controller halfway`` (or ``closed_loop_test(plant, "halfway")``),
or register it in Python with ``rczone.register_controller("halfway", factory)``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

#: Discharge temperature above the air-handler's per kelvin the zone is below the band's middle.
GAIN_K_PER_K = 8.0


class HalfwayController:
    """A proportional reheat rule held to the plant's own flow limits.

    Parameters
    ----------
    plant : rczone.control.plant.Plant
        The plant: its step (``dt``) and the zones it lets a controller run.
    """

    horizon = 0.0  # s of forecast it wants: the present values only

    def __init__(self, plant) -> None:
        self.interval = plant.dt
        self.zones = tuple(plant.zones)

    def act(
        self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]
    ) -> dict[str, float]:
        """The actions for the next step: per zone ``m_<zone>`` (kg/s) and ``Ts_<zone>`` (degC)."""
        actions = {}
        for z in self.zones:
            middle = 0.5 * (forecast[f"lower_{z}"][0] + forecast[f"upper_{z}"][0])
            below = max(0.0, middle - measurements[f"Ti_{z}"])
            actions[f"m_{z}"] = float(forecast[f"m_min_{z}"][0])  # the ventilation minimum now
            actions[f"Ts_{z}"] = float(measurements["T_ahu"] + GAIN_K_PER_K * below)
        return actions


def factory(plant, options):
    """``factory(plant, options) -> Controller``: what ``register_controller`` and the entry point name."""
    return HalfwayController(plant)
