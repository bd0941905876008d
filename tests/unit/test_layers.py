"""The package's layers, enforced: who may import whom.

Every ``import`` of every module is read from the source (module level and inside
functions alike, ``TYPE_CHECKING`` blocks included), and mapped to the top-level unit it
belongs to (``rczone.estimation.costs`` -> ``estimation``, ``rczone.control`` -> ``mpc``). Rules:

* ``kernels`` (compiled hot loops) import nothing of rczone but ``errors``;
* ``network`` imports nothing of rczone but ``errors`` and ``kernels`` (the one compiled assembly,
  ``kernels.problem.conductances``); ``simulation`` nothing but
  ``errors``, ``network`` and ``kernels``;
* ``results`` (the result protocol) and ``files`` (reading untrusted files, writing atomically)
  import nothing of rczone but ``errors``;
* ``estimation`` reaches no ``report``, ``cli``, ``postfit`` or ``calibration``, not even through
  another unit; ``postfit`` (the analyses of a fitted model) reaches no ``calibration``,
  ``diagnostics``, ``selection``, ``workflow``, ``report`` or ``cli`` (the calibration imports it); ``diagnostics`` reaches no ``report``; ``workflow`` (what the CLI and the API share)
  and ``study`` (the paper's study) reach no ``report`` or ``cli``;
* the units import each other without cycles;
* importing ``rczone.control`` does not load matplotlib (checked in a fresh interpreter).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import rczone

ROOT = Path(rczone.__file__).resolve().parent

#: unit -> the rczone units it may import (None: no restriction here)
ALLOWED = {
    "kernels": {"errors"},
    "network": {"errors", "kernels"},
    "simulation": {"errors", "network", "kernels"},
    "results": {"errors"},
    "files": {"errors"},
}
#: unit -> units it must not reach, directly or through others
FORBIDDEN_REACH = {
    "estimation": {"report", "cli", "calibration", "postfit"},
    "postfit": {"calibration", "diagnostics", "selection", "workflow", "report", "cli"},
    "diagnostics": {"report"},
    "workflow": {"report", "cli"},
    "study": {"report", "cli"},
}


def module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def unit_of(module: str) -> str | None:
    """``rczone.a.b`` -> ``a``; ``rczone`` itself -> None."""
    parts = module.split(".")
    return parts[1] if parts[0] == "rczone" and len(parts) > 1 else None


def imported_modules(source: str, module: str, is_package: bool) -> set[str]:
    """Every rczone module ``source`` imports, wherever the import statement is."""
    out: set[str] = set()
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            out.add(base)
            out.update(f"{base}.{a.name}" for a in node.names)
    return {m for m in out if m == "rczone" or m.startswith("rczone.")}


def unit_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """unit -> units it imports (itself excluded), over every module under ``root``."""
    graph: dict[str, set[str]] = {}
    for path in sorted(root.rglob("*.py")):
        module = module_name(path, root)
        unit = unit_of(module)
        if unit is None:
            continue
        imports = imported_modules(path.read_text(), module, path.name == "__init__.py")
        targets = {unit_of(m) for m in imports} - {None, unit}
        # "from rczone import __version__" names the package, not a unit
        targets -= {"__version__"}
        graph.setdefault(unit, set()).update(targets)
    return graph


def reach(graph: dict[str, set[str]], unit: str) -> set[str]:
    seen: set[str] = set()
    stack = [unit]
    while stack:
        for nxt in graph.get(stack.pop(), ()):
            if nxt not in seen:
                seen.add(nxt)
                stack.append(nxt)
    return seen


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one unit (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


GRAPH = unit_graph()


@pytest.mark.parametrize("unit", sorted(ALLOWED))
def test_low_layers_import_nothing_above_them(unit: str) -> None:
    extra = GRAPH.get(unit, set()) - ALLOWED[unit]
    assert not extra, f"{unit} imports {sorted(extra)}; it may import only {sorted(ALLOWED[unit])}"


@pytest.mark.parametrize("unit", sorted(FORBIDDEN_REACH))
def test_units_do_not_reach_the_layers_above_them(unit: str) -> None:
    bad = reach(GRAPH, unit) & FORBIDDEN_REACH[unit]
    assert not bad, f"{unit} reaches {sorted(bad)} through {sorted(GRAPH[unit])}"


def test_units_import_each_other_without_cycles() -> None:
    assert cycles(GRAPH) == []


def test_mpc_does_not_load_matplotlib() -> None:
    code = "import sys, rczone.control; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_the_checks_see_imports_inside_functions_and_relative_ones(tmp_path: Path) -> None:
    # a fake package whose kernels import the estimation layer inside a function, relatively
    pkg = tmp_path / "rczone"
    for sub in ("kernels", "estimation"):
        (pkg / sub).mkdir(parents=True)
        (pkg / sub / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("")
    (pkg / "kernels" / "loop.py").write_text(
        "def f():\n    from ..estimation import costs\n    return costs\n"
    )
    (pkg / "estimation" / "costs.py").write_text("import rczone.kernels.loop\n")
    graph = unit_graph(pkg)
    assert graph["kernels"] == {"estimation"}
    assert cycles(graph) == [["estimation", "kernels"]]


#: Modules allowed at the package root (everything else lives in a package that names its concept).
ROOT_MODULES = {"__init__.py", "errors.py"}


def test_no_loose_modules_at_the_package_root() -> None:
    loose = {p.name for p in ROOT.glob("*.py")} - ROOT_MODULES
    assert not loose, f"modules at the package root (put them in a package): {sorted(loose)}"
