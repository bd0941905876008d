"""Buildings, weather files and dates: every mistake is one line with a hint."""

from __future__ import annotations

import datetime as dt

import pytest

pytest.importorskip("pyenergyplus")

from rczone.emulators import catalog
from rczone.errors import ParameterError


def test_the_offices_and_chicago_are_shipped():
    assert {"office_small", "office_medium"} <= set(catalog.buildings())
    assert catalog.weather_file("usa_il_chicago").suffix == ".epw"


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: catalog.building_file("office_smal"), "did you mean 'office_small'"),
        (lambda: catalog.weather_file("usa_il_chicgo"), "did you mean 'usa_il_chicago'"),
        (lambda: catalog.parse_start("2017-01-05"), "MM-DD"),
        (lambda: catalog.parse_start("02-29"), "no 29 February"),
        (lambda: catalog.parse_start("13-01"), "not a day"),
    ],
)
def test_bad_choices_are_one_line(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def test_the_chicago_header_is_read():
    h = catalog.read_header(catalog.weather_file("usa_il_chicago"))
    assert h.utc_offset_h == -6
    assert catalog.timezone_name(h.utc_offset_h) == "Etc/GMT+6"
    assert (h.first, h.last) == (dt.date(catalog.YEAR, 1, 1), dt.date(catalog.YEAR, 12, 31))


def test_a_period_leaving_the_weather_file_is_refused():
    h = catalog.read_header(catalog.weather_file("usa_il_chicago"))
    assert catalog.check_period(h, dt.date(catalog.YEAR, 12, 30), 2, "x") == dt.date(catalog.YEAR, 12, 31)
    with pytest.raises(ParameterError, match="outside the weather file"):
        catalog.check_period(h, dt.date(catalog.YEAR, 12, 30), 3, "x")
    with pytest.raises(ParameterError, match="--days"):
        catalog.check_period(h, dt.date(catalog.YEAR, 1, 1), 0, "x")


def test_the_listing_names_buildings_zones_and_weather(capsys):
    from rczone.cli.main import main

    assert main(["emulate", "--list"]) == 0
    out = capsys.readouterr().out
    assert "office_medium: 18 zones (15 with air terminals)" in out and "usa_il_chicago" in out
    assert main(["emulate", "--building", "office_medium", "--list"]) == 0
    out = capsys.readouterr().out
    assert "Perimeter_bot_ZN_1\n" in out and "FirstFloor_Plenum *" in out
