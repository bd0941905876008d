"""Run rczone's benchmarks against the plain baseline and write ``bench/results.json``.

Usage (``make bench`` runs the first)::

    python bench/run.py                 # every benchmark
    python bench/run.py --only jml      # benchmarks whose name contains "jml"
    python bench/run.py --quick         # fewer repeats (a smoke run)
    python bench/run.py --skip-slow     # without the complete fits (minutes for the plain one)

Every benchmark runs rczone and the plain implementation (``bench/plain.py``) in this
process on the same data, checks that they agree, and reports the median wall time of
many repeats (``time.perf_counter``) after a warm-up call, so numba compilation is
excluded, with the fastest repeat beside it. Data: 720 one-minute samples (12 h), supply-air
flow changing at every sample, unless a benchmark says otherwise; the coupled-zone and peer
problems are defined in ``bench/problems.py``. Where the plain version would take too long
(the joint fit of four zones), its time is bounded below from the plain likelihood and the
number of evaluations, and the bound is reported instead.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

# single-threaded BLAS for both sides (set before numpy loads it): the matrices are tiny, and
# BLAS threads contending with other work on a small machine make timings erratic
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import plain  # noqa: E402
import problems  # noqa: E402
from rczone.files.atomic import write_json_atomic  # noqa: E402
from rczone.models import get_model  # noqa: E402
from rczone.simulation import simulate, steady_state  # noqa: E402
from rczone.simulation.simulate import transition_matrices  # noqa: E402

HERE = Path(__file__).resolve().parent
N_SAMPLES = 720
DT = 60.0


@dataclass(frozen=True)
class Case:
    """One benchmark: rczone's and the plain callable, their agreement check, and a time divisor."""

    name: str
    description: str
    ours: Callable[[], object]
    theirs: Callable[[], object] | None
    agree: Callable[[object, object], float]
    per: int = 1
    warmup: Callable[[], object] | None = None
    slow: bool = False
    target_s: float | None = None
    #: without ``theirs``: a lower bound of the plain time from our result and the results so far
    plain_bound: Callable[[object, dict], float] | None = None


def measure(
    f: Callable[[], object],
    budget_s: float,
    min_repeats: int,
    max_repeats: int = 100_000,
    warmup: Callable[[], object] | None = None,
) -> tuple[float, float, object]:
    """Median wall time of ``f()`` over repeats after one warm-up call (of ``warmup`` if given).

    Returns the median and the fastest repeat (s), and the last call's result. On a shared
    machine the median moves with the neighbours' load; the fastest repeat much less.
    """
    (warmup or f)()
    times = []
    start = time.perf_counter()
    while len(times) < max_repeats and (len(times) < min_repeats or time.perf_counter() - start < budget_s):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), float(np.min(times)), out


def scenario(n_inputs_names: tuple[str, ...], rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Times, inputs and a flow that changes at every sample (a damper under a PI loop, with noise)."""
    t = np.arange(N_SAMPLES) * DT
    h = t / 3600.0
    cols = []
    for name in n_inputs_names:
        if name == "Q":
            cols.append(300 + 200 * (h % 3 < 1.5) + 20 * rng.standard_normal(t.size))
        elif name == "Ts":
            cols.append(13 + 0.3 * rng.standard_normal(t.size))
        elif name == "To":
            cols.append(28 + 4 * np.sin(2 * np.pi * h / 24))
        else:
            cols.append(22 + 0.5 * np.sin(2 * np.pi * h / 24 + rng.uniform(0, 6)))
    u = np.column_stack(cols)
    m = np.clip(0.15 + 0.05 * np.sin(2 * np.pi * h / 2) + 0.01 * rng.standard_normal(t.size), 0.02, 0.4)
    return t, u, m[:, None]


def expand(tm: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Per-interval ``(Phi, Gamma)`` from :func:`transition_matrices`' distinct ones."""
    Phi, G0, _, which = tm
    return Phi[which], G0[which]


def rel(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def cases() -> list[Case]:
    rng = np.random.default_rng(20121210)
    out = []
    for name, model in (("13state", "full-scale"), ("2state", "second-order")):
        ss = get_model(model).state_space()
        t, u, m = scenario(ss.input_names, rng)
        x0 = steady_state(ss, u[0], m[0])
        out.append(
            Case(
                f"simulate_{name}",
                f"simulate {model} ({ss.n_states} states), {N_SAMPLES} samples, m varying",
                lambda ss=ss, t=t, u=u, m=m, x0=x0: simulate(ss, t, u, m, x0=x0).y,
                lambda ss=ss, t=t, u=u, m=m, x0=x0: plain.simulate(ss, t, u, m, x0),
                rel,
            )
        )
        if name == "2state":
            out.append(
                Case(
                    "discretize_2state_per_sample",
                    f"ZOH Phi, Gamma of {model}, {N_SAMPLES - 1} distinct (dt, m); time per sample",
                    lambda ss=ss, t=t, m=m: expand(transition_matrices(ss, t, m)),
                    lambda ss=ss, t=t, m=m: plain.discretize_all(ss, t, m),
                    lambda a, b: max(rel(a[0], b[0]), rel(a[1], b[1])),
                    per=N_SAMPLES - 1,
                )
            )
    out += jml_cases(rng)
    out += filter_cases(np.random.default_rng(20260512))
    return out


def jml_cases(rng: np.random.Generator) -> list[Case]:
    from rczone.estimation import Dataset, fit
    from rczone.estimation.kalman import kalman_nll_rc2
    from rczone.simulation.intervals import interval_groups

    net = get_model("second-order-paper")
    ss = net.state_space()
    t, u, m = scenario(ss.input_names, rng)
    x0 = steady_state(ss, u[0], m[0])
    y = simulate(ss, t, u, m, x0=x0).y + 0.05 * rng.standard_normal((t.size, 1))
    P0 = np.diag([0.1, 1.0])
    Qc = np.diag([1e-6, 1e-8])
    R = np.array([[0.05**2]])
    data = Dataset(t, u, m, y, net.input_names, net.flow_names, net.outputs)
    free = ["Cr", "Rw"]
    noise_free = {"sigma_v": 0.1, "sigma_w_Ti": 1e-3}
    noise_fixed = {"sigma_w_Tw": 1e-5, "sigma_x0_Ti": 0.1, "sigma_x0_Tw": 1.0}

    def ours_fit() -> np.ndarray:
        res = fit(
            net,
            data,
            free=free + list(noise_free),
            method="ml",
            fixed=noise_fixed,
            uncertainty=False,
            n_starts=1,
            optimizer="nelder-mead",  # the compiled direct search, as the plain fit (the default is L-BFGS)
        )
        return np.array([res.estimates[n] for n in free])

    def plain_fit() -> np.ndarray:
        theta, _ = plain.fit_ml(net, free, noise_free, noise_fixed, t, m, u, y)
        return theta[: len(free)]

    # flows as a building logs them: to 1 g/s (a few dozen levels in a night)
    mq = np.round(m, 3)
    groups = interval_groups(t, mq)
    n_levels = int(groups.max()) + 1
    return [
        Case(
            "jml_2state",
            f"Kalman -log L of {net.name} (2 states, bilinear), {N_SAMPLES} samples, m changing at every"
            " sample (discretization included; the fused 2-state kernel)",
            lambda: kalman_nll_rc2(ss, t, m, u, y, x0, P0, Qc, R),
            lambda: plain.kalman_nll(ss, t, m, u, y, x0, P0, Qc, R),
            lambda a, b: abs(a - b) / abs(b),
            target_s=60e-6,
        ),
        Case(
            "jml_2state_quantized_m",
            f"as jml_2state with m logged to 1 g/s ({n_levels} distinct (dt, m)): each discretized once",
            lambda: kalman_nll_rc2(ss, t, mq, u, y, x0, P0, Qc, R, groups=groups),
            lambda: plain.kalman_nll(ss, t, mq, u, y, x0, P0, Qc, R),
            lambda a, b: abs(a - b) / abs(b),
        ),
        Case(
            "fit_ml_2state",
            f"ML fit of {net.name}: Cr, Rw, sigma_v, sigma_w_Ti free, one Nelder-Mead start, {N_SAMPLES} samples",
            ours_fit,
            plain_fit,
            rel,
            slow=True,
        ),
    ]


def filter_cases(rng: np.random.Generator) -> list[Case]:
    """Likelihoods and fits of issue 12: coupled zones, the 13-state model, the 2-state peer task."""
    from rczone.estimation import Dataset, Objective, fit, make_spec
    from rczone.estimation.kalman import kalman_nll_rc2

    out = []
    # four coupled zones: 8 states, 4 outputs, 1,000 hourly samples
    net4, data4 = problems.four_zones(), problems.four_zone_data()
    truth4 = {**problems.FOUR_ZONE_TRUTH, **problems.FOUR_ZONE_NOISE}
    fixed4 = {k: v for k, v in problems.FOUR_ZONE_NOISE.items() if k not in problems.FOUR_ZONE_FREE}
    spec4 = make_spec(net4, problems.FOUR_ZONE_FREE, fixed=fixed4)
    obj4 = Objective(net4, data4, spec4, "ml")
    eta4 = spec4.to_eta(np.array([truth4[n] for n in spec4.names]))
    ss4 = net4.state_space()
    plain4 = plain_problem(net4, data4, truth4)
    out.append(
        Case(
            "nll_4zone",
            f"-log L of {net4.name}: 8 states, 4 outputs (one sigma_v each), 1,000 hourly samples, discretization"
            f" and initial state included (engine {obj4.engine!r})",
            lambda: obj4(eta4),
            lambda: plain.kalman_nll(ss4, *plain4),
            lambda a, b: abs(a - b) / abs(b),
            target_s=2e-3,
        )
    )
    start4 = {n: truth4[n] * float(np.exp(rng.uniform(-0.5, 0.5))) for n in problems.FOUR_ZONE_FREE}
    d4 = len(problems.FOUR_ZONE_FREE)
    rc4 = [n for n in problems.FOUR_ZONE_FREE if n in problems.FOUR_ZONE_TRUTH]

    def fit4():
        return fit(
            net4, data4, problems.FOUR_ZONE_FREE, method="ml", optimizer="lbfgs", start=start4, fixed=fixed4,
            uncertainty=False,
            n_starts=1,
        )  # fmt: skip

    out.append(
        Case(
            "fit_4zone",
            f"joint ML fit of {net4.name}: {d4} free (R, C, sigma_v per output, sigma_w per room), L-BFGS with"
            " exact gradients from starts up to a factor e^0.5 off, one local search (n_starts=1); agreement ="
            " largest relative error of the R and C estimates against the truth; plain = lower bound (the plain"
            " -log L times our evaluations: at least one plain likelihood each, its gradient not counted)",
            fit4,
            None,
            lambda res, _: max(abs(res.estimates[n] / truth4[n] - 1) for n in rc4),
            slow=True,
            target_s=20.0,
            plain_bound=lambda res, done: done["nll_4zone"]["plain_median_s"] * res.n_evals,
        )
    )
    # the 13-state single-output bilinear model; the flow constant over 30-minute stretches
    net13 = get_model("full-scale")
    ss13 = net13.state_space()
    t, u, m = scenario(ss13.input_names, rng)
    m = np.repeat(np.round(m[::30], 2), 30, axis=0)[: t.size]
    x0 = steady_state(ss13, u[0], m[0])
    y = simulate(ss13, t, u, m, x0=x0).y + 0.05 * rng.standard_normal((t.size, 1))
    data13 = Dataset(t, u, m, y, net13.input_names, net13.flow_names, net13.outputs)
    spec13 = make_spec(net13, ["sigma_v"], fixed={f"sigma_w_{s}": 1e-3 for s in net13.state_names})
    obj13 = Objective(net13, data13, spec13, "ml")
    eta13 = spec13.to_eta(spec13.start)
    plain13 = plain_problem(net13, data13, spec13.values(spec13.start))
    out.append(
        Case(
            "nll_13state",
            f"-log L of {net13.name} (13 states, one output, bilinear), {N_SAMPLES} one-minute samples, the"
            f" flow constant over 30-minute stretches ({data13.intervals[0].shape[0]} distinct intervals),"
            f" sigma_w 1e-3 on every state (engine {obj13.engine!r})",
            lambda: obj13(eta13),
            lambda: plain.kalman_nll(ss13, *plain13),
            lambda a, b: abs(a - b) / abs(b),
            target_s=1e-3,
        )
    )
    # the 2-state peer task (pySIP's Armadillo model)
    netp, datap = problems.peer_network(), problems.peer_data()
    valp = {**problems.PEER_TRUTH, **problems.PEER_NOISE, "x0_Tw": 26.6}
    specp = make_spec(
        netp,
        ["sigma_v"],
        fixed={k: v for k, v in valp.items() if k != "sigma_v"},
        start={"sigma_v": valp["sigma_v"]},
    )
    objp = Objective(netp, datap, specp, "ml", "foh")
    etap = specp.to_eta(specp.start)
    ssp = netp.state_space(problems.PEER_TRUTH)
    plainp = plain_problem(netp, datap, valp)
    out.append(
        Case(
            "nll_2state_lti_peer",
            f"-log L of the peer model {netp.name} (2 states, LTI, FOH), {datap.n_samples} half-hourly samples,"
            " discretization included (the fused 2-state kernel on the state space, as jml_2state)",
            lambda: kalman_nll_rc2(ssp, *plainp, hold="foh"),
            lambda: plain.kalman_nll(ssp, *plainp, hold="foh"),
            lambda a, b: abs(a - b) / abs(b),
            target_s=15e-6,
        )
    )
    out.append(
        Case(
            "nll_2state_lti_peer_values",
            "as nll_2state_lti_peer from parameter values: the objective of a fit (eta to theta, assembly,"
            f" initial state, likelihood; engine {objp.engine!r})",
            lambda: objp(etap),
            lambda: plain.kalman_nll(ssp, *plainp, hold="foh"),
            lambda a, b: abs(a - b) / abs(b),
        )
    )
    out += two_zone_gradient_cases()
    arma = problems.armadillo_data()
    if arma is not None:
        est = {**problems.PEER_TRUTH, "x0_Tw": 26.594539, "sigma_w_Tw": problems.PEER_NOISE["sigma_w_Tw"]}
        est |= {"sigma_v": problems.PEER_NOISE["sigma_v"]}
        startp = {k: (v + 1.0 if k == "x0_Tw" else 2.0 * v) for k, v in est.items()} | {"sigma_w_Ti": 1e-4}
        fixedp = {"sigma_x0_Tw": 0.1, "sigma_x0_Ti": 0.1, "x0_Ti": 26.7}
        free = problems.PEER_FREE

        def fitp():
            return fit(
                netp,
                arma,
                free,
                method="ml",
                optimizer="lbfgs",
                start=startp,
                fixed=fixedp,
                hold="foh",
                n_starts=1,
            )

        def fitp_global():
            return fit(
                netp, arma, free, method="ml", optimizer="lbfgs", start=startp, fixed=fixedp, hold="foh"
            )

        def plain_fitp():
            return plain.fit_ml_lbfgs(netp, free, startp, fixedp, arma, "foh")[0]

        out.append(
            Case(
                "fit_ml_peer",
                "complete ML fit of the peer task on pySIP's Armadillo data (232 samples, FOH): Ro, Ri, Cw, Ci,"
                " x0_Tw, sigma_w_Tw, sigma_w_Ti, sigma_v free from a factor 2 off, one local search (n_starts=1: L-BFGS"
                " with exact gradients, then the search's confirmation), standard errors included; plain = L-BFGS-B"
                " with forward differences; agreement on Ro, Ri, Cw, Ci",
                fitp,
                plain_fitp,
                lambda res, p: max(abs(res.estimates[n] / p[i] - 1) for i, n in enumerate(free[:4])),
                slow=True,
                target_s=30e-3,
            )
        )
        out.append(
            Case(
                "fit_ml_peer_global",
                "as fit_ml_peer with the default global search of rczone.estimation.fit (sampling of the box,"
                " several L-BFGS searches, confirmation); plain = the plain single search of fit_ml_peer (a lower"
                " bound of a plain global search); agreement = relative difference of -log L from fit_ml_peer's",
                fitp_global,
                None,
                lambda res, _: abs(res.llf / fitp().llf - 1),
                slow=True,
                plain_bound=lambda res, done: done["fit_ml_peer"]["plain_median_s"],
            )
        )
    return out


def two_zone_gradient_cases() -> list[Case]:
    """Issue 12: value and exact gradient of the joint two-zone virtual building (many distinct intervals)."""
    from rczone.calibration import dataset
    from rczone.estimation import engines
    from rczone.estimation.costs import Objective
    from rczone.estimation.fit import default_free
    from rczone.estimation.parameters import make_spec
    from rczone.models import load_model
    from rczone.virtual import generate_multizone_night

    zm = load_model(HERE.parent / "validation" / "models" / "virtual_two_zones.toml")
    net, data = zm.network, dataset(zm, generate_multizone_night(seed=1))
    spec = make_spec(net, list(default_free(net, "ml")))
    obj = Objective(net, data, spec, "ml")
    eta = spec.to_eta(spec.start)
    kernel = engines.derivatives_kernel

    def expm_route():
        # the same engine with the matrix-exponential (Fréchet) derivatives of every interval
        engines.derivatives_kernel = lambda rc: (
            lambda mod, der, how: kernel(False)(mod, der, how._replace(scale=np.empty(0)))
        )
        try:
            return obj.value_and_gradient(eta)
        finally:
            engines.derivatives_kernel = kernel

    return [
        Case(
            "grad_2zone_virtual",
            f"-log L and its exact gradient (Objective.value_and_gradient, engine {obj.gradient_engine!r}) of the"
            f" joint two-zone virtual building: {len(net.state_names)} states, 2 outputs, 2 flows, {spec.n_free} free,"
            f" {data.n_samples} samples, {data.intervals[0].shape[0]} distinct (dt, m1, m2); derivatives of the"
            " discretization by the symmetric eigen-decomposition; plain = the same with the matrix-exponential"
            " Fréchet derivatives",
            lambda: obj.value_and_gradient(eta),
            expm_route,
            lambda a, b: max(abs(a[0] - b[0]) / abs(b[0]), rel(a[1], b[1])),
        )
    ]


def plain_problem(net, data, values: dict) -> tuple:
    """``(t, m, u, y, x0, P0, Qc, R)`` of :func:`plain.kalman_nll` for parameter values (x0 as rczone derives it)."""
    from rczone.estimation.costs import initial_state

    ss = net.state_space({n: values[n] for n in net.free_parameter_names if n in values})
    outs = net.outputs
    sv = [values["sigma_v"]] if len(outs) == 1 else [values[f"sigma_v_{o}"] for o in outs]
    sw = [values[f"sigma_w_{s}"] for s in net.state_names]
    sx = [values[f"sigma_x0_{s}"] for s in net.state_names]
    x0 = initial_state(ss, values, data)
    return (
        data.t,
        data.m,
        data.u,
        data.y,
        x0,
        np.diag(np.square(sx)),
        np.diag(np.square(sw)),
        np.diag(np.square(sv)),
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="", help="run benchmarks whose name contains this text")
    ap.add_argument("--quick", action="store_true", help="short time budget (smoke run)")
    ap.add_argument("--skip-slow", action="store_true", help="skip the fit benchmarks (minutes)")
    ap.add_argument("--out", type=Path, default=HERE / "results.json")
    args = ap.parse_args(argv)
    budget = 0.2 if args.quick else 2.0
    results = {}
    print(f"rczone benchmarks on {os.cpu_count()} core(s); median wall time after warm-up")
    header = (
        f"{'benchmark':32s} {'rczone':>12s} {'(fastest)':>12s} {'plain':>12s} {'ratio':>8s} {'agree':>9s}"
    )
    print(header)
    print("-" * len(header))
    for case in cases():
        if args.only not in case.name:
            continue
        if case.slow and args.skip_slow:
            continue
        n_ours, n_plain = (7, 1) if case.slow else (5 if args.quick else 20, 1 if args.quick else 3)
        ours, fastest, out_ours = measure(case.ours, budget, n_ours, warmup=case.warmup)
        entry: dict = {}
        if case.theirs is not None:
            theirs, _, out_plain = measure(
                case.theirs, budget, n_plain, warmup=(lambda: None) if case.slow else None
            )
            theirs /= case.per
            agree = case.agree(out_ours, out_plain)
            entry["plain_median_s"] = theirs
        else:
            theirs = case.plain_bound(out_ours, {**previous_results(args.out), **results})
            agree = case.agree(out_ours, None)
            entry["plain_lower_bound_s"] = theirs
        ours, fastest = ours / case.per, fastest / case.per
        results[case.name] = {
            "median_s": ours,
            "fastest_s": fastest,
            "ratio_vs_plain": theirs / ours,
            **entry,
            "agreement_rel": agree,
            "target_s": case.target_s,
            "description": case.description,
        }
        target = (
            ""
            if case.target_s is None
            else f"  target {fmt(case.target_s)}"
            + (" met" if fastest <= case.target_s else " NOT met")
            + (" (median)" if ours <= case.target_s else "")
        )
        bound = "" if case.theirs is not None else " (bound)"
        print(
            f"{case.name:32s} {fmt(ours):>12s} {fmt(fastest):>12s} {fmt(theirs):>12s}"
            f" {theirs / ours:8.0f}x {agree:9.1e}{bound}{target}"
        )
        sys.stdout.flush()
    if args.only or args.skip_slow:
        # a partial run updates its entries and keeps the others from the last run
        results = {**previous_results(args.out), **results}
    write_json_atomic(args.out, results)
    print(f"wrote {args.out}")
    return 0


def previous_results(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def fmt(s: float) -> str:
    for unit, f in (("s", 1.0), ("ms", 1e3), ("us", 1e6)):
        if s * f >= 1.0:
            return f"{s * f:.3g} {unit}"
    return f"{s * 1e9:.3g} ns"


if __name__ == "__main__":
    raise SystemExit(main())
