"""The package travels: licence, typing marker, one version, metadata; sdist and wheel carry them.

The build and the API reference are slow (a build backend in a fresh environment, Sphinx over every
module): they are marked ``slow`` and run by ``.ci/run``.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tarfile
import tomllib
import zipfile
from email.parser import HeaderParser
from pathlib import Path

import pytest

import rczone

ROOT = Path(__file__).resolve().parents[2]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_the_version_is_written_once_in_the_package() -> None:
    project = PYPROJECT["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "rczone.__version__"}
    init = (ROOT / "src" / "rczone" / "__init__.py").read_text(encoding="utf-8")
    assert len(re.findall(r"^__version__ = ", init, flags=re.MULTILINE)) == 1
    assert re.fullmatch(r"\d+\.\d+\.\d+([ab]|rc)?\d*", rczone.__version__)


def test_the_changelog_has_an_entry_for_this_version() -> None:
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert re.search(
        rf"^## \[{re.escape(rczone.__version__)}\] - \d{{4}}-\d{{2}}-\d{{2}}$", text, re.MULTILINE
    )


def test_licence_file_matches_the_declared_licence() -> None:
    assert PYPROJECT["project"]["license"] == "BSD-3-Clause"
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("BSD 3-Clause License") and "the rczone developers" in text
    assert "Neither the name of the copyright holder" in text  # clause 3, which 2-clause BSD lacks


def test_metadata_names_no_url_that_does_not_exist() -> None:
    # the repository is unpublished (README): no invented host, no relative path posing as a URL
    for url in PYPROJECT["project"].get("urls", {}).values():
        assert re.match(r"https://[a-z0-9.-]+\.[a-z]{2,}/", url), url


def _build(tmp_path: Path) -> tuple[Path, Path]:
    out = tmp_path / "dist"
    subprocess.run(
        # no --sdist/--wheel: the wheel is built from the sdist, as pip builds it, outside the source tree
        [sys.executable, "-m", "build", "--outdir", str(out), str(ROOT)],
        check=True,
        capture_output=True,
        text=True,
    )
    (sdist,) = out.glob("rczone-*.tar.gz")
    (wheel,) = out.glob("rczone-*.whl")
    return sdist, wheel


@pytest.mark.slow
def test_sdist_and_wheel_ship_the_licence_the_typing_marker_and_the_metadata(tmp_path) -> None:
    sdist, wheel = _build(tmp_path)
    v = rczone.__version__
    with tarfile.open(sdist) as tf:
        names = set(tf.getnames())
    base = f"rczone-{v}"
    assert {f"{base}/LICENSE", f"{base}/src/rczone/py.typed", f"{base}/pyproject.toml"} <= names
    with zipfile.ZipFile(wheel) as zf:
        wnames = set(zf.namelist())
        meta = HeaderParser().parsestr(zf.read(f"rczone-{v}.dist-info/METADATA").decode("utf-8"))
    assert {f"rczone-{v}.dist-info/licenses/LICENSE", "rczone/py.typed"} <= wnames
    assert any(n.startswith("rczone/datasets/data/") for n in wnames)
    assert meta["Version"] == v and meta["License-Expression"] == "BSD-3-Clause"
    assert meta.get_all("License-File") == ["LICENSE"]
    classifiers = meta.get_all("Classifier")
    assert "Typing :: Typed" in classifiers and "Programming Language :: Python :: 3.11" in classifiers
    assert "system identification" in meta["Keywords"]
    assert meta.get_all("Project-URL") is None


@pytest.mark.slow
def test_the_api_reference_builds_without_warnings(tmp_path) -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-b",
            "html",
            "-q",
            "-E",
            "-W",
            "--keep-going",
            "docs",
            str(tmp_path),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    page = (tmp_path / "api" / "estimation.html").read_text(encoding="utf-8")
    assert "rczone.estimation.fit" in page and "Parameters" in page
    # the functions a user calls first have entries, and the Markdown guides are pages of the site
    top = (tmp_path / "api" / "toplevel.html").read_text(encoding="utf-8")
    for name in ("fit", "predict", "load_data", "diagnose", "select_models", "smooth"):
        assert f'id="rczone.{name}"' in top, name
    assert "column map" in (tmp_path / "your-building.html").read_text(encoding="utf-8")
