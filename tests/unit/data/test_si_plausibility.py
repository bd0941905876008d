"""Data without declared units (a frame, a file without a column map) are checked as SI.

Temperatures in degF read as degC fit as well as any: every entry point (a frame through the API,
a CSV or a Parquet file, the command line, a batch) builds the model's data set in one place,
which checks each signal against its plausible range, warns, and flags the fit.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import rczone
from rczone.calibration.dataset import dataset, prepare
from rczone.cli.main import main
from rczone.data import RczoneWarning
from rczone.data.units import signal_warnings
from tests.unit.selection.synthetic import prbs_zone

MODEL = "Ti+heater"


def to_degF(c):
    return c * 9.0 / 5.0 + 32.0


@pytest.fixture(scope="module")
def zone():
    return prbs_zone(days=1, seed=5)


@pytest.fixture(scope="module")
def fahrenheit(zone):
    f = zone.copy()
    f["Ti"] = to_degF(f["Ti"] + 18.0)  # a heated room, 64-75 degF
    f["To"] = to_degF(f["To"])
    return f


@pytest.mark.parametrize(
    ("values", "role", "hint"),
    [
        (to_degF(np.array([19.0, 21.0, 24.0])), "room", "'degF'"),
        (np.array([292.0, 294.0]), "room", "'K'"),
        (np.array([0.5, 40.0]), "flow", None),
    ],
    ids=["degF", "kelvin", "flow"],
)
def test_a_signal_outside_its_range_is_named_with_the_unit_that_fits(values, role, hint):
    (line,) = signal_warnings({"x": values}, {"x": role})
    assert line.startswith("column 'x'") and "taken as" in line
    if hint:
        assert f"the values look like {hint}" in line and "convert them to" in line


def test_plausible_signals_and_unchecked_names_give_nothing():
    assert signal_warnings({"Ti": np.array([18.0, 25.0]), "y": np.array([1e9])}, {"Ti": "room"}) == ()


def test_the_data_set_of_every_path_carries_the_finding(fahrenheit, zone):
    with pytest.warns(RczoneWarning, match=r"column 'Ti' \(room temperature.*'degF'"):
        data = dataset(MODEL, fahrenheit)
    assert len(data.warnings) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", RczoneWarning)
        assert dataset(MODEL, zone).warnings == ()


def test_a_frame_in_degF_is_fitted_but_flagged(fahrenheit):
    with pytest.warns(RczoneWarning, match="degF"):
        cal = rczone.fit(MODEL, fahrenheit, method="ls", n_starts=1, checks=False, profiles=False)
    assert not cal.verdict.trustworthy and cal.exit_code == 3
    assert any("implausible data" in r and "'degF'" in r for r in cal.verdict.reasons)
    assert cal.data_warnings and "implausible data" in json.dumps(cal.to_dict())


@pytest.mark.parametrize("name", ["predict", "diagnose"])
def test_predict_and_diagnose_warn(fahrenheit, name):
    with pytest.warns(RczoneWarning, match="degF"):
        getattr(rczone, name)(MODEL, fahrenheit)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_a_file_in_degF_is_refused_in_one_line(fahrenheit, tmp_path, capsys, suffix):
    """A file's columns are read as the default layout declares them (SI), and checked as read:
    the stricter answer, an error naming the unit that fits (the same check, raised)."""
    path = tmp_path / f"zone{suffix}"
    fahrenheit.to_csv(path, index=False) if suffix == ".csv" else fahrenheit.to_parquet(path)
    rc = main(["fit", str(path), "--model", MODEL, "--method", "ls", "--starts", "1"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1
    assert "column 'Ti' (room temperature" in err and "the values look like 'degF'" in err


def test_a_batch_zone_from_a_frame_is_flagged(fahrenheit):
    """fit-many's worker builds one data set per zone and calibrates on it (batch/task.py)."""
    from rczone.calibration import calibrate

    with pytest.warns(RczoneWarning, match="degF"):
        data = prepare(MODEL, fahrenheit)
    cal = calibrate(MODEL, data, method="ls", n_starts=1, analyses=False)
    assert not cal.verdict.trustworthy and cal.data_warnings == data.dataset.warnings


@pytest.mark.parametrize("entry", ["fit", "predict", "prepare"])
def test_the_warning_points_at_the_users_call_not_into_rczone(fahrenheit, entry):
    """However deep the entry point prepares the data set, the warning names the caller's line."""
    call = {
        "fit": lambda: rczone.fit(MODEL, fahrenheit, method="ls", n_starts=1, checks=False, profiles=False),
        "predict": lambda: rczone.predict(MODEL, fahrenheit),
        "prepare": lambda: prepare(MODEL, fahrenheit),
    }[entry]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    ours = [w for w in caught if issubclass(w.category, RczoneWarning)]
    assert ours and {w.filename for w in ours} == {__file__}


def test_a_hot_attic_is_a_boundary_not_outdoor_air(tmp_path):
    """A joint floor model's boundaries are adjacent spaces (attic, plenum) as often as outdoor air:
    an attic at 61 degC (EnergyPlus's small office in Phoenix's July) is plausible, the outdoor air
    ``To`` at 61 is not, and a room in degF is found whatever the boundaries."""
    from rczone.models import load_model

    path = tmp_path / "roof.toml"
    path.write_text(
        'name = "under the roof"\nboundaries = ["To", "TAttic"]\noutputs = ["Ti"]\n'
        'resistors = [["Ti", "To", "Rw"], ["Ti", "TAttic", "Rr"]]\n[nodes]\nTi = "Ci"\n[parameters]\n'
        'Ci = { value = 1e6, unit = "J/K" }\nRw = { value = 0.01, unit = "K/W" }\n'
        'Rr = { value = 0.02, unit = "K/W" }\n'
    )
    roles = load_model(path).signal_roles()
    assert roles["To"] == "outdoor" and roles["TAttic"] == "temperature"
    hot = np.array([35.0, 61.0, 48.0])
    signals = {"Ti": np.array([22.0, 24.0, 23.0]), "To": np.array([30.0, 40.0, 35.0]), "TAttic": hot}
    assert signal_warnings(signals, roles) == ()
    (line,) = signal_warnings({**signals, "To": hot}, roles)
    assert line.startswith("column 'To'")
    found = signal_warnings({**signals, "Ti": to_degF(signals["Ti"])}, roles)
    assert len(found) == 1 and "'degF'" in found[0]
