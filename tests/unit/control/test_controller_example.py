"""docs/extending.md's controller, installed from a temporary package, runs through the CLI and the API."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.unit.entrypoints import install

ROOT = Path(__file__).resolve().parents[3]
EXAMPLE = ROOT / "docs" / "examples" / "halfway_controller.py"


def _installed(tmp_path: Path) -> dict:
    """The example on a path with an entry point of the group ``rczone.controllers``, as pip leaves one."""
    site = install(
        tmp_path / "site",
        "halfway_controller",
        EXAMPLE.read_text(),
        "rczone.controllers",
        "halfway = halfway_controller:factory",
    )
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT / "src"), env.get("PYTHONPATH", "")])
    return env


_API = """
from rczone.control.closedloop import closed_loop_test
from rczone.emulators.registry import make_plant
r = closed_loop_test(make_plant("virtual", season="winter", days=0.1, seed=2), "halfway")
print(r.setup["controller"], r.scores["constraint_violations"])
"""


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_the_example_controller_runs_as_an_installed_plug_in(tmp_path):
    env = _installed(tmp_path)
    out = tmp_path / "s.json"
    cli = subprocess.run(
        [
            sys.executable,
            "-m",
            "rczone.cli",
            "control-test",
            "--controller",
            "halfway",
            "--days",
            "0.1",
            "--scenario",
            "winter",
            "--json",
            str(out),
        ],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert cli.returncode == 0, cli.stderr
    scores = json.loads(out.read_text())
    assert scores["setup"]["controller"] == "halfway" and scores["constraint_violations"] == 0
    api = subprocess.run(
        [sys.executable, "-c", _API], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert api.returncode == 0 and api.stdout.split() == ["halfway", "0"], api.stderr
