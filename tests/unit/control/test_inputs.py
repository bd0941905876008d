"""Input roles (saved with a model) and the forecast builder in the model's own input order."""

import numpy as np
import pytest

from rczone.control.inputs import input_roles, model_inputs, with_input_roles
from rczone.control.mpc import MPC, MPCSettings
from rczone.errors import InputShapeError, ModelFileError, ParameterError
from rczone.models import load_model
from rczone.models.zone import ZoneModel


def test_roles_follow_the_models_conventions_unless_declared():
    zm = load_model("second-order")
    assert input_roles(zm) == {"To": "measured", "Tsd": "measured", "Ts": "actuator", "Q": "unmeasured"}
    heater = load_model("TiTe+heater+solar")
    assert input_roles(heater, ["Ph"]) == {"To": "measured", "Ph": "actuator", "Ps": "measured"}
    declared = with_input_roles(heater, {"Ph": "actuator", "Ps": "unmeasured"})
    assert input_roles(declared)["Ps"] == "unmeasured"


def test_roles_are_saved_with_the_model(tmp_path):
    zm = with_input_roles(load_model("TiTh+heater"), {"Ph": "actuator", "To": "measured"})
    back = ZoneModel.load(zm.save(tmp_path / "house.json"))
    assert dict(back.inputs.roles) == {"Ph": "actuator", "To": "measured"}
    # an MPC on the saved model needs the actuator's limits, and decides it with them
    with pytest.raises(ParameterError, match="'Ph' is an actuator"):
        MPC(back)
    assert MPC(back, MPCSettings(heat_limits={"Ph": (0.0, 2000.0)})).heaters == ("Ph",)


def test_the_forecast_builder_fills_the_models_inputs_in_its_order():
    zm = load_model("second-order")
    series = {"To": np.arange(5.0), "Tf": 20.0, "Tc": 21.0, "Tn1": 22.0, "Tn2": 23.0, "Thw": 24.0, "x": 0.0}
    out = model_inputs(zm, series, 5)
    assert list(out) == ["To", "Tsd", "Q"]  # Ts is the supply air's: an actuator
    np.testing.assert_array_equal(out["To"], np.arange(5.0))
    np.testing.assert_allclose(out["Tsd"], 22.0)  # the mean of its mean_of columns, held
    np.testing.assert_allclose(out["Q"], zm.inputs.defaults["Q"])
    full = model_inputs(load_model("full-scale"), series, 5)
    assert list(full) == ["To", "Tf", "Tc", "Tn1", "Tn2", "Thw", "Q"]


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: model_inputs(load_model("second-order"), {"To": 1.0}, 3), InputShapeError, "Tf, Tc"),
        (
            lambda: model_inputs(load_model("second-order"), {"To": np.ones(2), "Tsd": 1.0}, 3),
            InputShapeError,
            "3 needed",
        ),
        (lambda: with_input_roles(load_model("TiTh+heater"), {"Pj": "actuator"}), ParameterError, "Ph"),
        (lambda: with_input_roles(load_model("TiTh+heater"), {"Ph": "decision"}), ParameterError, "actuator"),
        (
            lambda: ZoneModel.from_dict(
                {**load_model("TiTh+heater").to_dict(), "inputs": {"roles": {"Ph": "boss"}}}
            ),
            ModelFileError,
            "roles",
        ),
    ],
)
def test_bad_roles_and_forecasts_raise_one_line_errors(make, error, match):
    with pytest.raises(error, match=match):
        make()
