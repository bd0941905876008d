"""Estimation methods as plug-ins: the registry, a method's own options, a third party's method.

The third party's method is the complete example of docs/extending.md (a Huber-loss output-error
estimator), registered in Python and, in a subprocess, found through an entry point of a package
on the path, then run by ``rczone fit --method huber`` and ``rczone.fit(method="huber")``.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rczone.errors import ParameterError
from rczone.estimation import Dataset, fit
from rczone.estimation.methods import (
    REGISTRY,
    Method,
    method_names,
    method_of,
    register_method,
    unregister_method,
)
from rczone.estimation.methods.map import MapOptions
from rczone.estimation.methods.mcmc import McmcOptions
from rczone.estimation.settings import FitSettings
from rczone.simulation import simulate

from .nets import NET1

ROOT = Path(__file__).resolve().parents[3]
EXAMPLE = ROOT / "docs" / "examples" / "huber_method.py"
TRUTH = {"Cr": 1e6, "R": 0.01}


def load_example():
    spec = importlib.util.spec_from_file_location("huber_method", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve the module's annotations through it
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def huber():
    module = load_example()
    register_method(module.METHOD)
    yield module
    unregister_method("huber")


def spoiled(n: int = 193) -> tuple[Dataset, np.ndarray]:
    """Two days of NET1 at the truth, 0.02 K of noise, and eight samples spoiled by +4 K (a sensor glitch)."""
    rng = np.random.default_rng(3)
    t = np.arange(n) * 900.0
    h = t / 3600.0
    u = np.column_stack([10 + 5 * np.sin(2 * np.pi * h / 24), 500.0 * (h % 6 < 3)])
    y = simulate(NET1.state_space(), t, u).y + 0.02 * rng.standard_normal((n, 1))
    bad = rng.choice(np.arange(20, n), 8, replace=False)
    y[bad] += 4.0
    return Dataset(t, u, np.zeros((n, 0)), y, NET1.input_names, (), NET1.outputs), bad


def test_a_registered_method_runs_through_fit_with_its_own_options(huber):
    data, _ = spoiled()
    start = {"Cr": 2e6, "R": 0.02}
    robust = fit(NET1, data, ["Cr", "R"], method="huber", options={"scale_K": 0.1}, start=start)
    plain = fit(NET1, data, ["Cr", "R"], method="ls", n_starts=1, start=start)
    err = {r.method: abs(np.log(r.estimates["R"] / TRUTH["R"])) for r in (robust, plain)}
    # the glitches pull least squares off the truth; the Huber loss barely notices them
    assert err["huber"] < 0.02 and err["huber"] < 0.5 * err["ls"], err
    assert robust.method == "huber" and robust.options == {"scale_K": 0.1}
    assert robust.to_dict()["method_options"] == {"scale_K": 0.1}
    assert "huber" in method_names()


def test_the_method_record_is_checked():
    ok = {
        "name": "x",
        "title": "t",
        "kernel": "ls",
        "stochastic": False,
        "objective": "o",
        "rmse_kind": "open-loop",
        "run": lambda *a: None,
    }
    Method(**ok)
    for change, match in (
        ({"kernel": "lsq"}, "kernel must be one of ls, ml"),
        ({"search": "anneal"}, "search must be one of"),
        ({"name": "two words"}, "ASCII identifier"),
        ({"options": dict}, "MethodOptions subclass"),
        ({"run": 3}, "run must be callable"),
    ):
        with pytest.raises(ParameterError, match=match):
            Method(**{**ok, **change})


def test_the_registry_protects_built_in_names_and_refuses_a_second_method_of_a_name(huber):
    with pytest.raises(ParameterError, match="'ls' is built in"):
        register_method(dataclasses.replace(huber.METHOD, name="ls"))
    with pytest.raises(ParameterError, match="registered already"):
        register_method(dataclasses.replace(huber.METHOD))
    with pytest.raises(ParameterError, match="built in and cannot be removed"):
        unregister_method("ml")
    with pytest.raises(ParameterError, match="takes a rczone Method"):
        register_method("huber")
    with pytest.raises(ParameterError, match="unknown method 'hubr'; did you mean 'huber'"):
        method_of("hubr")
    assert tuple(REGISTRY)[:4] == ("ls", "ml", "map", "mcmc")


@pytest.mark.parametrize(
    ("method", "given", "match"),
    [
        ("ml", {"draws": 10}, "method 'ml' has no option 'draws'; it takes no options"),
        ("mcmc", {"draw": 10}, "did you mean 'draws'"),
        ("mcmc", {"draws": 5}, "option draws must be an integer from 10"),
        ("mcmc", {"chains": True}, "option chains must be an integer"),
        ("map", {"prior_spread": 0.0}, "option prior_spread must be a finite number > 0"),
        ("map", {"correlation_time_s": float("nan")}, "correlation_time_s must be a finite number"),
        ("map", McmcOptions(), "takes MapOptions, got McmcOptions"),
        ("map", [("prior_spread", 1)], "must be a mapping"),
    ],
)
def test_options_a_method_does_not_have_or_refuses_are_one_error(method, given, match):
    with pytest.raises(ParameterError, match=match):
        FitSettings(method=method, options=given)


def test_options_are_read_from_the_command_line_text_by_their_declared_types():
    assert McmcOptions.parse(["draws=500", "chains=2"], "mcmc") == McmcOptions(draws=500, chains=2)
    assert MapOptions.parse(["prior_spread=0.25"], "map") == MapOptions(prior_spread=0.25)
    for items, match in (
        (["draws"], "must be NAME=VALUE"),
        (["draws=5e2"], "'5e2' is not a valid int"),
        (["draws=٣٠٠"], "is not a valid int"),
        (["prior_spread=inf"], "is not a valid float"),
        (["drawz=3"], "did you mean 'draws'"),
    ):
        with pytest.raises(ParameterError, match=match):
            (MapOptions if "prior" in items[0] else McmcOptions).parse(items, "m")


def test_changing_the_method_of_settings_takes_the_new_method_s_defaults():
    s = FitSettings(method="mcmc", options={"draws": 100})
    assert FitSettings.of(s, method="map").options == MapOptions()
    with pytest.raises(ParameterError, match="unexpected keyword 'metod'; did you mean 'method'"):
        FitSettings.of(s, metod="ml")


def test_a_method_returning_something_else_than_a_fit_result_is_refused(huber):
    bad = dataclasses.replace(huber.METHOD, name="broken", run=lambda p, o, r: {"Cr": 1.0})
    register_method(bad)
    try:
        with pytest.raises(ParameterError, match="method 'broken' returned a dict, not a FitResult"):
            fit(NET1, spoiled()[0], ["Cr", "R"], method="broken")
    finally:
        unregister_method("broken")


def _installed(tmp_path: Path, module_text: str, entry: str = "huber = huber_method:METHOD") -> dict:
    """A package on a path with an entry point of the group ``rczone.methods``, as pip leaves one."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "huber_method.py").write_text(module_text)
    info = site / "rczone_huber-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: rczone-huber\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[rczone.methods]\n{entry}\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT / "src"), env.get("PYTHONPATH", "")])
    return env


def _rczone(args: list[str], env: dict, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "rczone.cli", *args],
        env=env,
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_an_installed_plug_in_is_found_by_the_command_line_and_the_api(tmp_path):
    env = _installed(tmp_path, EXAMPLE.read_text())
    listed = _rczone(["methods"], env, tmp_path)
    assert listed.returncode == 0 and "huber" in listed.stdout and "scale_K" in listed.stdout, listed.stderr
    run = _rczone(
        [
            "fit",
            "C",
            "--starts",
            "1",
            "--method",
            "huber",
            "--option",
            "scale_K=0.2",
            "--no-profiles",
            "--json",
            "-",
        ],
        env,
        tmp_path,
    )
    assert run.returncode in (0, 3), run.stderr
    out = json.loads(run.stdout)
    assert out["method"] == "huber" and out["method_options"] == {"scale_K": 0.2}
    assert set(out["parameters"]) >= {"Cr", "Rw"}
    api = subprocess.run(
        [
            sys.executable,
            "-c",
            "import rczone; c = rczone.fit('second-order-paper', 'C', method='huber', checks=False,"
            " options={'scale_K': 0.2}); print(c.result.method, c.result.options['scale_K'])",
        ],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert api.returncode == 0 and api.stdout.split() == ["huber", "0.2"], api.stderr


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_a_broken_plug_in_is_one_line_naming_it(tmp_path):
    env = _installed(tmp_path, "raise ImportError('no scipy here')\n")
    run = _rczone(["fit", "C", "--method", "huber"], env, tmp_path)
    assert run.returncode == 2
    assert "the method plug-in 'huber' (huber_method:METHOD) failed to load" in run.stderr
    assert "Traceback" not in run.stderr and len(run.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--method", "ml", "--draws", "10"], "method 'ml' has no option 'draws'"),
        (["--method", "mcmc", "--option", "draws=five"], "option draws: 'five' is not a valid int"),
        (["--method", "map", "--option", "prior=1"], "did you mean 'prior_spread'"),
    ],
)
def test_bad_method_options_on_the_command_line_are_one_line_and_exit_2(args, match, capsys):
    from rczone.cli.main import main

    rc = main(["fit", "C", *args])
    err = capsys.readouterr().err
    assert rc == 2 and match in err and len(err.strip().splitlines()) == 1, err
