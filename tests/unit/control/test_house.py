"""The heated house (emulator ``house``): its physics against the steady state, its options by name."""

import numpy as np
import pytest

from rczone.control.house import HousePlant
from rczone.emulators.registry import emulator_names, make_plant
from rczone.errors import ParameterError


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
