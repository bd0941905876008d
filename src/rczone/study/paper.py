"""The paper's study on the built-in virtual building: which order is enough, what the data identify.

Section III (model order) simulates the 13-state, 2nd- and 1st-order models on data sets A, B and C
and compares their frequency responses; section IV (identification) calibrates the reduced model on
one night and validates it on the others; the closed-loop study shows how strong the closed-loop
effect is. Each returns its numbers (the JSON of ``rczone demo``) and the curves its figures need;
:mod:`rczone.report.demo` lays them out. Lin, Middelkoop and Barooah, "Issues in identification of
control-oriented thermal models of zones in multi-zone buildings", IEEE CDC 2012.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rczone import datasets
from rczone.models import get_model
from rczone.models.comparison import (
    FrequencyComparison,
    TimeComparison,
    compare_frequency,
    compare_time,
    input_variation,
)
from rczone.models.paper import Q_PAPER
from rczone.models.reduction import F_PER_K, PAPER_DU_K, band_matched_model
from rczone.network import RCNetwork
from rczone.network.stochastic import measurement_noise_names, process_noise_name
from rczone.virtual.operation import Operation

ORDERS = ("full-scale", "second-order", "first-order")
SCENARIOS = {
    "A": "A: summer night, normal closed-loop control",
    "B": "B: winter night, normal closed-loop control",
    "C": "C: autumn night, forced-response test",
}
#: The paper's yardstick for section III, in K (1 F and 3 F).
PAPER_SECOND_ORDER_K = 1.0 / F_PER_K
PAPER_FIRST_ORDER_K = 3.0 / F_PER_K
#: Low-order variants judged at the paper's weights: parallel aggregation and band-matched values.
VARIANTS = (
    "second-order",
    "second-order-band",
    "second-order-paper",
    "second-order-paper-band",
    "first-order",
    "first-order-band",
)
#: The paper's unknowns (section IV: theta = [Cr, Rw], the initial state taken from the data), plus
#: the noise levels a likelihood fit needs (of the one output and state Ti).
_PAPER_NOISE = (*measurement_noise_names(("Ti",)), process_noise_name("Ti"))
PAPER_FREE = {
    "ls": ("Cr", "Rw"),
    "ml": ("Cr", "Rw", *_PAPER_NOISE),
    "map": ("Cr", "Rw", *_PAPER_NOISE),
}


def true_equivalent() -> dict[str, float] | None:
    """The reduced model's parameters aggregated from the virtual building's true construction."""
    try:
        from rczone.virtual.building import true_geometry
    except ImportError:  # pragma: no cover - the virtual building always ships with rczone
        return None
    from rczone.models import get_model as gm

    vals = gm("second-order-paper", true_geometry()).values()
    return {"Cr": vals["Cr"], "Rw": vals["Rw"]}


@dataclass(frozen=True)
class ModelOrderStudy:
    """Section III: the numbers, and the comparisons its figures plot.

    Attributes
    ----------
    results : dict
        Time- and frequency-domain errors (JSON-ready).
    time : list of TimeComparison
        The three orders on each data set.
    frequency : FrequencyComparison
        Gains and errors at m = 0.12 kg/s with the nights' input variation.
    paper_weights : FrequencyComparison
        The same at the paper's weights, with the band-matched variants.
    """

    results: dict[str, Any]
    time: list[TimeComparison]
    frequency: FrequencyComparison
    paper_weights: FrequencyComparison


@dataclass(frozen=True)
class IdentificationStudy:
    """Section IV: diagnose, two calibration attempts by LS, ML and MAP, and the MAP prior's rule.

    Attributes
    ----------
    results : dict
        Verdicts, estimates and validation errors (JSON-ready).
    attempts : dict of str to list of TimeComparison
        Per attempt, the calibration and validation nights with every method's prediction.
    """

    results: dict[str, Any]
    attempts: dict[str, list[TimeComparison]]


@dataclass(frozen=True)
class ClosedLoopStudy:
    """Closed-loop against forced fits for today's operation and the strongest closed-loop case.

    Attributes
    ----------
    results : dict
        Per case and method, both nights' fits (JSON-ready).
    comparisons : list of TimeComparison
        The A-style LS fits predicting the forced night.
    """

    results: dict[str, Any]
    comparisons: list[TimeComparison]


@dataclass(frozen=True)
class PaperStudy:
    """The whole study: its three parts and the virtual building's true reduced parameters.

    Attributes
    ----------
    model_order, identification, closed_loop
        The parts.
    """

    model_order: ModelOrderStudy
    identification: IdentificationStudy
    closed_loop: ClosedLoopStudy

    @property
    def results(self) -> dict[str, Any]:
        """Every number of the study (what ``rczone demo`` writes to ``results.json``)."""
        return {
            "model_order": self.model_order.results,
            "identification": self.identification.results,
            "closed_loop": self.closed_loop.results,
        }


def _counter(progress: Callable[[str], None]) -> Any:
    """``progress`` for a fit's search when it counts steps (``advance``, a CLI progress bar), else None."""
    return progress if hasattr(progress, "advance") else None


def model_order_study(progress: Callable[[str], None]) -> ModelOrderStudy:
    """Section III of the paper on the virtual building: three orders simulated and compared."""
    models = {k: get_model(k) for k in ORDERS}
    frames = {s: datasets.load(s) for s in SCENARIOS}
    results: dict[str, Any] = {"time_domain": {}, "frequency_domain": {}}
    comps = []
    for s, label in SCENARIOS.items():
        progress(f"simulating the three models on data set {s}")
        c = compare_time(models, frames[s], label=label, constants={"Q": Q_PAPER})
        comps.append(c)
        rmse, mx, diff = c.rmse(), c.max_error(), c.max_difference_to("full-scale")
        results["time_domain"][s] = {
            k: {"rmse_K": rmse[k], "max_error_K": mx[k], "max_diff_to_full_scale_K": diff.get(k, 0.0)}
            for k in ORDERS
        }
    progress("frequency responses at m = 0.12 kg/s")
    du = input_variation(list(frames.values()))
    fc = compare_frequency(models, "full-scale", du, m=0.12)
    maxe = fc.max_errors()
    results["frequency_domain"] = {
        "m_kg_s": 0.12,
        "band_hz": [float(fc.freq_hz[0]), float(fc.freq_hz[-1])],
        "du_K": du,
        "max_error_K": maxe,
    }
    ok2 = max(maxe["second-order"].values()) <= PAPER_SECOND_ORDER_K
    ok1 = max(maxe["first-order"].values()) <= PAPER_FIRST_ORDER_K
    results["frequency_domain"]["agrees_with_paper"] = {"second-order": ok2, "first-order": ok1}
    # e_i scales with du_i: the same models judged with each night's own input variation
    per_set = {}
    for s, f in frames.items():
        dus = input_variation([f])
        per_set[s] = {
            "du_K": dus,
            "max_error_K": compare_frequency(models, "full-scale", dus, m=0.12).max_errors(),
        }
    results["frequency_domain"]["per_data_set"] = per_set
    # relative gain error: |H_ref - H_k| / |H_ref(0)| (independent of du), and where it peaks
    rel = {}
    for k, errs in fc.errors.items():
        rel[k] = {}
        for i, e in errs.items():
            g0 = float(fc.gains["full-scale"][i][0])
            j = int(e.argmax())
            rel[k][i] = {
                "max_relative": float(e[j] / du[i] / g0) if du[i] and g0 else 0.0,
                "at_hz": float(fc.freq_hz[j]),
            }
    results["frequency_domain"]["relative_gain_error"] = rel

    progress("frequency responses at the paper's weights, parallel and band-matched values")
    fcp, results["frequency_domain"]["paper_weights"] = paper_weights_study()
    return ModelOrderStudy(results, comps, fc, fcp)


def _variant_model(name: str) -> RCNetwork:
    base = name.removesuffix("-band")
    return band_matched_model(base) if name.endswith("-band") else get_model(base)


def paper_weights_study() -> tuple[Any, dict[str, Any]]:
    """Eq.-7 errors at the paper's input amplitudes, parallel against band-matched values."""
    models = {"full-scale": get_model("full-scale"), **{k: _variant_model(k) for k in VARIANTS}}
    fc = compare_frequency(models, "full-scale", PAPER_DU_K, m=0.12)
    maxe = fc.max_errors()
    limit = {k: PAPER_FIRST_ORDER_K if k.startswith("first") else PAPER_SECOND_ORDER_K for k in VARIANTS}
    out = {
        "du_K": dict(PAPER_DU_K),
        "du_F": {k: v * F_PER_K for k, v in PAPER_DU_K.items()},
        "max_error_K": maxe,
        "max_error_F": {k: {i: e * F_PER_K for i, e in v.items()} for k, v in maxe.items()},
        "paper_bound_F": {k: v * F_PER_K for k, v in limit.items()},
        "agrees_with_paper": {k: max(maxe[k].values()) <= limit[k] for k in VARIANTS},
        "values": {k: models[k].values() for k in VARIANTS},
    }
    return fc, out


ATTEMPTS = {"1": ("A", ("B", "C")), "2": ("C", ("A", "B"))}
METHODS = ("ls", "ml", "map")


def identification_study(
    progress: Callable[[str], None],
    true_equivalent: dict[str, float] | None = None,
) -> IdentificationStudy:
    """Section IV of the paper: calibrate on one night, validate on the others."""
    from rczone.calibration import calibrate, predict
    from rczone.diagnostics import diagnose

    net = get_model("second-order-paper")
    frames = {s: datasets.load(s) for s in SCENARIOS}
    const = {"Q": Q_PAPER}
    out: dict[str, Any] = {"attempts": {}, "diagnose": {}}
    figures: dict[str, list[TimeComparison]] = {}
    for s, f in frames.items():
        progress(f"diagnosing data set {s}")
        d = diagnose(net, f, free=["Cr", "Rw"], constants=const)
        out["diagnose"][s] = {k: {"verdict": v.verdict, "reason": v.reason} for k, v in d.parameters.items()}
    for att, (cal_set, val_sets) in ATTEMPTS.items():
        res: dict[str, Any] = {"calibration": cal_set, "methods": {}}
        preds: dict[str, dict[str, Any]] = {s: {} for s in (cal_set, *val_sets)}
        for meth in METHODS:
            progress(f"attempt {att}: calibrating on {cal_set} by {meth.upper()}")
            cal = calibrate(
                net,
                frames[cal_set],
                method=meth,
                free=PAPER_FREE[meth],
                n_starts=3,
                seed=1,
                constants=const,
                progress=_counter(progress),
            )
            entry = {
                "parameters": {
                    n: {
                        "unit": net.parameters[n].unit,
                        "estimate": cal.result.estimates[n],
                        "std_error": cal.result.std_errors[n],
                        "construction": cal.result.parameters[n].construction,
                        "true_equivalent": (true_equivalent or {}).get(n),
                    }
                    for n in ("Cr", "Rw")
                },
                "validation": {},
            }
            for s in (cal_set, *val_sets):
                ol = predict(cal.model, frames[s], const)
                entry["validation"][s] = {"rmse_K": ol.rmse_K, "max_error_K": ol.max_abs_K}
                preds[s][meth] = ol.y_hat[:, 0]
            res["methods"][meth] = entry
        out["attempts"][att] = res
        figures[att] = [
            TimeComparison(
                f"{'calibration' if s == cal_set else 'validation'}: {SCENARIOS[s]}",
                frames[s]["time"].to_numpy(float),
                frames[s]["Ti"].to_numpy(float),
                {f"{m.upper()}": p for m, p in preds[s].items()},
            )
            for s in (cal_set, *val_sets)
        ]

    out["map_prior"] = _map_prior_study(net, frames, const, progress)
    return IdentificationStudy(out, figures)


def _map_prior_study(
    net: Any, frames: dict[str, Any], const: dict[str, float], progress: Callable[[str], None]
) -> dict[str, Any]:
    """MAP on the closed-loop nights with each rule's construction values as prior; judged on C."""
    from rczone.calibration import calibrate, predict
    from rczone.models.aggregation import REDUCED_RULE

    nets = {"parallel": net, "band": band_matched_model("second-order-paper")}
    rules: dict[str, Any] = {}
    for rule, n in nets.items():
        fits = {}
        for s in ("A", "B"):
            progress(f"MAP on {s} with {rule} construction values as prior")
            cal = calibrate(
                n,
                frames[s],
                method="map",
                free=PAPER_FREE["map"],
                n_starts=3,
                seed=1,
                constants=const,
                uncertainty=False,
                progress=_counter(progress),
            )
            fits[s] = {
                "Rw": cal.result.estimates["Rw"],
                "Cr": cal.result.estimates["Cr"],
                "own_rmse_K": cal.open_loop.rmse_K,
                "C_rmse_K": predict(cal.model, frames["C"], const).rmse_K,
            }
        v = n.values()
        rules[rule] = {"construction": {k: v[k] for k in ("Cr", "Rw", "Cw", "Rwin")}, "fits": fits}
    score = {r: float(np.mean([f["C_rmse_K"] for f in v["fits"].values()])) for r, v in rules.items()}
    return {
        "rules": rules,
        "mean_C_rmse_K": score,
        "better": min(score, key=score.get),
        "default": REDUCED_RULE,
    }


#: The strongest honest closed-loop case found (docs/paper.md): the thermostat in the supply jet.
CLOSED_LOOP_CASES = {"as shipped": Operation(), "thermostat at the diffuser": Operation(sensor="diffuser")}
#: Nights of the closed-loop study: the A-style and C-style nights (season, mode, seed).
CLOSED_LOOP_NIGHTS = {"A": ("summer", "closed-loop", 20110802), "C": ("autumn", "forced", 20111024)}


def closed_loop_study(progress: Callable[[str], None]) -> ClosedLoopStudy:
    """Closed-loop (A-style) against forced (C-style) LS and ML fits for today's operation and the strongest case."""
    from rczone.calibration import calibrate, predict
    from rczone.virtual.scenarios import generate_night

    net = get_model("second-order-paper")
    const = {"Q": Q_PAPER}
    out: dict[str, Any] = {}
    comps = []
    for case, op in CLOSED_LOOP_CASES.items():
        frames = {}
        for s, (season, mode, seed) in CLOSED_LOOP_NIGHTS.items():
            progress(f"closed-loop study ({case}): night {s}")
            frames[s] = (
                datasets.load(s) if op.is_default else generate_night(season, mode, seed, operation=op)
            )
        res: dict[str, Any] = {"operation": op.label()}
        for meth in ("ls", "ml"):
            fits = {}
            for s, f in frames.items():
                progress(f"closed-loop study ({case}): {meth.upper()} fit to night {s}")
                cal = calibrate(
                    net,
                    f,
                    method=meth,
                    free=PAPER_FREE[meth],
                    n_starts=3,
                    seed=1,
                    constants=const,
                    uncertainty=False,
                    progress=_counter(progress),
                )
                other = "C" if s == "A" else "A"
                fits[s] = {
                    "Rw": cal.result.estimates["Rw"],
                    "Cr": cal.result.estimates["Cr"],
                    "at_bound": [k for k, e in cal.result.parameters.items() if e.at_bound],
                    "own_rmse_K": cal.open_loop.rmse_K,
                    f"{other}_rmse_K": predict(cal.model, frames[other], const).rmse_K,
                }
                if meth == "ls" and s == "A":
                    comps.append(
                        TimeComparison(
                            f"{case}: LS fit to the A-style night, predicting the C-style night",
                            frames["C"]["time"].to_numpy(float),
                            frames["C"]["Ti"].to_numpy(float),
                            {"A-fit": predict(cal.model, frames["C"], const).y_hat[:, 0]},
                        )
                    )
            fits["rw_ratio_C_over_A"] = fits["C"]["Rw"] / fits["A"]["Rw"]
            res[meth] = fits
        ls = res["ls"]
        res["paper_strength"] = bool(ls["rw_ratio_C_over_A"] >= 5.0 and ls["A"]["own_rmse_K"] <= 0.2)
        out[case] = res

    return ClosedLoopStudy(out, comps)


def run_paper_study(progress: Callable[[str], None] | None = None) -> PaperStudy:
    """Run the paper's study on the virtual building.

    Parameters
    ----------
    progress : callable, optional
        Called with a short message before each step.

    Returns
    -------
    PaperStudy
    """
    progress = progress or (lambda _msg: None)
    return PaperStudy(
        model_order_study(progress),
        identification_study(progress, true_equivalent()),
        closed_loop_study(progress),
    )
