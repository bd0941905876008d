"""The Python API is the command line in Python: same defaults, same printout, same JSON."""

from __future__ import annotations

import inspect
import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import rczone
from rczone.cli.main import main
from rczone.files.atomic import _jsonable

#: A width both the console and summary() use (rich reads COLUMNS).
WIDTH = 100
FAST = ["--starts", "1", "--no-profiles"]


def _as_written(payload: dict) -> dict:
    """What a dict becomes once written as JSON by the command line."""
    return json.loads(json.dumps(_jsonable(payload), allow_nan=False))


@pytest.fixture(scope="module")
def night_c_fit():
    return rczone.fit("second-order-paper", "C", n_starts=1, profiles=False)


def test_fit_to_dict_is_what_the_cli_writes_and_summary_what_it_prints(
    tmp_path, capsys, monkeypatch, night_c_fit
):
    monkeypatch.setenv("COLUMNS", str(WIDTH))
    out = tmp_path / "fit.json"
    rc = main(["fit", "C", "--json", str(out), *FAST])
    printed = capsys.readouterr().out
    assert rc == night_c_fit.exit_code
    assert json.loads(out.read_text()) == _as_written(night_c_fit.to_dict())
    assert printed == night_c_fit.summary(width=WIDTH)


def test_a_multi_output_fit_is_the_same_from_python_and_the_cli(tmp_path, capsys, monkeypatch):
    from tests.unit.cli.test_multi_output_cli import MODEL, _simulate

    monkeypatch.setenv("COLUMNS", str(WIDTH))
    (tmp_path / "two.toml").write_text(MODEL)
    _simulate(n=480).to_csv(tmp_path / "two.csv", index=False)
    out = tmp_path / "fit.json"
    main(["fit", str(tmp_path / "two.csv"), "--model", str(tmp_path / "two.toml"), "--json", str(out), *FAST])
    printed = capsys.readouterr().out
    cal = rczone.fit(tmp_path / "two.toml", tmp_path / "two.csv", n_starts=1, profiles=False)
    assert json.loads(out.read_text()) == _as_written(cal.to_dict())
    assert printed == cal.summary(width=WIDTH)
    assert "open loop per output" in printed  # both outputs are reported


def test_predict_to_dict_is_what_the_cli_writes(tmp_path, capsys, monkeypatch, night_c_fit):
    monkeypatch.setenv("COLUMNS", str(WIDTH))
    night_c_fit.model.save(tmp_path / "zone.json")
    out = tmp_path / "pred.json"
    assert main(["predict", str(tmp_path / "zone.json"), "B", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    pred = rczone.predict(rczone.load_model(tmp_path / "zone.json"), "B")
    assert json.loads(out.read_text()) == _as_written(pred.to_dict())
    assert printed == pred.summary(width=WIDTH)


def test_api_defaults_are_the_cli_defaults() -> None:
    from rczone.cli.commands_fit import fit as cli_fit

    api = inspect.signature(rczone.fit).parameters
    cli = inspect.signature(cli_fit).parameters
    same = {
        "method": "method",
        "optimizer": "optimizer",
        "seed": "seed",
        "noise": "noise",
        "profiles": "profiles",
    }
    for a, c in same.items():
        assert api[a].default == cli[c].default, a
    assert cli["starts"].default == "auto" and api["n_starts"].default is None  # auto: the global search
    # options after the data are keyword-only
    for f in (rczone.fit, rczone.predict, rczone.load_data):
        params = list(inspect.signature(f).parameters.values())
        assert all(p.kind is p.KEYWORD_ONLY for p in params[2 if f is not rczone.load_data else 1 :]), f


def test_frames_carry_the_data_time_stamps_in_their_time_zone(tmp_path, night_c_fit) -> None:
    c = rczone.load_data("C")
    local = pd.date_range("2024-03-01 20:00", periods=len(c), freq="1min")
    c.drop(columns=["time"]).assign(Timestamp=local.strftime("%Y-%m-%d %H:%M:%S")).to_csv(
        tmp_path / "log.csv", index=False
    )
    channels = {"Ti": "degC", "To": "degC", "Ts": "degC", "m": "kg/s", "Q": "W", "Tsd": "degC"}
    (tmp_path / "map.toml").write_text(
        '[time]\ncolumn = "Timestamp"\ntimezone = "America/New_York"\n[columns]\n'
        + "".join(f'{k} = {{ column = "{k}", unit = "{u}" }}\n' for k, u in channels.items())
    )
    data = rczone.load_data(tmp_path / "log.csv", columns=tmp_path / "map.toml")
    assert str(data.index.tz) == "America/New_York"
    # the first stamp is 20:00 local, 01:00 UTC the next day (EST, UTC-5)
    assert data.index[0] == pd.Timestamp("2024-03-02 01:00", tz="UTC")
    pred = rczone.predict(night_c_fit.model, data)
    frame = pred.to_frame()
    assert isinstance(frame.index, pd.DatetimeIndex) and str(frame.index.tz) == "America/New_York"
    assert frame.index[0].hour == 20 and (frame.index == data.index[: len(frame)]).all()
    np.testing.assert_array_equal(frame["Ti_measured"].to_numpy(), data["Ti"].to_numpy()[: len(frame)])


def test_results_have_a_short_repr_and_html(night_c_fit) -> None:
    for r in (night_c_fit, night_c_fit.result):
        assert len(repr(r)) < 200 and "\n" not in repr(r)
        html = r._repr_html_()
        assert "<pre>" in html and "<table" in html and "Rw" in html


def test_import_rczone_loads_no_numerical_library() -> None:
    code = "import sys, rczone; print(sorted(m for m in ('numpy', 'numba', 'pandas', 'scipy') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_every_exported_name_resolves() -> None:
    for name in rczone.__all__:
        assert getattr(rczone, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'fitt'"):
        rczone.fitt  # noqa: B018


def test_diagnose_to_dict_is_what_the_cli_writes(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", str(WIDTH))
    out = tmp_path / "diag.json"
    assert main(["diagnose", "A", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    rep = rczone.diagnose("second-order-paper", "A")
    assert json.loads(out.read_text()) == _as_written(rep.to_dict())
    assert printed == rep.summary(width=WIDTH)
    frame = rep.to_frame()
    assert frame.loc["Rw", "unit"] == "K/W" and frame.loc["Cr", "unit"] == "J/K"  # units in the table
    assert len(repr(rep)) < 200


def test_select_to_dict_is_what_the_cli_writes(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", str(WIDTH))
    rczone.load_data("C").iloc[:240].to_csv(tmp_path / "short.csv", index=False)
    out = tmp_path / "sel.json"
    args = ["select", str(tmp_path / "short.csv"), "--model", "second-order-paper", "--model", "Ti+air+gain"]
    rc = main([*args, "--starts", "1", "--json", str(out)])
    printed = capsys.readouterr().out
    sel = rczone.select_models(["second-order-paper", "Ti+air+gain"], tmp_path / "short.csv", n_starts=1)
    assert rc == sel.exit_code
    assert json.loads(out.read_text()) == _as_written(sel.to_dict())
    assert printed == sel.summary(width=WIDTH)
    assert sel.selected in repr(sel) and len(repr(sel)) < 200


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "lsq"}, r"unknown method 'lsq'; did you mean 'ls'"),
        ({"optimizer": "bfgs"}, "optimizer must be 'auto' or one of"),
        ({"noise": "some"}, "noise must be one of measured, all"),
        ({"n_starts": 0}, "n_starts must be None"),
        ({"free": "Cr"}, "free must be a sequence of names"),
        ({"seed": 1.5}, "seed must be an integer"),
    ],
)
def test_bad_fit_options_are_one_clear_error_before_any_work(kwargs, match) -> None:
    with pytest.raises(rczone.ParameterError, match=match):
        rczone.fit("second-order-paper", "C", **kwargs)


def test_data_of_the_wrong_kind_is_a_data_error() -> None:
    with pytest.raises(rczone.DataError, match="data must be a DataFrame, a file or a built-in"):
        rczone.fit("second-order-paper", 42)
    with pytest.raises(rczone.DataError, match="does not exist"):
        rczone.predict("second-order-paper", "no-such-file.csv")


def test_check_on_other_data_enters_the_verdict() -> None:
    cal = rczone.fit("second-order-paper", "C", method="ls", n_starts=1, profiles=False, check_on=["A"])
    assert "other data" in cal.verdict.checked and "A" in cal.checks["other_fits"]


def test_data_sources_are_one_protocol(tmp_path) -> None:
    from rczone.workflow.datasource import DataSource, data_source

    rczone.load_data("C").iloc[:120].to_csv(tmp_path / "c.csv", index=False)
    log, night = data_source(tmp_path / "c.csv"), data_source("C")
    virtual = rczone.VirtualNight("autumn", "forced", 3)
    assert all(isinstance(s, DataSource) for s in (log, night, virtual))
    assert (log.label, log.files) == ("c.csv", (str(tmp_path / "c.csv"),))
    assert (night.label, night.files) == ("C", ()) and virtual.label == "virtual:autumn/forced/3"
    # a source and the name of one give the same frame, titled by the source
    by_source = rczone.load_data(rczone.TrendLog(str(tmp_path / "c.csv")))
    pd.testing.assert_frame_equal(by_source, rczone.load_data(tmp_path / "c.csv"))
    assert by_source.attrs["name"] == "c.csv"
    with pytest.raises(rczone.DataError, match="built-in data sets: A, B, C"):
        data_source("D")


def test_design_test_is_the_command_in_si_units(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", str(WIDTH))
    out, schedule = tmp_path / "d.json", tmp_path / "s.csv"
    args = ["design", "--actuate", "Ts=13,35", "--actuate", "m=0.02,0.12", "--condition", "To=16"]
    assert (
        main([*args, "--condition", "Tsd=22", "--hours", "2", "-o", str(schedule), "--json", str(out)]) == 0
    )
    printed = capsys.readouterr().out
    res = rczone.design_test(
        "second-order-paper",
        actuate={"Ts": (13, 35), "m": (0.02, 0.12)},
        conditions={"To": 16, "Tsd": 22},
        hours=2,
    )
    assert json.loads(out.read_text()) == _as_written(res.to_dict())
    assert printed == res.summary(width=WIDTH) + f"schedule written to {schedule}\n"
    pd.testing.assert_frame_equal(res.to_frame(), pd.read_csv(schedule), check_dtype=False)
