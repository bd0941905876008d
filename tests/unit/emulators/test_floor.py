"""The joint model of one floor from building.toml: rooms, walls and boundaries with 1/UA priors."""

from __future__ import annotations

import pytest

from rczone.emulators.floor import floor_model
from rczone.errors import DataError, ParameterError

DOC = {
    "building": "test",
    "zones": [
        {
            "name": "Core_1",
            "floor": 1,
            "floor_area": 100.0,
            "volume": 300.0,
            "conditioned": True,
            "exterior_ua": 0.0,
        },
        {
            "name": "Per_1",
            "floor": 1,
            "floor_area": 50.0,
            "volume": 150.0,
            "conditioned": True,
            "exterior_ua": 40.0,
        },
        {
            "name": "Plenum",
            "floor": 1,
            "floor_area": 150.0,
            "volume": 100.0,
            "conditioned": False,
            "exterior_ua": 5.0,
        },
        {
            "name": "Core_2",
            "floor": 2,
            "floor_area": 100.0,
            "volume": 300.0,
            "conditioned": True,
            "exterior_ua": 0.0,
        },
    ],
    "adjacency": [
        {"a": "Core_1", "b": "Per_1", "ua": 200.0},
        {"a": "Plenum", "b": "Core_1", "ua": 250.0},
        {"a": "Plenum", "b": "Core_2", "ua": 100.0},
    ],
}


def test_the_floor_has_its_rooms_walls_and_boundaries():
    net = floor_model(DOC, 1)
    assert net.outputs == ("TCore1", "TPer1")
    assert net.boundaries == ("To", "TPlenum")
    assert set(net.flow_names) == {"mCore1", "mPer1"}
    p = net.parameters
    assert p["Rw_Core1_Per1"].value == pytest.approx(1 / 200)
    assert p["Rb_Core1_Plenum"].value == pytest.approx(1 / 250)
    assert p["Rwin_Per1"].value == pytest.approx(1 / 40)
    assert "Rwin_Core1" not in p  # no exterior surface
    assert p["Ci_Core1"].value == pytest.approx(1.2 * 1005 * 300 * 5)


def test_the_next_floor_sees_the_plenum_below():
    net = floor_model(DOC, 2)
    assert net.outputs == ("TCore2",) and "TPlenum" in net.boundaries


@pytest.mark.parametrize(
    "doc, floor, error, match",
    [
        (DOC, 3, ParameterError, "no conditioned zone there"),
        ({"zones": []}, 1, DataError, "not a building file"),
        ({**DOC, "adjacency": [{"a": "Core_1", "b": "X", "ua": 1.0}]}, 1, DataError, "adjacency 1"),
        ({**DOC, "zones": [{**DOC["zones"][0], "volume": -1}]}, 1, DataError, "volume"),
    ],
)
def test_a_bad_building_file_is_one_line(doc, floor, error, match):
    with pytest.raises(error, match=match):
        floor_model(doc, floor)


def toml_of(doc) -> str:
    lines = [f'building = "{doc["building"]}"']
    for z in doc["zones"]:
        lines += ["[[zones]]"] + [
            f"{k} = {str(v).lower() if isinstance(v, bool) else repr(v)}" for k, v in z.items()
        ]
    for a in doc["adjacency"]:
        lines += ["[[adjacency]]"] + [f"{k} = {v!r}" for k, v in a.items()]
    return "\n".join(lines).replace("'", '"') + "\n"


def test_models_generate_from_a_building_file(tmp_path, capsys):
    from rczone.cli.main import main
    from rczone.models import load_model

    (tmp_path / "building.toml").write_text(toml_of(DOC))
    out = tmp_path / "floor1.toml"
    assert (
        main(
            ["models", "generate", "--from", str(tmp_path / "building.toml"), "--floor", "1", "-o", str(out)]
        )
        == 0
    )
    net = load_model(str(out)).network
    assert net.outputs == ("TCore1", "TPer1") and net.parameters["Rw_Core1_Per1"].value == pytest.approx(
        0.005
    )
    assert main(["models", "generate", "--from", str(tmp_path / "building.toml"), "--floor", "4"]) == 2
    assert main(["models", "generate", "--floor", "1"]) == 2
    err = [ln for ln in capsys.readouterr().err.strip().splitlines() if ln.startswith("error:")]
    assert len(err) == 2 and "no conditioned zone" in err[0] and "--from building.toml" in err[1]
