"""What the joint two-zone model's parameters *should* be, read off the virtual building's true network.

The model is ``validation/models/virtual_two_zones.toml`` (target + n1 and their shared partition).
Every truth here comes from the 152-state network of :func:`rczone.virtual.building.build_building`
(the true, perturbed construction), never from a fit, by rules stated before fitting:

* ``Rp``, ``Cp`` -- the shared partition's air-to-air DC resistance (films and layers in series) and
  its total capacity. The model keeps the partition's physical structure (one node per gypsum
  board), so the steady-state value is the right one at every period; :func:`partition_admittance_error`
  measures how well the nominal-ratio 3R2C reproduces the true ladder at the forced test's periods.
* ``Ca_t``, ``Ca_n1`` -- the air node's capacity (the zone's air).
* ``Cl_t``, ``Cl_n1`` -- construction value: furniture plus the room-side massive layer of every light
  surface that faces the air through a film only (gypsum boards of the other partitions and of the
  external wall, acoustic tiles; for n1 also both boards of its mirrored side wall and the tiles of
  its mirrored floor and ceiling). These all have per-area time constants (film + half layer) of
  1200-3000 s: at the forced test's 1-4 h periods they are neither lumped with the air nor inert.
* ``Cm_t``, ``Cm_n1`` -- construction value: the concrete of the exposed slabs; ``Rm_*`` the
  resistance from the air to their capacity centroid.
* hour-scale values of ``Cl``, ``Rm``, ``Cm`` (:func:`hour_scale_masses`): the model's light branch
  and slab branch together matched to the true storage admittance of all the zone's elements (the
  partition excepted; nodal analysis of the true network, DC conduction taken out) over 1-4 h. This is
  what the data of a forced night can see: a 100 mm slab at these periods is a diffusion problem
  (penetration depth 4-8 cm), and only part of each light layer follows the air.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from scipy.optimize import minimize_scalar

from rczone.models.split import WallSplit, exact_wall_response, lumped_wall_response
from rczone.network import RCNetwork
from rczone.virtual.building import build_building, true_geometry

#: Light-mass nodes of each zone in the true network: furniture and room-side light layers.
LIGHT_NODES = {
    "t": ("target_furn", ("t_n2", -1), ("t_hw", -1), ("t_o", -1), ("t_c", -1)),
    "n1": (
        "n1_furn",
        ("n1_side", 0),
        ("n1_side", -1),
        ("n1_hw", -1),
        ("n1_o", -1),
        ("n1_fl", 0),
        ("n1_ce", -1),
    ),
}
#: Slab ladders whose concrete nodes face each zone's air: (ladder, index of the exposed end).
SLABS = {"t": (("t_f", -1),), "n1": (("n1_fl", -1), ("n1_ce", 0))}
AIR = {"t": "Ti", "n1": "Tn1"}
#: Nominal split of the partition in the model file: film + half board, the middle (rest).
RATIO = (0.28585, 0.4283)
#: The middle of the 1-4 h periods a forced test with 60-150 min blocks excites, s.
HOUR_SCALE_PERIOD = 7200.0


def _ladder(net: RCNetwork, prefix: str) -> list[str]:
    """Node names of the wall ladder ``prefix``, far side first."""
    names = [n.name for n in net.nodes if n.name.rsplit("_", 1)[0] == prefix]
    return sorted(names, key=lambda s: int(s.rsplit("_", 1)[1]))


def _capacity(net: RCNetwork, names: list[str]) -> float:
    cap = {n.name: n.capacity for n in net.nodes}
    return float(sum(cap[n] for n in names))


def _chain_resistances(net: RCNetwork, names: list[str]) -> list[float]:
    """Series resistances along a ladder: air/boundary, nodes..., air/boundary."""
    inside = set(names)
    return [r.resistance for r in net.resistors if r.a in inside or r.b in inside]


def _slab(net: RCNetwork, prefix: str, end: int, air: str) -> tuple[float, float]:
    """Concrete capacity of slab ``prefix`` and the resistance from ``air`` to its capacity centroid.

    ``end`` is the ladder index of the node facing ``air`` (0: far side, -1: room side).
    """
    nodes = _ladder(net, prefix)
    cap = {n.name: n.capacity for n in net.nodes}
    res = {frozenset((r.a, r.b)): r.resistance for r in net.resistors}
    order = nodes if end == 0 else nodes[::-1]  # from the exposed face inwards
    dist, path, prev = {}, 0.0, air
    for n in order:
        path += res[frozenset((prev, n))]
        dist[n], prev = path, n
    concrete = [n for n in nodes if cap[n] > 2 * min(cap[m] for m in nodes)]  # the tile slice is light
    c = sum(cap[n] for n in concrete)
    return c, sum(cap[n] * dist[n] for n in concrete) / c


def true_values() -> dict[str, float]:
    """The joint model's parameters from the true network (SI: J/K, K/W)."""
    return dict(_true_values())


@cache
def _true_values() -> dict[str, float]:
    net = build_building().network
    part = _ladder(net, "t_n1")
    out = {
        "Rp": float(sum(_chain_resistances(net, part))),
        "Cp": _capacity(net, part),
        "Ca_t": _capacity(net, ["Ti"]),
        "Ca_n1": _capacity(net, ["Tn1"]),
    }
    for z, items in LIGHT_NODES.items():
        names = [i if isinstance(i, str) else _ladder(net, i[0])[i[1]] for i in items]
        out[f"Cl_{z}"] = _capacity(net, names)
    for z, slabs in SLABS.items():
        cs = [_slab(net, p, e, AIR[z]) for p, e in slabs]
        out[f"Cm_{z}"] = float(sum(c for c, _ in cs))
        out[f"Rm_{z}"] = float(1.0 / sum(1.0 / r for _, r in cs))
    return out


def _partition(cp: float) -> WallSplit:
    """The model file's partition element per m2 with the true ``Rp`` and capacity ``cp`` (J/K)."""
    rp, a = true_values()["Rp"], true_geometry().surface("n1").area
    r1, r2 = RATIO[0] * rp * a, RATIO[1] * rp * a
    return WallSplit(r1, r2, r1, cp / a / 2, cp / a / 2)


def partition_admittance_ratio(cp: float, periods_s: tuple[float, ...]) -> dict[str, np.ndarray]:
    """``|Y_model| / |Y_true|`` of the partition's room-side and transfer admittances at ``periods_s``.

    The model element is the file's 3R2C ``Rp1 - Cp/2 - Rp2 - Cp/2 - Rp3`` (nominal split ratios,
    true ``Rp``, capacity ``cp``); the truth is the exact layered-slab response of the true
    partition construction.
    """
    s = true_geometry().surface("n1")
    f = 1.0 / np.asarray(periods_s, dtype=float)
    exact = exact_wall_response(s.construction, f)
    model = lumped_wall_response(_partition(cp), f)
    return {k: np.abs(model[j]) / np.abs(exact[j]) for j, k in enumerate(("room", "transfer"))}


def hour_scale_partition_capacity(period_s: float = HOUR_SCALE_PERIOD) -> float:
    """The ``Cp`` for which the model's partition passes the true wall's heat between the zones at ``period_s``.

    Matches the transfer admittance magnitude (heat delivered to one zone per K of the other):
    that is the partition's only role the joint model cannot give to another element (its
    room-side storage is shared with the light-mass and air nodes). One node per 19 mm board
    lags less than the real board, so the matching ``Cp`` is below the construction total.
    """
    res = minimize_scalar(
        lambda lc: np.log(partition_admittance_ratio(np.exp(lc), (period_s,))["transfer"][0]) ** 2,
        bounds=(np.log(1e4), np.log(1e7)),
        method="bounded",
        options={"xatol": 1e-10},
    )
    return float(np.exp(res.x))


#: Elements (wall ladders and the furniture node) in contact with each zone's air, the shared
#: partition excepted: everything whose storage the model gives to the light-mass and slab nodes.
ZONE_ELEMENTS = {
    "t": ("target_furn", "t_n2", "t_hw", "t_o", "t_c", "t_f"),
    "n1": ("n1_furn", "n1_side", "n1_hw", "n1_o", "n1_fl", "n1_ce"),
}
#: The model file's light-branch time constants (``Rl = tau / Cl``), s, and the target slab's
#: resistance to the room below, K/W (held at nominal).
LIGHT_TAU = {"t": 2509.0, "n1": 2406.0}
RMF_T = 32.2e-3
#: Periods of the admittance match, s (the 1-4 h band the 60-150 min blocks excite).
MATCH_PERIODS = (3600.0, 5400.0, 7200.0, 10800.0, 14400.0)


def storage_admittance(zone: str, periods_s: tuple[float, ...] = MATCH_PERIODS) -> np.ndarray:
    """Heat into the zone's elements per K of its air (all other temperatures held), less their DC conduction, W/K.

    Nodal analysis of the true network's nodes of :data:`ZONE_ELEMENTS` at each period: the
    storage part of the zone's surface admittance, which the joint model represents by its
    dead-end branches (light mass, slab). The DC conduction through walls to held temperatures
    is carried by the model's massless resistors and the slab path, so it is taken out.
    """
    net = build_building().network
    air = AIR[zone]
    out = np.zeros(len(periods_s), dtype=complex)
    for el in ZONE_ELEMENTS[zone]:
        nodes = [el] if el.endswith("_furn") else _ladder(net, el)
        idx = {n: i for i, n in enumerate(nodes)}
        cap = np.array([next(x.capacity for x in net.nodes if x.name == n) for n in nodes])
        g = np.zeros((len(nodes), len(nodes)))
        drive = np.zeros(len(nodes))  # conductance from each node to the air
        ends = []  # (node index, conductance, other end is the air)
        r_series = 0.0
        for r in net.resistors:
            ia, ib = idx.get(r.a), idx.get(r.b)
            if ia is None and ib is None:
                continue
            c = 1.0 / r.resistance
            r_series += r.resistance
            if ia is not None and ib is not None:
                g[ia, ia] += c
                g[ib, ib] += c
                g[ia, ib] -= c
                g[ib, ia] -= c
                continue
            i, other = (ia, r.b) if ia is not None else (ib, r.a)
            g[i, i] += c
            if other == air:
                drive[i] += c
            ends.append((i, c, other == air))
        through = not all(to_air for _, _, to_air in ends)
        for k, p in enumerate(periods_s):
            w = 2 * np.pi / p
            t = np.linalg.solve(g + np.diag(1j * w * cap), drive.astype(complex))
            flow = sum(c * (1.0 - t[i]) for i, c, to_air in ends if to_air)
            out[k] += flow - (1.0 / r_series if through else 0.0)
    return out


def model_storage_admittance(
    zone: str, cl: float, rm: float, cm: float, periods_s: tuple[float, ...]
) -> np.ndarray:
    """The joint model's counterpart of :func:`storage_admittance`: light branch plus slab, W/K.

    The light branch's resistance is tied to ``cl`` by the model file's time constant; the
    target's slab continues to the room below through ``Rmf_t`` (its nominal value), whose DC
    conduction is taken out like the truth's.
    """
    tau, rmf = LIGHT_TAU[zone], (RMF_T if zone == "t" else None)
    w = 2 * np.pi / np.asarray(periods_s, dtype=float)
    light = 1.0 / (tau / cl + 1.0 / (1j * w * cl))
    if rmf is None:
        return light + 1.0 / (rm + 1.0 / (1j * w * cm))
    return light + 1.0 / (rm + 1.0 / (1j * w * cm + 1.0 / rmf)) - 1.0 / (rm + rmf)


@cache
def hour_scale_masses(zone: str) -> dict[str, float]:
    """``Cl``, ``Rm``, ``Cm`` of ``zone`` whose storage admittance best matches the truth over 1-4 h.

    Least squares of the complex relative error at :data:`MATCH_PERIODS`, from the construction
    values. Returns the values and ``max_error``, the largest relative error left.
    """
    from scipy.optimize import least_squares

    truth = storage_admittance(zone)
    t = true_values()
    x0 = np.log([t[f"Cl_{zone}"], t[f"Rm_{zone}"], t[f"Cm_{zone}"]])

    def resid(x: np.ndarray) -> np.ndarray:
        e = model_storage_admittance(zone, *np.exp(x), MATCH_PERIODS) / truth - 1.0
        return np.concatenate([e.real, e.imag])

    sol = least_squares(resid, x0, xtol=1e-12, ftol=1e-12)
    cl, rm, cm = np.exp(sol.x)
    err = model_storage_admittance(zone, cl, rm, cm, MATCH_PERIODS) / truth - 1.0
    return {"Cl": float(cl), "Rm": float(rm), "Cm": float(cm), "max_error": float(np.abs(err).max())}
