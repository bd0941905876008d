"""Emulators: buildings rczone did not write, run as a BMS would see them.

:mod:`~rczone.emulators.energyplus` runs the ASHRAE 90.1-2019 prototype buildings shipped by the
optional extra ``rczone[energyplus]`` (imported only when a run starts);
:mod:`~rczone.emulators.bms` turns a run into a trend export with column maps and a building file;
:mod:`~rczone.emulators.floor` generates the joint model of one floor from that building file.
"""

#: Emulator name -> the module that implements it (imported when used).
EMULATORS = {"energyplus": "rczone.emulators.energyplus"}

__all__ = ["EMULATORS"]
