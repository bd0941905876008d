"""Fit and validate rczone models on real measured building data (kept outside the project).

Usage::

    python validation/real_data.py [--shared ../shared] [--out validation-output]

Reads the data sets from the shared folder (default: ``shared`` next to the repository); their
licences do not allow shipping them (see each PROVENANCE.md), so nothing is copied. Prints
'skipped: data not found' and exits 0 when they are absent. For each data set: the data are
cleaned by a stated rule, split into a calibration part and the held-out last part, the
identifiability verdicts are computed, the model is fitted by LS and ML, and the fitted model
is simulated open loop on the held-out part. Results go to ``<out>/real_data.json``.
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
from rczone.estimation import Dataset, fit
from rczone.estimation.openloop import open_loop_error
from rczone.files.atomic import write_json_atomic
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir

HERE = Path(__file__).resolve().parent
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


def fit_and_validate(
    net: RCNetwork, cal: pd.DataFrame, val: pd.DataFrame, free: list[str], name: str
) -> dict:
    data_cal = Dataset.from_frame(cal, net, time="time")
    data_val = Dataset.from_frame(val, net, time="time")
    out: dict = {"samples_calibration": len(cal), "samples_validation": len(val), "methods": {}}
    rc = [n for n in free if net.parameters[n].kind in ("resistance", "capacitance")]
    d = diagnose(net, cal, free=rc, heat_input=None)
    out["diagnose"] = {k: {"verdict": v.verdict, "reason": v.reason} for k, v in d.parameters.items()}
    for method in ("ls", "ml"):
        extra = ["sigma_v", "sigma_w_Ti"] if method == "ml" else []
        res = fit(net, data_cal, free + extra, method=method)
        theta = {
            k: v
            for k, v in {**res.fixed, **res.estimates}.items()
            if k in net.parameters and not net.parameters[k].is_tied
        }
        ol_cal = open_loop_error(net, theta, data_cal)
        ol_val = open_loop_error(net, theta, data_val)
        out["methods"][method] = {
            "parameters": {n: {"estimate": res.estimates[n], "std_error": res.std_errors[n]} for n in free},
            "converged": res.converged,
            "flags": list(res.flags),
            "calibration_rmse_K": ol_cal.rmse_K,
            "validation_rmse_K": ol_val.rmse_K,
            "validation_max_error_K": ol_val.max_abs_K,
        }
        print(
            f"{name} {method.upper()}: "
            + ", ".join(f"{n} = {res.estimates[n]:.3g}" for n in free)
            + f"; open-loop RMSE {ol_cal.rmse_K:.2f} K (calibration), {ol_val.rmse_K:.2f} K"
            f" (held out, max {ol_val.max_abs_K:.2f} K)"
        )
    print(f"{name} diagnose: " + ", ".join(f"{k} {v['verdict']}" for k, v in out["diagnose"].items()))
    return out


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
    split = int(0.75 * len(clean))
    res = fit_and_validate(
        leec_network(), clean.iloc[:split], clean.iloc[split:], ["Ci", "Cm", "Rea", "Rim"], "LEEC"
    )
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
    frame = bacher_madsen_frame(shared)
    split = int(0.75 * len(frame))
    return fit_and_validate(
        bacher_madsen_network(),
        frame.iloc[:split],
        frame.iloc[split:],
        ["Ci", "Ce", "Rie", "Rea", "Aw"],
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
