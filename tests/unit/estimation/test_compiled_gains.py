"""Heat-input gains that are parameters, with affine ties, on the compiled path (issue 38).

A heating circuit that serves several rooms is one input split by estimated shares, the last
room's share tied to the rest (``1 - s_1 - s_2``, :mod:`rczone.models.multizone`); a window's
aperture is a gain on the irradiance. The compiled problem carries them as the terms of
``Gb = Gb0 + sum_t k_t theta[idx_t]`` (:class:`rczone.kernels.arrays.Slots`). Each case checks the
compiled engine is the one taken and compares it with independent computations:

* the value with the plain NumPy cost of ``tests/oracles.py`` (the network's own state space, the
  NumPy filter) at random points, for LS, ML and MAP, ZOH and FOH;
* the gradient of the likelihood (the reverse pass) with the compiled forward sensitivities and
  5-point differences of the value, and the least-squares gradient with 5-point differences;
* on the four-room model of docs/multizone.md, value and gradient with the general engine's.
"""

from __future__ import annotations

import numpy as np
import pytest

from rczone.estimation import Dataset, Objective, make_spec
from rczone.estimation.compiled import compiled_problem
from rczone.estimation.fit import default_free
from rczone.models.multizone import multizone
from rczone.network import Parameter
from rczone.simulation import simulate
from tests.oracles import objective_reference_cost

from .test_gradient import five_point
from .test_reverse_gradient import agree

#: Three rooms in a row, one circuit over all three (two free shares, the third ``1 - s_1 - s_2``),
#: the sun through a free aperture per room.
WALLS3 = [("1", "2"), ("2", "3")]


def rooms(n_rooms: int = 3, *, days: float = 0.7, seed: int = 5, **generated):
    """A generated network of ``n_rooms`` rooms and data simulated from shares away from the starts.

    The truth: the circuit ``Ph`` splits 50 / 30 / 20 %, apertures of 2-4 m2, the other values the
    generator's; 10-minute samples with 0.05 K sensor noise.
    """
    walls = [(str(i), str(i + 1)) for i in range(1, n_rooms)]
    generated = generated or {"circuits": {"Ph": [str(i) for i in range(1, n_rooms + 1)]}, "solar": True}
    net = multizone(n_rooms, walls, **generated)
    rng = np.random.default_rng(seed)
    truth = {f"Aw_{r}": 2.0 + r for r in range(1, n_rooms + 1) if f"Aw_{r}" in net.parameters}
    truth.update({"s_Ph_1": 0.5, "s_Ph_2": 0.3} if "s_Ph_1" in net.parameters else {})
    n = int(days * 86400 / 600) + 1
    t = np.arange(n) * 600.0
    cols = {
        "To": 5 + 3 * np.sin(2 * np.pi * t / 86400),
        "Ps": np.clip(np.sin(2 * np.pi * (t / 86400 - 0.25)), 0, None) * 300,
        "Ph": 500 + 1500 * (np.cumsum(rng.random(n) < 600 / 7200) % 2),
    }
    for name in net.input_names:  # a heater per room, or the generated circuits
        cols.setdefault(name, 300 + 900 * (np.cumsum(rng.random(n) < 600 / 5400) % 2))
    u = np.column_stack([cols[name] for name in net.input_names])
    m = np.zeros((n, 0))
    y = simulate(net.state_space(truth), t, u, m).y + 0.05 * rng.standard_normal((n, len(net.outputs)))
    return net, Dataset(t, u, m, y, net.input_names, (), net.outputs)


def _spec(net, method: str):
    """Every element, share and aperture free, and for a likelihood the noise levels ``rczone fit`` frees."""
    free = default_free(net, "ml")
    return make_spec(net, [n for n in free if method != "ls" or not n.startswith("sigma_")])


def _random_etas(spec, count: int, seed: int = 11):
    rng = np.random.default_rng(seed)
    lo, hi = spec.eta_lower, spec.eta_upper
    return [lo + (hi - lo) * rng.uniform(0.3, 0.7, spec.n_free) for _ in range(count)]


@pytest.mark.parametrize("method", ["ls", "ml", "map"])
@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_circuit_shares_and_apertures_are_compiled_and_equal_the_numpy_cost(method, hold) -> None:
    net, data = rooms()
    assert "s_Ph_3" in net.parameters and net.parameters["s_Ph_3"].expr == "1 - s_Ph_1 - s_Ph_2"
    spec = _spec(net, method)
    assert {"s_Ph_1", "s_Ph_2", "Aw_1", "Aw_3"} <= set(spec.names)
    obj = Objective(net, data, spec, method, hold, likelihood_weight=0.3 if method == "map" else 1.0)
    assert obj.engine == "compiled" and obj.gradient_engine == "compiled"
    # a term per free parameter in each gain: the shares of rooms 1 and 2, two in room 3's, the apertures
    assert obj.compiled.slots.gain_idx.shape == (1 + 1 + 2 + 3,)
    for eta in _random_etas(spec, 4):
        assert obj(eta) == pytest.approx(objective_reference_cost(obj, spec.to_theta(eta)), rel=1e-11)


@pytest.mark.parametrize(("method", "hold"), [("ml", "zoh"), ("ml", "foh"), ("map", "zoh")])
def test_the_reverse_gradient_through_the_shares_is_exact(method, hold) -> None:
    net, data = rooms()
    spec = _spec(net, method)
    obj = Objective(net, data, spec, method, hold, likelihood_weight=0.3 if method == "map" else 1.0)
    eta = _random_etas(spec, 1, seed=3)[0]
    agree(obj, eta)  # reverse pass = forward sensitivities (1e-8) = 5-point differences (1e-6)
    # the gains' own components, which the noise levels' dwarf in the norm: each to 1e-6 of itself
    # or 1e-8 of the largest (the sun through room 3's aperture moves the likelihood least)
    g = obj.value_and_gradient(eta)[1]
    names = ("s_Ph_1", "s_Ph_2", "Aw_1", "Aw_3")
    idx = [spec.names.index(name) for name in names]
    ref = [
        five_point(lambda x, i=i: obj(eta + x[0] * np.eye(spec.n_free)[i]), np.zeros(1), 1e-3)[0] for i in idx
    ]
    scale = max(abs(r) for r in ref)
    for name, i, r in zip(names, idx, ref, strict=True):
        assert g[i] == pytest.approx(r, rel=1e-6, abs=1e-8 * scale), name


def test_the_least_squares_gradient_through_the_shares_is_exact() -> None:
    net, data = rooms()
    spec = _spec(net, "ls")
    obj = Objective(net, data, spec, "ls")
    assert obj.gradient_engine == "compiled"
    eta = _random_etas(spec, 1, seed=4)[0]
    j, g = obj.value_and_gradient(eta)
    assert j == pytest.approx(obj(eta), rel=1e-12)
    ref = five_point(obj, eta, 1e-3)
    np.testing.assert_allclose(g, ref, rtol=0, atol=1e-6 * np.linalg.norm(ref))


def test_a_fixed_share_is_a_constant_and_a_nonlinear_share_stays_general() -> None:
    net, data = rooms()
    # s_Ph_1 held: its part of s_Ph_1 and of 1 - s_Ph_1 - s_Ph_2 is packed as a constant gain
    spec = make_spec(net, ["Ci_1", "Rw_1_2", "s_Ph_2", "Aw_2", "sigma_v_T1"], fixed={"s_Ph_1": 0.45})
    obj = Objective(net, data, spec, "ml")
    assert obj.engine == "compiled" and obj.compiled.slots.gain_idx.shape == (3,)
    for eta in _random_etas(spec, 3):
        assert obj(eta) == pytest.approx(objective_reference_cost(obj, spec.to_theta(eta)), rel=1e-11)
    agree(obj, _random_etas(spec, 1, seed=8)[0])
    # a share that is not affine in the parameters (a product of two) takes the general engine
    squared = net.replace_parameters([Parameter("s_Ph_3", "gain", expr="s_Ph_1 * s_Ph_2")])
    general = Objective(squared, data, _spec(squared, "ml"), "ml")
    assert compiled_problem(general) is None and general.engine == "general"
    theta = general.spec.start * 1.05
    assert general(general.spec.to_eta(theta)) == pytest.approx(
        objective_reference_cost(general, theta), rel=1e-11
    )


def test_the_four_room_model_of_the_docs_equals_the_general_engine() -> None:
    """The generated model of docs/multizone.md (``--circuit Ph1=1,2 --circuit Ph2=3,4 --mass``):
    12 states, 4 outputs, 37 free; one day of data. Value and gradient of the compiled engine
    (reverse pass) equal the general engine's (forward sensitivities of the Python-built model)."""
    circuits = {"Ph1": ["1", "2"], "Ph2": ["3", "4"]}
    net, data = rooms(4, days=1.0, circuits=circuits, mass=True)
    spec = _spec(net, "ml")
    assert spec.n_free == 37 and len(net.state_names) == 12
    fast = Objective(net, data, spec, "ml")
    slow = Objective(net, data, spec, "ml", engine="general")
    assert (fast.engine, slow.engine) == ("compiled", "general")
    for eta in _random_etas(spec, 2, seed=21):
        j, g = fast.value_and_gradient(eta)
        j_ref, g_ref = slow.value_and_gradient(eta)
        assert j == pytest.approx(j_ref, rel=1e-11)
        np.testing.assert_allclose(g, g_ref, rtol=0, atol=1e-8 * np.linalg.norm(g_ref))


def test_the_compile_count_pairs_of_rooms_take_the_compiled_engine() -> None:
    """The generated two-room pairs whose fits ``tests/unit/kernels/test_compile_once.py`` counts
    compilations of (a circuit's shares, or apertures) run on the compiled engine, so that test
    counts the compiled kernels' specializations for models with parameter gains and ties."""
    from tests.unit.kernels.test_compile_once import ROOMS, rooms_case

    for name in ROOMS:
        net, frame = rooms_case(name)
        data = Dataset.from_frame(frame, net, time="time")
        obj = Objective(net, data, _spec(net, "ml"), "ml")
        assert obj.engine == "compiled" and obj.compiled.slots.gain_idx.size == 2, name


@pytest.mark.slow
def test_a_fit_of_three_rooms_on_one_circuit_recovers_the_shares() -> None:
    """``rczone.fit`` of the three-room circuit model on three days of its own simulated data (about
    20 s of CPU with its checks): the compiled engine, and the shares 50 / 30 % and apertures 3, 4,
    5 m2 it was simulated with inside 2.5 standard errors of the estimates (starts 1/3 and 2 m2)."""
    import pandas as pd

    import rczone

    net, data = rooms(days=3.0)
    frame = pd.DataFrame(
        {"time": data.t}
        | {name: data.u[:, i] for i, name in enumerate(data.input_names)}
        | {name: data.y[:, i] for i, name in enumerate(data.output_names)}
    )
    out = rczone.fit(net, frame, n_starts=1).to_dict()
    assert out["engine"] == "compiled"
    truth = {"s_Ph_1": 0.5, "s_Ph_2": 0.3, "Aw_1": 3.0, "Aw_2": 4.0, "Aw_3": 5.0}
    for name, value in truth.items():
        p = out["parameters"][name]
        assert abs(p["estimate"] - value) < 2.5 * p["std_error"], (name, p["estimate"], p["std_error"])
