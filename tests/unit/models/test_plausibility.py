"""The plausibility line: UA, time constants and solar aperture against values worked out by hand."""

from __future__ import annotations

import json
import math

import pytest

from rczone.cli.main import main
from rczone.errors import ParameterError
from rczone.models import load_model
from rczone.models.plausibility import plausibility
from rczone.network.network import CP_AIR
from tests.unit.cli import test_fit_flags

#: The zone of the fit-flag tests (a fixture: two days of a two-boundary room simulated at its declared values).
zone = test_fit_flags.zone
MODEL = test_fit_flags.MODEL


def test_one_state_room_ua_is_one_over_ria_and_its_time_constant_ci_ria() -> None:
    zm = load_model("Ti+heater+solar").with_values({"Ci": 2.0e6, "Ria": 0.01, "Aw": 3.5})
    p = plausibility(zm)
    assert p.ua == pytest.approx(100.0, rel=1e-12)
    assert p.time_constants == pytest.approx((2.0e4,), rel=1e-12)
    assert p.solar_aperture == pytest.approx(3.5)
    assert p.warnings == () and math.isnan(p.guess_ua)
    assert "UA 100 W/K" in p.line() and "5.56 h" in p.line() and "solar aperture 3.5 m2" in p.line()


def test_supply_air_at_the_operating_flow_adds_m_cp_to_ua() -> None:
    zm = load_model("Ti+air").with_values({"Ci": 2.0e6, "Ria": 0.01})
    p = plausibility(zm, flow=0.1)
    assert p.ua == pytest.approx(100.0 + 0.1 * CP_AIR, rel=1e-12)
    assert p.time_constants == pytest.approx((2.0e6 / (100.0 + 0.1 * CP_AIR),), rel=1e-12)
    assert p.solar_aperture is None


def test_two_state_room_and_envelope() -> None:
    """UA of the series path; time constants from the roots of the 2x2 characteristic polynomial."""
    ci, ce, rie, rea = 1.5e6, 2.0e7, 2.0e-3, 1.0e-2
    zm = load_model("TiTe+heater").with_values({"Ci": ci, "Ce": ce, "Rie": rie, "Rea": rea})
    p = plausibility(zm)
    assert p.ua == pytest.approx(1.0 / (rie + rea), rel=1e-12)
    # A = [[-a, a], [b, -b - c]] with a = 1/(Ci Rie), b = 1/(Ce Rie), c = 1/(Ce Rea)
    a, b, c = 1 / (ci * rie), 1 / (ce * rie), 1 / (ce * rea)
    tr, det = -(a + b + c), a * c
    lam = sorted(((tr - math.sqrt(tr * tr - 4 * det)) / 2, (tr + math.sqrt(tr * tr - 4 * det)) / 2))
    assert p.time_constants == pytest.approx((-1 / lam[1], -1 / lam[0]), rel=1e-10)
    assert p.warnings == ()


def test_a_room_heavier_than_its_envelope_is_warned_about() -> None:
    zm = load_model("TiTe+heater").with_values({"Ci": 5.0e7, "Ce": 1.0e6})
    (w,) = plausibility(zm).warnings
    assert "room node Ti holds more heat (5e+07 J/K) than the envelope Te (1e+06 J/K)" in w


def test_ua_and_time_constants_far_from_the_declared_values_are_warned_about() -> None:
    guess = load_model("Ti+heater").with_values({"Ci": 2.0e6, "Ria": 0.005})  # the user's values
    near = plausibility(guess.with_values({"Ci": 3.0e6, "Ria": 0.02}), guess)
    assert near.warnings == () and near.guess_ua == pytest.approx(200.0)
    assert near.reference == "judged against the values declared in Ti+heater"
    far = plausibility(guess.with_values({"Ci": 1.0e6, "Ria": 0.2}), guess)
    assert [w.split(" is ")[0] for w in far.warnings] == ["UA 5 W/K", "time constant 1 (2.31 d)"]
    assert "0.025 times the values declared in Ti+heater (200 W/K)" in far.warnings[0]
    d = far.to_dict()
    assert d["ua_W_per_K"] == pytest.approx(5.0) and d["guess_time_constants_s"] == pytest.approx([1.0e4])
    assert json.loads(json.dumps(d)) == d


def test_rczone_fit_prints_writes_and_reports_the_plausibility_line(zone, tmp_path, capsys) -> None:
    """The two-room-boundary zone of the fit-flag tests: Ti to To through Rie + Rea, to Tx through Rx."""
    (tmp_path / "room.toml").write_text(MODEL)
    args = ["fit", str(zone / "zone.csv"), "--model", str(tmp_path / "room.toml"), "--method", "ls"]
    rc = main(
        [*args, "--json", str(tmp_path / "fit.json"), "--report", str(tmp_path / "rep"), "--no-profiles"]
    )
    out = capsys.readouterr().out
    assert rc == 0, out
    d = json.loads((tmp_path / "fit.json").read_text())
    est = {k: v["estimate"] for k, v in d["parameters"].items()}
    # Ti loses heat through Rie + Rea to To and through Rx to Tx, in parallel
    ua = 1 / (est["Rie"] + est["Rea"]) + 1 / est["Rx"]
    assert d["plausibility"]["ua_W_per_K"] == pytest.approx(ua, rel=1e-9)
    assert d["plausibility"]["guess_ua_W_per_K"] == pytest.approx(1 / 0.012 + 20, rel=1e-9)
    assert d["plausibility"]["warnings"] == [] and d["plausibility"]["solar_aperture_m2"] is None
    assert f"plausibility: UA {ua:.4g} W/K" in out
    assert "plausibility: UA" in (tmp_path / "rep" / "report.html").read_text()


def test_generic_values_of_a_built_in_model_are_not_a_reference() -> None:
    generic = load_model("Ti+heater")  # rczone's starting values: no building's
    fitted = generic.with_values({"Ci": 1.0e6, "Ria": 0.6})  # UA 1.7 W/K, 60 times the generic 100
    p = plausibility(fitted, generic)
    assert p.warnings == () and "not judged" in p.reference and "--floor-area" in p.reference
    assert "not judged" in p.line()


def test_a_floor_area_judges_ua_and_capacity_against_the_reference_ranges() -> None:
    from rczone.models.plausibility import CAPACITY_PER_AREA, UA_PER_AREA, reference_ranges

    generic = load_model("Ti+heater")
    area = 100.0
    ranges = reference_ranges(area)
    assert ranges["ua"] == pytest.approx((UA_PER_AREA[0] * area, UA_PER_AREA[1] * area))
    assert ranges["time_constant"][0] == pytest.approx(CAPACITY_PER_AREA[0] / UA_PER_AREA[1])
    # UA 1 / Ria: 100 W/K is inside 15..1000 W/K; a capacity of 1e6 J/K is below 4e6 J/K
    p = plausibility(generic.with_values({"Ci": 1.0e6, "Ria": 0.01}), generic, floor_area=area)
    assert "100 m2 of floor" in p.reference
    assert len(p.warnings) == 1 and "summed heat capacity 1e+06 J/K is outside" in p.warnings[0]
    slow = plausibility(generic.with_values({"Ci": 7.0e7, "Ria": 1.0}), generic, floor_area=area)
    assert any("slowest time constant" in w for w in slow.warnings)  # 7e7 s, beyond 4.9e6 s
    ok = plausibility(generic.with_values({"Ci": 2.0e7, "Ria": 0.01}), generic, floor_area=area)
    assert ok.warnings == ()  # 100 W/K, 2e7 J/K, 56 h: a plausible 100 m2 house
    with pytest.raises(ParameterError, match="floor area must be a positive number"):
        reference_ranges(-5.0)


def test_rczone_fit_floor_area_judges_against_the_reference_ranges(zone, tmp_path, capsys) -> None:
    (tmp_path / "room.toml").write_text(MODEL)
    args = ["fit", str(zone / "zone.csv"), "--model", str(tmp_path / "room.toml"), "--method", "ls"]
    main([*args, "--starts", "1", "--floor-area", "2", "--json", str(tmp_path / "fit.json"), "--no-profiles"])
    out = " ".join(capsys.readouterr().out.split())
    d = json.loads((tmp_path / "fit.json").read_text())["plausibility"]
    assert d["reference"] == "judged against the reference ranges for 2 m2 of floor" and d["reference"] in out
    # UA of tens of W/K is far above 10 W/(m2 K) times 2 m2: the warning names the range
    assert any("outside the reference range for 2 m2 of floor" in w for w in d["warnings"])
    assert main([*args, "--floor-area", "-3"]) == 2
    assert "floor area must be a positive number" in capsys.readouterr().err
