"""The rczone virtual building: a simulated multi-zone office floor standing in for the paper's data.

Modules: :mod:`~rczone.virtual.walls` (fine RC walls from construction layers),
:mod:`~rczone.virtual.building` (the floor as one RC network, true construction),
:mod:`~rczone.virtual.control` (VAV thermostats), :mod:`~rczone.virtual.weather`
(outdoor temperature), :mod:`~rczone.virtual.sensors` (BMS sensors),
:mod:`~rczone.virtual.emulator` (exact closed-loop simulation),
:mod:`~rczone.virtual.scenarios` (the data sets A, B, C and :func:`generate_night`),
:mod:`~rczone.virtual.multizone` (several zones forced at once, for joint multi-zone fits) and
:mod:`~rczone.virtual.playback` (a designed test schedule played in the building).
"""

from rczone.virtual.building import VirtualBuilding, build_building, true_geometry
from rczone.virtual.multizone import generate_multizone_night
from rczone.virtual.scenarios import SCENARIOS, generate_night, scenario

__all__ = [
    "SCENARIOS",
    "VirtualBuilding",
    "build_building",
    "generate_multizone_night",
    "generate_night",
    "scenario",
    "true_geometry",
]
