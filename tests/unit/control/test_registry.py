"""A user's controller, written here against the Plant protocol, runs by name and as a plug-in."""

import json
import sys

import numpy as np
import pytest

from rczone.cli.main import main
from rczone.control import ControllerOptions, controller_names, make_controller, register_controller, registry
from rczone.control.closedloop import closed_loop_test
from rczone.control.virtualplant import VirtualPlant
from rczone.errors import ParameterError
from tests.unit.entrypoints import install


class HalfwayController:
    """A user's rule: the ventilation minimum the plant states, reheat aiming at the band's middle."""

    horizon = 0.0

    def __init__(self, plant):
        self.interval = plant.dt
        self.zone = plant.zones[0]

    def act(self, t, measurements, forecast):
        z = self.zone
        mid = 0.5 * (forecast[f"lower_{z}"][0] + forecast[f"upper_{z}"][0])
        ts = measurements["T_ahu"] + max(0.0, 8.0 * (mid - measurements[f"Ti_{z}"]))
        return {f"m_{z}": float(forecast[f"m_min_{z}"][0]), f"Ts_{z}": ts}


def halfway(plant, options):
    return HalfwayController(plant)


@pytest.fixture
def registered():
    register_controller("halfway", halfway)
    yield "halfway"
    registry.unregister_controller("halfway")  # leave the registry as it was


def test_a_registered_controller_runs_through_the_api_held_to_the_zones_limits(registered):
    r = closed_loop_test(VirtualPlant("summer", days=0.1, seed=1), registered)
    assert r.setup["controller"] == "halfway" and r.scores["constraint_violations"] == 0
    lim = r.setup["constraints"]["target"]
    occ = r.series["occupied"]
    np.testing.assert_allclose(r.series["m"][occ], lim["flow_min_occupied"])
    np.testing.assert_allclose(r.series["m"][~occ], lim["flow_min_unoccupied"])
    assert "halfway" in controller_names()


def test_a_registered_controller_runs_through_control_test(registered, tmp_path, capsys):
    out = tmp_path / "s.json"
    args = ["control-test", "--controller", "halfway", "--days", "0.05", "--json", str(out)]
    assert main(args) == 0
    assert json.loads(out.read_text())["setup"]["controller"] == "halfway"


def test_a_plug_in_is_found_through_its_entry_point(tmp_path, monkeypatch, capsys):
    # an installed distribution declaring rczone.controllers = {"plugged": module:factory}
    text = "from tests.unit.control.test_registry import halfway as factory\n"
    install(tmp_path, "my_ctrl", text, "rczone.controllers", "plugged = my_ctrl:factory")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "plugged" in controller_names()
    plant = VirtualPlant("summer", days=0.05)
    assert isinstance(make_controller("plugged", plant, ControllerOptions()), HalfwayController)
    out = tmp_path / "s.json"
    assert main(["control-test", "--controller", "plugged", "--days", "0.05", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["constraint_violations"] == 0
    sys.modules.pop("my_ctrl", None)


@pytest.mark.parametrize(
    ("name", "factory", "match"),
    [("", lambda p, o: None, "name"), ("x", 3, "callable"), ("notacontroller", lambda p, o: object(), "act")],
)
def test_bad_registrations_are_one_line_errors(name, factory, match):
    try:
        with pytest.raises(ParameterError, match=match):
            register_controller(name, factory)
            make_controller(name, VirtualPlant("summer", days=0.01))
    finally:
        registry.unregister_controller(name)
