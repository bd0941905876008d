"""Run rczone's benchmarks against the plain baseline and write ``bench/results.json``.

Usage (``make bench`` runs the first)::

    python bench/run.py                 # every benchmark
    python bench/run.py --only jml      # benchmarks whose name contains "jml"
    python bench/run.py --quick         # fewer repeats (a smoke run)
    python bench/run.py --skip-slow     # without the complete fits (minutes for the plain one)

Every benchmark runs rczone and the plain implementation (``bench/plain.py``) in this
process on the same data, checks that they agree, and reports the median wall time of
many repeats (``time.perf_counter``) after a warm-up call, so numba compilation is
excluded. Data: 720 one-minute samples (12 h), supply-air flow changing at every sample.
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
from rczone.atomic import write_json_atomic  # noqa: E402
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
    theirs: Callable[[], object]
    agree: Callable[[object, object], float]
    per: int = 1
    warmup: Callable[[], object] | None = None
    slow: bool = False


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
    return out


def jml_cases(rng: np.random.Generator) -> list[Case]:
    from rczone.estimation import Dataset, fit
    from rczone.estimation.costs import ml_cost
    from rczone.kernels.kalman import interval_groups, kalman_nll_rc2

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
        res = fit(net, data, free=free + list(noise_free), method="ml", fixed=noise_fixed, uncertainty=False)
        return np.array([res.estimates[n] for n in free])

    def plain_fit() -> np.ndarray:
        theta, _ = plain.fit_ml(net, free, noise_free, noise_fixed, t, m, u, y)
        return theta[: len(free)]

    values = {**net.values(), **noise_free, **noise_fixed}
    # flows as a building logs them: to 1 g/s (a few dozen levels in a night)
    mq = np.round(m, 3)
    groups = interval_groups(t, mq)
    n_levels = int(groups.max()) + 1
    return [
        Case(
            "jml_2state",
            f"Kalman -log L of {net.name} (2 states), {N_SAMPLES} samples, m varying (discretization included)",
            lambda: kalman_nll_rc2(ss, t, m, u, y, x0, P0, Qc, R),
            lambda: plain.kalman_nll(ss, t, m, u, y, x0, P0, Qc, R),
            lambda a, b: abs(a - b) / abs(b),
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
            warmup=lambda: ml_cost(net, values, data),
            slow=True,
        ),
    ]


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
        theirs, _, out_plain = measure(
            case.theirs, budget, n_plain, warmup=(lambda: None) if case.slow else None
        )
        ours, fastest, theirs = ours / case.per, fastest / case.per, theirs / case.per
        agree = case.agree(out_ours, out_plain)
        results[case.name] = {
            "median_s": ours,
            "fastest_s": fastest,
            "ratio_vs_plain": theirs / ours,
            "plain_median_s": theirs,
            "agreement_rel": agree,
            "description": case.description,
        }
        print(
            f"{case.name:32s} {fmt(ours):>12s} {fmt(fastest):>12s} {fmt(theirs):>12s}"
            f" {theirs / ours:8.0f}x {agree:9.1e}"
        )
        sys.stdout.flush()
    if args.only or args.skip_slow:
        # a partial run updates its entries and keeps the others from the last run
        try:
            previous = json.loads(args.out.read_text())
        except (OSError, ValueError):
            previous = {}
        results = {**previous, **results}
    write_json_atomic(args.out, results)
    print(f"wrote {args.out}")
    return 0


def fmt(s: float) -> str:
    for unit, f in (("s", 1.0), ("ms", 1e3), ("us", 1e6)):
        if s * f >= 1.0:
            return f"{s * f:.3g} {unit}"
    return f"{s * 1e9:.3g} ns"


if __name__ == "__main__":
    raise SystemExit(main())
