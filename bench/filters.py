"""The one Kalman filter in original against modal coordinates on the likelihoods of ``bench/run.py``.

Usage::

    python bench/filters.py [--repeats 200] [--out /tmp/filters.json]

For ``nll_13state`` (13 states, the flow constant over 30-minute stretches) and ``nll_4zone``
(8 states, 4 outputs, hourly, LTI) the packed problem's model is assembled once at the
benchmark's parameter values; then, as :func:`rczone.kernels.problem.value_general` does, the
likelihood is computed by :func:`rczone.kernels.kalman.kalman_filter` (a) after
:func:`rczone.kernels.discretize.interval_matrices`, and (b) with the ``basis`` of
:func:`rczone.kernels.discretize.modal_matrices` (modal coordinates). The script prints the median time of each
(after a warm-up call, so compilation is excluded), their ratio, their agreement and whether
the rule of :func:`rczone.kernels.kalman.modal_pays` picks the faster one; the machine's load
average is printed beside them.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import problems  # noqa: E402
from rczone.estimation import Dataset, Objective, make_spec  # noqa: E402
from rczone.kernels.arrays import Discretization, FilterOptions, FilterStart, Observation, Series  # noqa: E402
from rczone.kernels.discretize import interval_matrices, modal_matrices  # noqa: E402
from rczone.kernels.kalman import (  # noqa: E402
    kalman_filter,
    modal_pays,
    no_sensitivities,
    outputs,
)
from rczone.kernels.problem import assembled  # noqa: E402
from rczone.models import get_model  # noqa: E402
from rczone.simulation import simulate, steady_state  # noqa: E402


def objectives() -> dict[str, tuple[Objective, np.ndarray]]:
    """The two multi-state likelihood problems of ``bench/run.py`` and their parameter values."""
    rng = np.random.default_rng(0)
    net4, data4 = problems.four_zones(), problems.four_zone_data()
    truth4 = {**problems.FOUR_ZONE_TRUTH, **problems.FOUR_ZONE_NOISE}
    fixed4 = {k: v for k, v in problems.FOUR_ZONE_NOISE.items() if k not in problems.FOUR_ZONE_FREE}
    spec4 = make_spec(net4, problems.FOUR_ZONE_FREE, fixed=fixed4)
    obj4 = Objective(net4, data4, spec4, "ml")
    net13 = get_model("full-scale")
    ss13 = net13.state_space()
    n = 720
    t = np.arange(n) * 60.0
    u = np.column_stack([20 + rng.standard_normal(n).cumsum() * 0.01 for _ in ss13.input_names])
    m = np.repeat(np.round(rng.uniform(0.02, 0.2, n // 30 + 1), 2), 30)[:n, None]
    y = simulate(ss13, t, u, m, x0=steady_state(ss13, u[0], m[0])).y + 0.05 * rng.standard_normal((n, 1))
    data13 = Dataset(t, u, m, y, net13.input_names, net13.flow_names, net13.outputs)
    spec13 = make_spec(net13, ["sigma_v"], fixed={f"sigma_w_{s}": 1e-3 for s in net13.state_names})
    obj13 = Objective(net13, data13, spec13, "ml")
    return {
        "nll_13state": (obj13, spec13.start),
        "nll_4zone": (obj4, np.array([truth4[k] for k in spec4.names])),
    }


def both_filters(prob, theta: np.ndarray):
    """The filter's ``-log L`` (without the constant) in original and in modal coordinates, as callables."""
    mod, _, ok = assembled(theta, prob, 0)
    assert ok
    _, _, u, y, keys, which, _ = prob.data
    foh, _, steady_rtol, _ = prob.consts
    n, p, ny = mod.A0.shape[0], mod.B0.shape[1], mod.C.shape[0]
    scale = np.sqrt(mod.cap)
    obs = Observation(
        mod.C, np.zeros((ny, p)), mod.r, np.zeros((ny, 0, n)), np.zeros((ny, 0, p)), np.zeros((ny, 0))
    )
    prior = FilterStart(mod.x0, mod.P0, np.zeros((0, n)), np.zeros((0, n, n)))
    series = Series(u, y, which)

    def general() -> float:
        mats = interval_matrices(mod, Discretization(keys, scale, foh, True))
        return kalman_filter(
            mats,
            no_sensitivities(keys.shape[0], n, p),
            obs,
            prior,
            series,
            FilterOptions(foh, False, steady_rtol),
            outputs(y.shape[0], n, ny, 0, False, False),
        ).nll

    def modal() -> float:
        mats, basis = modal_matrices(mod, Discretization(keys, scale, foh, True))
        return kalman_filter(
            mats,
            no_sensitivities(keys.shape[0], n, p),
            obs,
            prior,
            series,
            FilterOptions(foh, False, steady_rtol),
            outputs(y.shape[0], n, ny, 0, False, False),
            basis,
        ).nll

    return general, modal


def median_time(f, repeats: int) -> float:
    f()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    results = {}
    for name, (obj, theta) in objectives().items():
        general, modal = both_filters(obj._packed, np.asarray(theta, dtype=float))
        g, m = general(), modal()
        tg, tm = median_time(general, args.repeats), median_time(modal, args.repeats)
        which, n = obj._packed.data.which, obj._packed.form.L.shape[1]
        rule = "modal" if modal_pays(which, n) else "general"
        faster = "modal" if tm < tg else "general"
        results[name] = {
            "general_median_s": tg,
            "modal_median_s": tm,
            "general_over_modal": tg / tm,
            "relative_difference": abs(g - m) / abs(g),
            "modal_pays_chooses": rule,
            "faster": faster,
        }
        print(
            f"{name}: general {tg * 1e3:.3f} ms, modal {tm * 1e3:.3f} ms, general/modal {tg / tm:.2f},"
            f" -log L differ by {abs(g - m) / abs(g):.1e} relative; modal_pays chooses {rule}"
            f" ({'the faster' if rule == faster else 'NOT the faster'})"
        )
    print("load average", os.getloadavg())
    if args.out is not None:
        args.out.write_text(json.dumps({**results, "load": os.getloadavg()}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
