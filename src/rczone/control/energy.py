"""How the energy of a VAV zone is counted: fan, reheat coil and the AHU's cooling coil.

One zone of a VAV system with reheat (Lin et al. 2012, section II) receives ``m`` kg/s of air
that the air-handling unit (AHU) delivers at ``T_ahu`` and the zone's reheat coil warms to the
discharge temperature ``Ts``. Per zone, in W:

* **reheat** ``m cp (Ts - T_ahu)``, the reheat coil's thermal power;
* **cooling** ``m cp max(min(Ti, To) - T_ahu, 0)``: the AHU's cooling coil brings the cooler of
  the return air (at the room temperature) and the outdoor air (an economizer) down to
  ``T_ahu``; nothing when outdoor air is at least as cold as the supply;
* **fan** ``SFP m / rho``, a specific fan power (W per m3/s) times the zone's volume flow
  (EN 16798-3 gives SFP classes; 1500 W/(m3/s) is class SFP 3 — a linear share of the fan's
  power per zone, not the affinity law of one fan).

Energies are the sum of the three (thermal coil loads and the fan's electricity, without
COPs or efficiencies): this is the quantity the reference MPC minimizes and the closed-loop
test reports as ``energy_kWh``.

References
----------
.. [1] ASHRAE Guideline 36-2018, *High-performance sequences of operation for HVAC systems*,
   section 5.6 (VAV terminal unit with reheat) and 5.16 (economizer).
.. [2] EN 16798-3:2017, *Energy performance of buildings — Ventilation for non-residential
   buildings*, table 9 (specific fan power classes).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rczone.data.units import DEFAULT_AIR_DENSITY
from rczone.network import CP_AIR

#: Specific fan power, W per m3/s of supply air.
SFP = 1500.0
#: Fan power per kg/s of supply air, W s/kg.
FAN_W_PER_KG_S = SFP / DEFAULT_AIR_DENSITY


class ZonePower(NamedTuple):
    """Power per interval, W: reheat coil, cooling coil (the zone's share), fan; arrays of one shape."""

    reheat: np.ndarray
    cooling: np.ndarray
    fan: np.ndarray

    @property
    def total(self) -> np.ndarray:
        return self.reheat + self.cooling + self.fan


def zone_power(m: np.ndarray, ts: np.ndarray, t_ahu: np.ndarray, ti: np.ndarray, to: np.ndarray) -> ZonePower:
    """Reheat, cooling and fan power (W) of one zone (see the module notes); arrays broadcast."""
    m, ts, t_ahu, ti, to = (np.asarray(v, float) for v in (m, ts, t_ahu, ti, to))
    return ZonePower(
        m * CP_AIR * np.maximum(ts - t_ahu, 0.0),
        m * CP_AIR * np.maximum(np.minimum(ti, to) - t_ahu, 0.0),
        m * FAN_W_PER_KG_S,
    )
