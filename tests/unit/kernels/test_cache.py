"""Where numba's cache of rczone's kernels goes: beside the package when writable, else the user's cache folder."""

from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from numba.core import config

from rczone.kernels import cache

SRC = Path(cache.__file__).resolve().parents[2]  # the folder that holds the package rczone

# run in a new process from a copy of the package: compile one small kernel, report where it went
CHILD = """
import json, os, sys
import numpy as np
import rczone.kernels.problem as problem
t = np.arange(4.0); e = np.ones((4, 1))
problem.trapezoid(t, e, np.empty((4, 1, 0)), np.zeros(0), np.zeros(0))
print(json.dumps({
    "variable": os.environ.get("NUMBA_CACHE_DIR"),
    "module": problem.__file__,
    "path": problem.trapezoid._cache._cache_path,
    "hits": sum(problem.trapezoid.stats.cache_hits.values()),
    "misses": sum(problem.trapezoid.stats.cache_misses.values()),
}))
"""


def _read_only(root: Path) -> None:
    for path in [root, *root.rglob("*")]:
        mode = path.stat().st_mode
        path.chmod(mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))


def _writable_again(root: Path) -> None:
    for path in [root, *root.rglob("*")]:
        path.chmod(path.stat().st_mode | stat.S_IWUSR)


def _child(site: Path, home: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != cache.CACHE_VARIABLE}
    env.update(
        PYTHONPATH=str(site), HOME=str(home), XDG_CACHE_HOME=str(home / "cache"), LOCALAPPDATA=str(home)
    )
    proc = subprocess.run([sys.executable, "-c", CHILD], env=env, cwd=home, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
def test_a_read_only_installed_copy_caches_in_the_users_folder(tmp_path):
    site, home = tmp_path / "site", tmp_path / "home"
    home.mkdir()
    shutil.copytree(SRC / "rczone", site / "rczone", ignore=shutil.ignore_patterns("__pycache__", "*.nb*"))
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        # a privileged user writes through permission bits; a file where numba's folder would be
        # is what a read-only file system is for everybody
        (site / "rczone" / "kernels" / "__pycache__").write_text("")
    _read_only(site)
    try:
        first = _child(site, home)
        second = _child(site, home)
        written = [p for p in (site / "rczone").rglob("*.nb*")]
    finally:
        _writable_again(site)
    assert Path(first["module"]).is_relative_to(site)  # the copy ran, not the source tree
    folder = Path(first["variable"])
    assert folder.is_relative_to(home) and folder.parts[-2:] == ("rczone", "numba"), folder
    assert Path(first["path"]).is_relative_to(folder)
    assert list(folder.rglob("*.nbi")), "nothing cached in the user's folder"
    assert written == []
    # the first process compiled, the second loaded from the user's folder
    assert (first["misses"], first["hits"]) == (1, 0)
    assert (second["misses"], second["hits"]) == (0, 1)


def test_a_writable_package_keeps_numbas_own_folder(tmp_path, monkeypatch):
    monkeypatch.setenv(cache.CACHE_VARIABLE, "")
    assert cache.use_writable_cache(tmp_path) is None
    assert os.environ[cache.CACHE_VARIABLE] == ""


def test_the_users_own_setting_wins(tmp_path, monkeypatch):
    blocked = tmp_path / "pkg"
    blocked.mkdir()
    (blocked / "__pycache__").write_text("")  # not a folder: nothing can be written there
    monkeypatch.setenv(cache.CACHE_VARIABLE, str(tmp_path / "mine"))
    assert cache.use_writable_cache(blocked) is None
    assert os.environ[cache.CACHE_VARIABLE] == str(tmp_path / "mine")


@pytest.mark.parametrize("usable", [True, False], ids=["user-folder", "nowhere"])
def test_an_unwritable_package_moves_the_cache_when_the_user_folder_can_take_it(
    tmp_path, monkeypatch, usable
):
    blocked = tmp_path / "pkg"
    blocked.mkdir()
    (blocked / "__pycache__").write_text("")
    target = tmp_path / "xdg"
    if not usable:
        target.write_text("")  # a file: the user's folder cannot be made either
    # restored afterwards: this process's own kernels keep their cache
    monkeypatch.setenv(cache.CACHE_VARIABLE, "")
    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)
    monkeypatch.setattr(cache, "user_cache_folder", lambda: target / "rczone" / "numba")
    got = cache.use_writable_cache(blocked)
    if usable:
        assert got == target / "rczone" / "numba"
        assert os.environ[cache.CACHE_VARIABLE] == config.CACHE_DIR == str(got)
    else:  # numba's own fallbacks decide
        assert got is None and os.environ[cache.CACHE_VARIABLE] == ""
