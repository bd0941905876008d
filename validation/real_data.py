"""Fit and validate rczone models on real measured building data (kept outside the project).

Usage::

    python validation/real_data.py [--shared ../shared] [--out validation-output]

Reads the data sets from the shared folder (default: ``shared`` next to the repository); their
licences do not allow shipping them (see each PROVENANCE.md), so nothing is copied. Prints
'skipped: data not found' and exits 0 when they are absent. For each data set: the data are
cleaned by a stated rule, split into a calibration part and the held-out last part, the
identifiability verdicts are computed, the model is fitted by LS and ML (``rczone.fit`` with
``holdout=0.25``, so each fit carries the verdict ``rczone fit --holdout 0.25`` gives), and the
fitted model is simulated open loop on the held-out part. Results go to ``<out>/real_data.json``;
the tables of docs/validation.md are printed as Markdown.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from rczone.data import load_zone_data
from rczone.data.quality import RczoneWarning
from rczone.diagnostics import diagnose
from rczone.estimation import Dataset
from rczone.files.atomic import write_json_atomic
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from rczone.postfit.openloop import open_loop_error

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from verdicts import verdict_cell  # noqa: E402

DEFAULT_SHARED = HERE.parent.parent / "shared"


def leec_network() -> RCNetwork:
    """Classroom air (with furniture) and the exposed thermal mass; envelope to outdoors; supply air."""
    return RCNetwork(
        "LEEC classroom TiTm",
        nodes=[Node("Ti", "Ci"), Node("Tm", "Cm")],
        boundaries=["To"],
        resistors=[Resistor("Ti", "To", "Rea"), Resistor("Ti", "Tm", "Rim")],
        parameters=[
            Parameter("Ci", "capacitance", 2e6, unit="J/K", description="air and furniture"),
            Parameter("Cm", "capacitance", 5e7, unit="J/K", description="exposed walls and slab"),
            Parameter("Rea", "resistance", 5e-3, unit="K/W", description="envelope and infiltration"),
            Parameter("Rim", "resistance", 2.5e-4, unit="K/W", description="air to exposed mass"),
        ],
        heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
        supply_air=[SupplyAir("Ti", flow="m", temperature="Ts")],
        outputs=["Ti"],
    )


def bacher_madsen_network() -> RCNetwork:
    """The TiTe model of Bacher & Madsen (2011): interior and envelope, heater and solar into the interior."""
    return RCNetwork(
        "Bacher-Madsen TiTe",
        nodes=[Node("Ti", "Ci"), Node("Te", "Ce")],
        boundaries=["Ta"],
        resistors=[Resistor("Ti", "Te", "Rie"), Resistor("Te", "Ta", "Rea")],
        parameters=[
            Parameter("Ci", "capacitance", 1.3e6, unit="J/K"),
            Parameter("Ce", "capacitance", 1.3e7, unit="J/K"),
            Parameter("Rie", "resistance", 2e-3, unit="K/W"),
            Parameter("Rea", "resistance", 2e-2, unit="K/W"),
            Parameter("Aw", "gain", 5.0, unit="m2", description="effective window area"),
        ],
        heat_inputs=[HeatInput("Ph", {"Ti": 1.0}), HeatInput("Ps", {"Ti": "Aw"})],
        outputs=["Ti"],
    )


def stuck_mask(frame: pd.DataFrame, columns: list[str], hours: float = 6.0) -> np.ndarray:
    """Samples where every one of ``columns`` has not changed over the previous ``hours`` (a frozen logger)."""
    t = frame["time"].to_numpy(float)
    dt = float(np.median(np.diff(t)))
    n = max(2, round(hours * 3600 / dt))
    frozen = np.ones(len(frame), bool)
    for c in columns:
        r = frame[c].rolling(n, min_periods=n)
        frozen &= ((r.max() - r.min()).fillna(1.0) == 0.0).to_numpy()
    return frozen


def longest_clean_run(mask: np.ndarray) -> slice:
    best, start = (0, 0), None
    for i, bad in enumerate(np.r_[mask, True]):
        if not bad and start is None:
            start = i
        elif bad and start is not None:
            if i - start > best[1] - best[0]:
                best = (start, i)
            start = None
    return slice(*best)


#: The held-out part: the last quarter of the samples (``rczone fit --holdout 0.25``).
HOLDOUT = 0.25
#: Columns of the tables: per data set, the parameters shown (in the JSON's order).
SHOWN = {
    "leec_classroom_vav": ("Ci", "Cm", "Rea", "Rim"),
    "bacher_madsen_prbs": ("Ci", "Ce", "Rie", "Rea", "Aw"),
}
#: Units of the parameters in the tables' headers.
UNITS = {"C": "J/K", "R": "K/W", "A": "m2"}


def fit_and_validate(net: RCNetwork, frame: pd.DataFrame, free: list[str], name: str) -> dict:
    """Diagnose, fit by LS and ML with the last :data:`HOLDOUT` held out, and score open loop.

    Each fit is ``rczone.fit(..., holdout=HOLDOUT)`` (``rczone fit --holdout 0.25``), so its verdict
    is the one rczone gives: the fit's own flags and the held-out checks
    (:mod:`rczone.postfit.evidence`).
    """
    import rczone
    from rczone.models import load_model
    from rczone.workflow.holdout import before, split_time

    at = split_time(frame, HOLDOUT, model=load_model(net))
    cal, val = before(frame, at), frame[frame["time"] >= at]
    data_cal = Dataset.from_frame(cal, net, time="time")
    data_val = Dataset.from_frame(val, net, time="time")
    out: dict = {"samples_calibration": len(cal), "samples_validation": len(val), "methods": {}}
    rc = [n for n in free if net.parameters[n].kind in ("resistance", "capacitance")]
    d = diagnose(net, cal, free=rc, heat_input=None)
    out["diagnose"] = {k: {"verdict": v.verdict, "reason": v.reason} for k, v in d.parameters.items()}
    for method in ("ls", "ml"):
        extra = ["sigma_v", "sigma_w_Ti"] if method == "ml" else []
        fitted = rczone.fit(
            net, frame, method=method, free=free + extra, checks=False, holdout=HOLDOUT, label=name
        )
        res = fitted.result
        theta = {
            k: v
            for k, v in {**res.fixed, **res.estimates}.items()
            if k in net.parameters and not net.parameters[k].is_tied
        }
        ol_cal = open_loop_error(net, theta, data_cal)
        ol_val = open_loop_error(net, theta, data_val)
        out["methods"][method] = {
            "parameters": {
                n: {
                    "estimate": res.estimates[n],
                    "std_error": res.std_errors[n],
                    "at_bound": bool(res.parameters[n].at_bound),
                }
                for n in free
            },
            "converged": res.converged,
            "flags": list(res.flags),
            "verdict": fitted.verdict.to_dict(),
            "calibration_rmse_K": ol_cal.rmse_K,
            "validation_rmse_K": ol_val.rmse_K,
            "validation_max_error_K": ol_val.max_abs_K,
        }
        print(
            f"{name} {method.upper()}: "
            + ", ".join(f"{n} = {res.estimates[n]:.3g}" for n in free)
            + f"; open-loop RMSE {ol_cal.rmse_K:.2f} K (calibration), {ol_val.rmse_K:.2f} K"
            f" (held out, max {ol_val.max_abs_K:.2f} K); {verdict_cell(fitted.verdict)}"
        )
    print(f"{name} diagnose: " + ", ".join(f"{k} {v['verdict']}" for k, v in out["diagnose"].items()))
    return out


def estimate_cell(p: dict) -> str:
    """An estimate and its standard error on one power of ten (``4.84e6 ± 0.09e6``), or ``(at bound)``."""
    v, se = p["estimate"], p["std_error"]
    e = int(np.floor(np.log10(abs(v)))) if v else 0
    scaled = abs(e) >= 3
    text = (lambda x: f"{x / 10**e:.2f}e{e}") if scaled else (lambda x: f"{x:.3g}")
    if p.get("at_bound"):
        return f"{v:.2g} (at bound)"
    if not np.isfinite(se):
        return text(v)
    return f"{text(v)} ± {text(se)}" if scaled else f"{v:.3g} ± {se:.2g}"


def markdown(results: dict) -> str:
    """The tables of docs/validation.md: per data set, each method's estimates, errors and verdict."""
    blocks = []
    for name, res in results.items():
        shown = SHOWN[name]
        head = " | ".join(f"{n} ({UNITS[n[0]]})" for n in shown)
        lines = [
            f"| method | {head} | RMSE calib. (K) | RMSE held out (K) | max held out (K) | verdict |",
            "|" + "---|" * (len(shown) + 5),
        ]
        for method, m in res["methods"].items():
            cells = " | ".join(estimate_cell(m["parameters"][n]) for n in shown)
            lines.append(
                f"| {method.upper()} | {cells} | {m['calibration_rmse_K']:.2f} | {m['validation_rmse_K']:.2f} |"
                f" {m['validation_max_error_K']:.2f} | {verdict_cell(m['verdict'])} |"
            )
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks)


def leec_frame(shared: Path) -> tuple[pd.DataFrame, np.ndarray]:
    """The LEEC classroom's longest stretch without frozen sensors, and the mask of frozen samples."""
    folder = shared / "data" / "leec_classroom_vav"
    with warnings.catch_warnings():  # the loader warns about the frozen logger; handled below
        warnings.simplefilter("ignore", RczoneWarning)
        frame = load_zone_data(
            folder / "LEEC_classroom_VAV_hourly.csv", HERE / "maps" / "leec.toml"
        ).to_frame()
    frame = frame.dropna(subset=["Ti", "To", "Ts", "m"]).reset_index(drop=True)
    frame["Q"] = 0.0
    bad = stuck_mask(frame, ["Ti", "Ts", "Tw"], hours=6.0)
    return frame.iloc[longest_clean_run(bad)].reset_index(drop=True), bad


def leec(shared: Path) -> dict:
    """LEEC classroom: the longest stretch without frozen sensors, last 25 % held out."""
    clean, bad = leec_frame(shared)
    res = fit_and_validate(leec_network(), clean, ["Ci", "Cm", "Rea", "Rim"], "LEEC")
    res["cleaning"] = (
        f"frozen logger: samples where Ti, Ts and the wall-mass temperature have not changed for 6 h are"
        f" excluded ({int(bad.sum())} of {bad.size}); the longest clean stretch ({len(clean)} hours) is used"
    )
    return res


def bacher_madsen_frame(shared: Path, outdoor: str = "Ta") -> pd.DataFrame:
    """The Bacher-Madsen PRBS record in SI units (hours to s, kW to W); the outdoor column named ``outdoor``."""
    raw = pd.read_csv(shared / "data" / "bacher_madsen_prbs" / "inputPRBS1.csv")
    return pd.DataFrame(
        {
            "time": raw["t"] * 3600.0,
            "Ti": raw["yTi"],
            outdoor: raw["Ta"],
            "Ph": raw["Ph"] * 1e3,
            "Ps": raw["Ps"] * 1e3,
        }
    )


def bacher_madsen(shared: Path) -> dict:
    """Bacher-Madsen PRBS experiment: TiTe, last 25 % held out."""
    return fit_and_validate(
        bacher_madsen_network(),
        bacher_madsen_frame(shared),
        list(SHOWN["bacher_madsen_prbs"]),
        "Bacher-Madsen",
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=DEFAULT_SHARED)
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    args = ap.parse_args(argv)
    if not (args.shared / "data").is_dir():
        print(f"skipped: data not found under {args.shared / 'data'}")
        return 0
    results = {}
    for name, run in (("leec_classroom_vav", leec), ("bacher_madsen_prbs", bacher_madsen)):
        try:
            results[name] = run(args.shared)
        except FileNotFoundError as exc:
            print(f"skipped {name}: {exc}")
    write_json_atomic(args.out / "real_data.json", results)
    print(f"results written to {args.out / 'real_data.json'}")
    print(markdown(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
