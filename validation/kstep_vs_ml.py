"""Held-out RMSE and interval score per horizon: the ML fit against the k-step fit of the same model (issue 36).

Usage::

    python validation/kstep_vs_ml.py [--shared ../shared] [--out validation-output] [--only NAME]

For each real data set (read from the shared folder; their licences do not allow shipping them):
fit the model by ML on the first 75 % (``rczone fit``'s default: process noise on the measured
states), then by the k-step criterion from that fit (:func:`rczone.estimation.kstep_fit.fit_kstep`,
horizons one step, 1 h and 6 h), and score both on the last 25 %: the filter runs over the whole
record with the calibration estimates, each held-out sample is predicted from the filtered state
k steps earlier (:func:`rczone.estimation.forecast.k_step_bands`); RMSE, the 2-sigma band's coverage
and its interval score (Gneiting & Raftery 2007) per horizon. Prints 'skipped: data not found' and
exits 0 without the shared folder. Writes ``<out>/kstep_vs_ml.json`` and prints a Markdown table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from rczone.calibration.conformal import ALPHA, interval_score
from rczone.estimation import Dataset, fit
from rczone.estimation.forecast import k_step_bands
from rczone.estimation.kstep_fit import fit_kstep
from rczone.files.atomic import write_json_atomic
from rczone.models import load_model
from rczone.postfit.innovations import innovation_analysis

HERE = Path(__file__).resolve().parent
DEFAULT_SHARED = HERE.parent.parent / "shared"
sys.path.insert(0, str(HERE))
from latent_force import DATASETS  # noqa: E402
from real_data import bacher_madsen_frame  # noqa: E402
from verdicts import fit_verdict, verdict_cell  # noqa: E402

#: Horizons the k-step fit sums, s (besides one step).
FIT_HORIZONS_S = (3600.0, 21600.0)
#: Horizons scored, s (besides one step).
SCORE_HORIZONS_S = (3600.0, 21600.0, 86400.0)
#: Share of the samples held out at the end.
HOLDOUT = 0.25


def _steps(dt: float, seconds: tuple[float, ...], n: int) -> list[int]:
    return sorted({1, *(max(1, round(s / dt)) for s in seconds)} & set(range(1, n)))


def scores(network, values, data: Dataset, first: int, steps: list[int]) -> dict:
    """RMSE, coverage and interval score of the held-out samples per horizon (steps)."""
    bands = k_step_bands(network, values, data, steps)
    out = {}
    for k in steps:
        e = (data.y - bands[k].y_hat)[first:, 0]
        sd = bands[k].sd[first:, 0]
        ok = np.isfinite(e) & np.isfinite(sd)
        e, sd = e[ok], sd[ok]
        out[k] = {
            "rmse_K": float(np.sqrt(np.mean(e**2))),
            "coverage_2sigma": float(np.mean(np.abs(e) <= 2 * sd)),
            "interval_score_K": float(np.mean(interval_score(e, -2 * sd, 2 * sd, ALPHA))),
        }
    return out


def one(name: str, network, frame) -> dict:
    """ML and k-step fits on the first 75 % of ``frame``, both scored on the rest."""
    data = Dataset.from_frame(frame, network, time="time")
    first = round(data.n_samples * (1 - HOLDOUT))
    cal = Dataset(
        data.t[:first], data.u[:first], data.m[:first] if data.m is not None and data.m.size else None,
        data.y[:first], data.input_names, data.flow_names, data.output_names,
    )  # fmt: skip
    dt = float(np.median(np.diff(data.t)))
    fit_steps = _steps(dt, FIT_HORIZONS_S, first // 4)
    score_steps = _steps(dt, SCORE_HORIZONS_S, data.n_samples - first)
    t0 = time.process_time()
    ml = fit(network, cal, method="ml")
    t_ml = time.process_time() - t0
    ks = fit_kstep(network, cal, horizons=fit_steps, ml=ml)
    t_ks = time.process_time() - t0 - t_ml
    ml_values = {**ml.fixed, **{n: e.value for n, e in ml.parameters.items()}}
    white = innovation_analysis(network, ml_values, cal).white
    verdict = fit_verdict(network, ml, cal, white).to_dict()
    return {
        "model": network.name,
        "dt_s": dt,
        "calibration_samples": first,
        "held_out_samples": data.n_samples - first,
        "fit_horizons": fit_steps,
        "ml": {"values": ml_values, "flags": list(ml.flags), "verdict": verdict, "cpu_s": t_ml, "scores": scores(network, ml_values, data, first, score_steps)},
        "kstep": {
            "values": ks.values,
            "notes": list(ks.notes),
            "criterion_K2": ks.objective,
            "criterion_at_ml_K2": ks.objective_ml,
            "noise_scale": ks.noise_scale,
            "cpu_s": t_ks,
            "scores": scores(network, ks.values, data, first, score_steps),
        },
    }  # fmt: skip


def markdown(results: dict) -> str:
    """The table of docs/validation.md."""
    lines = [
        "| data set | model | horizon | RMSE ML (K) | RMSE k-step (K) | interval score ML (K) | interval score k-step (K) | coverage ML | coverage k-step | verdict of the ML fit |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        verdict = verdict_cell(r["ml"]["verdict"]) if r["ml"].get("verdict") else "not recorded"
        for row, (k, a) in enumerate(r["ml"]["scores"].items()):
            b = r["kstep"]["scores"][k]
            h = int(k) * r["dt_s"] / 3600
            lines.append(
                f"| {name} | {r['model']} | {k} ({h:g} h) | {a['rmse_K']:.3f} | {b['rmse_K']:.3f} |"
                f" {a['interval_score_K']:.3f} | {b['interval_score_K']:.3f} | {a['coverage_2sigma']:.0%} |"
                f" {b['coverage_2sigma']:.0%} | {verdict if row == 0 else ''} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=DEFAULT_SHARED)
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument(
        "--only", action="append", choices=list(DATASETS), help="run only this data set (repeatable)"
    )
    args = ap.parse_args(argv)
    if not (args.shared / "data").is_dir():
        print(f"skipped: data not found under {args.shared / 'data'}")
        return 0
    results = {}
    for name, (path, load) in DATASETS.items():
        if args.only and name not in args.only:
            continue
        if not (args.shared / "data" / path).is_file():
            print(f"skipped {name}: not found")
            continue
        network, frame = load(args.shared)
        if name == "bacher_madsen_prbs":  # the default fit's model of docs/validation.md (2 states)
            network, frame = (
                load_model("TiTe+heater+solar").network,
                bacher_madsen_frame(args.shared, outdoor="To"),
            )
        results[name] = one(name, network, frame)
        print(markdown({name: results[name]}), flush=True)
        write_json_atomic(args.out / "kstep_vs_ml.json", results)
    print(markdown(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
