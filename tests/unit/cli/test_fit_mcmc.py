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


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
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


@pytest.mark.parametrize(
    ("options", "needle"),
    [
        (["--optimizer", "lbfgs"], "optimizer 'lbfgs' would be ignored"),
        (["--starts", "3"], "starts 3 would be ignored"),
        (["--optimizer", "powell", "--starts", "1"], "optimizer 'powell' and starts 1 would be ignored"),
    ],
)
def test_search_options_with_mcmc_are_refused_not_ignored(zone, capsys, options, needle) -> None:
    """The sampler starts its chains from one L-BFGS search: --optimizer and --starts have no meaning."""
    rc = main(
        ["fit", str(zone / "zone.csv"), "--model", str(zone / "zone.toml"), "--method", "mcmc", *options]
    )
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert rc == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert needle in lines[0] and "method 'mcmc' samples the posterior" in lines[0]


def test_sampler_options_without_mcmc_are_refused_not_ignored(zone, capsys) -> None:
    rc = main(
        ["fit", str(zone / "zone.csv"), "--model", str(zone / "zone.toml"), "--method", "ml", "--draws", "50"]
    )
    err = capsys.readouterr().err
    assert rc == 2 and "method 'ml' has no option 'draws'; it takes no options" in err
    assert len([ln for ln in err.splitlines() if ln.strip()]) == 1


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_fit_many_samples_with_the_manifest_sampler_table(zone, tmp_path, capsys) -> None:
    """fit-many hands the manifest's draws/tune/chains to the sampler (the McmcOptions of fit)."""
    manifest = tmp_path / "m.toml"
    manifest.write_text(
        f'model = "{(zone / "zone.toml").as_posix()}"\nmethods = ["mcmc"]\ndiagnose = false\n'
        "sampler = { draws = 20, tune = 30, chains = 2 }\n"
        f'[[zone]]\nid = "z"\ndata = "{(zone / "zone.csv").as_posix()}"\n'
    )
    rc = main(
        [
            "fit-many",
            str(manifest),
            "--out",
            str(tmp_path / "out"),
            "--workers",
            "1",
            "--backend",
            "processes",
        ]
    )
    capsys.readouterr()
    row = pd.read_parquet(tmp_path / "out" / "results.parquet").iloc[0]
    assert row["status"] == "ok", row["error"]
    assert (row["draws"], row["tune"], row["chains"]) == (20, 30, 2)
    # 40 draws cannot reach 100 effective draws per chain: flagged, as fit says (exit 3)
    assert rc == 3 and not row["trustworthy"] and row["min_ess_bulk"] < 200


def test_a_bad_sampler_table_in_fit_many_is_one_line_and_exit_2(zone, tmp_path, capsys) -> None:
    manifest = tmp_path / "m.toml"
    manifest.write_text('methods = ["mcmc"]\nsampler = { chain = 2 }\n[[zone]]\nid = "z"\ndata = "C"\n')
    rc = main(["fit-many", str(manifest), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2 and "has no option 'chain'; did you mean 'chains'" in err and "Traceback" not in err
