"""The paper's models: equations as written in SPEC section 2, values by hand, documented claims.

Oracles: SPEC eq. (2) written out here entry by entry; construction values recomputed here from
the geometry (areas, per-m2 R and C of the constructions, window and door U-values); the
claims about aggregation options stated in ``rczone.models.aggregation``'s docstring.
"""

from dataclasses import replace

import numpy as np
import pytest

from rczone.construction import AIR_CP, ashrae_construction, office_241
from rczone.errors import InputShapeError
from rczone.models import (
    SURROUNDINGS,
    first_order,
    full_scale,
    second_order,
    second_order_reduced,
    surroundings_to_tsd,
)
from rczone.simulation import simulate
from rczone.simulation.frequency import frequency_response, gain_error

SURF = (("o", "To"), ("f", "Tf"), ("c", "Tc"), ("n1", "Tn1"), ("n2", "Tn2"), ("hw", "Thw"))
BAND = np.logspace(-5, -3, 60)
#: SPEC eq. (7) weights: 45 F for Ts and To, 10 F for the surroundings, in K.
DU = {"Ts": 25.0, "Tsd": 50.0 / 9.0, "To": 25.0}


def test_full_scale_matrices_are_spec_eq2_written_by_hand():
    net = full_scale()
    v = net.values()
    ss = net.state_space()
    x = {n: i for i, n in enumerate(ss.state_names)}
    u = {n: i for i, n in enumerate(ss.input_names)}
    n, p = len(x), len(u)
    A, B = np.zeros((n, n)), np.zeros((n, p))
    i = x["Ti"]
    A[i, i] = -(1 / v["Rwin"] + sum(1 / v[f"R{s}w1"] for s, _ in SURF)) / v["Cr"]
    B[i, u["To"]] += 1 / (v["Rwin"] * v["Cr"])
    B[i, u["Q"]] = 1 / v["Cr"]
    for s, far in SURF:
        w1, w2 = x[f"T{s}w1"], x[f"T{s}w2"]
        r1, r2, r3, c1, c2 = (v[f"R{s}w1"], v[f"R{s}w2"], v[f"R{s}w3"], v[f"C{s}w1"], v[f"C{s}w2"])
        A[i, w1] = 1 / (r1 * v["Cr"])
        A[w1, i], A[w1, w1], A[w1, w2] = 1 / (r1 * c1), -(1 / r1 + 1 / r2) / c1, 1 / (r2 * c1)
        A[w2, w1], A[w2, w2] = 1 / (r2 * c2), -(1 / r2 + 1 / r3) / c2
        B[w2, u[far]] += 1 / (r3 * c2)
    np.testing.assert_allclose(ss.A, A, rtol=1e-12, atol=1e-20)
    np.testing.assert_allclose(ss.B, B, rtol=1e-12, atol=1e-20)
    N = np.zeros((1, n, n))
    N[0, i, i] = -AIR_CP / v["Cr"]
    M = np.zeros((1, n, p))
    M[0, i, u["Ts"]] = AIR_CP / v["Cr"]
    np.testing.assert_allclose(ss.N, N, rtol=1e-12)
    np.testing.assert_allclose(ss.M, M, rtol=1e-12)
    assert ss.state_names[0] == "Ti" and ss.output_names == ("Ti",)


@pytest.mark.parametrize("split", ["matched", "symmetric"])
def test_construction_values_by_hand(split):
    g = office_241()
    cap = {s.name: s.area * s.construction.c_total for s in g.surfaces}
    cond = {s.name: s.area / s.construction.r_total for s in g.surfaces}
    cond["hw"] += g.door.u_value * g.door.area
    full = full_scale(g, split=split).values()
    assert full["Cr"] == pytest.approx(
        g.floor_area * g.height * 1.2 * 1005 + 15 * 608 * 1630 * 0.0254, rel=1e-12
    )
    assert full["Rwin"] == pytest.approx(1 / (2.8 * 3.0), rel=1e-12)
    for s in cap:
        assert full[f"C{s}w1"] + full[f"C{s}w2"] == pytest.approx(cap[s], rel=1e-12)
        r = full[f"R{s}w1"] + full[f"R{s}w2"] + full[f"R{s}w3"]
        assert 1 / r == pytest.approx(cond[s], rel=1e-12)
    internal = [s for s in cap if s != "o"]
    two = second_order(g, split=split).values()
    assert two["Cw"] == pytest.approx(sum(cap[s] for s in internal), rel=1e-12)
    assert two["Rwin"] == pytest.approx(1 / (2.8 * 3.0 + cond["o"]), rel=1e-12)
    assert two["R1"] + two["R2"] == pytest.approx(1 / sum(cond[s] for s in internal), rel=1e-12)
    one = first_order(g, split=split).values()
    assert one["Cr"] == pytest.approx(full["Cr"] + sum(cap.values()), rel=1e-12)
    assert one["Rw"] == pytest.approx(two["R1"] + two["R2"], rel=1e-12)
    assert first_order(g, split=split, capacity="room").values()["Cr"] == pytest.approx(full["Cr"])


def test_symmetric_split_gives_the_halfway_wall_node():
    """With every surface split symmetrically, the capacity centroid is mid-layer: R1/R2 follow.

    The ceiling gets the outside film on its far side so that R1 != R2.
    """
    g = office_241()
    ceiling = g.surface("c")
    ceiling = replace(ceiling, construction=ashrae_construction(ceiling.construction.name, exterior=True))
    g = replace(g, surfaces=tuple(ceiling if s.name == "c" else s for s in g.surfaces))
    two = second_order(g, split="symmetric").values()
    # centroid of a symmetric element is film_in + R_layers/2 (scaled by the door factor on hw)
    k_hw = (1 / (1 / g.surface("hw").resistance + g.door.u_value * g.door.area)) / g.surface("hw").resistance
    pa = 1 / sum(
        s.area / (s.construction.film_in + s.construction.r_layers / 2) / (k_hw if s.name == "hw" else 1.0)
        for s in g.surfaces
        if s.far_side != "To"
    )
    pb = 1 / sum(
        s.area / (s.construction.film_out + s.construction.r_layers / 2) / (k_hw if s.name == "hw" else 1.0)
        for s in g.surfaces
        if s.far_side != "To"
    )
    assert two["R1"] / (two["R1"] + two["R2"]) == pytest.approx(pa / (pa + pb), rel=1e-12)
    assert abs(two["R1"] - two["R2"]) > 1e-3 * two["R1"]


def weighted_errors(net, full_resp):
    r = frequency_response(net.state_space().lti(0.12), BAND)
    return {k: float(np.max(e)) for k, e in gain_error(full_resp, r, DU).items()}


@pytest.mark.parametrize("split", ["matched", "symmetric"])
def test_default_external_capacity_has_the_smallest_frequency_error(split):
    full = frequency_response(full_scale(split=split).state_space().lti(0.12), BAND).summed(
        {"Tsd": SURROUNDINGS}
    )
    total = {
        opt: sum(weighted_errors(second_order(split=split, external_capacity=opt), full).values())
        for opt in ("none", "room-side", "all")
    }
    assert total["none"] == min(total.values())


def test_first_order_default_capacity_has_the_smaller_frequency_error_with_the_matched_split():
    full = frequency_response(full_scale().state_space().lti(0.12), BAND).summed({"Tsd": SURROUNDINGS})
    total = {opt: sum(weighted_errors(first_order(capacity=opt), full).values()) for opt in ("all", "room")}
    assert total["all"] < total["room"]


def test_documented_eq7_errors_of_office_241():
    """Figures quoted in rczone.models.aggregation (largest weighted error over 1e-5..1e-3 Hz, K)."""
    full = frequency_response(full_scale().state_space().lti(0.12), BAND).summed({"Tsd": SURROUNDINGS})
    two = weighted_errors(second_order(), full)
    assert two == pytest.approx({"Ts": 2.038, "Tsd": 0.375, "To": 0.390}, abs=0.02)
    one = weighted_errors(first_order(), full)
    assert one == pytest.approx({"Ts": 5.314, "Tsd": 0.554, "To": 0.332}, abs=0.05)
    assert weighted_errors(second_order_reduced(), full)["Tsd"] < 0.5


def test_surroundings_to_tsd():
    names = full_scale().input_names
    rng = np.random.default_rng(0)
    u = rng.normal(20.0, 3.0, size=(7, len(names)))
    low, low_names = surroundings_to_tsd(u, names)
    assert low_names == second_order().input_names
    cols = [names.index(n) for n in SURROUNDINGS]
    np.testing.assert_allclose(low[:, 1], u[:, cols].sum(axis=1) / 5, rtol=1e-14)
    for k, n in ((0, "To"), (2, "Ts"), (3, "Q")):
        np.testing.assert_array_equal(low[:, k], u[:, names.index(n)])
    assert low.shape == (7, 4)


@pytest.mark.parametrize(
    ("u", "names", "match"),
    [
        (np.zeros(8), full_scale().input_names, r"shape \(n_samples, 8\)"),
        (np.zeros((3, 7)), full_scale().input_names, r"shape \(n_samples, 8\)"),
        (np.zeros((3, 7)), ("To", "Tf", "Tc", "Tn1", "Tn2", "Ts", "Q"), "'Thw' is missing"),
        (np.zeros((3, 4)), ("To", "Tsd", "Ts", "Q"), "'Tf' is missing"),
    ],
)
def test_surroundings_to_tsd_bad_inputs(u, names, match):
    with pytest.raises(InputShapeError, match=match):
        surroundings_to_tsd(u, names)


def test_low_order_models_settle_where_the_full_model_does_with_equal_surroundings():
    """Simulated to steady state on equal surroundings, all models end at the same Ti."""
    full, two, one = full_scale(), second_order(), first_order()
    names = full.input_names
    t = np.arange(0.0, 30 * 86400.0 + 1, 3600.0)
    row = {"To": 30.0, "Tf": 24.0, "Tc": 24.0, "Tn1": 24.0, "Tn2": 24.0, "Thw": 24.0, "Ts": 13.0, "Q": 50.0}
    u = np.tile([row[n] for n in names], (t.size, 1))
    m = np.full((t.size, 1), 0.05)
    y_full = simulate(full.state_space(), t, u, m=m, x0=np.full(13, 22.0)).y[-1, 0]
    low_u, _ = surroundings_to_tsd(u, names)
    for net in (two, one):
        x0 = np.full(len(net.state_names), 22.0)
        y = simulate(net.state_space(), t, low_u, m=m, x0=x0).y[-1, 0]
        assert y == pytest.approx(y_full, abs=1e-6)
