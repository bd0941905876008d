"""The emulator: energy conservation over a night and the size of its ZOH cache."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from rczone.virtual.building import build_building
from rczone.virtual.emulator import run
from rczone.virtual.scenarios import forced_schedule


@pytest.fixture(scope="module")
def night():
    bld = build_building()
    rng = np.random.default_rng(7)
    g_run, g_sched = rng.spawn(2)
    return bld, run(bld, "autumn", g_run, warmup=3600.0, forced={"target": forced_schedule(g_sched)})


def _state_integrals(ss, r) -> np.ndarray:
    """Exact integral of the state over each interval, from an augmented matrix exponential.

    d/dt [x, u, z] = [[A, B, 0], [0, 0, 0], [I, 0, 0]] [x, u, z] with z = int x dt.
    """
    n, p = ss.A.shape[0], ss.B.shape[1]
    dt = float(r.t[1] - r.t[0])
    cache = {}
    out = np.empty((len(r.u), n))
    for k in range(len(r.u)):
        key = tuple(r.m[k])
        if key not in cache:
            A, B = ss.matrices(r.m[k])
            M = np.zeros((2 * n + p, 2 * n + p))
            M[:n, :n], M[:n, n : n + p], M[n + p :, :n] = A, B, np.eye(n)
            E = expm(M * dt)
            cache[key] = (E[n + p :, :n], E[n + p :, n : n + p])
        Zx, Zu = cache[key]
        out[k] = Zx @ r.x[k] + Zu @ r.u[k]
    return out


def test_energy_is_conserved_over_a_night(night):
    """Sum C_i dT_i equals the heat brought in through boundary resistors, gains and supply air.

    The heat flows are computed from the network's resistor list and node capacities, not
    from the state-space matrices (which are only used to integrate the node temperatures).
    """
    bld, r = night
    net = bld.network
    ss = net.state_space()
    dt = float(r.t[1] - r.t[0])
    ix = {s: i for i, s in enumerate(r.state_names)}
    cap = np.array([nd.capacity for nd in net.nodes if nd.name in ix])
    order = [nd.name for nd in net.nodes if nd.name in ix]
    cap = cap[[order.index(s) for s in r.state_names]]
    stored = float(cap @ (r.x[-1] - r.x[0]))

    zint = _state_integrals(ss, r)
    boundary = 0.0
    for res in net.resistors:
        for a, b in ((res.a, res.b), (res.b, res.a)):
            if a in net.boundaries:
                boundary += float(np.sum(r.input(a) * dt - zint[:, ix[b]]) / res.resistance)
    gains = sum(float(np.sum(r.input(h.name)) * dt) for h in net.heat_inputs)
    supply = 0.0
    for s in net.supply_air:
        supply += float(np.sum(r.flow(s.flow) * s.cp * (r.input(s.temperature) * dt - zint[:, ix[s.node]])))
    gross = abs(boundary) + abs(gains) + abs(supply)
    assert abs(stored) > 1e-3 * gross  # the balance is not trivially zero
    assert stored == pytest.approx(boundary + gains + supply, rel=1e-6, abs=1e-6 * gross)


def test_flows_are_discrete_levels_and_cache_small(night):
    _, r = night
    assert set(np.unique(r.m)) <= {0.02, 0.05, 0.08, 0.12}
    assert r.n_discretizations == len({tuple(row) for row in r.m})
    assert r.n_discretizations < 60


def test_inputs_within_physical_ranges(night):
    bld, r = night
    for z in bld.zones:
        ts = r.input(bld.supply_name(z))
        assert ts.min() > 10.0
        assert ts.max() < 37.0
        assert np.all(r.input(bld.gain_name(z)) >= bld.gains[z] - 1e-9)
