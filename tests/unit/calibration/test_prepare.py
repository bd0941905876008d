"""A frame's data set is prepared once and handed on unchanged (calibration.dataset.prepare)."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from rczone.calibration import calibrate, prepare
from rczone.calibration.dataset import dataset
from rczone.diagnostics import diagnose
from rczone.postfit.profiles import profile_checks
from tests.unit.selection.synthetic import prbs_zone

MODEL = "TiTe+heater"


@pytest.fixture(scope="module")
def frame():
    return prbs_zone(days=1.0, seed=3)


def test_prepared_data_are_the_model_s_data_set(frame):
    prepared = prepare(MODEL, frame)
    direct = dataset(MODEL, frame)
    for name in ("t", "u", "y"):
        np.testing.assert_array_equal(getattr(prepared.dataset, name), getattr(direct, name))
    assert prepared.frame is frame and prepared.stretch["samples"] == len(frame)


def test_prepared_data_are_handed_on_not_rebuilt(frame):
    prepared = prepare(MODEL, frame)
    assert prepare(MODEL, prepared) is prepared
    assert prepare(MODEL, prepared, constants=None) is prepared  # None: the constants it was made with


def test_other_constants_or_another_model_prepare_again(frame):
    prepared = prepare(MODEL, frame)
    held = prepare(MODEL, prepared, constants={"To": 5.0})
    assert held is not prepared and np.all(
        held.dataset.u[:, list(held.dataset.input_names).index("To")] == 5.0
    )
    other = prepare("Ti+heater+solar", prepared)
    assert (
        other is not prepared and other.dataset.input_names == dataset("Ti+heater+solar", frame).input_names
    )


def test_a_fit_and_its_analyses_read_the_prepared_data(frame, monkeypatch):
    """After prepare, neither the fit nor the profiles nor diagnose build a data set again."""
    ds = importlib.import_module("rczone.calibration.dataset")  # the package exports the function

    prepared = prepare(MODEL, frame)
    built = []
    real = ds.dataset
    monkeypatch.setattr(ds, "dataset", lambda *a, **k: built.append(a) or real(*a, **k))
    cal = calibrate(MODEL, prepared, method="ls", n_starts=1)
    profile_checks(cal.model, cal.data, cal.result, n_points=3)
    diagnose(cal.model, cal.data, operating_point="model")
    assert cal.data is prepared and built == []
