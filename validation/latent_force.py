"""Latent-force disturbances on real data: the same model with and without one (issue 23, item 3).

Usage::

    python validation/latent_force.py [--shared ../shared] [--out validation-output] [--only NAME]
        [--kind auto|matern32|periodic] [--noise auto|measured|all] [--hold zoh|foh]

Reads the real data sets from the shared folder (their licences do not allow shipping them; see
each PROVENANCE.md) and, for each, fits by ML on the first 75 % a model *without* and the same
model *with* an unmeasured heat input at the room air whose prior is a Gaussian process
(:mod:`rczone.network.disturbance`). One recipe for every data set, each choice made on the
calibration part alone:

* process noise on the measured states (``rczone fit``'s default), on every state only when that
  leaves an R or C of the model without the disturbance at a bound (:data:`NOISES`);
* a Matérn-3/2 disturbance, magnitude in [1, 2000] W, length scale from three sampling intervals
  (a shorter one is white noise at that sampling) to two days; if a parameter of that fit ends at a
  bound, the quasi-periodic daily one instead (period 24 h, fixed; decay from one to twenty days)
  (:data:`AUTO`, :func:`disturbance_bounds`).

Reported per data set:

* the likelihood-ratio test of the nesting that :func:`rczone.selection.nesting.nesting` finds
  (the disturbance's magnitude -> 0): statistic, degrees of freedom, the ``chi2(df)`` p-value
  (the one that decides) and the chi-bar-squared one;
* the Ljung-Box p-value of each model's standardized one-step innovations on the calibration part
  (:attr:`rczone.Calibration.innovations`; closer to white is larger);
* the verdict ``rczone fit`` gives each fit on the calibration part (every fit is
  :func:`rczone.fit`, the model with the disturbance started from the estimates of the one without);
* the held-out 6-h prediction error: the filter runs over the whole record with the calibration
  estimates, and each held-out sample is predicted from the filtered state 6 h earlier with the
  measured inputs (:func:`rczone.estimation.forecast.k_step_band`), RMSE over the held-out part.

Prints 'skipped: data not found' and exits 0 when the shared folder is absent. Writes
``<out>/latent_force.json`` and prints the table as Markdown (the form in docs/validation.md).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.special import chdtrc

from rczone.estimation import Dataset
from rczone.estimation.forecast import k_step_band
from rczone.files.atomic import write_json_atomic
from rczone.models import load_model
from rczone.network import LatentForce, Parameter, RCNetwork
from rczone.network.stochastic import is_noise_name
from rczone.selection.compare import chi_bar_sf
from rczone.selection.nesting import nesting

HERE = Path(__file__).resolve().parent
DEFAULT_SHARED = HERE.parent.parent / "shared"
sys.path.insert(0, str(HERE))
from real_data import bacher_madsen_frame, leec_frame, leec_network  # noqa: E402
from verdicts import verdict_cell  # noqa: E402

#: Prediction horizon of the held-out check, s.
HORIZON_S = 6 * 3600.0
#: Level of the likelihood-ratio test.
ALPHA = 0.05


#: Period of the quasi-periodic disturbance, s (the day that occupancy and the sun follow).
DAY = 86400.0
#: Shortest Matérn length scale, in sampling intervals: at ``ell = 3 dt`` neighbouring samples of
#: the force correlate at 0.9 (``(1 + r) exp(-r)``, ``r = sqrt(3)/3``); a shorter one cannot be
#: told from white process noise at that sampling.
SAMPLES_PER_LENGTH_SCALE = 3


def disturbance_bounds(kind: str, dt: float) -> tuple[float, float]:
    """Bounds (s) of ``ld`` for a record sampled every ``dt`` s.

    ``matern32``: from :data:`SAMPLES_PER_LENGTH_SCALE` sampling intervals to two days (a slower
    gain is a change of the building, not a disturbance); ``periodic``: the decay of the daily
    profile from one period (a profile that is forgotten within a day is not a daily pattern) to
    twenty.
    """
    if kind == "periodic":
        return DAY, 20 * DAY
    return SAMPLES_PER_LENGTH_SCALE * dt, 2 * DAY


def with_disturbance(
    net: RCNetwork, kind: str = "matern32", node: str = "Ti", *, dt: float = 1800.0
) -> RCNetwork:
    """``net`` plus a disturbance ``Qd`` at ``node``: magnitude ``sd`` in [1, 2000] W, ``ld`` in :func:`disturbance_bounds`.

    ``matern32``: a smooth gain of length scale ``ld``; ``periodic``: a daily gain (period
    :data:`DAY`, fixed) whose profile drifts over ``ld``.
    """
    periodic = kind == "periodic"
    lo, hi = disturbance_bounds(kind, dt)
    params = [
        Parameter("sd", "magnitude", 100.0, bounds=(1.0, 2000.0), description="std of the unmeasured gains"),
        Parameter(
            "ld",
            "time",
            min(max(2 * DAY if periodic else 4 * 3600.0, 1.5 * lo), 0.5 * hi),
            bounds=(lo, hi),
            description="decay of the daily profile" if periodic else "length scale of the gains",
        ),
    ]
    extra = {}
    if periodic:
        params.append(Parameter("Pd", "time", DAY, fixed=True, description="a day"))
        extra["period"] = "Pd"
    return RCNetwork(
        f"{net.name}+Qd",
        net.nodes,
        net.boundaries,
        net.resistors,
        [*net.parameters.values(), *params],
        net.heat_inputs,
        net.supply_air,
        net.outputs,
        net.description,
        disturbances=[LatentForce("Qd", kind, node, magnitude="sd", length_scale="ld", **extra)],
    )


def _one(
    net: RCNetwork,
    cal: pd.DataFrame,
    full: Dataset,
    split: int,
    start: dict | None = None,
    noise: str = "all",
    hold: str = "zoh",
) -> tuple[dict, object, tuple[str, ...]]:
    """``rczone fit`` of ``net`` on the calibration part ``cal`` from the values ``start``, and its scores.

    The fit (:func:`rczone.fit`) carries the verdict ``rczone fit`` gives it on these data and the
    whiteness of its innovations; the 6-h error is scored on the samples of ``full`` from ``split``.
    """
    import rczone

    t0 = time.process_time()
    zm = load_model(net)
    if start:
        theta = {k: v for k, v in start.items() if k in net.parameters}
        zm = zm.with_values(theta, {k: v for k, v in start.items() if k not in theta})
    fitted = rczone.fit(zm, cal, noise=noise, hold=hold, checks=False)
    res, white = fitted.result, fitted.innovations
    free = tuple(fitted.model.provenance["free"])
    values = {**res.fixed, **res.estimates}
    dt = float(np.median(np.diff(full.t)))
    y_hat, _ = k_step_band(net, values, full, max(1, round(HORIZON_S / dt)), hold)
    err = (full.y - y_hat)[split:, 0]  # the room air (the first output)
    out = {
        "loglik": res.llf,
        "n_params": res.n_params,
        "converged": res.converged,
        "flags": list(res.flags),
        "at_bound": [e.name for e in res.parameters.values() if e.at_bound],
        "verdict": fitted.verdict.to_dict(),
        "ljung_box_p": white.ljung_box_p,
        "rmse_6h_K": float(np.sqrt(np.nanmean(err**2))),
        "estimates": {k: float(v) for k, v in res.estimates.items()},
        "cpu_s": round(time.process_time() - t0, 1),
    }
    return out, res, free


#: Kinds tried in turn by ``kind="auto"``: the next one only when a fit with the previous one has
#: a parameter at a bound of its box (the data cannot resolve that prior; docs/validation.md).
AUTO = ("matern32", "periodic")
#: Process-noise placements tried in turn for the model without the disturbance: on the measured
#: states (``rczone fit``'s default), on every state only when that leaves an R or C at a bound.
#: With noise on an unmeasured state, that state can become a free random walk (on the LEEC
#: classroom the mass does: ``Cm`` and ``Rea`` at their bounds) that absorbs the slow unmeasured
#: heat a disturbance is there to model; without it, a heater node can collapse (Bacher-Madsen:
#: ``Ch`` at its floor).
NOISES = ("measured", "all")


def at_bounds(fit_row: dict) -> list[str]:
    """The parameters of a fit at a bound of their box, noise levels aside (they may sit at their floor)."""
    return [n for n in fit_row["at_bound"] if not is_noise_name(n)]


def compare(
    plain: RCNetwork,
    frame: pd.DataFrame,
    kind: str = "auto",
    node: str = "Ti",
    calibration_fraction: float = 0.75,
    noise: str = "auto",
    hold: str = "zoh",
) -> dict:
    """Fit ``plain`` and :func:`with_disturbance` of it; the test, the whiteness and the 6-h error of each.

    Every choice is made on the calibration part alone (the held-out part never enters it), in the
    order a practitioner would: ``noise="auto"`` takes the first of :data:`NOISES` whose fit without
    the disturbance has no R or C at a bound; ``kind="auto"`` the first of :data:`AUTO` whose fit
    has no parameter at a bound (the last one tried otherwise).
    """
    split = int(calibration_fraction * len(frame))
    full = Dataset.from_frame(frame, plain, time="time")
    cal = frame.iloc[:split]
    dt = float(np.median(np.diff(full.t[:split])))
    base = {}
    for placement in NOISES if noise == "auto" else (noise,):
        a, res_a, free_a = _one(plain, cal, full, split, noise=placement, hold=hold)
        base[placement] = a
        if not at_bounds(a):
            break
    noise = placement
    tried = {}
    for k in AUTO if kind == "auto" else (kind,):
        rich = with_disturbance(plain, k, node, dt=dt)
        # the search starts from the simpler model's estimates (as `select` does): the richer model's
        # likelihood is then at least the simpler one's up to the disturbance's start
        start = {n: v for n, v in res_a.estimates.items() if n in free_a}
        b, res_b, free_b = _one(rich, cal, full, split, start=start, noise=noise, hold=hold)
        b["kind"] = k
        tried[k] = b
        if not at_bounds(b):
            break
    nest = nesting(plain, rich, free_a, free_b)
    if nest is None:  # pragma: no cover - with_disturbance always nests
        raise RuntimeError("the model with the disturbance does not nest the model without")
    stat = 2.0 * (res_b.llf - res_a.llf)
    p = float(chdtrc(nest.df, max(stat, 0.0)))
    return {
        "samples_calibration": split,
        "samples_held_out": len(frame) - split,
        "noise": noise,
        "hold": hold,
        "without": a,
        "with": b,
        "tried": {  # every fit the choices above made, the chosen ones included
            "noise": {k: {n: t[n] for n in ("loglik", "at_bound", "estimates")} for k, t in base.items()},
            "kind": {
                k: {n: t[n] for n in ("loglik", "ljung_box_p", "rmse_6h_K", "at_bound", "estimates")}
                for k, t in tried.items()
            },
        },
        "test": {
            "restriction": nest.describe(),
            "statistic": stat,
            "df": nest.df,
            "p_value": p,
            "p_chi_bar": chi_bar_sf(stat, nest.df, nest.n_boundary),
            "selected": "with" if p < ALPHA else "without",
        },
    }


def bacher_madsen(shared: Path) -> tuple[RCNetwork, pd.DataFrame]:
    """Bacher-Madsen PRBS experiment; the model the forward selection picks (TiTeTh, heater, solar)."""
    frame = bacher_madsen_frame(shared, outdoor="To")
    return load_model("TiTeTh+heater+solar").network, frame


def armadillo(shared: Path) -> tuple[RCNetwork, pd.DataFrame]:
    """Armadillo Box (pySIP data set H2, 30 min); interior and envelope, heater into the interior.

    Without the solar input: with an aperture ``Aw Ps`` into the interior, ``Aw`` runs to 0 with and
    without the disturbance (the irradiance column does not explain the room), and the flag would
    hide the comparison.
    """
    raw = pd.read_csv(shared / "data" / "armadillo_pysip" / "armadillo_data_H2.csv")
    frame = pd.DataFrame(
        {"time": raw["Time"], "Ti": raw["T_int"], "To": raw["T_ext"], "Ph": raw["P_hea"], "Ps": raw["I_sol"]}
    )
    return load_model("TiTe+heater").network, frame.drop(columns="Ps")


def leec(shared: Path) -> tuple[RCNetwork, pd.DataFrame]:
    """LEEC classroom: the cleaning of validation/real_data.py (longest stretch without a frozen logger)."""
    return leec_network(), leec_frame(shared)[0][["time", "Ti", "To", "Ts", "m", "Q"]]


DATASETS: dict[str, tuple[str, Callable[[Path], tuple[RCNetwork, pd.DataFrame]]]] = {
    "bacher_madsen_prbs": ("bacher_madsen_prbs/inputPRBS1.csv", bacher_madsen),
    "armadillo_pysip": ("armadillo_pysip/armadillo_data_H2.csv", armadillo),
    "leec_classroom_vav": ("leec_classroom_vav/LEEC_classroom_VAV_hourly.csv", leec),
}


def markdown(results: dict) -> str:
    """One row per data set and model."""
    lines = [
        "| data set | model | process noise | log L | k | LR (df) | p (chi2) | Ljung-Box p | 6-h RMSE held out (K) |"
        " at a bound | verdict |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        t = r["test"]
        for which in ("without", "with"):
            m = r[which]
            label = m["model"] + (" **(selected)**" if t["selected"] == which else "")
            test = f"{t['statistic']:.1f} ({t['df']}) | {t['p_value']:.2g}" if which == "with" else "| "
            lines.append(
                f"| {name} | {label} | {r['noise']} | {m['loglik']:.1f} | {m['n_params']} | {test} | {m['ljung_box_p']:.2g} |"
                f" {m['rmse_6h_K']:.3f} | {', '.join(m['at_bound']) or '-'} | {verdict_cell(m['verdict'])} |"
            )
    return "\n".join(lines)


def run(
    shared: Path,
    only: list[str] | None = None,
    kind: str = "auto",
    node: str = "Ti",
    noise: str = "auto",
    hold: str = "zoh",
) -> dict:
    """Every data set found under ``shared`` (or the ``only`` ones): :func:`compare` of its model."""
    results = {}
    for name, (path, load) in DATASETS.items():
        if only and name not in only:
            continue
        if not (shared / "data" / path).is_file():
            print(f"skipped {name}: {shared / 'data' / path} not found")
            continue
        plain, frame = load(shared)
        res = compare(plain, frame, kind, node, noise=noise, hold=hold)
        res["without"]["model"], res["with"]["model"] = plain.name, f"{plain.name}+Qd ({res['with']['kind']})"
        results[name] = res
        t = res["test"]
        print(
            f"{name}: LR {t['statistic']:.1f} (df {t['df']}, p {t['p_value']:.2g}); Ljung-Box p"
            f" {res['without']['ljung_box_p']:.2g} -> {res['with']['ljung_box_p']:.2g}; 6-h RMSE"
            f" {res['without']['rmse_6h_K']:.3f} -> {res['with']['rmse_6h_K']:.3f} K ({res['with']['kind']},"
            f" noise on {res['noise']} states)",
            flush=True,
        )
    return results


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=DEFAULT_SHARED)
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument(
        "--kind",
        choices=("auto", *AUTO),
        default="auto",
        help="the disturbance's kind for every data set (auto: Matérn-3/2, the daily kernel if that ends at a bound)",
    )
    ap.add_argument("--node", default="Ti", help="the node the disturbance enters (default Ti)")
    ap.add_argument(
        "--noise",
        choices=("auto", *NOISES),
        default="auto",
        help="process noise of every fit (auto: on the measured states, on all if that leaves an R or C at a bound)",
    )
    ap.add_argument(
        "--only", action="append", choices=list(DATASETS), help="run only this data set (repeatable)"
    )
    ap.add_argument(
        "--hold", choices=("zoh", "foh"), default="zoh", help="inputs between samples (default zoh)"
    )
    args = ap.parse_args(argv)
    if not (args.shared / "data").is_dir():
        print(f"skipped: data not found under {args.shared / 'data'}")
        return 0
    results = run(args.shared, args.only, args.kind, args.node, args.noise, args.hold)
    write_json_atomic(args.out / "latent_force.json", results)
    print(markdown(results))
    return 0 if all(math.isfinite(r["test"]["statistic"]) for r in results.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
