"""``rczone fit --method mcmc`` end to end on a short run: console, JSON, report, saved draws, predict."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from rczone.cli.main import main
from rczone.models import read_model_file
from rczone.simulation import simulate

MODEL = """
name = "sampled zone"
boundaries = ["To"]
resistors = [["Ti", "Te", "Rie"], ["Te", "To", "Rea"]]

[nodes]
Ti = "Ci"
Te = "Ce"

[heat_inputs]
Ph = "Ti"

[parameters]
Ci = { value = 2.0, unit = "MJ/K", prior = { dist = "lognormal", median = 2.0, sigma = 0.5 } }
Ce = { value = 20.0, unit = "MJ/K" }
Rie = { value = 2.0, unit = "K/kW", prior = { dist = "normal", mean = 2.0, sigma = 0.5 } }
Rea = { value = 10.0, unit = "K/kW" }
"""


@pytest.fixture(scope="module")
def zone(tmp_path_factory):
    """Two days at 10 min from the model at its declared values, a PRBS heater, 0.02 K noise."""
    d = tmp_path_factory.mktemp("mcmc")
    (d / "zone.toml").write_text(MODEL)
    zm = read_model_file(d / "zone.toml")
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 2 * 86400.0, 600.0)
    to = 5 + 3 * np.sin(2 * np.pi * t / 86400.0)
    ph = np.repeat(rng.choice([0.0, 2000.0], t.size // 12 + 1), 12)[: t.size]
    y = simulate(zm.state_space(), t, np.column_stack([to, ph]), x0=np.array([19.0, 12.0])).y[:, 0]
    frame = pd.DataFrame({"time": t, "Ti": y + rng.normal(0, 0.02, t.size), "To": to, "Ph": ph})
    frame.to_csv(d / "zone.csv", index=False)
    return d


def test_a_short_run_writes_everything_and_exits_3_because_it_is_not_converged(zone, capsys) -> None:
    out = zone / "fit.json"
    args = ["fit", str(zone / "zone.csv"), "--model", str(zone / "zone.toml"), "--method", "mcmc"]
    args += ["--draws", "30", "--tune", "40", "--chains", "2", "--json", str(out), "--no-profiles"]
    args += ["--save-model", str(zone / "fitted.json"), "--report", str(zone / "rep")]
    rc = main(args)
    text = " ".join(capsys.readouterr().out.split())
    d = json.loads(out.read_text())
    assert rc == 3 and d["exit_code"] == 3 and not d["trustworthy"]
    assert "ess" in d["issues"] and not d["posterior"]["converged"]
    assert d["posterior"]["chains"] == 2 and d["posterior"]["draws"] == 30
    assert d["posterior"]["prior"]["Ci"] == {"dist": "lognormal", "median": 2e6, "sigma": 0.5}
    assert d["posterior"]["prior"]["Rea"] is None  # flat in log Rea within the bounds
    assert "posterior" in text and "R-hat" in text and "not converged" in text
    assert "effective sample size" in text
    assert (zone / "rep" / "trace.png").exists() and (zone / "rep" / "pairs.png").exists()
    assert "Posterior draws" in (zone / "rep" / "report.html").read_text()
    # the saved model carries draws: predict pushes them through the filter
    pj = zone / "pred.json"
    # on its own calibration data with no warm-up, the envelope's start is estimated from these data
    # (the default would start it at the steady state, 7 K from where the data were simulated)
    args = ["predict", str(zone / "fitted.json"), str(zone / "zone.csv"), "--json", str(pj)]
    rc = main([*args, "--initial-state", "estimated"])
    capsys.readouterr()
    p = json.loads(pj.read_text())
    assert rc == 0 and "60 posterior draws" in p["band"]
    assert p["coverage_2sigma"]["Ti"] > 0.8


@pytest.mark.parametrize(("flag", "value"), [("--draws", "3"), ("--chains", "0"), ("--tune", "-2")])
def test_bad_sampler_options_are_one_line_and_exit_2(zone, capsys, flag, value) -> None:
    rc = main(
        ["fit", str(zone / "zone.csv"), "--model", str(zone / "zone.toml"), "--method", "mcmc", flag, value]
    )
    err = capsys.readouterr().err
    assert rc == 2
    assert flag.lstrip("-") in err and "Traceback" not in err
