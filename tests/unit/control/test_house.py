"""The heated house (emulator ``house``): its physics against the steady state, its options by name."""

import numpy as np
import pytest

from rczone.control.closedloop import closed_loop_test
from rczone.control.house import HousePlant
from rczone.control.registry import ControllerOptions, make_controller
from rczone.emulators.registry import emulator_names, make_plant
from rczone.errors import ParameterError
from rczone.models import load_model


def test_a_held_power_settles_at_the_steady_state_of_the_envelope():
    # TiTh+heater at steady state: all the heater's power leaves through Ria, Ti = To + P Ria
    plant = make_plant("house", days=2.0, seed=0, heat_limit=2500.0)
    plant.t_out[:] = 0.0
    plant.noise[:] = 0.0
    while plant.time < plant.end - 1e-9:
        y = plant.step({"P_house": 1000.0})
    assert y["Ti_house"] == pytest.approx(1000.0 * plant.truth.theta["Ria"], abs=1e-3)
    assert y["P_house"] == 1000.0 and "house" in emulator_names()


def test_a_command_beyond_the_heater_is_clipped_and_counted():
    plant = HousePlant(days=0.01, heat_limit=1500.0)
    plant.step({"P_house": 4000.0})
    while plant.time < plant.end - 1e-9:
        plant.step({"P_house": 1500.0})
    assert plant.power[0] == 1500.0 and plant.kpis()["constraint_violations"] == 1


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"heat_limit": 0.0}, "heat_limit"),
        ({"heat_limit": True}, "heat_limit"),
        ({"days": 1e-9}, "scored minute"),
        ({"seed": -1}, "seed"),
        ({"season": "winter"}, "heat_limit"),  # not an option of the house: it names those it takes
    ],
)
def test_bad_options_are_one_error(options, match):
    with pytest.raises(ParameterError, match=match):
        make_plant("house", **options)


def test_an_unknown_action_is_refused():
    with pytest.raises(ParameterError, match="P_house"):
        HousePlant(days=0.01).step({"m_house": np.float64(0.1)})


def test_the_prediction_scores_tell_the_house_own_model_from_the_library_one():
    # the plant's own model predicts it to the sensor's noise; the built-in values (10-15 % off) do not
    own = HousePlant(days=1.0, seed=2)
    truth = closed_loop_test(own, "thermostat", model=own.truth).scores
    library = closed_loop_test(HousePlant(days=1.0, seed=2), "thermostat", model=load_model("TiTh+heater"))
    assert truth["open_loop_rmse_K"] < 0.1 < 0.5 < library.scores["open_loop_rmse_K"]


def test_the_controllers_get_the_plant_heater_limit():
    plant = make_plant("house", days=0.1, heat_limit=1200.0)
    mpc = make_controller("mpc", plant, ControllerOptions(load_model("TiTe+heater")))
    assert dict(mpc.mpc.settings.heat_limits) == {"Ph": (0.0, 1200.0)}
    assert make_controller("thermostat", plant).limits == (0.0, 1200.0)
