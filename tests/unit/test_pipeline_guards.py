"""The fit pipeline's shape, guarded: settings travel whole, and the API has what the command line has.

* No function below the workflow (outside ``workflow/`` and ``cli/``) takes more than two
  :class:`~rczone.estimation.settings.FitSettings` fields as separate parameters: a new setting
  then passes no layer by name (the sampler's draws once passed through eight places). The few
  exceptions are listed with their reason.
* Every option of ``rczone fit``, ``select``, ``predict`` and ``diagnose`` has a keyword of the
  matching Python function (python-control's ``kwargs_test`` idea), or is listed with its reason.
"""

from __future__ import annotations

import ast
import dataclasses
import inspect
from pathlib import Path

import pytest
import typer

import rczone
from rczone.estimation.settings import FitSettings

SRC = Path(rczone.__file__).resolve().parent
FIELDS = {f.name for f in dataclasses.fields(FitSettings)}

#: (module, function) -> why it takes settings fields one by one.
SETTINGS_EXCEPTIONS = {
    ("batch/manifest.py", "_free_problem"): "a cache (functools.lru_cache) of the free-set check per model"
    " file: its key must be hashable, and FitSettings holds mappings; it builds the FitSettings itself",
    ("diagnostics/identifiability.py", "diagnose"): "a diagnosis, not a fit: free names the parameters whose"
    " identifiability is asked, seed, hold and constants are its own; it builds one FitSettings for its quick fit",
    ("estimation/parameters.py", "make_spec"): "builds the parameter spec from names and values already"
    " resolved against a model (the settings' free set, the model's values merged into fixed)",
    ("estimation/search.py", "global_search"): "the search algorithm itself, run on a bare cost in its tests;"
    " the pipeline hands it the FitProblem's budget in one place (estimation.minimize.minimize_fit)",
}


def settings_fields_taken(root: Path = SRC) -> dict[tuple[str, str], list[str]]:
    out = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        if rel.split("/")[0] in ("workflow", "cli"):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                hit = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs) if x.arg in FIELDS]
                if len(hit) > 2:
                    out[(rel, node.name)] = hit
    return out


def test_no_function_below_the_workflow_re_spells_the_fit_settings():
    taken = settings_fields_taken()
    unexplained = {k: v for k, v in taken.items() if k not in SETTINGS_EXCEPTIONS}
    assert not unexplained, f"take a FitSettings instead of its fields one by one: {unexplained}"
    stale = set(SETTINGS_EXCEPTIONS) - set(taken)
    assert not stale, f"listed exceptions that no longer take the fields: {stale}"


def test_the_guard_sees_a_function_that_re_spells_them(tmp_path):
    """The scan is not blind: a module with such a function is found, one under workflow/ is not."""
    for unit in ("estimation", "workflow"):
        (tmp_path / unit).mkdir()
        (tmp_path / unit / "bad.py").write_text("def f(x, method, seed, hold=1):\n    pass\n")
    assert settings_fields_taken(tmp_path) == {("estimation/bad.py", "f"): ["method", "seed", "hold"]}


#: command -> the Python functions that together take its options.
API = {
    "fit": ("fit",),
    "select": ("select_models",),
    "predict": ("predict", "score_horizons"),
    "diagnose": ("diagnose",),
}
#: A command-line parameter's name -> the API keyword it is called there.
RENAMED = {
    "model_name": "model",
    "model_file": "model",
    "model_opt": "model",  # predict --model MODEL DATA, the positional MODEL's other spelling
    "column_map": "columns",
    "const": "constants",
    "fix": "fixed",
    "bound": "bounds",
    "starts": "n_starts",
    "option": "options",
}
#: What a command writes or shows: the API returns the result (whose to_dict(), to_frame() and
#: report write it) and prints nothing, so it has no --quiet either.
WRITTEN = {"json_out", "report_dir", "save_model", "out", "quiet"}
#: (command, parameter) -> why the API has no keyword of that name, and the keyword that does it.
OPTION_EXCEPTIONS = {
    ("fit", "draws"): ("options", "shorthand of options={'draws': N} (method mcmc's own option)"),
    ("fit", "tune"): ("options", "shorthand of options={'tune': N} (method mcmc's own option)"),
    ("fit", "chains"): ("options", "shorthand of options={'chains': N} (method mcmc's own option)"),
}


@pytest.mark.parametrize("command", sorted(API))
def test_every_command_line_option_has_an_api_keyword(command):
    from rczone.cli.main import app

    click = typer.main.get_command(app).commands[command]
    keywords = {k for fn in API[command] for k in inspect.signature(getattr(rczone, fn)).parameters}
    missing = []
    for param in click.params:
        name = RENAMED.get(param.name, param.name)
        if param.name in WRITTEN:
            continue
        if (command, param.name) in OPTION_EXCEPTIONS:
            target, _why = OPTION_EXCEPTIONS[(command, param.name)]
            assert target in keywords, (command, param.name, target)
            continue
        if name not in keywords:
            missing.append(param.opts[0])
    assert not missing, f"rczone {command} options without an API keyword: {missing}"


#: The readers below the data-source protocol: the command line reaches files only through it.
READERS = {"rczone.workflow.reader", "rczone.data", "rczone.data.zonedata", "rczone.data.reader"}


def readers_imported_by_the_cli(root: Path = SRC) -> dict[str, list[str]]:
    out = {}
    for path in sorted((root / "cli").glob("*.py")):
        names = []
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module in READERS:
                names += [
                    f"{node.module}.{a.name}" for a in node.names if "read" in a.name or "load" in a.name
                ]
        if names:
            out[path.name] = names
    return out


def test_the_command_line_reads_data_through_the_data_source_protocol():
    """CLI, API and batch read a zone's data the same way (issue 34): rczone.workflow.datasource."""
    assert readers_imported_by_the_cli() == {}


def dataset_builders(root: Path = SRC) -> list[tuple[str, str]]:
    """(module, function) of every call of ``dataset(model, frame, ...)`` in the package.

    ``emulators/catalog.dataset()`` (pyenergyplus' file catalogue, no argument) is not a data set.
    """
    out = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        for fn in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for node in ast.walk(fn):
                    if (
                        isinstance(node, ast.Call)
                        and getattr(node.func, "id", getattr(node.func, "attr", None)) == "dataset"
                        and (node.args or node.keywords)
                    ):
                        out.append((rel, fn.name))
    return out


def test_a_frame_becomes_a_data_set_in_one_place():
    """Entry points prepare the data once (calibration.dataset.prepare); below, it is handed on."""
    builders = dataset_builders()
    assert builders == [("calibration/dataset.py", "prepare")], builders
