"""When the fast paths apply, when they refuse, and their error messages."""

from __future__ import annotations

import numpy as np
import pytest

from rczone.errors import InputShapeError
from rczone.estimation.kalman import kalman_nll_rc2, rc2_applicable
from rczone.kernels.propagate import propagate
from rczone.network import BilinearStateSpace, HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from rczone.simulation import simulate, zoh
from rczone.simulation.discretize import symmetrizing_scale
from rczone.simulation.simulate import (
    _FORMS_KEPT,
    _rank_one_form_of,
    transition_matrices,
)
from tests.netfactory import one_r_one_c, thirteen_state
from tests.oracles import propagate_reference

NET2 = RCNetwork(
    "two",
    [Node("Ti", "Cr"), Node("Tw", "Cw")],
    ["To", "Tsd"],
    [Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"), Resistor("Tw", "Tsd", "R2")],
    [
        Parameter("Cr", "capacitance", 8e5),
        Parameter("Cw", "capacitance", 6e6),
        Parameter("Rwin", "resistance", 0.05),
        Parameter("R1", "resistance", 0.005),
        Parameter("R2", "resistance", 0.005),
    ],
    heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
    supply_air=[SupplyAir("Ti", "m", "Ts")],
)
A_RC = np.array([[-2.0, 1.0], [0.5, -1.0]])  # diag(1, 2) A is symmetric
CAP = np.array([1.0, 2.0])


@pytest.mark.parametrize(
    ("A", "N", "cap", "expected"),
    [
        (A_RC, np.zeros((0, 2, 2)), CAP, np.sqrt(CAP)),
        (A_RC, np.array([[[-1.0, 0.0], [0.0, 0.0]]]), CAP, np.sqrt(CAP)),
        (A_RC, np.zeros((0, 2, 2)), np.array([2.0, 1.0]), None),  # wrong capacities
        (A_RC, np.zeros((0, 2, 2)), np.array([1.0, -2.0]), None),  # negative capacity
        (A_RC, np.zeros((0, 2, 2)), np.array([1.0, np.nan]), None),
        (A_RC, np.zeros((0, 2, 2)), np.ones(3), None),  # wrong shape
        (A_RC, np.array([[[0.0, 1.0], [0.0, 0.0]]]), CAP, None),  # flow term not symmetrizable
        (np.array([[-1.0, 0.0], [3.0, -1.0]]), np.zeros((0, 2, 2)), np.ones(2), None),  # block system
    ],
)
def test_symmetrizing_scale_accepts_only_rc_structure(A, N, cap, expected):
    got = symmetrizing_scale(A, N, cap)
    if expected is None:
        assert got is None
    else:
        np.testing.assert_allclose(got, expected)


def test_non_rc_state_space_falls_back_to_the_matrix_exponential():
    # lower block-triangular, like the sensitivity equations: not similar to a symmetric matrix
    A = np.array([[-1e-3, 0.0], [4e-4, -2e-3]])
    ss = BilinearStateSpace(
        A,
        np.array([[[-1e-4, 0.0], [0.0, 0.0]]]),
        np.array([[1e-3], [0.0]]),
        np.zeros((1, 2, 1)),
        np.eye(2),
        np.zeros((2, 1)),
        ("a", "b"),
        ("u",),
        ("m",),
        ("a", "b"),
        np.ones(2),
    )
    t = np.array([0.0, 60.0, 180.0])
    m = np.array([[0.1], [0.3], [0.3]])
    Phi, G0, _, which = transition_matrices(ss, t, m)
    for k in range(2):
        ref = zoh(*ss.matrices(m[k]), t[k + 1] - t[k])
        np.testing.assert_allclose(Phi[which[k]], ref[0], rtol=1e-13)
        np.testing.assert_allclose(G0[which[k]], ref[1], rtol=1e-13)


def test_propagate_wrapper_accepts_non_contiguous_and_integer_arrays():
    rng = np.random.default_rng(0)
    Phi = rng.standard_normal((2, 3, 3)) / 3
    G0, G1 = rng.standard_normal((2, 2, 3, 2))
    which = np.array([0, 1, 1, 0], dtype=np.int32)
    u = np.asfortranarray(rng.integers(0, 5, (5, 2)))
    x0 = np.arange(3)
    np.testing.assert_allclose(
        propagate(Phi, G0, G1, which, u, x0), propagate_reference(Phi, G0, G1, which, u, x0), rtol=1e-13
    )


def _two_state_args(ss: BilinearStateSpace, N: int = 5) -> tuple:
    t = np.arange(N) * 60.0
    return (
        ss,
        t,
        np.full((N, ss.n_flows), 0.1),
        np.full((N, ss.n_inputs), 20.0),
        np.full((N, 1), 21.0),
        np.full(ss.n_states, 20.0),
        np.eye(ss.n_states),
        np.eye(ss.n_states) * 1e-6,
        np.array([[0.01]]),
    )


def test_rc2_applicability():
    assert rc2_applicable(thirteen_state(np.random.default_rng(0)).state_space(), 1) is False
    assert rc2_applicable(one_r_one_c().state_space(), 1) is False


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"hold": "linear"}, "hold must be one of"),
        ({"y": np.full((5, 2), 21.0)}, "needs one output"),
        ({"ss": "one_state"}, "needs a 2-state RC model"),
        ({"ss": "block"}, r"needs an RC model \(diag\(capacities\) A"),
    ],
)
def test_kalman_nll_rc2_rejects_what_it_cannot_do(change, match):
    args = list(_two_state_args(NET2.state_space()))
    kwargs = {}
    if change.get("ss") == "one_state":
        args = list(_two_state_args(one_r_one_c().state_space()))
    elif change.get("ss") == "block":
        ss = NET2.state_space()
        args[0] = BilinearStateSpace(
            ss.A + np.array([[0.0, 0.0], [1e-3, 0.0]]),
            ss.N,
            ss.B,
            ss.M,
            ss.C,
            ss.D,
            ss.state_names,
            ss.input_names,
            ss.flow_names,
            ss.output_names,
            ss.capacities,
        )
    elif "y" in change:
        args[4] = change["y"]
    else:
        kwargs = change
    with pytest.raises(InputShapeError, match=match):
        kalman_nll_rc2(*args, **kwargs)


def test_rank_one_form_is_kept_per_state_space_and_flow_range():
    ss = thirteen_state(np.random.default_rng(4)).state_space()
    rng = np.random.default_rng(4)
    t = np.arange(100) * 60.0
    u = 20 + rng.standard_normal((100, ss.n_inputs))
    m = rng.uniform(0.05, 0.2, (100, 1))
    first = simulate(ss, t, u, m).x
    kept = ss.__dict__["_rank_one_forms"]
    form = kept[float(np.max(m))]
    again = simulate(ss, t, u, m).x
    np.testing.assert_array_equal(first, again)  # the kept form gives the same numbers
    assert kept[float(np.max(m))] is form
    fresh = thirteen_state(
        np.random.default_rng(4)
    ).state_space()  # an equal model computes its own, no sharing by value
    np.testing.assert_array_equal(simulate(fresh, t, u, m).x, first)
    for k in range(_FORMS_KEPT + 3):  # the store stays bounded
        _rank_one_form_of(ss, 1.0 + k)
    assert len(kept) == _FORMS_KEPT


@pytest.mark.parametrize("hold", ["zoh", "foh"])
@pytest.mark.parametrize("given_x0", [True, False])
def test_compiled_two_state_simulation_equals_the_matrix_exponential_loop(hold, given_x0) -> None:
    """The compiled 2-state path against one scipy expm per interval and a Python loop (irregular t, m varying)."""
    from scipy.linalg import expm

    rng = np.random.default_rng(24)
    ss = NET2.state_space()
    n = 60
    t = np.cumsum(rng.choice([60.0, 60.0, 120.0], n))
    m = np.repeat(rng.uniform(0.02, 0.3, (n // 3, 1)), 3, axis=0)
    u = np.column_stack(
        [rng.normal(28, 2, n), rng.normal(22, 1, n), rng.normal(300, 50, n), rng.normal(14, 1, n)]
    )
    A0, B0 = ss.matrices(m[0])
    x0 = np.array([23.0, 25.0]) if given_x0 else np.linalg.solve(A0, -B0 @ u[0])
    got = simulate(ss, t, u, m, x0=x0 if given_x0 else None, hold=hold)
    p = ss.n_inputs
    Phi, G0, G1 = np.empty((n - 1, 2, 2)), np.empty((n - 1, 2, p)), np.zeros((n - 1, 2, p))
    for k in range(n - 1):
        A, B = ss.matrices(m[k])
        blk = np.zeros((2 + 2 * p, 2 + 2 * p))
        dt = t[k + 1] - t[k]
        blk[:2, :2], blk[:2, 2 : 2 + p], blk[2 : 2 + p, 2 + p :] = A * dt, B * dt, np.eye(p)
        E = expm(blk)
        Phi[k] = E[:2, :2]
        if hold == "foh":
            G0[k], G1[k] = E[:2, 2 : 2 + p] - E[:2, 2 + p :], E[:2, 2 + p :]
        else:
            G0[k] = E[:2, 2 : 2 + p]
    x = propagate_reference(Phi, G0, G1, np.arange(n - 1), u, x0)
    np.testing.assert_allclose(got.x, x, rtol=1e-10)
    np.testing.assert_allclose(got.y, x @ ss.C.T + u @ ss.D.T, rtol=1e-10)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda t, u, m: (t[::-1].copy(), u, m), "strictly increasing"),
        (
            lambda t, u, m: (t, np.where(np.arange(t.size)[:, None] == 5, np.nan, u), m),
            "not finite at sample 5",
        ),
        (lambda t, u, m: (t, u, np.full_like(m, np.inf)), "not finite at sample 0"),
    ],
)
def test_compiled_two_state_simulation_leaves_bad_inputs_to_the_checks(change, match) -> None:
    ss = NET2.state_space()
    n = 20
    t, u, m = change(np.arange(n) * 60.0, np.full((n, ss.n_inputs), 20.0), np.full((n, 1), 0.1))
    with pytest.raises(InputShapeError, match=match):
        simulate(ss, t, u, m)
