"""Unit conversion against published definitions (NIST SP 811) and plausibility hints."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.data.units import canonical_unit, check_plausible, to_si
from rczone.errors import DataError

# (value, unit, quantity, density, expected SI value) -- expected values from definitions:
# t/degC = (t/degF - 32)/1.8; T/K - 273.15; 1 cfm = 4.719474e-4 m3/s; 1 Btu_IT = 1055.05585262 J.
CONVERSIONS = [
    (32.0, "degF", "temperature", 1.2, 0.0),
    (212.0, "°F", "temperature", 1.2, 100.0),
    (-40.0, "F", "temperature", 1.2, -40.0),
    (273.15, "K", "temperature", 1.2, 0.0),
    (21.5, "celsius", "temperature", 1.2, 21.5),
    (0.12, "kg/s", "flow", 1.2, 0.12),
    (1.0, "m3/s", "flow", 1.2, 1.2),
    (3600.0, "m^3/h", "flow", 1.25, 1.25),
    (100.0, "L/s", "flow", 1.2, 0.12),
    (1000.0, "cfm", "flow", 1.0, 0.4719474),
    (1000.0, "ft3/min", "flow", 1.2, 1.2 * 0.4719474),
    (2.5, "kW", "power", 1.2, 2500.0),
    (50.0, "w", "power", 1.2, 50.0),
    (1000.0, "Btu/h", "power", 1.2, 1000.0 * 1055.05585262 / 3600.0),  # Btu_IT = 1055.05585262 J
]


@pytest.mark.parametrize(("value", "unit", "quantity", "rho", "expected"), CONVERSIONS)
def test_to_si_matches_definitions(value, unit, quantity, rho, expected):
    got = to_si(np.array([value, np.nan]), unit, quantity, "c", air_density=rho)
    assert got[0] == pytest.approx(expected, rel=1e-7, abs=1e-12)
    assert np.isnan(got[1])


def test_to_si_returns_a_new_array():
    raw = np.array([20.0])
    assert to_si(raw, "degC", "temperature") is not raw


def test_canonical_spellings():
    assert canonical_unit(" DegF ", "temperature", "c") == "degF"
    assert canonical_unit("CFM", "flow", "c") == "cfm"


BAD = [
    (
        lambda: to_si([1.0], "degG", "temperature", "RM1"),
        r"column 'RM1': unknown temperature unit 'degG'; known units: degC, degF, K",
    ),
    (
        lambda: to_si([1.0], "gpm", "flow", "F1"),
        r"unknown flow unit 'gpm'; known units: kg/s, m3/s, m3/h, L/s, cfm$",
    ),
    (lambda: to_si([1.0], "m3/s", "flow", "F1", air_density=0.0), r"air_density must be a positive number"),
    (lambda: to_si([1.0], "W", "energy", "E"), r"unknown quantity 'energy'"),
]


@pytest.mark.parametrize(("call", "pattern"), BAD)
def test_bad_units(call, pattern):
    with pytest.raises(DataError, match=pattern):
        call()


PLAUSIBILITY = [
    # (raw values, declared unit, role, expected message pattern)
    (
        [21.0, 70.0, 72.0],
        "degC",
        "room",
        r"2 value\(s\) outside .*\[-30, 60\] degC .*data row 2: 70 degC.*look like 'degF'",
    ),
    ([294.0, 295.0], "degC", "room", r"look like 'K'"),
    ([0.1, -0.02], "kg/s", "flow", r"zone air mass flow.*data row 2.*flows must be >= 0"),
    ([150.0, 200.0], "m3/s", "flow", r"look like 'm3/h' or 'L/s' or 'cfm'"),
    ([5e7], "W", "power", r"heat input.*check the declared unit"),
]


@pytest.mark.parametrize(("raw", "unit", "role", "pattern"), PLAUSIBILITY)
def test_implausible_values(raw, unit, role, pattern):
    quantity = {"room": "temperature", "flow": "flow", "power": "power"}[role]
    si = to_si(raw, unit, quantity, "x")
    with pytest.raises(DataError, match=pattern):
        check_plausible(si, np.asarray(raw), role, unit, "x")


def test_plausible_values_pass_and_nan_is_ignored():
    raw = np.array([-29.0, 59.0, np.nan])
    check_plausible(raw, raw, "room", "degC", "x")
    check_plausible(np.array([0.0, 3.0]), np.array([0.0, 3.0]), "flow", "kg/s", "m")


def test_rows_are_reported_as_given():
    raw = np.array([20.0, 80.0])
    with pytest.raises(DataError, match=r"data row 42"):
        check_plausible(raw, raw, "room", "degC", "x", rows=np.array([10, 41]))
