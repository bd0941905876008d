"""Held-out RMSE and interval score per horizon: the ML fit against the k-step fit of the same model (issue 36).

Usage::

    python validation/kstep_vs_ml.py [--shared ../shared] [--out validation-output] [--only NAME]

For each real data set (read from the shared folder; their licences do not allow shipping them):
fit the model by ML on the first 75 % (``rczone fit --holdout 0.25``: process noise on the measured
states), then by the k-step criterion from that fit (``rczone fit --method kstep``, horizons one
step, 1 h and 6 h), and score both on the last 25 %: the filter runs over the whole
record with the calibration estimates, each held-out sample is predicted from the filtered state
k steps earlier (:func:`rczone.estimation.forecast.k_step_bands`); RMSE, the 2-sigma band's coverage
and its interval score (Gneiting & Raftery 2007) per horizon. Prints 'skipped: data not found' and
exits 0 without the shared folder. Writes ``<out>/kstep_vs_ml.json`` and prints a Markdown table,
each fit with the verdict rczone gives it (``rczone fit --holdout``: flags, robust standard
errors, held-out checks).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from rczone.calibration.conformal import ALPHA, interval_score
from rczone.estimation import Dataset
from rczone.estimation.forecast import k_step_bands
from rczone.files.atomic import write_json_atomic
from rczone.models import load_model
from rczone.workflow.holdout import split_time

HERE = Path(__file__).resolve().parent
DEFAULT_SHARED = HERE.parent.parent / "shared"
sys.path.insert(0, str(HERE))
from latent_force import DATASETS  # noqa: E402
from real_data import bacher_madsen_frame  # noqa: E402
from verdicts import verdict_cell  # noqa: E402

#: Horizons the k-step fit sums, s (besides one step).
FIT_HORIZONS_S = (3600.0, 21600.0)
#: Horizons scored, s (besides one step).
SCORE_HORIZONS_S = (3600.0, 21600.0, 86400.0)
#: Share of the samples held out at the end (``rczone fit --holdout 0.25``).
HOLDOUT = 0.25
#: Data sets' names in the table.
TITLES = {
    "bacher_madsen_prbs": "Bacher–Madsen",
    "armadillo_pysip": "Armadillo",
    "leec_classroom_vav": "LEEC classroom",
}


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


def _label(seconds: float) -> str:
    """A horizon as the page writes it (``5 min``, ``1 h``), to the second (the sampling is not exact)."""
    seconds = round(seconds)
    return f"{seconds / 3600:g} h" if seconds >= 3600 else f"{seconds / 60:g} min"


def one(name: str, network, frame) -> dict:
    """ML and k-step fits on the first 75 % of ``frame``, both scored on the rest, each with rczone's verdict.

    The ML fit is ``rczone fit --holdout 0.25`` (:func:`rczone.fit`); the k-step fit is ``rczone fit
    --method kstep --starts 1 --holdout 0.25`` from that fitted model (its likelihood search starts
    and ends at the ML estimate, the k-step criterion then starts from it). Each carries the
    verdict rczone gives it: its own flags, the robust standard errors and the held-out checks.
    """
    import rczone

    data = Dataset.from_frame(frame, network, time="time")
    at = split_time(frame, HOLDOUT, model=load_model(network))
    first = int(np.sum(data.t < at))
    dt = float(np.median(np.diff(data.t)))
    fit_steps = _steps(dt, FIT_HORIZONS_S, first // 4)
    score_steps = _steps(dt, SCORE_HORIZONS_S, data.n_samples - first)
    fits = {}
    t0 = time.process_time()
    ml = rczone.fit(network, frame, holdout=HOLDOUT, checks=False, label=name)
    fits["ml"] = (ml, time.process_time() - t0)
    t0 = time.process_time()
    ks = rczone.fit(
        ml.model, frame, method="kstep", options={"horizons": fit_steps}, n_starts=1,
        holdout=HOLDOUT, checks=False, label=name,
    )  # fmt: skip
    fits["kstep"] = (ks, time.process_time() - t0)
    out = {
        "model": network.name,
        "dt_s": dt,
        "calibration_samples": first,
        "held_out_samples": data.n_samples - first,
        "fit_horizons": fit_steps,
    }
    for method, (cal, cpu) in fits.items():
        values = {**cal.result.fixed, **cal.result.estimates}
        out[method] = {
            "values": values,
            "flags": list(cal.result.flags),
            "notes": list(cal.result.notes),
            "verdict": cal.verdict.to_dict(),
            "cpu_s": cpu,
            "scores": scores(network, values, data, first, score_steps),
        }
        print(f"{name} {method}: {cpu:.0f} s CPU, {verdict_cell(cal.verdict)}", flush=True)
    return out


def markdown(results: dict) -> str:
    """The table of docs/validation.md; the data set, model and each fit's verdict on its first row."""
    lines = [
        "| data set | model | horizon | RMSE ML (K) | RMSE k-step (K) | interval score ML (K) | interval score k-step (K) |"
        " coverage ML | coverage k-step | verdict ML | verdict k-step |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        for row, (k, a) in enumerate(r["ml"]["scores"].items()):
            b = r["kstep"]["scores"][k]
            once = [TITLES.get(name, name), r["model"]] if row == 0 else ["", ""]
            verdicts = [verdict_cell(r[m]["verdict"]) for m in ("ml", "kstep")] if row == 0 else ["", ""]
            cells = [
                *once,
                _label(int(k) * r["dt_s"]),
                *(f"{x[key]:.3f}" for key in ("rmse_K", "interval_score_K") for x in (a, b)),
                *(f"{100 * x['coverage_2sigma']:.0f} %" for x in (a, b)),
                *verdicts,
            ]
            lines.append("|" + "|".join(f" {c} " if c else " " for c in cells) + "|")
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
