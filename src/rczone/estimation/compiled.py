"""When an estimation problem can run as one compiled call, and the arrays it runs on.

A problem qualifies when the fused 2-state path of the costs applies (two capacitive
states, one measured output, the network's plain conductance form, a measured first sample,
no initial-state parameters), every resistor, capacity and noise level is a constant or
proportional to one free parameter (``R1 = Rw/2`` is; ``R = Ra + Rb`` is not), and the
checks the Python path makes on every parameter cannot fail unseen: every tied parameter of
the network (used by an element or not) is proportional, every resistance and capacitance is
positive by construction (positive constants, positive factors of log-transformed free
parameters), and every free parameter that sets an element value is log-transformed. Then
:func:`rczone.kernels.rc2fit.cost_z` evaluates the cost and
:func:`rczone.kernels.rc2fit.nelder_mead` minimizes it without returning to Python.
Anything else returns None and takes the general path, with the same results.

Layout of the problem tuple (contiguous float64 / int64 / bool arrays)::

    (kind,                                    # LS, ML or MAP
     (L, P, E, Gb0, Nf, Mf, output_state),    # conductance form of the network
     (t, m, u, y, groups),                    # data, y one column, interval groups
     (res_idx, res_k, cap_idx, cap_k, noise_idx, noise_k),
     (eta_lower, eta_upper, log),             # direct-search transform
     (prior_idx, prior_log_construction, prior_spread, likelihood_weight),
     (foh, phi2, symmetry_rtol),
     scratch)                                 # (N,) buffer for the open-loop errors

A slot ``(idx, k)`` has the value ``k * theta[idx]``, or ``k`` when ``idx < 0``. Noise slots
are ``sigma_v``, ``sigma_w_<state>`` (2), ``sigma_x0_<state>`` (2) in state order.
"""

from __future__ import annotations

import numpy as np

from rczone.estimation.costs import Objective, fused_path_applies
from rczone.kernels import rc2fit
from rczone.kernels.kalman import _PHI2
from rczone.network.parameters import proportional_base
from rczone.simulation.discretize import SYMMETRY_RTOL

_KIND = {"ls": rc2fit.LS, "ml": rc2fit.ML, "map": rc2fit.MAP}


def _slot(objective: Objective, name: str | float) -> tuple[int, float] | None:
    """``(idx, k)`` of one element value, or None if it is not proportional to one parameter."""
    spec = objective.spec
    if not isinstance(name, str):
        return -1, float(name)
    params = objective.network.parameters
    if name in params:
        base = proportional_base(params, name)
        if base is None:
            return None
        k, name = base
        if name is None:
            return -1, k
    else:
        k = 1.0
    if name in spec.names:
        return spec.names.index(name), k
    v = spec.fixed.get(name)
    if v is None:
        return None
    return -1, k * float(v)


def _always_valid(objective: Objective) -> bool:
    """Whether every parameter value the Python path checks is valid for every free value.

    The compiled cost checks only the values it uses; the Python path resolves and checks
    every declared parameter. They agree when nothing can fail: every tie proportional, every
    resistance and capacitance a positive multiple of a positive value.
    """
    spec = objective.spec
    for name, p in objective.network.parameters.items():
        base = proportional_base(objective.network.parameters, name)
        if base is None:
            return False
        if p.kind not in ("resistance", "capacitance"):
            continue
        k, b = base
        if b is None:
            sign = k
        elif b in spec.names:
            sign = k if spec.log[spec.names.index(b)] else -1.0
        else:
            sign = k * spec.fixed.get(b, -1.0)
        if not sign > 0:
            return False
    return True


def compiled_problem(objective: Objective) -> tuple | None:
    """The problem tuple of ``objective`` for :mod:`rczone.kernels.rc2fit`, or None."""
    net, data, spec = objective.network, objective.data, objective.spec
    if objective.method not in _KIND or not fused_path_applies(net, spec.fixed, data):
        return None
    if any(n.startswith("x0_") for n in spec.names) or not _always_valid(objective):
        return None
    form = net.conductance_form
    states = net.state_names
    names = (
        list(form.resistances),
        list(form.capacities),
        ["sigma_v", *(f"sigma_w_{s}" for s in states), *(f"sigma_x0_{s}" for s in states)],
    )
    if objective.method == "ls":
        names = (names[0], names[1], [])  # no noise in output-error least squares
    slots = []
    for group in names:
        got = [_slot(objective, n) for n in group]
        # a free parameter setting an element value must be positive by its transform
        if any(g is None or (g[0] >= 0 and not spec.log[g[0]]) for g in got):
            return None
        slots.append((np.array([g[0] for g in got], dtype=np.int64), np.array([g[1] for g in got])))
    if objective.method == "ls":
        slots[2] = (np.full(5, -1, dtype=np.int64), np.zeros(5))
    prior = np.flatnonzero(
        np.array([k in ("resistance", "capacitance") for k in spec.kinds], dtype=bool)
        & np.isfinite(spec.construction)
    )
    groups = np.empty(0, dtype=np.int64) if data.interval_groups is None else data.interval_groups
    c = np.ascontiguousarray
    return (
        _KIND[objective.method],
        (form.L, form.P, form.E, form.Gb0, form.Nf, form.Mf, int(form.output_state[0])),
        (c(data.t), c(data.m), c(data.u), c(data.y[:, 0]), groups),
        (slots[0][0], slots[0][1], slots[1][0], slots[1][1], slots[2][0], slots[2][1]),
        (c(spec.eta_lower), c(spec.eta_upper), c(spec.log, dtype=bool)),
        (
            prior.astype(np.int64),
            np.log(spec.construction[prior]) if prior.size else np.empty(0),
            float(objective.prior_spread),
            float(objective.likelihood_weight),
        ),
        (objective.hold == "foh", _PHI2, float(SYMMETRY_RTOL)),
        np.empty(data.t.shape[0]),
    )


def compiled_cost(problem: tuple, eta: np.ndarray) -> float:
    """The compiled cost at optimizer values ``eta`` (for tests and checks)."""
    lo, hi, _ = problem[4]
    f = (np.asarray(eta, dtype=float) - lo) / (hi - lo)
    with np.errstate(divide="ignore"):
        z = np.log(f) - np.log1p(-f)
    return float(rc2fit.cost_z(z, problem))
