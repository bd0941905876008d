"""Joint fit of two zones of the virtual building (a multi-zone forced test), with its figures.

Usage::

    python validation/multizone_virtual.py [--seed 1] [--check-seed 2] [--out validation-output]
        [--figures docs/figures]

Generates the multi-zone forced night ``seed`` (target and n1 forced,
:func:`rczone.virtual.multizone.generate_multizone_night`) and runs, through the command line,

    rczone fit NIGHT.csv --model validation/models/virtual_two_zones.toml --json fit.json --save-model fit-model.json --no-profiles
    rczone predict fit-model.json NIGHT.csv --out pred-fit.csv
    rczone predict fit-model.json CHECK.csv --out pred-check.csv

(``CHECK`` is another night, ``check-seed``, not used by the fit). Prints the recovery table
(estimate, truth from :mod:`tests.acceptance.multizone_truth`, ratio; for ``Cp``, ``Cl``,
``Rm``, ``Cm`` also their hour-scale truths) as Markdown with the wall
times of the generation and the fit, and writes ``multizone_fit.png`` (measured vs predicted
air temperatures of the two excited zones on the fitted night) and ``multizone_check.png`` (on
the other night) to the figures folder. Run from the repository root.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd

from rczone.cli.main import main as rczone
from rczone.virtual.multizone import generate_multizone_night

HERE = Path(__file__).resolve().parent
MODEL = HERE / "models" / "virtual_two_zones.toml"
#: Excited zones and their data columns (air temperature, supply temperature).
ZONES = (("target", "Ti", "Ts"), ("n1", "Tn1", "Ts_n1"))


def plot(pred: pd.DataFrame, night: pd.DataFrame, title: str, path: Path) -> None:
    """Measured vs predicted air temperatures (with the 2-sigma band) of the excited zones."""
    fig, axes = plt.subplots(len(ZONES), 1, figsize=(9, 6), sharex=True)
    h = pred["time"] / 3600 + 18
    for ax, (zone, col, ts) in zip(axes, ZONES, strict=True):
        ax.fill_between(h, pred[f"{col}_lower"], pred[f"{col}_upper"], color="C1", alpha=0.2, lw=0)
        ax.plot(h, pred[f"{col}_measured"], "k.", ms=2, label="measured")
        ax.plot(h, pred[f"{col}_predicted"], "C1", lw=1.5, label="predicted (open loop), 2-sigma band")
        ax.set_ylabel(f"{col} ({zone}), degC")
        hot = night[ts] > 25
        ax.fill_between(h, 0, 1, where=hot, transform=ax.get_xaxis_transform(), color="C3", alpha=0.08, lw=0)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(title, fontsize=10)
    axes[-1].set_xlabel("hour (18 = 6 pm; red: this zone's reheat on)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run(seed: int, check_seed: int, out: Path, figures: Path) -> int:
    sys.path.insert(0, str(HERE.parent))
    from tests.acceptance.multizone_truth import hour_scale_masses, hour_scale_partition_capacity, true_values

    out.mkdir(parents=True, exist_ok=True)
    figures.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    night = generate_multizone_night("autumn", seed)
    t_gen = time.perf_counter() - t0
    check = generate_multizone_night("autumn", check_seed)
    data, other = out / f"multizone-{seed}.csv", out / f"multizone-{check_seed}.csv"
    night.to_csv(data, index=False)
    check.to_csv(other, index=False)
    fit_json, fitted = out / "fit.json", out / "fit-model.json"
    t0 = time.perf_counter()
    rc = rczone(
        [
            "fit",
            str(data),
            "--model",
            str(MODEL),
            "--json",
            str(fit_json),
            "--save-model",
            str(fitted),
            "--no-profiles",
        ]
    )
    t_fit = time.perf_counter() - t0
    if rc not in (0, 3):
        return rc
    preds = {}
    for name, path in (("fit", data), ("check", other)):
        p = out / f"pred-{name}.csv"
        if rczone(["predict", str(fitted), str(path), "--out", str(p)]) != 0:
            return 1
        preds[name] = pd.read_csv(p)
    res = json.loads(fit_json.read_text())
    truth = true_values()
    hour = {"Cp": hour_scale_partition_capacity()}
    for z in ("t", "n1"):
        hour.update({f"{k}_{z}": v for k, v in hour_scale_masses(z).items() if k != "max_error"})
    print(
        f"\ngeneration {t_gen:.1f} s; rczone fit (default settings, --json) {t_fit:.1f} s; exit code {rc}\n"
    )
    print("| parameter | estimate | std. error | nominal start | truth | estimate / truth |")
    print("|---|---|---|---|---|---|")
    for k, v in res["parameters"].items():
        tr = truth.get(k)
        ratio = f"{v['estimate'] / tr:.3f}" if tr else "-"
        se = f"{v['std_error']:.3g}" if v.get("std_error") is not None else "-"
        start = f"{v['construction']:.4g}" if v.get("construction") is not None else "-"
        tr_s = f"{tr:.4g}" if tr else "-"
        print(f"| {k} | {v['estimate']:.4g} | {se} | {start} | {tr_s} | {ratio} |")
        if k in hour and hour[k] > 100 * tr:  # a sink without end at these periods
            print(f"| {k} (hour-scale truth) | | | | unbounded | - |")
        elif k in hour:
            print(f"| {k} (hour-scale truth) | | | | {hour[k]:.4g} | {v['estimate'] / hour[k]:.3f} |")
    for name, night_df, s in (("fit", night, seed), ("check", check, check_seed)):
        pr = preds[name]
        rmse = {
            c: float(((pr[f"{c}_measured"] - pr[f"{c}_predicted"]) ** 2).mean() ** 0.5) for _, c, _ in ZONES
        }
        print(
            f"\nopen-loop RMSE on night {s} ({name}): " + ", ".join(f"{c} {v:.3f} K" for c, v in rmse.items())
        )
        title = f"joint fit of target + n1, {'fitted night' if name == 'fit' else 'another night'} (seed {s})"
        plot(pr, night_df, title, figures / f"multizone_{name}.png")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--check-seed", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("validation-output") / "multizone")
    ap.add_argument("--figures", type=Path, default=HERE.parent / "docs" / "figures")
    a = ap.parse_args()
    return run(a.seed, a.check_seed, a.out, a.figures)


if __name__ == "__main__":
    sys.exit(main())
