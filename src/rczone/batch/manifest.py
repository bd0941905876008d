"""The batch manifest: which zones to calibrate, on which data, with which model and methods.

A manifest is a small TOML file. Top-level keys are defaults for every zone; each
``[[zone]]`` names one zone and either a data file or a virtual-building night; each
``[[generate]]`` expands into many virtual-building nights (seasons x modes x seeds)::

    model = "second-order-paper"     # default model (rczone.models.get_model)
    methods = ["ls", "ml"]           # one task per zone and method
    optimizer = "nelder-mead"
    n_starts = 1
    diagnose = true                  # identifiability verdicts per zone
    # free = ["Cr", "Rw"]            # default: the method's usual set for the model
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

Unknown keys, duplicate zone ids, unknown methods or models are errors naming the place in
the file, with a suggestion where one is close.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from rczone.errors import DataError, did_you_mean
from rczone.textfiles import read_toml

METHODS = ("ls", "ml", "map")
OPTIMIZERS = ("nelder-mead", "powell", "lbfgs")
SEASONS = ("summer", "winter", "autumn")
MODES = ("closed-loop", "forced")
SETTINGS = ("model", "methods", "optimizer", "n_starts", "diagnose", "free", "columns", "constants")
ZONE_KEYS = ("id", "data", "virtual", *SETTINGS)
GENERATE_KEYS = ("prefix", "seasons", "modes", "seeds", *SETTINGS)
TOP_KEYS = (*SETTINGS, "zone", "generate")
DEFAULTS: dict[str, object] = {
    "model": "second-order-paper",
    "methods": ("ls", "ml"),
    "optimizer": "nelder-mead",
    "n_starts": 1,
    "diagnose": True,
    "free": None,
    "columns": None,
    "constants": None,
}


@dataclass(frozen=True)
class Task:
    """One calibration: a zone's data, a model and one method.

    ``source`` is ``("file", path, column_map or None)`` or ``("virtual", season, mode, seed)``.
    """

    zone: str
    method: str
    model: str
    source: tuple
    optimizer: str = "nelder-mead"
    n_starts: int = 1
    diagnose: bool = True
    free: tuple[str, ...] | None = None
    constants: tuple[tuple[str, float], ...] = ()

    @property
    def key(self) -> str:
        """Unique name of the task (zone and method)."""
        return f"{self.zone}::{self.method}"


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


def _settings(base: Mapping[str, object], table: Mapping, where: str) -> dict[str, object]:
    out = dict(base)
    for k in SETTINGS:
        if k in table:
            out[k] = table[k]
    methods = out["methods"]
    if isinstance(methods, str):
        methods = [methods]
    if not isinstance(methods, (list, tuple)) or not methods:
        raise _err(where, f"methods must be a list of {METHODS}, got {out['methods']!r}")
    for m in methods:
        if m not in METHODS:
            raise _err(where, f"unknown method {m!r}; " + did_you_mean(str(m), METHODS))
    out["methods"] = tuple(methods)
    if out["optimizer"] not in OPTIMIZERS:
        raise _err(
            where,
            f"unknown optimizer {out['optimizer']!r}; " + did_you_mean(str(out["optimizer"]), OPTIMIZERS),
        )
    if not isinstance(out["n_starts"], int) or isinstance(out["n_starts"], bool) or out["n_starts"] < 1:
        raise _err(where, f"n_starts must be a positive integer, got {out['n_starts']!r}")
    if not isinstance(out["diagnose"], bool):
        raise _err(where, f"diagnose must be true or false, got {out['diagnose']!r}")
    free = out["free"]
    if free is not None and (not isinstance(free, list) or not all(isinstance(x, str) for x in free)):
        raise _err(where, f"free must be a list of parameter names, got {free!r}")
    const = out["constants"]
    if const is not None and (
        not isinstance(const, dict) or not all(isinstance(v, (int, float)) for v in const.values())
    ):
        raise _err(where, f"constants must be a table of numbers, e.g. {{ Q = 50.0 }}, got {const!r}")
    from rczone.models import model_names

    if out["model"] not in model_names():
        raise _err(
            where, f"unknown model {out['model']!r}; " + did_you_mean(str(out["model"]), model_names())
        )
    return out


def _seeds(spec: object, where: str) -> list[int]:
    if isinstance(spec, list) and spec and all(isinstance(s, int) and not isinstance(s, bool) for s in spec):
        return list(spec)
    if isinstance(spec, str):
        m = re.fullmatch(r"\s*(\d+)\s*\.\.\s*(\d+)\s*", spec)
        if m and int(m.group(1)) <= int(m.group(2)):
            return list(range(int(m.group(1)), int(m.group(2)) + 1))
    raise _err(where, f'seeds must be a list of integers or a range like "0..99", got {spec!r}')


def _virtual(spec: object, where: str) -> tuple:
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
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise _err(where, f"seed must be an integer, got {seed!r}")
    return ("virtual", season, mode, seed)


def _tasks(zone: str, source: tuple, s: Mapping[str, object]) -> list[Task]:
    return [
        Task(
            zone=zone,
            method=m,
            model=str(s["model"]),
            source=source,
            optimizer=str(s["optimizer"]),
            n_starts=int(s["n_starts"]),
            diagnose=bool(s["diagnose"]),
            free=tuple(s["free"]) if s["free"] else None,
            constants=tuple(sorted((k, float(v)) for k, v in (s["constants"] or {}).items())),
        )
        for m in s["methods"]
    ]


def _data_path(folder: Path, data: str) -> str:
    """A data file relative to the manifest's folder, or a built-in data set name (A, B, C)."""
    from rczone import datasets

    p = Path(data) if Path(data).is_absolute() else (folder / data).resolve()
    return data if not p.exists() and data in datasets.names() else str(p)


def parse_manifest(doc: Mapping, path: Path) -> Manifest:
    """Build a :class:`Manifest` from a parsed TOML document (``path``: where relative files live)."""
    where = str(path)
    _check_keys(doc, TOP_KEYS, where)
    base = _settings(DEFAULTS, doc, where)
    folder = path.parent
    tasks: list[Task] = []
    ids: set[str] = set()

    def add(zone: str, source: tuple, s: Mapping[str, object], w: str) -> None:
        if zone in ids:
            raise _err(w, f"duplicate zone id {zone!r}")
        ids.add(zone)
        tasks.extend(_tasks(zone, source, s))

    zones = doc.get("zone", [])
    if not isinstance(zones, list):
        raise _err(where, "write zones as [[zone]] tables")
    for i, z in enumerate(zones, 1):
        w = f"{where}, zone {i}"
        _check_keys(z, ZONE_KEYS, w)
        zid = z.get("id")
        if not isinstance(zid, str) or not zid:
            raise _err(w, "every [[zone]] needs an id (a non-empty string)")
        s = _settings(base, z, f"{w} ({zid})")
        if ("data" in z) == ("virtual" in z):
            raise _err(f"{w} ({zid})", 'give exactly one of data = "file" or virtual = { ... }')
        if "data" in z:
            cols = s["columns"]
            source = (
                "file",
                _data_path(folder, str(z["data"])),
                str((folder / str(cols)).resolve()) if cols else None,
            )
        else:
            source = _virtual(z["virtual"], f"{w} ({zid})")
        add(zid, source, s, f"{w} ({zid})")
    gens = doc.get("generate", [])
    if not isinstance(gens, list):
        raise _err(where, "write generators as [[generate]] tables")
    for i, g in enumerate(gens, 1):
        w = f"{where}, generate {i}"
        _check_keys(g, GENERATE_KEYS, w)
        s = _settings(base, g, w)
        prefix = str(g.get("prefix", "night"))
        seasons, modes = g.get("seasons", ["autumn"]), g.get("modes", ["forced"])
        for season in seasons:
            for mode in modes:
                for seed in _seeds(g.get("seeds", [0]), w):
                    src = _virtual({"season": season, "mode": mode, "seed": seed}, w)
                    add(f"{prefix}-{season}-{mode}-{seed}", src, s, w)
    if not tasks:
        raise _err(where, "no zones: add [[zone]] or [[generate]] tables")
    return Manifest(path, tuple(tasks))


def read_manifest(path: str | Path) -> Manifest:
    """Read and check a manifest file."""
    path = Path(path)
    if not path.exists():
        raise DataError(f"manifest {str(path)!r} does not exist")
    return parse_manifest(read_toml(path, "manifest"), path)
