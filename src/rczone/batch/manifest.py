"""The batch manifest: which zones to calibrate, on which data, with which model and methods.

A manifest is a small TOML file. Top-level keys are defaults for every zone; each
``[[zone]]`` names one zone and either a data file or a virtual-building night; each
``[[generate]]`` expands into many virtual-building nights (seasons x modes x seeds)::

    model = "second-order-paper"     # a built-in model, or a model file (rczone.models.load_model)
    methods = ["ls", "ml"]           # one task per zone and method
    optimizer = "auto"
    n_starts = "auto"                # global search (rczone fit's default); 1 = one local search
    # seed = 0                       # seed of the global search
    # noise = "measured"             # ML and MAP: process noise on the measured states, or "all"
    diagnose = true                  # identifiability verdicts per zone
    # free = ["Cr", "Rw"]            # default: the method's usual set for the model
    # sampler = { draws = 1000, tune = 1000, chains = 4 }   # the options of a sampling method ("mcmc")
    # options = { map = { prior_spread = 0.5 } }             # any method's own options, by method
    # columns = "maps/bms.toml"      # default column map for data files
    # constants = { Q = 50.0 }       # inputs held constant when the data lack them

    [[zone]]
    id = "pugh-241"
    data = "logs/pugh-241.csv"       # CSV/Parquet, relative to the manifest's folder
    columns = "maps/pugh.toml"       # any default can be overridden per zone
    methods = ["ml"]

    [[zone]]
    id = "virtual-7"
    virtual = { season = "autumn", mode = "forced", seed = 7 }

    [[generate]]                     # 2 x 2 x 250 = 1000 zone-nights
    prefix = "night"
    seasons = ["summer", "autumn"]
    modes = ["closed-loop", "forced"]
    seeds = "0..249"                 # inclusive range, or a list of integers

``model`` is a built-in name or a model file (``.toml``, or ``.json`` saved by ``rczone fit
--save-model``) relative to the manifest's folder. The fit options of a zone become the one
settings object of a fit, :class:`~rczone.estimation.settings.FitSettings` (the command line's and
the Python API's), and its data a :class:`~rczone.workflow.datasource.DataSource`: a task carries
paths and seeds, never frames, so a worker reads its zone's data where it runs.

The search keys apply to the methods that search and ``sampler`` to those that sample (``"mcmc"``),
so one table can list both kinds of method; ``options`` holds a table of each method's own options
(:attr:`rczone.estimation.methods.Method.options`, ``rczone fit --option NAME=VALUE``), by method
name. A ``sampler`` or ``options`` table of a zone replaces the top-level one, and keys it leaves
out take the method's defaults.

Unknown keys, duplicate zone ids, unknown methods or models are errors naming the place in
the file, with a suggestion where one is close. A manifest that would expand into more than
:data:`MAX_TASKS` calibrations is refused before anything is built.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import stat
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path

from rczone.errors import DataError, RczoneError, did_you_mean
from rczone.estimation.methods import method_names, method_of
from rczone.estimation.optimize import OPTIMIZERS as LOCAL_OPTIMIZERS
from rczone.estimation.settings import MAX_STARTS, NOISE_PLACEMENTS, FitSettings
from rczone.files.text import nfkc, read_toml, regular_file
from rczone.workflow.datasource import BuiltinNight, DataSource, TrendLog, VirtualNight

MAX_TASKS = 200_000
"""Most calibrations (zones x methods) one manifest may ask for."""
MODEL_FILE_SUFFIXES = (".toml", ".json")
OPTIMIZERS = ("auto", *LOCAL_OPTIMIZERS)
SEASONS = ("summer", "winter", "autumn")
MODES = ("closed-loop", "forced")
SETTINGS = (
    "model",
    "methods",
    "optimizer",
    "n_starts",
    "seed",
    "noise",
    "diagnose",
    "free",
    "columns",
    "constants",
    "sampler",
    "options",
)
ZONE_KEYS = ("id", "data", "virtual", *SETTINGS)
GENERATE_KEYS = ("prefix", "seasons", "modes", "seeds", *SETTINGS)
TOP_KEYS = (*SETTINGS, "zone", "generate")
DEFAULTS: dict[str, object] = {
    "model": "second-order-paper",
    "methods": ("ls", "ml"),
    "optimizer": "auto",
    "n_starts": "auto",
    "seed": 0,
    "noise": "measured",
    "diagnose": True,
    "free": None,
    "columns": None,
    "constants": None,
    "sampler": None,
    "options": None,
}


@dataclass(frozen=True)
class Task:
    """One calibration: a zone's data, a model and the settings of one fit.

    Attributes
    ----------
    zone : str
        The zone's id.
    model : str
        A built-in model name or a model file (resolved).
    source : DataSource
        Where the zone's data come from (a trend log, a built-in night, a virtual night): paths
        and seeds, read where the task runs.
    settings : FitSettings
        The fit (method, free parameters, search), as ``rczone fit`` and :func:`rczone.fit` take it.
    diagnose : bool
        Identifiability verdicts for the zone at the fitted values.
    """

    zone: str
    model: str
    source: DataSource
    settings: FitSettings
    diagnose: bool = True

    @property
    def method(self) -> str:
        """The estimation method of the fit."""
        return self.settings.method

    @property
    def key(self) -> str:
        """Unique name of the task (zone and method)."""
        return f"{self.zone}::{self.method}"

    @property
    def fingerprint(self) -> str:
        """Hash of everything that determines the task's result.

        Every setting of the task, and the contents of the files it reads (the data file, the
        column map, a model file): a stored result is reused only for the same fingerprint, so
        a changed setting or an edited file is computed anew, never resumed.
        """
        files = list(self.source.files)
        if Path(self.model).suffix.lower() in MODEL_FILE_SUFFIXES:
            files.append(self.model)
        doc = {
            "zone": self.zone,
            "model": self.model,
            "source": {"kind": type(self.source).__name__, **asdict(self.source)},
            "settings": asdict(self.settings),
            "diagnose": self.diagnose,
            "files": [file_digest(f) for f in files],
        }
        text = json.dumps(doc, sort_keys=True, default=str)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:32]


def file_digest(path: str) -> str:
    """SHA-256 of a file's contents, or a marker when it is absent or unreadable.

    A built-in data set name (no such file) stands for itself; a file that cannot be read
    makes the task fail on its own, so its result is keyed by the reason.
    """
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return "absent"
    if not stat.S_ISREG(st.st_mode):  # a pipe or a device is never opened (it could wait forever)
        return "not a regular file"
    # size, times and inode: a file edited in any way (even with its size and mtime restored) is read again
    return _digest(path, st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)


@lru_cache(maxsize=4096)
def _digest(path: str, size: int, mtime_ns: int, ctime_ns: int, inode: int) -> str:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        return f"unreadable: {exc.strerror}"
    return h.hexdigest()


@dataclass(frozen=True)
class Manifest:
    """A parsed manifest: the tasks in file order."""

    path: Path
    tasks: tuple[Task, ...] = field(default_factory=tuple)

    @property
    def zones(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(t.zone for t in self.tasks))


def _err(where: str, msg: str) -> DataError:
    return DataError(f"manifest {where}: {msg}")


def _check_keys(table: Mapping, allowed: tuple[str, ...], where: str) -> None:
    for k in table:
        if k not in allowed:
            raise _err(where, f"unknown key {k!r}; " + did_you_mean(k, allowed))


def _settings(base: Mapping[str, object], table: Mapping, where: str, folder: Path) -> dict[str, object]:
    out = dict(base)
    for k in SETTINGS:
        if k in table:
            out[k] = table[k]
    methods = out["methods"]
    if isinstance(methods, str):
        methods = [methods]
    if not isinstance(methods, (list, tuple)) or not methods:
        raise _err(where, f"methods must be a list of {method_names()}, got {out['methods']!r}")
    for m in methods:
        if m not in method_names():
            raise _err(where, f"unknown method {m!r}; " + did_you_mean(str(m), method_names()))
    if len(set(methods)) < len(methods):
        raise _err(where, f"methods lists a method twice: {methods!r}")
    out["methods"] = tuple(methods)
    if not isinstance(out["optimizer"], str) or out["optimizer"] not in OPTIMIZERS:
        raise _err(
            where,
            f"unknown optimizer {out['optimizer']!r}; " + did_you_mean(str(out["optimizer"]), OPTIMIZERS),
        )
    n_starts = out["n_starts"]
    if n_starts != "auto" and (
        not isinstance(n_starts, int) or isinstance(n_starts, bool) or not 1 <= n_starts <= MAX_STARTS
    ):
        raise _err(
            where,
            f'n_starts must be "auto" or an integer from 1 to {MAX_STARTS} (rczone.estimation.settings.MAX_STARTS),'
            f" got {n_starts!r}",
        )
    seed = out["seed"]
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**63:
        raise _err(where, f"seed must be a non-negative integer, got {seed!r}")
    if out["noise"] not in NOISE_PLACEMENTS:
        raise _err(
            where, f"unknown noise {out['noise']!r}; " + did_you_mean(str(out["noise"]), NOISE_PLACEMENTS)
        )
    if not isinstance(out["diagnose"], bool):
        raise _err(where, f"diagnose must be true or false, got {out['diagnose']!r}")
    if isinstance(out["free"], list):
        out["free"] = nfkc(out["free"])  # names in one Unicode form (as model files)
    if isinstance(out["constants"], dict):
        out["constants"] = {nfkc(k): v for k, v in out["constants"].items()}
    free = out["free"]
    if free is not None and (not isinstance(free, list) or not all(isinstance(x, str) for x in free)):
        raise _err(where, f"free must be a list of parameter names, got {free!r}")
    const = out["constants"]
    if const is not None and (
        not isinstance(const, dict)
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in const.values())
        or not all(math.isfinite(v) for v in const.values())
    ):
        raise _err(where, f"constants must be a table of finite numbers, e.g. {{ Q = 50.0 }}, got {const!r}")
    if out["columns"] is not None:
        _text(out["columns"], "columns", where)
    out["sampler"], out["options"] = _method_options(out, where)
    out["model"] = _model(out["model"], folder, where)
    if const:
        spec = str(out["model"])
        problem = _constants_problem(
            spec, file_digest(spec) if Path(spec).is_absolute() else "", tuple(sorted(const))
        )
        if problem:
            raise _err(where, problem)
    return out


def _method_options(out: Mapping[str, object], where: str) -> tuple[dict, dict]:
    """The ``sampler`` table and the ``options`` tables (by method), each checked by its method's options."""
    sampler, options = out["sampler"], out["options"]
    example = "{ draws = 1000, tune = 1000, chains = 4 }"
    if sampler is not None and not isinstance(sampler, dict):
        raise _err(where, f"sampler must be a table like {example}, got {sampler!r}")
    if options is not None and not (
        isinstance(options, dict) and all(isinstance(v, dict) for v in options.values())
    ):
        raise _err(
            where,
            f"options must be a table of tables by method, e.g. {{ map = {{ prior_spread = 0.5 }} }}, got {options!r}",
        )
    sampler, options = dict(sampler or {}), {str(k): dict(v) for k, v in (options or {}).items()}
    try:
        for m in out["methods"]:
            if method_of(str(m)).search == "sample":
                method_of(str(m)).make_options(sampler)
    except RczoneError as exc:
        raise _err(where + ".sampler", str(exc)) from None
    try:
        for name in dict.fromkeys([*map(str, out["methods"]), *options]):  # a default table may name a
            meth = method_of(name)  # method only some zones run
            meth.make_options({**(sampler if meth.search == "sample" else {}), **options.get(name, {})})
    except RczoneError as exc:
        raise _err(where + (".options" if options else ""), str(exc)) from None
    return sampler, options


def _resolve(path: Path, what: str, where: str) -> Path:
    """``path`` with its links resolved; a link loop is one line (pathlib raises RuntimeError)."""
    try:
        return path.resolve()
    except (RuntimeError, OSError) as exc:
        raise _err(where, f"{what} {str(path)!r} cannot be resolved: a symbolic link loop? ({exc})") from None


def _text(value: object, what: str, where: str) -> str:
    if not isinstance(value, str) or not value or "\x00" in value:
        raise _err(where, f"{what} must be a non-empty string, got {value!r}")
    return value


def _model(spec: object, folder: Path, where: str) -> str:
    """A built-in model name, or a model file resolved against the manifest's folder."""
    spec = _text(spec, "model", where)
    if Path(spec).suffix.lower() in MODEL_FILE_SUFFIXES:
        path = _resolve(folder / spec, "model file", where)
        try:
            regular_file(path, "model file")
        except FileNotFoundError:
            raise _err(where, f"model file {spec!r} does not exist (looked for {str(path)!r})") from None
        except DataError as exc:
            raise _err(where, str(exc)) from None
        spec = str(path)
    problem = _model_problem(spec, file_digest(spec) if Path(spec).is_absolute() else "")
    if problem:
        raise _err(where, problem)
    return spec


@lru_cache(maxsize=64)
def _model_problem(spec: str, digest: str) -> str:  # digest: an edited model file is checked again
    """Why ``spec`` is not a usable model ("" if it is): loaded once per model, not per zone."""
    from rczone.errors import RczoneError
    from rczone.models import load_model

    try:
        load_model(spec)
    except RczoneError as exc:
        return str(exc)
    return ""


@lru_cache(maxsize=256)
def _constants_problem(spec: str, digest: str, names: tuple[str, ...]) -> str:
    """Why the constants ``names`` do not fit the model ``spec`` ("" if they do): each must be an input."""
    from rczone.errors import RczoneError
    from rczone.models import load_model

    try:
        load_model(spec).check_constants(dict.fromkeys(names, 0.0))
    except RczoneError as exc:
        return str(exc)
    return ""


def _digest_of(spec: str) -> str:
    return file_digest(spec) if Path(spec).is_absolute() else ""


@lru_cache(maxsize=256)
def _free_problem(spec: str, digest: str, method: str, free: tuple[str, ...] | None, noise: str) -> str:
    """Why the free parameters of a fit do not fit the model ``spec`` ("" if they do).

    Checked when the manifest is read, so an unknown parameter in one zone stops the run before
    anything is computed (issue 39), as ``rczone fit --free`` does.
    """
    from rczone.estimation.freeset import ADD
    from rczone.estimation.parameters import check_name
    from rczone.models import load_model

    try:
        network = load_model(spec).network
        for name in free or ():
            check_name(network, name.removeprefix(ADD), "free parameter")
        FitSettings(method=method, free=free, noise=noise).free_for(network)
    except RczoneError as exc:
        return str(exc)
    return ""


def _seeds(spec: object, where: str) -> range | list[int]:
    """The seeds of a generator, as a list or a lazy range (its size is checked before expanding)."""
    if isinstance(spec, list) and spec and all(isinstance(s, int) and not isinstance(s, bool) for s in spec):
        return list(spec)
    if isinstance(spec, str):
        m = re.fullmatch(r"\s*(\d{1,18})\s*\.\.\s*(\d{1,18})\s*", spec)
        if m and int(m.group(1)) <= int(m.group(2)):
            return range(int(m.group(1)), int(m.group(2)) + 1)
    raise _err(where, f'seeds must be a list of integers or a range like "0..99", got {spec!r}')


def _names(value: object, allowed: tuple[str, ...], what: str, where: str) -> list[str]:
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise _err(where, f"{what} must be a non-empty list of {allowed}, got {value!r}")
    for v in value:
        if v not in allowed:
            raise _err(where, f"unknown {what[:-1]} {v!r}; " + did_you_mean(v, allowed))
    return value


def _virtual(spec: object, where: str) -> VirtualNight:
    if not isinstance(spec, dict):
        raise _err(
            where,
            f'virtual must be a table like {{ season = "autumn", mode = "forced", seed = 7 }}, got {spec!r}',
        )
    _check_keys(spec, ("season", "mode", "seed"), f"{where}.virtual")
    season, mode, seed = spec.get("season"), spec.get("mode", "closed-loop"), spec.get("seed", 0)
    if season not in SEASONS:
        raise _err(where, f"unknown season {season!r}; " + did_you_mean(str(season), SEASONS))
    if mode not in MODES:
        raise _err(where, f"unknown mode {mode!r}; " + did_you_mean(str(mode), MODES))
    try:
        return VirtualNight(season, mode, seed)
    except RczoneError as exc:
        raise _err(where, str(exc)) from None


def _tasks(zone: str, source: DataSource, s: Mapping[str, object], where: str) -> list[Task]:
    """One task per method, each with the fit's settings (:class:`FitSettings`).

    The search keys go to the methods that search, ``sampler`` to the ones that sample, ``options``
    to the method it names.
    """
    tasks = []
    try:
        for m in s["methods"]:
            samples = method_of(str(m)).search == "sample"
            settings = FitSettings(
                method=str(m),
                free=tuple(s["free"]) if s["free"] else None,
                optimizer="auto" if samples else str(s["optimizer"]),
                n_starts=None if samples or s["n_starts"] == "auto" else int(s["n_starts"]),
                seed=int(s["seed"]),
                noise=str(s["noise"]),
                constants={k: float(v) for k, v in sorted((s["constants"] or {}).items())},
                checks=False,  # the batch's own check is `diagnose`, once per zone
                profiles=False,
                options={**(s["sampler"] if samples else {}), **s["options"].get(str(m), {})},
            )
            spec = str(s["model"])
            problem = _free_problem(spec, _digest_of(spec), settings.method, settings.free, settings.noise)
            if problem:
                raise DataError(problem)  # said with the zone below
            tasks.append(Task(zone, str(s["model"]), source, settings, bool(s["diagnose"])))
        return tasks
    except RczoneError as exc:  # checked above already; a setting FitSettings refuses is still one line
        raise _err(where, str(exc)) from None


def _data_source(folder: Path, data: str, columns: object, where: str) -> DataSource:
    """A data file relative to the manifest's folder (with its column map), or a built-in data set."""
    from rczone import datasets

    path = Path(data) if Path(data).is_absolute() else _resolve(folder / data, "data file", where)
    if not path.exists() and data in datasets.names():
        return BuiltinNight(data)
    cols = str(_resolve(folder / str(columns), "column map", where)) if columns else None
    return TrendLog(str(path), cols)


def _tables(doc: Mapping, name: str, where: str) -> list[Mapping]:
    tables = doc.get(name, [])
    if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        raise _err(where, f"write {name}s as [[{name}]] tables")
    return tables


def parse_manifest(doc: Mapping, path: Path) -> Manifest:
    """Build a :class:`Manifest` from a parsed TOML document (``path``: where relative files live)."""
    where = str(path)
    if not isinstance(doc, Mapping):
        raise _err(where, f"expected a TOML document, got {type(doc).__name__}")
    _check_keys(doc, TOP_KEYS, where)
    folder = path.parent
    base = _settings(DEFAULTS, doc, where, folder)
    tasks: list[Task] = []
    ids: set[str] = set()

    def add(zone: str, source: DataSource, s: Mapping[str, object], w: str) -> None:
        if zone in ids:
            raise _err(w, f"duplicate zone id {zone!r}")
        ids.add(zone)
        tasks.extend(_tasks(zone, source, s, w))

    def check_size(extra: int, w: str) -> None:
        if len(tasks) + extra > MAX_TASKS:
            raise _err(
                w,
                f"{len(tasks) + extra:,} calibrations (zones x methods) exceed the limit of {MAX_TASKS:,}"
                " (rczone.batch.manifest.MAX_TASKS); split the manifest",
            )

    zones = _tables(doc, "zone", where)
    check_size(len(zones), where)
    for i, z in enumerate(zones, 1):
        w = f"{where}, zone {i}"
        _check_keys(z, ZONE_KEYS, w)
        zid = z.get("id")
        if not isinstance(zid, str) or not zid.strip():
            raise _err(w, "every [[zone]] needs an id (a non-empty string)")
        s = _settings(base, z, f"{w} ({zid})", folder)
        if ("data" in z) == ("virtual" in z):
            raise _err(f"{w} ({zid})", 'give exactly one of data = "file" or virtual = { ... }')
        if "data" in z:
            data = _text(z["data"], "data", f"{w} ({zid})")
            source = _data_source(folder, data, s["columns"], f"{w} ({zid})")
        else:
            source = _virtual(z["virtual"], f"{w} ({zid})")
        add(zid, source, s, f"{w} ({zid})")
    for i, g in enumerate(_tables(doc, "generate", where), 1):
        w = f"{where}, generate {i}"
        _check_keys(g, GENERATE_KEYS, w)
        s = _settings(base, g, w, folder)
        prefix = _text(g.get("prefix", "night"), "prefix", w)
        seasons = _names(g.get("seasons", ["autumn"]), SEASONS, "seasons", w)
        modes = _names(g.get("modes", ["forced"]), MODES, "modes", w)
        seeds = _seeds(g.get("seeds", [0]), w)
        check_size(len(seasons) * len(modes) * len(seeds) * len(s["methods"]), w)
        for season in seasons:
            for mode in modes:
                for seed in seeds:
                    src = _virtual({"season": season, "mode": mode, "seed": seed}, w)
                    add(f"{prefix}-{season}-{mode}-{seed}", src, s, w)
    if not tasks:
        raise _err(where, "no zones: add [[zone]] or [[generate]] tables")
    return Manifest(path, tuple(tasks))


def read_manifest(path: str | Path) -> Manifest:
    """Read and check a manifest file."""
    path = Path(path)
    try:
        doc = read_toml(path, "manifest")
    except FileNotFoundError:
        raise DataError(f"manifest {str(path)!r} does not exist") from None
    return parse_manifest(doc, path)
