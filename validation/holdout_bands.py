"""Held-out coverage of 2-sigma bands calibrated in several ways (issue 22, defect 4).

Usage::

    python validation/holdout_bands.py [--shared ../shared] [--out validation-output] [--only NAME] [--selected MODEL.json]

For each data set the default ML fit (``rczone.calibrate``, process noise on the measured node) is
made on the calibration part, and the 2-sigma band of its k-step and open-loop predictions is
scored on the held-out part (the filter warmed up on the calibration part, as ``rczone predict
--warmup`` does). Every calibration below uses the calibration part only:

* ``raw``: the model's noise levels;
* ``in-sample``: per-horizon factors from the fit's own k-step errors on its calibration data
  (:func:`rczone.calibration.bands.calibrate_band`, rczone's default);
* ``block-max B``: the fit's own errors on each of ``B`` blocks of the calibration part give a
  factor per block, and the largest is used (a conformal bound on the next block's factor when
  the blocks are exchangeable: it is exceeded with probability at most ``1 / (B + 1)``);
* ``rolling B``: rolling-origin validation inside the calibration part (Tashman 2000): refit (one
  local search from the fit's estimates) on the samples before each of ``B`` origins spread over
  the second half, score the k-step errors of the next block with the refit's own band, and take
  the factor that puts 95.45 % of the pooled standardized errors inside two standard deviations;
* ``block-out B``: the same with each of ``B`` blocks left out of the refit (its outputs missing)
  and scored (blocked cross-validation);
* ``jackknife B``: the in-sample factors, plus the spread of the held-out predictions of the ``B``
  leave-one-block-out refits as the estimates' uncertainty (the block jackknife variance, Kunsch
  1989, valid for a misspecified model where the inverse Hessian is not).

Data sets: the Bacher & Madsen PRBS house (TiTe with heater and solar aperture, split at
2009-02-09T12:00 as ``tests/validation/test_holdout_bands.py``), the same house with the model
``rczone select --forward --holdout`` chooses from the whole family on the calibration part
(``bacher_madsen_selected``: the selection's own fit, process noise on every state; the held-out
days play no part in the choice), the Armadillo box (pySIP's H2, TiTe with heater, the last 25 %
held out) and a synthetic zone simulated from a known TiTe model with process noise on the room
node only (the default fit's own structure, so its raw band is right by construction;
Euler-Maruyama, independent of rczone's filter; the last 25 % held out).

``members`` (``--only members``) is, for the Bacher & Madsen split, the held-out RMSE and 2-sigma coverage (the
band ``rczone predict --horizons`` gives: noise levels times the saved factors and the estimates'
covariance) at 5 min, 15 min, 1 h, 3 h, 6 h, 12 h and open loop of the selected model and of
family members around it, each fitted by ``rczone fit --noise measured`` (its default) or
``--noise all`` (``select``'s), with persistence, ARX and every R, C or gain at a bound.
Prints 'skipped: data not found' for the real sets when the shared folder is absent. Writes
``<out>/holdout_bands.json`` and prints the coverage table as Markdown (docs/validation.md).

References
----------
.. [1] L. J. Tashman, "Out-of-sample tests of forecasting accuracy: an analysis and review",
   International Journal of Forecasting 16 (2000) 437-450.
.. [2] H. R. Kunsch, "The jackknife and the bootstrap for general stationary observations",
   The Annals of Statistics 17 (1989) 1217-1241.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from rczone.calibration import calibrate, dataset
from rczone.calibration.bands import quantile_scale
from rczone.calibration.holdout import holdout_start
from rczone.calibration.horizons import horizon_scores
from rczone.calibration.prediction import noise_values
from rczone.estimation import fit
from rczone.estimation.fit import noise_bounds
from rczone.estimation.forecast import k_step_bands, noise_band
from rczone.files.atomic import write_json_atomic
from rczone.models import ZoneModel, load_model
from rczone.workflow.reader import read_model_frame

HERE = Path(__file__).resolve().parent
DEFAULT_SHARED = HERE.parent.parent / "shared"
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))
from tests.unit.selection.synthetic import TRUE_MODEL, TRUE_VALUES, inputs, simulate_sde  # noqa: E402
from verdicts import verdict_cell  # noqa: E402

#: Horizons scored, s (one step where the samples are coarser), then open loop.
HORIZONS_S = (300.0, 900.0, 3600.0, 3 * 3600.0, 6 * 3600.0)
#: Number of folds of each scheme.
FOLDS = {"block-max": (4,), "rolling": (2, 3, 4, 5, 6), "block-out": (4,), "jackknife": (4, 6)}


#: The Bacher & Madsen data, column map and split (``tests/validation/test_holdout_bands.py``).
BM_DATA = Path("data") / "bacher_madsen_prbs" / "inputPRBS1.csv"
BM_MAP = HERE / "maps" / "bacher_madsen.toml"
BM_SPLIT = "2009-02-09T12:00"

#: Horizons of the model comparison, 5-min steps (5 min ... 12 h), then open loop.
MEMBER_HORIZONS = (1, 3, 12, 36, 72, 144, None)

#: Family members compared with the selected model, and the process noise each is fitted with.
MEMBERS = (
    ("TiTe+heater+solar", "measured"),
    ("TiTe+heater+solar", "all"),
    ("TiTeAe+heater+solar", "measured"),
    ("TiTeAe+heater+solar", "all"),
    ("TiTeTh+heater+solar", "measured"),
    ("TiTeTh+heater+solar", "all"),
    ("TiTmTe+heater+solar", "measured"),
    ("TiTmTe+heater+solar", "all"),
    ("TiTmTh+heater+solar", "all"),
    ("TiTmThTsn+heater+solar", "all"),
    ("TiTmThTsnAs+heater+solar", "measured"),
    ("TiTmTeThAeRia+heater+solar", "measured"),
    ("TiTmTeThAeRia+heater+solar", "all"),
)


def bound_flags(zm: ZoneModel) -> list[str]:
    """The fitted model's flags that say an estimate is at a bound of its search box."""
    return [str(f) for f in zm.provenance.get("flags", []) if "at a bound" in str(f)]


def bm_frame(shared: Path, zm: ZoneModel) -> tuple[pd.DataFrame, float]:
    """The PRBS house's signals of ``zm`` through its column map, and the split time (s)."""
    frame = read_model_frame(shared / BM_DATA, BM_MAP, zm)
    t = frame["time"].to_numpy(float)
    return frame, holdout_start(t, BM_SPLIT, timezone="Europe/Copenhagen")


def bacher_madsen(shared: Path) -> tuple[str, pd.DataFrame, float]:
    """The PRBS house through its column map; held out from 2009-02-09T12:00 (Copenhagen)."""
    return "TiTe+heater+solar", *bm_frame(shared, load_model("TiTe+heater+solar"))


def select_on_calibration(shared: Path) -> ZoneModel:
    """The model ``rczone select --forward --holdout`` picks from the whole family, fitted on the calibration part."""
    from rczone.cli.main import main as rczone

    with tempfile.TemporaryDirectory() as tmp:
        saved = Path(tmp) / "selected.json"
        cmd = ["select", str(shared / BM_DATA), "--columns", str(BM_MAP), "--forward", "--holdout", BM_SPLIT]
        report = Path(tmp) / "select.json"
        code = rczone([*cmd, "--save-model", str(saved), "--json", str(report)])
        if code not in (0, 3):
            raise RuntimeError(f"rczone select failed (exit code {code})")
        chosen = json.loads(report.read_text())
        # the verdict select gives the selected fit, its held-out checks included
        SELECTED["verdict"] = chosen["models"][chosen["selected"]]["verdict"]
        return load_model(saved)


#: The selected model, once chosen (or read from ``--selected``), and the verdict select gave its fit:
#: the selection runs once per run.
SELECTED: dict[str, object] = {}


def selected_model(shared: Path) -> ZoneModel:
    """:func:`select_on_calibration`, run once."""
    if "model" not in SELECTED:
        SELECTED["model"] = select_on_calibration(shared)
    return SELECTED["model"]


def bacher_madsen_selected(shared: Path) -> tuple[ZoneModel, pd.DataFrame, float]:
    """The PRBS house with the model forward selection chooses on the calibration part (its own fit)."""
    zm = selected_model(shared)
    return zm, *bm_frame(shared, zm)


def armadillo(shared: Path) -> tuple[str, pd.DataFrame, float]:
    """pySIP's H2 (30 min), without the irradiance (its aperture runs to 0, docs/validation.md)."""
    raw = pd.read_csv(shared / "data" / "armadillo_pysip" / "armadillo_data_H2.csv")
    frame = pd.DataFrame({"time": raw["Time"], "Ti": raw["T_int"], "To": raw["T_ext"], "Ph": raw["P_hea"]})
    return "TiTe+heater", frame, float(frame["time"].iloc[round(0.75 * len(frame))])


def synthetic(_shared: Path, seed: int = 1) -> tuple[str, pd.DataFrame, float]:
    """Six days at 5 min from the known TiTe model, process noise on the room node only."""
    rng = np.random.default_rng(seed)
    dt = 300.0
    frame = inputs(int(6 * 86400 / dt) + 1, dt, rng).drop(columns="Ps")
    u = frame[["To", "Ph"]].to_numpy()
    _, y = simulate_sde(TRUE_MODEL, TRUE_VALUES, frame["time"].to_numpy(), u, {"Ti": 2e-3}, 0.02, rng)
    frame["Ti"] = y[:, 0]
    return "TiTe+heater", frame, float(frame["time"].iloc[round(0.75 * len(frame))])


DATASETS = {
    "bacher_madsen_prbs": ("bacher_madsen_prbs/inputPRBS1.csv", bacher_madsen),
    "bacher_madsen_selected": ("bacher_madsen_prbs/inputPRBS1.csv", bacher_madsen_selected),
    "armadillo_pysip": ("armadillo_pysip/armadillo_data_H2.csv", armadillo),
    "synthetic": (None, synthetic),
}


def head(data, n: int):
    """The first ``n`` samples of a Dataset."""
    return dataclasses.replace(data, t=data.t[:n], u=data.u[:n], m=data.m[:n], y=data.y[:n])


class Case:
    """A default fit on the calibration part (or a model fitted on it), and its errors on any part with any values."""

    def __init__(self, model: str | ZoneModel, frame: pd.DataFrame, split: float) -> None:
        cal_frame = frame[frame["time"].to_numpy(float) < split]
        started = time.perf_counter()
        self.model = calibrate(load_model(model), cal_frame).model if isinstance(model, str) else model
        self.fit_s = time.perf_counter() - started
        self.net = self.model.network
        self.values = {**self.model.theta, **noise_values(self.model)}
        self.free = list(self.model.provenance["free"])
        self.cal = dataset(self.model, cal_frame)
        self.full = dataset(self.model, frame)
        self.first = self.cal.n_samples
        dt = float(np.median(np.diff(self.full.t)))
        self.steps = list(dict.fromkeys(max(1, round(h / dt)) for h in HORIZONS_S))
        self.horizons = [*self.steps, None]

    def refit(self, data) -> dict:
        """One local search on ``data`` from the fit's estimates (inside the data's noise bounds)."""
        box = noise_bounds(self.net, data, self.free)
        start = {
            k: min(max(self.values[k], box[k][0] * 1.01), box[k][1] / 1.01) if k in box else self.values[k]
            for k in self.free
        }
        held = {k: v for k, v in self.values.items() if k not in self.free}
        res = fit(
            self.net, data, self.free, method="ml", n_starts=1, start=start, fixed=held, uncertainty=False
        )
        return {**res.fixed, **res.estimates}

    def errors(self, values: dict, data, a: int, b: int) -> dict:
        """Per horizon, the errors and the model's standard deviations on samples ``a:b`` of ``data``.

        k steps ahead from the filtered states; open loop from the filter's estimate at ``a``.
        """
        bands = k_step_bands(self.net, values, data, self.steps)
        out = {k: ((data.y - bands[k].y_hat)[a:b, 0], bands[k].sd[a:b, 0]) for k in self.steps}
        y_ol, sd_ol = noise_band(self.net, values, head(data, b), known=max(a, 1))
        out[None] = ((data.y[:b] - y_ol)[a:b, 0], sd_ol[a:b, 0])
        return out

    def predictions(self, values: dict) -> dict:
        """Per horizon, the predictions of the held-out part (warm-up: the calibration part)."""
        bands = k_step_bands(self.net, values, self.full, self.steps)
        out = {k: bands[k].y_hat[self.first :, 0] for k in self.steps}
        out[None] = noise_band(self.net, values, self.full, known=self.first)[0][self.first :, 0]
        return out


def factors(pieces: list[dict], horizons: list) -> dict:
    """Per horizon, the factor that puts 95.45 % of the pooled standardized errors inside 2 sigma."""
    out = {}
    for k in horizons:
        z = np.concatenate([e / sd for e, sd in (p[k] for p in pieces)])
        out[k] = quantile_scale(z, np.ones_like(z)) or float("nan")
    return out


def coverage(case: Case, scale: dict, extra: dict | None = None) -> dict:
    """Per horizon, the held-out share inside ``+-2 sqrt((scale sd)^2 + extra^2)`` (NaN: no factor)."""
    held = case.errors(case.values, case.full, case.first, case.full.n_samples)
    out = {}
    for k in case.horizons:
        if not np.isfinite(scale[k]):  # too few errors to calibrate this horizon
            out[k] = float("nan")
            continue
        e, sd = held[k]
        total = np.hypot(scale[k] * sd, 0.0 if extra is None else extra[k])
        ok = np.isfinite(e)
        out[k] = float(np.mean(np.abs(e[ok]) <= 2 * total[ok]))
    return out


def evaluate(case: Case) -> dict:
    """Factors and held-out coverage of every calibration scheme."""
    hs, cal, n = case.horizons, case.cal, case.cal.n_samples
    rows: dict[str, dict] = {}

    def row(name: str, scale: dict, extra: dict | None = None) -> None:
        rows[name] = {"factor": scale, "coverage": coverage(case, scale, extra)}
        if extra is not None:
            rows[name]["extra_sd_K"] = {k: float(np.nanmean(v)) for k, v in extra.items()}

    ones = dict.fromkeys(hs, 1.0)
    row("raw", ones)
    in_sample = factors([case.errors(case.values, cal, 0, n)], hs)
    row("in-sample", in_sample)
    for b in FOLDS["block-max"]:
        cuts = np.round(np.linspace(0, n, b + 1)).astype(int)
        per_block = [
            factors([case.errors(case.values, cal, lo, hi)], hs) for lo, hi in itertools.pairwise(cuts)
        ]
        row(f"block-max {b}", {k: max(f[k] for f in per_block) for k in hs})
    for b in FOLDS["rolling"]:
        cuts = np.round(n * (0.5 + 0.5 * np.arange(b + 1) / b)).astype(int)
        pieces = [case.errors(case.refit(head(cal, lo)), cal, lo, hi) for lo, hi in itertools.pairwise(cuts)]
        row(f"rolling {b}", factors(pieces, hs))
    for b in sorted({*FOLDS["block-out"], *FOLDS["jackknife"]}):
        cuts = np.round(np.linspace(0, n, b + 1)).astype(int)
        pieces, replicas = [], []
        for lo, hi in itertools.pairwise(cuts):
            y = cal.y.copy()
            y[lo:hi] = np.nan
            values = case.refit(dataclasses.replace(cal, y=y))
            pieces.append(case.errors(values, cal, lo, hi))
            replicas.append(case.predictions(values))
        if b in FOLDS["block-out"]:
            row(f"block-out {b}", factors(pieces, hs))
        if b in FOLDS["jackknife"]:
            spread = {}
            for k in hs:
                p = np.stack([r[k] for r in replicas])
                spread[k] = np.sqrt((b - 1) / b * np.sum((p - p.mean(axis=0)) ** 2, axis=0))
            row(f"jackknife {b}", in_sample, spread)
    return rows


def label(k, dt: float) -> str:
    """A horizon's column title."""
    if k is None:
        return "open loop"
    s = k * dt
    return f"{s / 3600:g} h" if s >= 3600 else f"{s / 60:g} min"


def _steps_key(value) -> str:
    """A scores table's ``steps`` (None or NaN: open loop) as a JSON key."""
    return "open" if value is None or value != value else str(int(value))


def member_row(zm: ZoneModel, frame: pd.DataFrame, split: float, verdict: dict | None = None) -> dict:
    """Held-out RMSE per horizon of a model fitted on the calibration part and of the baselines, its coverage, its flags.

    The scores and band of ``rczone predict --horizons ... --baselines`` with the calibration part
    as warm-up (:func:`rczone.calibration.horizons.horizon_scores`); ``verdict`` is the one rczone
    gives the fit with this held-out part (``fit --holdout``, ``select --holdout``), as JSON.
    """
    table = horizon_scores(zm, frame, horizons=MEMBER_HORIZONS, start=split).table
    out: dict = {
        "at_bound": bound_flags(zm),
        "flags": [str(f) for f in zm.provenance.get("flags", [])],
        "verdict": verdict,
    }
    for name, part in table.groupby("predictor", sort=False):
        out[name] = {"rmse_K": {_steps_key(r.steps): float(r.rmse_K) for r in part.itertuples()}}
    rows = table[table["predictor"] == "model"].itertuples()
    out["model"]["coverage"] = {_steps_key(r.steps): float(r.coverage_2sigma) for r in rows}
    return out


def members(shared: Path, selected: ZoneModel) -> dict:
    """:func:`member_row` of the selected model and of every :data:`MEMBERS` fit on the calibration part.

    Each member is ``rczone fit DATA --columns MAP --model NAME --noise NOISE --holdout SPLIT``
    (:func:`rczone.fit`), so its verdict is the one that command gives: the fit's own flags, the
    robust standard errors and the held-out checks.
    """
    import rczone

    frame, split = bm_frame(shared, selected)
    verdict = SELECTED.get("verdict")
    out = {f"{selected.network.name} (selected, noise all)": member_row(selected, frame, split, verdict)}
    for name, noise in MEMBERS:
        fitted = rczone.fit(
            name,
            shared / BM_DATA,
            columns=BM_MAP,
            noise=noise,
            holdout=BM_SPLIT,
            checks=False,
            label="Bacher-Madsen",
        )
        frame, split = bm_frame(shared, fitted.model)
        out[f"{name} (noise {noise})"] = member_row(fitted.model, frame, split, fitted.verdict.to_dict())
        print(f"{name} (noise {noise}): done, {verdict_cell(fitted.verdict)}", flush=True)
    return out


def _short(key: str) -> str:
    """``"TiTeTh+heater+solar (noise all)"`` -> ``"TiTeTh, noise all"``."""
    name, _, rest = key.partition(" (")
    return f"{name.partition('+')[0]}, {rest.rstrip(')')}"


def members_markdown(rows: dict) -> str:
    """The model comparison as Markdown: 2-sigma coverage with the parameters at a bound, then RMSE with the baselines."""
    keys = [_steps_key(k) for k in MEMBER_HORIZONS]
    titles = " | ".join(label(None if k == "open" else int(k), 300.0) for k in keys)
    lines = [f"| 2σ coverage | {titles} | at a bound | verdict |", "|---" * (len(keys) + 3) + "|"]
    for name, r in rows.items():
        cells = " | ".join(f"{100 * r['model']['coverage'][k]:.0f} %" for k in keys)
        bound = ", ".join(f.partition(" ")[0] for f in r["at_bound"]) or "none"
        verdict = verdict_cell(r["verdict"]) if r.get("verdict") else "not recorded"
        lines.append(f"| {_short(name)} | {cells} | {bound} | {verdict} |")
    lines += ["", f"| RMSE (K) | {titles} |", "|---" * (len(keys) + 1) + "|"]
    for name, r in rows.items():
        lines.append(
            f"| {_short(name)} | " + " | ".join(f"{r['model']['rmse_K'][k]:.3f}" for k in keys) + " |"
        )
    first = next(iter(rows.values()))
    for base in ("persistence", "arx"):
        if base in first:
            lines.append(f"| {base} | " + " | ".join(f"{first[base]['rmse_K'][k]:.3f}" for k in keys) + " |")
    return "\n".join(lines)


def markdown(results: dict) -> str:
    """The coverage tables, one per data set."""
    lines = []
    for name, r in results.items():
        keys = list(next(iter(r["schemes"].values()))["coverage"])
        titles = [label(None if k == "open" else int(k), r["dt_s"]) for k in keys]
        lines += [f"{name} ({r['model']}, {r['held_out_samples']} samples held out)", ""]
        lines += ["| calibration | " + " | ".join(titles) + " |", "|---" * (len(keys) + 1) + "|"]
        for scheme, v in r["schemes"].items():
            cells = (f"{c:.0%}" if np.isfinite(c) else "—" for c in (v["coverage"][k] for k in keys))
            lines.append(f"| {scheme} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def run(shared: Path, only: list[str] | None) -> dict:
    """Every data set's schemes (``only``: those named), keyed by data set."""
    results = {}
    for name, (path, load) in DATASETS.items():
        if only and name not in only:
            continue
        if path is not None and not (shared / "data" / path).exists():
            print(f"{name}: skipped: data not found")
            continue
        model, frame, split = load(shared)
        case = Case(model, frame, split)
        schemes = evaluate(case)
        key = {k: ("open" if k is None else str(k)) for k in case.horizons}
        results[name] = {
            "model": case.model.network.name,
            "at_bound": bound_flags(case.model),
            "dt_s": float(np.median(np.diff(case.full.t))),
            "calibration_samples": case.first,
            "held_out_samples": case.full.n_samples - case.first,
            "fit_s": case.fit_s,
            "schemes": {
                s: {part: {key[k]: float(x) for k, x in v[part].items()} for part in v}
                for s, v in schemes.items()
            },
        }
        print(f"{name}: done ({case.fit_s:.0f} s fit)", flush=True)
    return results


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=DEFAULT_SHARED)
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument(
        "--only",
        action="append",
        choices=[*DATASETS, "members"],
        help="run only this data set, or the model comparison (repeatable)",
    )
    ap.add_argument(
        "--selected",
        type=Path,
        help="a model saved by rczone select --forward --holdout on the Bacher-Madsen split: skip the selection",
    )
    args = ap.parse_args(argv)
    if args.selected:
        SELECTED["model"] = load_model(args.selected)
    results = run(args.shared, args.only)
    if (not args.only or "members" in args.only) and (args.shared / BM_DATA).exists():
        results["members"] = members(args.shared, selected_model(args.shared))
    write_json_atomic(args.out / "holdout_bands.json", results)
    print(markdown({k: v for k, v in results.items() if k != "members"}))
    if "members" in results:
        print(members_markdown(results["members"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
