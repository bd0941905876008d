"""Emulators by name: the built-in ones, a user's registered in Python, and a plug-in's entry point."""

import json
import sys

import pytest

import rczone
from rczone.cli.main import main
from rczone.control.closedloop import closed_loop_test
from rczone.control.virtualplant import VirtualPlant
from rczone.emulators import registry
from rczone.emulators.registry import emulator_names, make_plant, register_emulator
from rczone.errors import ParameterError
from tests.unit.entrypoints import install


class ColdVirtualPlant(VirtualPlant):
    """A user's emulator: the virtual building with its outdoor forecast reported 1 K too cold."""

    def forecast(self, horizon, *, interval=None):
        out = dict(super().forecast(horizon, interval=interval))
        out["To"] = out["To"] - 1.0
        return out


def cold(**options):
    return ColdVirtualPlant(**options)


@pytest.fixture
def registered():
    rczone.register_emulator("cold", cold)
    yield "cold"
    registry.unregister_emulator("cold")


def test_the_built_in_virtual_building_is_made_by_name_with_its_own_options():
    plant = make_plant("virtual", season="winter", days=0.1, seed=3)
    assert plant.describe() == VirtualPlant("winter", days=0.1, seed=3).describe()
    assert {"virtual", "energyplus"} <= set(emulator_names())


def test_an_option_the_emulator_does_not_take_is_one_error_naming_those_it_does():
    with pytest.raises(ParameterError, match=r"no option 'building'.*season"):
        make_plant("virtual", building="office_small")
    with pytest.raises(ParameterError, match=r"unknown emulator 'virtaul'.*virtual"):
        make_plant("virtaul")


def test_a_registered_emulator_runs_a_controller_through_the_api(registered):
    plant = make_plant(registered, season="summer", days=0.05, seed=1)
    assert isinstance(plant, ColdVirtualPlant)
    reference = VirtualPlant("summer", days=0.05, seed=1)
    assert plant.forecast(3600.0)["To"][0] == pytest.approx(reference.forecast(3600.0)["To"][0] - 1.0)
    r = closed_loop_test(plant, "thermostat")
    assert r.scores["constraint_violations"] == 0 and "cold" in emulator_names()


def test_a_factory_that_returns_no_plant_is_refused():
    register_emulator("broken", lambda **o: object())
    try:
        with pytest.raises(ParameterError, match="plant interface"):
            make_plant("broken")
    finally:
        registry.unregister_emulator("broken")


def test_a_plug_in_emulator_is_found_through_its_entry_point(tmp_path, monkeypatch):
    text = "from tests.unit.emulators.test_registry import cold as factory\n"
    install(tmp_path, "my_plant", text, "rczone.emulators", "plugged = my_plant:factory")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "plugged" in emulator_names()
    assert isinstance(make_plant("plugged", days=0.05), ColdVirtualPlant)
    out = tmp_path / "s.json"
    args = ["control-test", "--emulator", "plugged", "--controller", "thermostat", "--days", "0.05"]
    assert main([*args, "--json", str(out)]) == 0
    assert json.loads(out.read_text())["constraint_violations"] == 0
    sys.modules.pop("my_plant", None)


def test_an_unknown_emulator_on_the_command_line_is_one_line_and_exit_2(capsys):
    assert main(["control-test", "--emulator", "virtaul"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown emulator 'virtaul'" in err[0] and "virtual" in err[0]
