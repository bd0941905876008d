"""`rczone diagnose` and `rczone design` end to end: any model, the user's units, honest outcomes."""

import json

import numpy as np
import pandas as pd
import pytest

from rczone.cli.main import main
from rczone.models import model_to_toml
from rczone.simulation import simulate
from tests.unit.diagnostics.synthetic import family, heated, night

TRUE = {"Rw": 0.012, "Cr": 6e5}
FAR = {"Rw": 0.025, "Cr": 1.5e6}  # far from the construction values (8.4e-3, 4.5e5)
F_PER_C, CFM_PER_KG_S = 9 / 5, 60 / 1.2 / 0.3048**3


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("diag")
    night("forced", seed=1, theta=TRUE).to_csv(d / "forced.csv", index=False)
    night("closed-loop", seed=2, theta=TRUE).to_csv(d / "closed.csv", index=False)
    night("forced", seed=3, hours=8, theta=FAR).to_csv(d / "far.csv", index=False)
    both = family("TiTe+heater", ("Ti", "Te"))
    (d / "two.toml").write_text(model_to_toml(both))
    heated(both, "prbs", hours=48).to_csv(d / "heated.csv", index=False)
    return d


def _json(path):
    return json.loads(path.read_text())


def _one_error(capsys, rc, message):
    err = capsys.readouterr().err
    assert rc == 2, err
    assert message in err and "Traceback" not in err, err
    assert len([ln for ln in err.splitlines() if ln.startswith("error:")]) == 1


# ---- diagnose ------------------------------------------------------------------------------


def test_diagnose_flags_the_closed_loop_night(files, capsys):
    out = files / "diag.json"
    assert main(["diagnose", str(files / "closed.csv"), "--json", str(out)]) == 0
    d = _json(out)
    assert d["parameters"]["Rw"]["verdict"] in ("weak", "not identifiable")
    assert "stayed within" in d["parameters"]["Rw"]["reason"]
    assert d["operating_point"]["source"] == "model" and d["outputs"] == ["Ti"]


def test_diagnose_builtin_sets_with_report(tmp_path, capsys):
    """The closed-loop nights A and B cannot identify Rw, the forced night C can; C needs a quick fit."""
    verdicts, sources = {}, {}
    for name in "ABC":
        out = tmp_path / f"{name}.json"
        args = ["diagnose", name, "--json", str(out)] + (
            ["--report", str(tmp_path / "rep")] if name == "C" else []
        )
        assert main(args) == 0
        d = _json(out)
        verdicts[name] = d["parameters"]["Rw"]["verdict"]
        sources[name] = d["operating_point"]["source"]
    assert verdicts == {"A": "not identifiable", "B": "not identifiable", "C": "identifiable"}
    assert sources == {"A": "model", "B": "model", "C": "fit"}
    assert "operating point: a quick least-squares fit" in " ".join(capsys.readouterr().out.split())
    html = (tmp_path / "rep" / "report.html").read_text()
    assert "Operating point: a quick least-squares fit" in html and "<img" in html
    assert (tmp_path / "rep" / "data_overview.png").exists()


def test_diagnose_says_when_it_fitted_first_and_where(files, capsys):
    out = files / "far.json"
    assert main(["diagnose", str(files / "far.csv"), "--json", str(out)]) == 0
    op = _json(out)["operating_point"]
    assert op["source"] == "fit" and op["residual_K"] > op["threshold_K"] > op["fit_residual_K"]
    assert op["theta"]["Rw"] == pytest.approx(FAR["Rw"], rel=0.05)
    text = " ".join(capsys.readouterr().out.split())
    assert "operating point: a quick least-squares fit (the model's values miss the data" in text
    out2 = files / "far_model.json"
    assert main(["diagnose", str(files / "far.csv"), "--operating-point", "model", "--json", str(out2)]) == 0
    op2 = _json(out2)["operating_point"]
    assert op2["source"] == "model" and not op2["reproduces_data"]
    assert "as asked" in " ".join(capsys.readouterr().out.split())


def test_diagnose_any_model_and_every_output(files, capsys):
    out = files / "two.json"
    rep = files / "rep_two"
    args = ["diagnose", str(files / "heated.csv"), "--model", str(files / "two.toml"), "--json", str(out)]
    assert main([*args, "--report", str(rep)]) == 0
    html = (rep / "report.html").read_text()
    assert (
        "two.toml model" in html
        and "Operating point: the model" in html
        and (rep / "data_overview.png").exists()
    )
    d = _json(out)
    assert d["outputs"] == ["Ti", "Te"] and d["free"] == ["Ci", "Ce", "Rie", "Rea"]
    assert {v["verdict"] for v in d["parameters"].values()} == {"identifiable"}
    assert d["n_effective"] == pytest.approx(2 * 577 * 300 / 1800)
    assert "outputs analysed together: Ti, Te" in capsys.readouterr().out
    # a family model by name, one output, on the same file
    out1 = files / "one.json"
    assert main(["diagnose", str(files / "heated.csv"), "--model", "TiTe+heater", "--json", str(out1)]) == 0
    assert _json(out1)["outputs"] == ["Ti"] and _json(out1)["n_effective"] < d["n_effective"]


def test_diagnose_reads_the_users_units_through_a_column_map(files, tmp_path, capsys):
    """The same night in degF and cfm, through a column map: the same verdicts and numbers as in SI."""
    si = pd.read_csv(files / "forced.csv")
    log = pd.DataFrame(
        {
            "stamp": si["time"],
            "RM-T": si["Ti"] * F_PER_C + 32,
            "OA-T": si["To"] * F_PER_C + 32,
            "SA-T": si["Ts"] * F_PER_C + 32,
            "SA-F": si["m"] * CFM_PER_KG_S,
            "AVG-T": si["Tsd"] * F_PER_C + 32,
        }
    )
    log.to_csv(tmp_path / "log.csv", index=False)
    (tmp_path / "map.toml").write_text(
        '[time]\ncolumn = "stamp"\nformat = "seconds"\n[columns]\n'
        'Ti = { column = "RM-T", unit = "degF" }\nTo = { column = "OA-T", unit = "degF" }\n'
        'Ts = { column = "SA-T", unit = "degF" }\nm = { column = "SA-F", unit = "cfm" }\n'
        'Tsd = { column = "AVG-T", unit = "degF" }\nQ = { value = 50, unit = "W" }\n'
    )
    a, b = tmp_path / "si.json", tmp_path / "us.json"
    assert main(["diagnose", str(files / "forced.csv"), "--json", str(a)]) == 0
    rc = main(
        ["diagnose", str(tmp_path / "log.csv"), "--columns", str(tmp_path / "map.toml"), "--json", str(b)]
    )
    assert rc == 0
    da, db = _json(a), _json(b)
    for k in ("Cr", "Rw"):
        assert db["parameters"][k]["verdict"] == da["parameters"][k]["verdict"]
        assert db["expected_rel_se"][k] == pytest.approx(da["expected_rel_se"][k], rel=1e-6)


def test_diagnose_constants_and_settings(files, capsys):
    out = files / "const.json"
    rc = main(
        [
            "diagnose",
            str(files / "forced.csv"),
            "--const",
            "Q=120",
            "--model-error",
            "0.1",
            "--json",
            str(out),
        ]
    )
    assert rc == 0
    d = _json(out)
    assert d["settings"]["constants"] == {"Q": 120.0} and d["settings"]["model_error_K"] == 0.1
    assert "held constant: Q = 120" in capsys.readouterr().out


def test_diagnose_escapes_user_strings(files, tmp_path, capsys):
    path = tmp_path / "[bold]zone.csv"
    pd.read_csv(files / "closed.csv").to_csv(path, index=False)
    assert main(["diagnose", str(path)]) == 0
    assert "[bold]zone.csv" in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["{d}/forced.csv", "--operating-point", "sometimes"], "operating_point must be one of"),
        (["{d}/forced.csv", "--free", "Rww"], "did you mean 'Rw'"),
        (["{d}/forced.csv", "--free", "R1"], "'R1' is tied"),
        (["{d}/forced.csv", "--const", "Q"], "--const must be NAME=VALUE"),
        (["{d}/forced.csv", "--sigma", "0"], "must be > 0"),
        (["{d}/forced.csv", "--model", "TiTe+heatr"], "did you mean 'heater'"),
        (["{d}/heated.csv"], "missing column(s) 'Ts', 'm' that the model needs"),
        (["{d}/nothing.csv"], "does not exist"),
    ],
)
def test_diagnose_mistakes_exit_2_with_one_line(files, capsys, args, message):
    _one_error(capsys, main(["diagnose", *(a.replace("{d}", str(files)) for a in args)]), message)


# ---- design --------------------------------------------------------------------------------

AIR = ["--actuate", "Ts=12,35", "--actuate", "m=0.02,0.12", "--condition", "To=18", "--condition", "Tsd=22"]


def test_design_writes_a_playable_schedule(tmp_path, capsys):
    sched, js = tmp_path / "schedule.csv", tmp_path / "design.json"
    assert main(["design", *AIR, "--hours", "4", "--out", str(sched), "--json", str(js)]) == 0
    s = pd.read_csv(sched)
    assert list(s.columns) == ["time_s", "day", "clock", "Ts_setpoint_degC", "m_setpoint_kg_s"] and len(s) > 1
    assert s["clock"].iloc[0] == "18:00"  # default start: 6 pm
    assert s["Ts_setpoint_degC"].between(12, 35).all() and s["m_setpoint_kg_s"].between(0.02, 0.12).all()
    # every command is held at least the minimum hold time (30 min default)
    assert (s["time_s"].diff().dropna() >= 1800).all()
    d = _json(js)
    assert d["within_band"] and 17 <= d["predicted_min_degC"] < d["predicted_max_degC"] <= 28
    assert all(0 < v < 0.25 for v in d["expected_rel_se"].values())
    assert d["limits"]["ranges"] == {"Ts": [12.0, 35.0], "m": [0.02, 0.12]}


def test_design_in_degf_and_cfm_is_the_si_design_converted(tmp_path, capsys):
    si, us = tmp_path / "si.csv", tmp_path / "us.csv"
    short = ["--hours", "3", "--min-hold", "60"]
    assert main(["design", *AIR, *short, "--out", str(si)]) == 0
    flows = f"m={0.02 * CFM_PER_KG_S!r},{0.12 * CFM_PER_KG_S!r}"
    args = [
        "--actuate",
        "Ts=53.6,95",
        "--actuate",
        flows,
        "--condition",
        "To=64.4",
        "--condition",
        "Tsd=71.6",
    ]
    rc = main(["design", *args, "--units", "degF,cfm", "--limits", "62.6,82.4", *short, "--out", str(us)])
    assert rc == 0
    a, b = pd.read_csv(si), pd.read_csv(us)
    assert list(b.columns) == ["time_s", "day", "clock", "Ts_setpoint_degF", "m_setpoint_cfm"]
    np.testing.assert_array_equal(a["time_s"], b["time_s"])
    np.testing.assert_allclose(b["Ts_setpoint_degF"], a["Ts_setpoint_degC"] * F_PER_C + 32, rtol=1e-5)
    np.testing.assert_allclose(b["m_setpoint_cfm"], a["m_setpoint_kg_s"] * CFM_PER_KG_S, rtol=1e-5)
    assert "degF" in capsys.readouterr().out


def test_design_takes_units_time_zone_and_night_from_a_column_map(tmp_path, capsys):
    (tmp_path / "map.toml").write_text(
        '[time]\ntimezone = "America/New_York"\n[night]\nstart = "19:30"\nend = "07:00"\n[columns]\n'
        'Ti = { column = "RM-T", unit = "degF" }\nTs = { column = "SA-T", unit = "degF" }\n'
        'To = { column = "OA-T", unit = "degF" }\nm = { column = "SA-F", unit = "L/s" }\n'
        'Tsd = { column = "AVG-T", unit = "degF" }\n'
    )
    base = ["design", "--columns", str(tmp_path / "map.toml"), "--hours", "2", "--condition", "To=60"]
    base += ["--condition", "Tsd=72", "--actuate", "Ts=55,95", "--actuate", "m=20,100", "--limits", "63,82"]
    out = tmp_path / "a.csv"
    assert main([*base, "--out", str(out)]) == 0
    s = pd.read_csv(out)
    assert list(s.columns) == ["time_s", "day", "clock", "Ts_setpoint_degF", "m_setpoint_L_s"]
    assert s["clock"].iloc[0] == "19:30" and s["m_setpoint_L_s"].between(20, 100).all()
    out2 = tmp_path / "b.csv"
    assert main([*base, "--start", "2026-10-24T18:00", "--out", str(out2)]) == 0
    assert pd.read_csv(out2)["clock"].iloc[0] == "2026-10-24T18:00:00-04:00"


def test_design_for_a_heater_schedules_its_power(tmp_path, capsys):
    out, js = tmp_path / "heat.csv", tmp_path / "heat.json"
    args = ["design", "--model", "TiTe+heater", "--actuate", "Ph=0,2", "--units", "kW", "--condition", "To=5"]
    args += ["--limits", "15,30", "--hours", "24", "--min-hold", "120", "--out", str(out), "--json", str(js)]
    assert main(args) == 0
    s = pd.read_csv(out)
    assert list(s.columns) == ["time_s", "day", "clock", "Ph_setpoint_kW"]
    assert s["Ph_setpoint_kW"].isin([0.0, 0.5, 1.0, 1.5, 2.0]).all() and {0.0, 2.0} <= set(
        s["Ph_setpoint_kW"]
    )
    # independent check: play the CSV on the model from the start (mid-band, the envelope in equilibrium)
    zm = family("TiTe+heater")
    t = np.arange(0.0, 24 * 3600 + 1, 60.0)
    ph = 1000.0 * s["Ph_setpoint_kW"].to_numpy()[np.searchsorted(s["time_s"].to_numpy(), t, side="right") - 1]
    u = np.column_stack([np.full(t.size, 5.0), ph])
    ss = zm.state_space()
    A, B = ss.matrices(0.0)
    x0 = np.array([22.5, -(A[1, 0] * 22.5 + B[1] @ u[0]) / A[1, 1]])
    ti = simulate(ss, t, u, None, x0=x0).y[:, 0]
    d = _json(js)
    assert 15 <= ti.min() and ti.max() <= 30
    assert ti.min() == pytest.approx(d["predicted_min_degC"], abs=1e-6)
    assert ti.max() == pytest.approx(d["predicted_max_degC"], abs=1e-6)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "give the inputs the test may drive and their ranges with --actuate"),
        (["--actuate", "Ts=55,95", "--actuate", "m=0.02,0.12"], "the values look like degF"),
        (["--actuate", "Ts=12,35", "--actuate", "m=40,250"], "--units (e.g. --units cfm)"),
        ([*AIR, "--limits", "65,78"], "the values look like degF"),
        ([*AIR, "--limits", "25,20"], "band must be (low, high) with low < high"),
        ([*AIR, "--limits", "cold"], "--limits must be two numbers"),
        (
            [*AIR[:4], "--condition", "To=30", "--condition", "Tsd=35", "--limits", "17,20"],
            "cannot stay inside",
        ),
        (AIR[:4], "conditions lack To, Tsd"),
        (["--actuate", "To=0,30"], "'To' is a boundary temperature"),
        (["--actuate", "Ts=12"], "--actuate must be NAME=LOW,HIGH"),
        (["--actuate", "Ts=12,35", "--actuate", "Ts=13,30"], "gives 'Ts' twice"),
        (["--actuate", "Tz=12,35"], "not an input of model"),
        ([*AIR, "--units", "degK"], "did you mean"),
        ([*AIR, "--units", "degF,degC"], "two temperature units"),
        ([*AIR, "--start", "25:00"], "--start must be a time of day"),
        ([*AIR, "--initial", "30"], "outside the band"),
        ([*AIR, "--free", "Rx"], "unknown free parameter 'Rx'"),
    ],
)
def test_design_mistakes_exit_2_with_one_line(tmp_path, capsys, args, message):
    _one_error(capsys, main(["design", *args, "--out", str(tmp_path / "s.csv")]), message)
    assert not (tmp_path / "s.csv").exists()


def test_a_parameter_at_its_bound_is_never_identifiable(tmp_path, capsys):
    """The data were made with Ci = 2e7 J/K; the model file caps Ci at 3e6 J/K.

    The quick fit pins Ci at that bound. Local sensitivities there say nothing about where the data
    want Ci, so the verdict is "not identifiable" with the bound named, and the operating point says
    it is degenerate (issue: an office's Ci at the family's former 1e9 J/K bound was called identifiable).
    """
    zm = family("TiTe+heater", theta={"Ci": 2e7})
    heated(zm, "prbs", hours=48).to_csv(tmp_path / "heated.csv", index=False)
    toml = model_to_toml(family("TiTe+heater"))
    capped = toml.replace("bounds = [10000.0, 10000000000.0]", "bounds = [10000.0, 3000000.0]")
    assert capped != toml
    (tmp_path / "capped.toml").write_text(capped)
    out = tmp_path / "d.json"
    args = ["diagnose", str(tmp_path / "heated.csv"), "--model", str(tmp_path / "capped.toml")]
    assert main([*args, "--json", str(out)]) == 0
    d = _json(out)
    op = d["operating_point"]
    assert op["source"] == "fit" and op["theta"]["Ci"] == pytest.approx(3e6, rel=0.01)
    assert op["at_bound"] == {"Ci": "upper"}
    assert "Ci at its upper bound" in op["reason"] and "push it beyond" in op["reason"]
    ci = d["parameters"]["Ci"]
    assert ci["verdict"] == "not identifiable" and ci["at_bound"] == "upper"
    assert "upper bound" in ci["reason"] and "widen the bounds" in ci["advice"]
    # the other parameters are not at a bound and keep verdicts from their own evidence
    assert all(d["parameters"][n]["at_bound"] is None for n in ("Ce", "Rie", "Rea"))


def test_diagnose_hold_is_the_one_asked_for_else_the_fitted_models(tmp_path, capsys):
    """Half-hourly data simulated with a linear (FOH) heater: --hold foh reproduces them, zoh does not.

    Truth by construction: the data are the FOH simulation plus 0.02 K of noise, so at the true
    values the FOH residual is the noise level and the ZOH one is larger. A model fitted with FOH
    (provenance ``hold``) is diagnosed with FOH unless told otherwise.
    """
    from rczone.simulation import steady_state

    zm = family("TiTe+heater")
    frame = heated(zm, "prbs", hours=96, dt=1800.0, noise=0.0)
    u = frame[list(zm.network.input_names)].to_numpy()
    t = frame["time"].to_numpy()
    ss = zm.state_space()
    y = simulate(ss, t, u, x0=steady_state(ss, u[0], 0.0), hold="foh").y[:, 0]
    frame["Ti"] = y + 0.02 * np.random.default_rng(5).standard_normal(t.size)
    frame.to_csv(tmp_path / "d.csv", index=False)
    zm.with_values({}, hold="foh").save(tmp_path / "foh.json")
    zm.save(tmp_path / "plain.json")
    runs = {}
    for name, model, extra in (
        ("zoh", "plain.json", ["--hold", "zoh"]),
        ("plain", "plain.json", []),
        ("foh", "plain.json", ["--hold", "FOH"]),
        ("fitted", "foh.json", []),
        ("fitted-zoh", "foh.json", ["--hold", "zoh"]),
    ):
        out = tmp_path / f"diagnosed-{name}.json"
        args = ["diagnose", str(tmp_path / "d.csv"), "--model", str(tmp_path / model), "--json", str(out)]
        assert main([*args, "--operating-point", "model", *extra]) == 0, capsys.readouterr().err
        runs[name] = _json(out)
    res = {k: v["operating_point"]["residual_K"] for k, v in runs.items()}
    assert res["foh"] == pytest.approx(0.02, rel=0.25) and res["zoh"] > 2 * res["foh"]
    assert [runs[k]["settings"]["hold"] for k in runs] == ["zoh", "zoh", "foh", "foh", "zoh"]
    se = {k: v["expected_rel_se"] for k, v in runs.items()}
    assert se["plain"] == se["zoh"] == se["fitted-zoh"] and se["fitted"] == se["foh"] != se["zoh"]
    assert "inputs between samples: linear (foh)" in " ".join(capsys.readouterr().out.split())
    rc = main(
        ["diagnose", str(tmp_path / "d.csv"), "--model", str(tmp_path / "plain.json"), "--hold", "linear"]
    )
    _one_error(capsys, rc, "hold must be one of zoh, foh")
