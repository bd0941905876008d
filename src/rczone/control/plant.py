"""What a controller sees of a building, and what a building asks of a controller: two small protocols.

The shape is BOPTEST's [1]_: a test case (here a :class:`Plant`) is advanced one step at a time
with the actuator values a controller chose, returns what a building-management system would
read, gives forecasts of the boundary conditions and of the comfort band, price and limits, and
scores the run from its own meters. A controller (:class:`Controller`) sees nothing else. Any
emulator (the virtual building, :class:`~rczone.control.virtualplant.VirtualPlant`; an
EnergyPlus model; a real building's BMS) implements :class:`Plant`; any controller (the zone's
thermostat, the reference MPC, a user's) implements :class:`Controller`, and
:func:`~rczone.control.closedloop.closed_loop_test` runs one against the other.

Names (all values SI: s, degC, kg/s, W; one float per name):

* **measurements** (:meth:`Plant.measure`, :meth:`Plant.step`): ``time`` (s), ``To`` (outdoor),
  ``T_ahu`` (the air-handling unit's supply temperature), and per zone its sensed air temperature
  ``Ti_<zone>``, metered supply flow ``m_<zone>`` and discharge temperature ``Ts_<zone>`` (over
  the last step; NaN before the first);
* **actions** (:meth:`Controller.act`): per controlled zone ``m_<zone>`` (supply flow, kg/s) and
  ``Ts_<zone>`` (discharge-temperature set point, degC: the zone's reheat coil heats the AHU's air
  towards it, with its own lag; it cannot cool below ``T_ahu`` nor heat above the coil's limit);
* **forecasts** (:meth:`Plant.forecast`): ``time``, ``To``, ``T_ahu``, ``price`` (per kWh), and
  per controlled zone ``lower_<zone>``, ``upper_<zone>`` (comfort band, degC), ``occupied_<zone>``
  (1 or 0), and the limits of :meth:`Plant.constraints`; one value per ``interval`` from now,
  ``horizon / interval + 1`` values;
* **constraints** (:meth:`Plant.constraints`): per controlled zone ``m_min_<zone>``,
  ``m_max_<zone>`` (kg/s; the ventilation minimum follows the occupancy schedule) and
  ``ts_max_<zone>`` (degC), one value per control interval from now: the tightest over the
  interval. Every controller is held to them; a run counts the samples outside them.
* **KPIs** (:meth:`Plant.kpis`): scored on the plant's own (true) temperatures and meters over
  the scored part of the run: ``comfort_Kh``, ``energy_kWh`` (and ``reheat_kWh``, ``cooling_kWh``,
  ``fan_kWh``), ``cost``, ``peak_flow_kg_s``, ``max_discharge_degC``, ``constraint_violations``.

References
----------
.. [1] D. Blum, J. Arroyo, S. Huang, J. Drgoňa, F. Jorissen, H. T. Walnum, Y. Chen, K. Benne,
   D. Vrabie, M. Wetter, L. Helsen, "Building optimization testing framework (BOPTEST) for
   simulation-based benchmarking of control strategies in buildings", Journal of Building
   Performance Simulation 14(5) (2021) 586-610.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol, runtime_checkable

import numpy as np

from rczone.errors import ParameterError


@runtime_checkable
class Plant(Protocol):
    """A building (or one zone of it) advanced step by step by a controller (see the module notes).

    Attributes
    ----------
    dt : float
        The plant's step, s: :meth:`step` holds the actions this long.
    zones : tuple of str
        The zones a controller runs (``m_<zone>``, ``Ts_<zone>`` in its actions); every other zone
        is run by the plant itself.
    end : float
        Plant time at which the test ends, s.
    """

    dt: float
    zones: tuple[str, ...]
    end: float

    def describe(self) -> Mapping[str, object]:
        """The test's settings as plain values, the zones' limits under ``constraints`` included.

        A result records it; two runs are compared only when these agree.

        Returns
        -------
        mapping of str to object
        """
        ...

    def measure(self) -> Mapping[str, float]:
        """What the BMS reads now (``time`` included), without advancing.

        Returns
        -------
        mapping of str to float
        """
        ...

    def step(self, actions: Mapping[str, float]) -> Mapping[str, float]:
        """Hold ``actions`` for :attr:`dt` and return the measurements at the end of the step.

        Parameters
        ----------
        actions : mapping of str to float
            ``m_<zone>`` and ``Ts_<zone>`` for every zone of :attr:`zones`.

        Returns
        -------
        mapping of str to float
            As :meth:`measure`.
        """
        ...

    def forecast(self, horizon: float, *, interval: float | None = None) -> Mapping[str, np.ndarray]:
        """Forecasts from now over ``horizon`` s, one value per ``interval`` s (default :attr:`dt`).

        Parameters
        ----------
        horizon : float
            s (0: now only).
        interval : float, optional
            s.

        Returns
        -------
        mapping of str to ndarray
            Each of shape ``(round(horizon / interval) + 1,)``; the constraints one shorter (one
            per interval).
        """
        ...

    def constraints(self, horizon: float, *, interval: float | None = None) -> Mapping[str, np.ndarray]:
        """The limits per control interval from now over ``horizon`` s (the tightest in each).

        Parameters
        ----------
        horizon : float
            s.
        interval : float, optional
            s (default :attr:`dt`).

        Returns
        -------
        mapping of str to ndarray
            ``m_min_<zone>``, ``m_max_<zone>``, ``ts_max_<zone>``, each of shape
            ``(max(1, round(horizon / interval)),)``.
        """
        ...

    def kpis(self) -> Mapping[str, float]:
        """The scores of the run so far, from the plant's own meters (see the module notes).

        Returns
        -------
        mapping of str to float
        """
        ...


@runtime_checkable
class Controller(Protocol):
    """Chooses the actions of a :class:`Plant`'s zones from its measurements and forecasts.

    :meth:`act` is called once per plant step; a controller that decides less often (an MPC every
    10 min) holds its last decision in between.

    Attributes
    ----------
    horizon : float
        How far ahead it wants the plant's forecast, s (0: only the present values).
    interval : float
        The forecast's spacing it wants, s.
    """

    horizon: float
    interval: float

    def act(
        self, t: float, measurements: Mapping[str, float], forecast: Mapping[str, np.ndarray]
    ) -> Mapping[str, float]:
        """The actions to hold over the next plant step.

        Parameters
        ----------
        t : float
            Plant time, s.
        measurements : mapping of str to float
            :meth:`Plant.measure` now.
        forecast : mapping of str to ndarray
            :meth:`Plant.forecast` now, over :attr:`horizon` at :attr:`interval`.

        Returns
        -------
        mapping of str to float
            ``m_<zone>`` and ``Ts_<zone>`` per zone of the plant.
        """
        ...


def forecast_times(
    now: float, step: float, horizon: float, interval: float | None
) -> tuple[np.ndarray, float]:
    """The times of a forecast from ``now`` over ``horizon`` s, and its interval (default ``step``).

    Raises
    ------
    ParameterError
        For a negative or non-finite horizon, or an interval that is not a positive number.
    """
    iv = step if interval is None else float(interval)
    if not (np.isfinite(horizon) and horizon >= 0 and np.isfinite(iv) and iv > 0):
        raise ParameterError(
            f"a forecast needs horizon >= 0 and interval > 0 s, got {horizon!r}, {interval!r}"
        )
    return now + iv * np.arange(round(horizon / iv) + 1), iv


def forecast_steps(horizon: float, interval: float) -> int:
    """The number of intervals in ``horizon`` (at least one): the length of a constraint array."""
    return max(1, round(horizon / interval))
