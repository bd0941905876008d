"""Unit conversion to SI at the data boundary, and plausibility checks after conversion.

Every measured channel is converted once, when it is loaded, to the units used inside
rczone:

=============  =========================================  ==========
quantity       accepted units (aliases in brackets)       SI inside
=============  =========================================  ==========
temperature    degC [C, °C, celsius], degF [F, °F,        degC
               fahrenheit], K [kelvin]
flow           kg/s, m3/s [m^3/s], m3/h [m^3/h], L/s      kg/s
               [l/s], cfm [ft3/min]
power          W, kW, Btu/h [BTU/h]                       W
irradiance     W/m2 [W/m^2], kW/m2 [kW/m^2]               W/m2
=============  =========================================  ==========

Temperatures are kept in degrees Celsius rather than kelvin. The RC equations are affine
in the temperatures (only differences of temperatures and the product m*cp*(Ts - Ti)
appear), so a constant offset between the two scales cancels and the fitted R and C are
the same in degC and K; degC keeps the numbers readable for building engineers.

Volume flows are turned into mass flows with an air density ``rho`` (kg/m3, default
:data:`DEFAULT_AIR_DENSITY` = 1.2, air at about 20 degC and sea level), which the column
map can override. Exact definitions are used: 1 ft = 0.3048 m, 1 Btu_IT/h = 0.29307107 W.

After conversion each channel is checked against a plausible range for its *role*
(:data:`PLAUSIBLE`): a room temperature outside [-30, 60] degC, a negative flow, or a
zone flow above 20 kg/s almost always means a wrong declared unit, so it is an error,
and the message says which other unit would have made the values plausible.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rczone.errors import DataError, did_you_mean

DEFAULT_AIR_DENSITY = 1.2
"""Air density (kg/m3) used to turn volume flows into mass flows unless configured."""

FOOT = 0.3048
"""One international foot in metres (exact)."""

BTU_PER_HOUR = 0.29307107
"""One Btu_IT per hour in watts."""

SI_UNITS = {"temperature": "degC", "flow": "kg/s", "power": "W", "irradiance": "W/m2"}
"""The unit each quantity has inside rczone."""

_ALIASES = {
    "temperature": {
        "degC": ("degc", "c", "°c", "celsius", "deg c", "degrees c"),
        "degF": ("degf", "f", "°f", "fahrenheit", "deg f", "degrees f"),
        "K": ("k", "kelvin"),
    },
    "flow": {
        "kg/s": ("kg/s",),
        "m3/s": ("m3/s", "m^3/s", "m³/s"),
        "m3/h": ("m3/h", "m^3/h", "m³/h"),
        "L/s": ("l/s",),
        "cfm": ("cfm", "ft3/min", "ft^3/min"),
    },
    "power": {
        "W": ("w",),
        "kW": ("kw",),
        "Btu/h": ("btu/h", "btuh", "btu/hr"),
    },
    "irradiance": {
        "W/m2": ("w/m2", "w/m^2", "w/m²"),
        "kW/m2": ("kw/m2", "kw/m^2", "kw/m²"),
    },
}

# Volume-flow units: cubic metres per second per unit.
_VOLUME_M3S = {"m3/s": 1.0, "m3/h": 1.0 / 3600.0, "L/s": 1e-3, "cfm": FOOT**3 / 60.0}
_POWER_W = {"W": 1.0, "kW": 1e3, "Btu/h": BTU_PER_HOUR, "W/m2": 1.0, "kW/m2": 1e3}


@dataclass(frozen=True)
class Plausible:
    """Plausible range of one role of channel, in SI units.

    Attributes
    ----------
    label : str
        What the channel is, for messages (``"room temperature"``).
    quantity : str
        ``"temperature"``, ``"flow"`` or ``"power"``.
    low, high : float
        Inclusive bounds in SI units (degC, kg/s, W).
    """

    label: str
    quantity: str
    low: float
    high: float


PLAUSIBLE = {
    "room": Plausible("room temperature", "temperature", -30.0, 60.0),
    "outdoor": Plausible("outdoor temperature", "temperature", -60.0, 60.0),
    "supply": Plausible("supply-air temperature", "temperature", -30.0, 60.0),
    "flow": Plausible("zone air mass flow", "flow", 0.0, 20.0),
    "power": Plausible("heat input", "power", -1e6, 1e6),
    "temperature": Plausible("temperature", "temperature", -60.0, 100.0),
    "irradiance": Plausible("solar irradiance", "irradiance", -50.0, 2000.0),
}
"""Plausible ranges by role. ``"temperature"`` is the loose default for other temperatures."""


def known_units(quantity: str) -> tuple[str, ...]:
    """Canonical unit names accepted for ``quantity``."""
    if quantity not in _ALIASES:
        raise DataError(f"unknown quantity {quantity!r}; {did_you_mean(quantity, _ALIASES)}")
    return tuple(_ALIASES[quantity])


def canonical_unit(unit: str, quantity: str, column: str) -> str:
    """Return the canonical spelling of ``unit`` for ``quantity``.

    Raises
    ------
    DataError
        If the unit is not known for the quantity; the message names the column, lists
        the known units and suggests close ones.
    """
    known = known_units(quantity)
    key = str(unit).strip().lower()
    for canon, aliases in _ALIASES[quantity].items():
        if key == canon.lower() or key in aliases:
            return canon
    spellings = list(known) + [a for al in _ALIASES[quantity].values() for a in al]
    hint = did_you_mean(str(unit), spellings)
    hint = "" if hint.startswith("known names") else f"; {hint}"
    raise DataError(
        f"column {column!r}: unknown {quantity} unit {unit!r}; known units: {', '.join(known)}{hint}"
    )


def to_si(
    values: np.ndarray,
    unit: str,
    quantity: str,
    column: str = "?",
    air_density: float = DEFAULT_AIR_DENSITY,
) -> np.ndarray:
    """Convert ``values`` given in ``unit`` to the SI unit of ``quantity``.

    Parameters
    ----------
    values : array_like
        Raw values; NaN stays NaN.
    unit : str
        Declared unit (any accepted spelling).
    quantity : str
        ``"temperature"`` (to degC), ``"flow"`` (to kg/s), ``"power"`` (to W) or ``"irradiance"``
        (to W/m2).
    column : str
        Source column name, used in error messages.
    air_density : float
        kg/m3, used only for volume flows.

    Returns
    -------
    ndarray of float
        A new array in SI units.
    """
    x = np.array(values, dtype=float)
    canon = canonical_unit(unit, quantity, column)
    if quantity == "temperature":
        if canon == "degF":
            return (x - 32.0) * (5.0 / 9.0)
        if canon == "K":
            return x - 273.15
        return x
    if quantity == "flow":
        if canon == "kg/s":
            return x
        if not (np.isfinite(air_density) and air_density > 0):
            raise DataError(f"air_density must be a positive number of kg/m3, got {air_density!r}")
        return x * (_VOLUME_M3S[canon] * air_density)
    return x * _POWER_W[canon]


def implausible(
    si_values: np.ndarray,
    raw_values: np.ndarray,
    role: str,
    unit: str,
    column: str,
    *,
    air_density: float = DEFAULT_AIR_DENSITY,
    rows: np.ndarray | None = None,
) -> str | None:
    """What is wrong with values outside the role's plausible range, or None if nothing is.

    Parameters
    ----------
    si_values : ndarray
        Values after conversion to SI.
    raw_values : ndarray
        The same values as read (used to test which other unit would fit).
    role : str
        A key of :data:`PLAUSIBLE`.
    unit : str
        The declared unit (or the SI unit a frame without a column map is taken to be in).
    column : str
        Source column (for the message).
    air_density : float
        kg/m3, to test alternative volume-flow units.
    rows : ndarray of int, optional
        0-based data-row number of each value, for the message (default: position).

    Returns
    -------
    str or None
        One line: the column, how many values, the range, the first value, and a hint naming the
        units that would make every value plausible.
    """
    rng = PLAUSIBLE[role]
    si = np.asarray(si_values, dtype=float)
    finite = np.isfinite(si)
    bad = finite & ((si < rng.low) | (si > rng.high))
    if not bad.any():
        return None
    where = np.flatnonzero(bad)
    first = int(where[0])
    row = int(rows[first]) if rows is not None else first
    si_unit = SI_UNITS[rng.quantity]
    raw = np.asarray(raw_values, dtype=float)
    what = (
        f"column {column!r} ({rng.label}, declared {unit!r}): {where.size} value(s) outside the plausible"
        f" range [{rng.low:g}, {rng.high:g}] {si_unit} after conversion"
        f" (first at data row {row + 1}: {float(raw[first]):g} {unit})"
    )
    fits = []
    for other in known_units(rng.quantity):
        if other == canonical_unit(unit, rng.quantity, column):
            continue
        alt = to_si(raw, other, rng.quantity, column, air_density)
        vals = alt[np.isfinite(alt)]
        if vals.size and np.all((vals >= rng.low) & (vals <= rng.high)):
            fits.append(other)
    if fits:
        hint = f"the values look like {' or '.join(repr(f) for f in fits)}; declare that unit"
    elif rng.quantity == "flow" and np.nanmin(si) < 0:
        hint = "flows must be >= 0; check the sign convention or sensor offset"
    else:
        hint = "check the declared unit and the sensor"
    return f"{what}; {hint}"


def check_plausible(
    si_values: np.ndarray,
    raw_values: np.ndarray,
    role: str,
    unit: str,
    column: str,
    air_density: float = DEFAULT_AIR_DENSITY,
    rows: np.ndarray | None = None,
) -> None:
    """Raise :class:`DataError` if converted values fall outside the role's plausible range.

    The parameters are those of :func:`implausible`, whose line is the error's message.
    """
    problem = implausible(si_values, raw_values, role, unit, column, air_density=air_density, rows=rows)
    if problem is not None:
        raise DataError(problem)


def signal_warnings(signals: Mapping[str, np.ndarray], roles: Mapping[str, str]) -> tuple[str, ...]:
    """Plausibility of the signals a model reads from a frame taken to be in SI units.

    A frame handed to the API, or a trend log read without a column map, declares no units: its
    temperatures are taken as degC, flows as kg/s, heat as W. Temperatures in degF or K then pass
    every check of shape and gaps and give a fit that looks good and means nothing; this is the
    check the column map's path makes after conversion (:func:`check_plausible`), made where every
    path (frame, CSV, Parquet, API, command line, batch) builds a model's data set. It returns the
    findings instead of raising: the fit is flagged with them (and the command exits 3), so data
    that are right but unusual are still fitted, never silently.

    Parameters
    ----------
    signals : mapping of str to ndarray
        Each channel's values, by name, in the units rczone takes them to be in.
    roles : mapping of str to str
        The plausibility role (a key of :data:`PLAUSIBLE`) of each channel to check; channels not
        named here are not checked.

    Returns
    -------
    tuple of str
        One line per implausible channel, with the unit that would make it plausible.
    """
    found = []
    for name, role in roles.items():
        if name not in signals:
            continue
        unit = SI_UNITS[PLAUSIBLE[role].quantity]
        x = np.asarray(signals[name], dtype=float)
        problem = implausible(x, x, role, unit, name)
        if problem is not None:
            problem = problem.replace(f"declared {unit!r}", f"taken as {unit!r}", 1)
            problem = problem.replace(
                "; declare that unit", f"; convert them to {unit} (or declare the unit in a column map)"
            )
            found.append(problem)
    return tuple(found)
