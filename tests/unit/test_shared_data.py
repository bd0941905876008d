"""A missing shared reference skips a local run but fails a CI run (tests/shared_data.py)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.shared_data import require

TESTS = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("value", ["true", "True", "1", "yes"])
def test_a_missing_reference_fails_in_ci(monkeypatch, tmp_path, value) -> None:
    monkeypatch.setenv("CI", value)
    with pytest.raises(pytest.fail.Exception, match="CI=true"):
        require(tmp_path / "absent.csv")


@pytest.mark.parametrize("value", [None, "", "false", "0"])
def test_a_missing_reference_skips_outside_ci(monkeypatch, tmp_path, value) -> None:
    if value is None:
        monkeypatch.delenv("CI", raising=False)
    else:
        monkeypatch.setenv("CI", value)
    with pytest.raises(pytest.skip.Exception, match=r"absent\.csv"):
        require(tmp_path / "absent.csv")


def test_a_present_reference_runs_in_ci_and_only_missing_paths_are_named(monkeypatch, tmp_path) -> None:
    monkeypatch.setenv("CI", "true")
    present = tmp_path / "here.csv"
    present.write_text("x\n")
    require(present, tmp_path)  # neither skips nor fails
    with pytest.raises(pytest.fail.Exception) as err:
        require(present, tmp_path / "gone")
    assert "gone" in str(err.value) and "here.csv" not in str(err.value)


def test_no_test_skips_on_shared_data_by_itself() -> None:
    """Every test that reads SHARED goes through require(): a skipif or skip of its own would vanish in CI."""
    offenders = []
    for path in TESTS.rglob("test_*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
        if "SHARED" not in names:
            continue
        attrs = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
        if attrs & {"skip", "skipif"}:
            offenders.append(path.name)
    assert offenders == []
