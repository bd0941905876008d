"""Column maps through the command line (issue 22, defects 6 and 7, missing 3).

A trend log in a BMS's shape (the time as an unnamed index column, the heater as two circuits in
kW, an irradiance column the model does not use) is built from a synthetic zone's frame; fitting
it through its column map must give the fit of the zone's own frame, which needs no map.
"""

import json

import pytest

import rczone
from rczone.cli.main import main
from tests.unit.selection.synthetic import prbs_zone

MAP = """
name = "BMS export"
[time]
column = ""
[columns]
Ti = "room"
To = "outdoor"
Ph = { expr = "HC1_kW + HC2_kW", unit = "kW" }
Ps = { column = "sun", unit = "W/m2" }
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cmap")
    zone = prbs_zone(days=1, seed=4)
    zone.to_csv(d / "zone.csv", index=False)
    bms = zone.set_index("time").rename(columns={"Ti": "room", "To": "outdoor"})
    bms.index.name = None  # pandas writes an empty header cell for it
    bms["HC1_kW"] = 0.4 * bms.pop("Ph") / 1000.0
    bms["HC2_kW"] = 1.5 * bms["HC1_kW"]
    bms["sun"] = 100.0
    bms.to_csv(d / "bms.csv")
    (d / "map.toml").write_text(MAP)
    return d


def _fit(files, data, *extra):
    out = files / f"{data}.json"
    args = ["fit", str(files / data), "--model", "TiTe+heater", "--method", "ls", "--starts", "1"]
    rc = main([*args, "--no-profiles", "--json", str(out), *extra])
    return rc, json.loads(out.read_text())


def test_a_bms_export_through_its_map_fits_as_the_plain_frame(files, capsys):
    rc0, plain = _fit(files, "zone.csv")
    rc1, mapped = _fit(files, "bms.csv", "--columns", str(files / "map.toml"))
    err = capsys.readouterr().err
    assert rc0 == rc1
    for name, est in plain["parameters"].items():
        assert mapped["parameters"][name]["estimate"] == pytest.approx(est["estimate"], rel=1e-6)
    # the unused irradiance is said once, quietly, and is no error
    assert err.count("note: map.toml maps Ps, which TiTe+heater does not use: ignored") == 1


def test_without_the_empty_time_column_the_error_says_how(files, tmp_path, capsys):
    bad = tmp_path / "map.toml"
    bad.write_text(MAP.replace('column = ""\n', ""))
    rc = main(["fit", str(files / "bms.csv"), "--model", "TiTe+heater", "--columns", str(bad)])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert "no time column 'time'; the column 1 has no name" in err and 'column = "" under [time]' in err


def test_a_typo_of_the_heater_is_an_error_naming_it(files, tmp_path, capsys):
    bad = tmp_path / "map.toml"
    bad.write_text(MAP.replace("Ph = ", "Phh = "))
    rc = main(["fit", str(files / "bms.csv"), "--model", "TiTe+heater", "--columns", str(bad)])
    err = capsys.readouterr().err
    assert rc == 2 and "did you mean 'Ph'?" in err and "'Ts'" not in err


def test_the_fit_alone_line_of_select_runs_as_printed(files, capsys, monkeypatch):
    """Defect 8: the printed command keeps --columns and the other options, and pastes as one line."""
    import shlex

    monkeypatch.setenv("COLUMNS", "60")  # a narrow terminal must not break the command
    monkeypatch.chdir(files)
    args = ["select", "bms.csv", "--model", "Ti+heater", "--model", "TiTe+heater", "--columns", "map.toml"]
    assert main([*args, "--starts", "1", "--seed", "3", "--hold", "foh"]) in (0, 3)
    lines = capsys.readouterr().out.splitlines()
    command = lines[lines.index(next(ln for ln in lines if ln.startswith("the same fit alone"))) + 1 :]
    command = next(ln for ln in command if ln.startswith("rczone fit"))
    words = shlex.split(command)
    assert words[:5] == ["rczone", "fit", "bms.csv", "--model", "TiTe+heater"]
    assert {"--columns", "--hold", "--starts", "--seed"} <= set(words)
    assert main(words[1:]) in (0, 3)  # exit 2 before the fix: the map was dropped


def test_the_json_of_fit_select_and_predict_lists_the_ignored_channels(files, capsys):
    """The irradiance the map carries and no model uses is listed in every JSON, not only on stderr."""
    _, mapped = _fit(files, "bms.csv", "--columns", str(files / "map.toml"))
    assert mapped["ignored_channels"] == ["Ps"]
    _, plain = _fit(files, "zone.csv")  # no map: nothing mapped, nothing ignored
    assert plain["ignored_channels"] == []
    # a map whose every channel the model uses ignores nothing
    (files / "used.toml").write_text(MAP.replace('Ps = { column = "sun", unit = "W/m2" }\n', ""))
    _, used = _fit(files, "bms.csv", "--columns", str(files / "used.toml"))
    assert used["ignored_channels"] == []
    cmap = ["--columns", str(files / "map.toml")]
    sel, model = files / "sel.json", files / "ml.json"
    args = ["select", str(files / "bms.csv"), "--model", "Ti+heater", "--model", "TiTe+heater", *cmap]
    assert main([*args, "--starts", "1", "--json", str(sel), "--save-model", str(model)]) in (0, 3)
    assert json.loads(sel.read_text())["ignored_channels"] == ["Ps"]
    # the Python API's results say the same (the CLI writes their to_dict())
    api = rczone.predict(model, files / "bms.csv", columns=files / "map.toml")
    assert api.to_dict()["ignored_channels"] == ["Ps"] and api.ignored_channels == ("Ps",)
    for extra in ([], ["--horizons", "1,open"]):
        pred = files / "pred.json"
        assert main(["predict", str(model), str(files / "bms.csv"), *cmap, *extra, "--json", str(pred)]) == 0
        assert json.loads(pred.read_text())["ignored_channels"] == ["Ps"]
    capsys.readouterr()
