"""When an estimation problem can run as one compiled call, and the arrays it runs on.

A problem qualifies when the network has its plain conductance form (every node
capacitive, numeric ``cp``), every resistor, capacity, noise level and given
initial state is a constant or proportional to one free parameter (``R1 = Rw/2`` is;
``R = Ra + Rb`` is not), every heat-input gain is affine in the free parameters (a circuit's
shares ``s_1`` and ``1 - s_1``, :mod:`rczone.models.multizone`; packed as the terms of
``Gb = Gb0 + sum_t k_t theta[idx_t]``, so the gains stay data to one compiled kernel), and the
checks the Python path makes on every parameter cannot fail unseen: every tied parameter of the
network (used by an element or not) is affine, and proportional where its kind must be positive
(resistances, capacitances, magnitudes, times), every such value is positive by construction
(positive constants, positive factors of log-transformed free parameters), and every free
parameter that sets an element value is log-transformed. Then :mod:`rczone.kernels.problem` computes the cost and its
gradient, and :func:`rczone.kernels.neldermead.nelder_mead` minimizes it without
returning to Python. Anything else returns None and takes the general engine of
:mod:`rczone.estimation.costs`, with the same results.

The layout of the problem tuple is documented in :mod:`rczone.kernels.problem`.
"""

from __future__ import annotations

import numpy as np

from rczone.estimation.methods import REGISTRY, method_of
from rczone.estimation.priors import LogPrior
from rczone.kernels.arrays import (
    ConductanceArrays,
    Problem,
    ProblemConstants,
    ProblemData,
    SearchBox,
    Slots,
)
from rczone.kernels.kalman import STEADY_RTOL
from rczone.kernels.problem import cost, theta_of_z
from rczone.network.parameters import POSITIVE_KINDS, affine_tie, proportional_base
from rczone.network.stochastic import (
    initial_spread_names,
    initial_state_names,
    measurement_noise_names,
    process_noise_names,
)
from rczone.simulation.discretize import SYMMETRY_RTOL


def _kind(method: str) -> int:
    """The problem kind of :mod:`rczone.kernels.problem` (``LS, ML, MAP = 0, 1, 2``) of a registered method."""
    m = method_of(method)
    return 0 if m.kernel == "ls" else 2 if m.prior else 1


def _slot(objective, name: str | float) -> tuple[int, float] | None:
    """``(idx, k)`` of one value, or None if it is not proportional to one parameter or has no value."""
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


def _always_valid(objective) -> bool:
    """Whether every parameter value the Python path checks is valid for every free value.

    The compiled cost checks only the values it uses; the Python path resolves and checks
    every declared parameter. They agree when nothing can fail: every tie affine (finite for
    finite values), every value of a positive kind a positive multiple of a positive value.
    """
    spec = objective.spec
    params = objective.network.parameters
    for name, p in params.items():
        if p.kind not in POSITIVE_KINDS:
            if affine_tie(params, name) is None:
                return False
            continue
        base = proportional_base(params, name)
        if base is None:
            return False
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


def _gain_terms(objective, form) -> tuple[np.ndarray, tuple[np.ndarray, ...]] | None:
    """``(Gb_const, (state, input, idx, k))``: the parameter gains' constants and their terms in ``theta``.

    Each gain ``(state, input, name)`` of the conductance ``form`` is an affine tie
    (:class:`rczone.network.parameters.AffineTie`) of base
    parameters; the constant and the fixed bases' share go to ``Gb_const`` (n, p), each free base
    is one term. None where a gain is not affine or a base has no value.
    """
    spec, params = objective.spec, objective.network.parameters
    gb = np.array(form.Gb0, dtype=float, copy=True)
    terms: list[tuple[int, int, int, float]] = []
    for i, j, name in form.gains:
        tie = affine_tie(params, name)
        if tie is None:
            return None
        gb[i, j] += tie.constant
        for base, k in tie.terms:
            if base in spec.names:
                terms.append((i, j, spec.names.index(base), k))
            elif base in spec.fixed:
                gb[i, j] += k * float(spec.fixed[base])
            else:
                return None
    cols = list(zip(*terms, strict=True)) if terms else [(), (), (), ()]
    ints = tuple(np.array(c, dtype=np.int64) for c in cols[:3])
    return gb, (*ints, np.array(cols[3], dtype=float))


def _slots(objective, names) -> tuple[np.ndarray, np.ndarray] | None:
    got = [_slot(objective, n) for n in names]
    if any(g is None for g in got):
        return None
    return np.array([g[0] for g in got], dtype=np.int64), np.array([g[1] for g in got])


def compiled_problem(objective) -> Problem | None:
    """The packed problem of an :class:`~rczone.estimation.costs.Objective` for :mod:`rczone.kernels.problem`, or None."""
    net, data, spec = objective.network, objective.data, objective.spec
    form = net.conductance_form
    if objective.method not in REGISTRY or form is None or not _always_valid(objective):
        return None
    gains = _gain_terms(objective, form)
    if gains is None:
        return None
    states = net.state_names
    elements = []
    for group in (form.resistances, form.capacities):
        sl = _slots(objective, group)
        # a free parameter setting an element value must be positive by its transform
        if sl is None or any(i >= 0 and not spec.log[i] for i in sl[0]):
            return None
        elements.append(sl)
    noise = []
    for group in (
        measurement_noise_names(net.outputs),
        process_noise_names(states),
        initial_spread_names(states),
    ):
        if method_of(objective.method).kernel == "ls":
            noise.append((np.full(len(group), -1, dtype=np.int64), np.zeros(len(group))))
            continue
        sl = _slots(objective, group)
        if sl is None:
            return None
        noise.append(sl)
    x0_names = initial_state_names(states)
    given = np.array([n in spec.names or n in spec.fixed for n in x0_names], dtype=bool)
    x0_idx = np.array([spec.names.index(n) if n in spec.names else -1 for n in x0_names], dtype=np.int64)
    x0_k = np.array([1.0 if n in spec.names else float(spec.fixed.get(n, 0.0)) for n in x0_names])
    # the MAP prior, packed for the one compiled evaluation (rczone.kernels.problem.prior_terms)
    prior = objective.map_prior or LogPrior(spec, (None,) * len(spec.names), ())  # LS, ML: none
    penalty = prior.packed(objective.likelihood_weight)
    keys, which = data.intervals
    groups = np.empty(0, dtype=np.int64) if data.interval_groups is None else data.interval_groups
    fused = len(states) == 2 and len(net.outputs) == 1

    def c(a, dtype=None):  # writable contiguous copies: one compiled specialization for every caller
        return np.array(a, dtype=dtype, order="C", copy=True)

    return Problem(
        _kind(objective.method),
        ConductanceArrays(
            form.L, form.P, form.E, c(gains[0]), form.Nf, form.Mf, np.array(form.output_state, dtype=np.int64)
        ),
        ProblemData(c(data.t), c(data.m), c(data.u), c(data.y), c(keys), c(which), c(groups)),
        Slots(*elements[0], *elements[1], *noise[0], *noise[1], *noise[2], x0_idx, x0_k, given, *gains[1]),
        SearchBox(c(spec.eta_lower), c(spec.eta_upper), c(spec.log, dtype=bool)),
        penalty,
        ProblemConstants(objective.hold == "foh", float(SYMMETRY_RTOL), float(STEADY_RTOL), fused),
        np.empty(data.t.shape[0]),
    )


def compiled_cost(problem: Problem, eta: np.ndarray) -> float:
    """The compiled cost at optimizer values ``eta`` (for tests and checks)."""
    lo, hi, logp = problem.box
    f = (np.asarray(eta, dtype=float) - lo) / (hi - lo)
    with np.errstate(divide="ignore"):
        z = np.log(f) - np.log1p(-f)
    # the compiled search's steps (rczone.kernels.neldermead), from Python
    return cost(theta_of_z(z, lo, hi, logp), problem)
