"""Where the shared reference material and real data live: ``../shared`` next to the repository.

They are not part of rczone (their licences keep the data out). Tests that need them call
:func:`require`: on a developer's machine without the folder they skip, but in CI (``CI=true``)
a missing reference fails the test, so that reference checks cannot vanish from a green run.
``RCZONE_SHARED`` points elsewhere.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

SHARED = Path(os.environ.get("RCZONE_SHARED", Path(__file__).resolve().parents[2] / "shared"))

#: Values of ``CI`` that mean "running in continuous integration" (GitHub, GitLab and most CIs set ``true``).
_CI_TRUE = ("true", "1", "yes")


def in_ci() -> bool:
    """Whether the tests run in CI, where every reference check must run."""
    return os.environ.get("CI", "").strip().lower() in _CI_TRUE


def require(*paths: Path, what: str = "shared reference") -> None:
    """Skip the calling test when a path is missing; fail it instead when running in CI.

    Parameters
    ----------
    *paths : Path
        Files or folders the test needs.
    what : str
        What they are, for the message.
    """
    missing = [str(p) for p in paths if not Path(p).exists()]
    if not missing:
        return
    msg = f"{what} not available: {', '.join(missing)} (set RCZONE_SHARED or place ../shared)"
    if in_ci():
        pytest.fail(f"{msg}; CI=true, so a missing reference fails instead of skipping", pytrace=False)
    pytest.skip(msg)
