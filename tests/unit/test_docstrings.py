"""Meta-tests of the public surface: documented parameters, and examples that run.

As python-control's ``docstrings_test.py``: every name :mod:`rczone` exports has a numpydoc
docstring that documents each of its parameters (a class: its constructor's, under Parameters
or Attributes), parsed by numpydoc itself; and the examples in the docstrings of the network,
simulation and MPC modules run as doctests.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import pkgutil

import pytest

import rczone

docscrape = pytest.importorskip("numpydoc.docscrape")

EXPORTED = [n for n in rczone.__all__ if n != "__version__"]


def documented(obj) -> set[str]:
    """Names a numpydoc docstring documents (``a, b : float`` counts both; ``**kw`` as ``kw``)."""
    doc = docscrape.NumpyDocString(inspect.getdoc(obj) or "")
    sections = ["Parameters", "Other Parameters"] + (["Attributes"] if inspect.isclass(obj) else [])
    return {n.strip().lstrip("*") for s in sections for p in doc[s] for n in p.name.split(",") if n.strip()}


@pytest.mark.parametrize("name", EXPORTED)
def test_every_exported_name_documents_its_parameters(name: str) -> None:
    obj = getattr(rczone, name)
    assert inspect.getdoc(obj), f"rczone.{name} has no docstring"
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return
    try:
        params = [p for p in inspect.signature(obj).parameters.values() if p.name not in ("self", "cls")]
    except (TypeError, ValueError):  # no signature to check
        return
    missing = [p.name for p in params if p.name not in documented(obj)]
    assert not missing, f"rczone.{name}: parameters {missing} are not documented"


def test_the_check_sees_an_undocumented_parameter() -> None:
    def f(a, *, b=1, **options):
        """Do something.

        Parameters
        ----------
        a : int
            A number.
        """

    assert documented(f) == {"a"}


def _modules(*packages: str) -> list[str]:
    out = []
    for name in packages:
        mod = importlib.import_module(name)
        out.append(name)
        if hasattr(mod, "__path__"):
            out += [f"{name}.{m.name}" for m in pkgutil.iter_modules(mod.__path__)]
    return out


DOCTESTED = _modules("rczone.network", "rczone.simulation", "rczone.control")


@pytest.mark.parametrize("module", DOCTESTED)
def test_docstring_examples_run(module: str) -> None:
    result = doctest.testmod(
        importlib.import_module(module),
        optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS,
        report=False,
    )
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples in {module} fail"


def test_the_network_simulation_and_mpc_modules_have_examples() -> None:
    finder = doctest.DocTestFinder()
    for package in ("rczone.network", "rczone.simulation", "rczone.control"):
        examples = sum(
            len(t.examples) for m in _modules(package) for t in finder.find(importlib.import_module(m))
        )
        assert examples >= 3, package
