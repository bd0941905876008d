"""Band-matched reduction: low-order values fitted to the full model's frequency response.

The parallel aggregation (:mod:`rczone.models.aggregation`) keeps every steady-state gain of the
full-scale model exactly but lumps six surfaces whose time constants range from minutes to days
into one wall. Over the band that MPC needs (the paper's 1e-5 to 1e-3 Hz, section III) that costs
the 2nd-order model up to 3.7 F of eq.-7 error from the supply air for ``office_241``, against the
paper's ~1 F. This module gives the alternative: the low-order values that best reproduce the
full model's responses over the band, from the construction data alone (no measurement).

What is matched
    The room temperature's complex responses ``H_i(jw)`` to the supply temperature ``Ts``, the
    common-mode surroundings ``Tsd`` (the sum over the five surroundings, Lin et al. 2012, eq. (6)) and the
    outdoor temperature ``To``, at the flow(s) ``flows`` (default the paper's largest,
    0.12 kg/s), on ``n_freq`` log-spaced frequencies over ``band_hz``. Each error is weighted by
    the input's amplitude ``du_i`` (default the paper's 45 F, 10 F and 45 F, :data:`PAPER_DU_K`),
    so ``du_i |H_full,i - H_low,i|`` is in kelvin and bounds the paper's eq.-7 error
    ``du_i | |H_full,i| - |H_low,i| |`` (the phase is matched too: MPC needs it).
Cost
    The worst weighted error over inputs and frequencies (minimax), found by a least-squares
    start on all the weighted errors followed by SLSQP on the epigraph form
    ``min t s.t. du_i |e_i(w_k)| <= t``. Parameters are varied in ``ln``; the result is returned
    only if it improves on the parallel aggregation's worst error, else the parallel values.
Which parameters move
    With ``keep_dc=True`` (the default) every steady-state gain of the parallel aggregation is
    kept: ``Rwin`` and the wall's total resistance stay, and only the dynamics are matched:
    ``Cr`` and ``Cw`` and, for the 2nd-order model, the room-side share ``R1 / (R1 + R2)``. With
    ``keep_dc=False`` every parameter is free; the fitted ``Rwin`` and ``R1 + R2`` (or ``Rw``)
    then trade some steady-state accuracy for the band (which starts at 1e-5 Hz, not 0 Hz).

The full model's responses are computed here from the surface elements' transmission matrices
(:func:`rczone.models.split.lumped_wall_response`), not from the network's state space, and the
low-order responses from their closed forms; ``tests/properties/test_reduction.py`` checks both
against :func:`rczone.simulation.frequency.frequency_response` of the declared networks.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, IEEE CDC 2012, section III, eqs. (6)-(7).
.. [2] M. M. Gouda, S. Danaher, C. P. Underwood, "Building thermal model reduction using
   nonlinear constrained optimization", Building and Environment 37 (2002) 1255-1265 (low-order
   RC values fitted to a detailed model's response).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cache

import numpy as np

from rczone.construction.room import AIR_CP, ZoneGeometry, office_241
from rczone.errors import ParameterError, did_you_mean
from rczone.models.aggregation import OUTDOOR, first_order_values, reduced_values, second_order_values
from rczone.models.elements import SurfaceElement, surface_elements
from rczone.models.split import lumped_wall_response
from rczone.network import RCNetwork

#: The paper's frequency band of interest, Hz (section III-C).
PAPER_BAND_HZ = (1e-5, 1e-3)
#: The paper's flow for the frequency comparison (its largest), kg/s.
PAPER_FLOW = 0.12
#: Fahrenheit degrees per kelvin of temperature difference.
F_PER_K = 1.8
#: The paper's input amplitudes for eq. 7: 45 F (Ts), 10 F (surroundings), 45 F (To), in K.
PAPER_DU_K = {"Ts": 45.0 / F_PER_K, "Tsd": 10.0 / F_PER_K, "To": 45.0 / F_PER_K}
#: Inputs whose responses are matched, in order.
MATCHED_INPUTS = ("Ts", "Tsd", "To")
#: Free parameters of each low-order structure.
STRUCTURES = {
    "second-order": ("Cr", "Cw", "Rwin", "R1", "R2"),
    "second-order-paper": ("Cr", "Rw", "Cw", "Rwin"),
    "first-order": ("Cr", "Rwin", "Rw"),
}


@dataclass(frozen=True)
class BandFit:
    """A band-matched reduction and how well it matches.

    Attributes
    ----------
    structure : str
        ``"second-order"``, ``"second-order-paper"`` or ``"first-order"``.
    values : dict of str to float
        The structure's base parameters (SI).
    parallel : dict of str to float
        The parallel-aggregation values of the same structure (the start).
    max_error_K : dict of str to float
        Worst weighted complex error ``du_i |H_full,i - H_low,i|`` over the band and flows, K.
    parallel_max_error_K : dict of str to float
        The same for the parallel values.
    """

    structure: str
    values: dict[str, float]
    parallel: dict[str, float]
    max_error_K: dict[str, float]
    parallel_max_error_K: dict[str, float]


def full_response(
    cr: float, rwin: float, elements: Sequence[SurfaceElement], freq_hz: np.ndarray, m: float
) -> dict[str, np.ndarray]:
    """Responses of the full-scale room temperature to ``Ts``, ``Tsd`` (summed surroundings), ``To``.

    From the room's heat balance with every surface's 3R2C admittances: with
    ``D = m cp + 1/Rwin + sum_s Y_room,s + j w Cr``, ``H_Ts = m cp / D``,
    ``H_Tsd = sum_internal Y_tr,s / D`` and ``H_To = (1/Rwin + sum_external Y_tr,s) / D``.

    Returns
    -------
    dict of input name to complex ndarray, shape (K,)
    """
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    den = m * AIR_CP + 1.0 / rwin + 1j * w * cr
    num_sd = np.zeros(w.size, dtype=complex)
    num_o = np.full(w.size, 1.0 / rwin, dtype=complex)
    for el in elements:
        y_room, y_tr, _ = lumped_wall_response(el.split, freq_hz)
        den = den + y_room
        if el.far_side == OUTDOOR:
            num_o = num_o + y_tr
        else:
            num_sd = num_sd + y_tr
    return {"Ts": m * AIR_CP / den, "Tsd": num_sd / den, "To": num_o / den}


def low_order_response(
    structure: str, values: Mapping[str, float], freq_hz: np.ndarray, m: float
) -> dict[str, np.ndarray]:
    """Closed-form responses of a low-order model (Lin et al. 2012, eqs. (3)-(4)) to ``Ts``, ``Tsd``, ``To``.

    The 2R1C wall ``Ti -R1- Tw -R2- Tsd`` (``Cw`` at ``Tw``) has the room admittance
    ``1 / (R1 + 1/(j w Cw + 1/R2))`` and the transfer admittance
    ``1 / (R1 R2 (1/R1 + 1/R2 + j w Cw))``; the 1st-order wall is the resistor ``Rw``.
    """
    _check_structure(structure)
    v = _full_values(structure, values)
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    if structure == "first-order":
        y_room = y_tr = np.full(w.size, 1.0 / v["Rw"], dtype=complex)
    else:
        r1, r2, cw = v["R1"], v["R2"], v["Cw"]
        y_room = 1.0 / (r1 + 1.0 / (1j * w * cw + 1.0 / r2))
        y_tr = 1.0 / (r1 * r2 * (1.0 / r1 + 1.0 / r2 + 1j * w * cw))
    den = m * AIR_CP + 1.0 / v["Rwin"] + y_room + 1j * w * v["Cr"]
    return {"Ts": m * AIR_CP / den, "Tsd": y_tr / den, "To": (1.0 / v["Rwin"]) / den}


def _full_values(structure: str, values: Mapping[str, float]) -> dict[str, float]:
    v = {k: float(x) for k, x in values.items()}
    if structure == "second-order-paper":
        v["R1"] = v["R2"] = v["Rw"] / 2.0
    return v


def _check_structure(structure: str) -> None:
    if structure not in STRUCTURES:
        raise ParameterError(
            f"unknown low-order structure {structure!r}; expected one of {', '.join(STRUCTURES)}; "
            + did_you_mean(structure, STRUCTURES)
        )


def _parallel(structure: str, cr: float, rwin: float, elements: Sequence[SurfaceElement]) -> dict[str, float]:
    if structure == "second-order":
        return second_order_values(cr, rwin, elements)
    if structure == "second-order-paper":
        return reduced_values(cr, rwin, elements, rule="parallel")
    return first_order_values(cr, rwin, elements)


def band_matched(
    cr: float,
    rwin: float,
    elements: Sequence[SurfaceElement],
    structure: str = "second-order",
    du: Mapping[str, float] | None = None,
    band_hz: tuple[float, float] = PAPER_BAND_HZ,
    flows: Sequence[float] = (PAPER_FLOW,),
    n_freq: int = 60,
    keep_dc: bool = True,
) -> BandFit:
    """Low-order values of ``structure`` matched to the full model over ``band_hz`` (module docstring).

    Parameters
    ----------
    cr, rwin : float
        Room capacity (J/K) and window resistance (K/W) of the full model.
    elements : sequence of SurfaceElement
        The full model's surface elements (:func:`rczone.models.elements.surface_elements`).
    structure : {"second-order", "second-order-paper", "first-order"}
    du : mapping of "Ts", "Tsd", "To" to K, optional
        Input amplitudes weighting the errors; default :data:`PAPER_DU_K`.
    band_hz : (float, float)
        Lowest and highest frequency, Hz.
    flows : sequence of float
        Constant flows (kg/s) at which the responses are matched together.
    n_freq : int
        Log-spaced frequencies per flow.
    keep_dc : bool
        Keep every steady-state gain of the parallel aggregation (``Rwin`` and the wall's total
        resistance fixed; only ``Cr``, ``Cw`` and, for the 2nd-order model, the room-side share
        ``R1 / (R1 + R2)`` are matched), or match every parameter.

    Returns
    -------
    BandFit
    """
    _check_structure(structure)
    weights = dict(PAPER_DU_K if du is None else du)
    missing = [i for i in MATCHED_INPUTS if i not in weights]
    if missing:
        raise ParameterError(f"du lacks {missing}; give the amplitude (K) of each of {list(MATCHED_INPUTS)}")
    if any(not (np.isfinite(weights[i]) and weights[i] >= 0) for i in MATCHED_INPUTS):
        raise ParameterError(f"du values must be finite and >= 0 K, got {weights}")
    lo, hi = band_hz
    if not (0 < lo < hi and np.isfinite(hi)):
        raise ParameterError(f"band_hz must be (low, high) with 0 < low < high, got {band_hz!r}")
    flows_t = tuple(float(m) for m in flows)
    if not flows_t or any(not (np.isfinite(m) and m >= 0) for m in flows_t):
        raise ParameterError(f"flows must be a non-empty sequence of flows >= 0 kg/s, got {flows!r}")
    if n_freq < 2:
        raise ParameterError(f"n_freq must be >= 2, got {n_freq!r}")
    return _band_matched(
        float(cr),
        float(rwin),
        tuple(elements),
        structure,
        tuple(float(weights[i]) for i in MATCHED_INPUTS),
        (float(lo), float(hi)),
        flows_t,
        int(n_freq),
        bool(keep_dc),
    )


def _free(structure: str, keep_dc: bool) -> tuple[str, ...]:
    if not keep_dc:
        return STRUCTURES[structure]
    return {
        "second-order": ("Cr", "Cw", "alpha"),
        "second-order-paper": ("Cr", "Cw"),
        "first-order": ("Cr",),
    }[structure]


def _values_from(x: np.ndarray, free: tuple[str, ...], start: Mapping[str, float]) -> dict[str, float]:
    """Map the optimizer's variables (``ln`` values, logit of ``alpha``) to parameter values."""
    v = dict(start)
    for name, xi in zip(free, x, strict=True):
        if name == "alpha":  # room-side share of the DC wall resistance R1 + R2
            a = 1.0 / (1.0 + np.exp(-xi))
            rw = start["R1"] + start["R2"]
            v["R1"], v["R2"] = a * rw, (1.0 - a) * rw
        else:
            v[name] = float(np.exp(xi))
    return v


def _x_from(values: Mapping[str, float], free: tuple[str, ...]) -> np.ndarray:
    out = []
    for name in free:
        if name == "alpha":
            a = values["R1"] / (values["R1"] + values["R2"])
            out.append(np.log(a / (1.0 - a)))
        else:
            out.append(np.log(values[name]))
    return np.array(out)


@cache
def _band_matched(
    cr: float,
    rwin: float,
    elements: tuple[SurfaceElement, ...],
    structure: str,
    du: tuple[float, ...],
    band: tuple[float, float],
    flows: tuple[float, ...],
    n_freq: int,
    keep_dc: bool,
) -> BandFit:
    f = np.logspace(np.log10(band[0]), np.log10(band[1]), n_freq)
    names = STRUCTURES[structure]
    free = _free(structure, keep_dc)
    ref = [full_response(cr, rwin, elements, f, m) for m in flows]
    par = _parallel(structure, cr, rwin, elements)
    start = {n: float(par[n]) for n in names}

    def errors(x: np.ndarray) -> np.ndarray:
        # shape (n_flows, n_inputs, K), complex, weighted: K
        vals = _values_from(x, free, start)
        out = np.empty((len(flows), len(MATCHED_INPUTS), f.size), dtype=complex)
        for a, m in enumerate(flows):
            low = low_order_response(structure, vals, f, m)
            for b, i in enumerate(MATCHED_INPUTS):
                out[a, b] = du[b] * (low[i] - ref[a][i])
        return out

    def worst(x: np.ndarray) -> np.ndarray:
        return np.abs(errors(x)).max(axis=(0, 2))

    x0 = _x_from(start, free)
    from scipy.optimize import least_squares, minimize  # imported here: 0.2 s at start-up

    ls = least_squares(lambda x: errors(x).view(float).ravel(), x0, xtol=1e-12, ftol=1e-12)
    x1 = ls.x
    scale = max(float(worst(x1).max()), 1e-12)

    def epigraph(z: np.ndarray) -> np.ndarray:
        return z[-1] - np.abs(errors(z[:-1])).ravel() / scale

    sol = minimize(
        lambda z: z[-1],
        np.append(x1, 1.0),
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": epigraph}],
        options={"maxiter": 300, "ftol": 1e-10},
    )
    candidates = [x0, x1] + ([sol.x[:-1]] if np.all(np.isfinite(sol.x)) else [])
    best = min(candidates, key=lambda x: float(worst(x).max()))
    return BandFit(
        structure,
        {n: _values_from(best, free, start)[n] for n in names},
        start,
        dict(zip(MATCHED_INPUTS, map(float, worst(best)), strict=True)),
        dict(zip(MATCHED_INPUTS, map(float, worst(x0)), strict=True)),
    )


def band_matched_model(
    name: str, geometry: ZoneGeometry | None = None, keep_dc: bool = True, **options: str
) -> RCNetwork:
    """One of the paper's low-order models with band-matched instead of parallel construction values.

    Parameters
    ----------
    name : {"second-order", "second-order-paper", "first-order"}
    geometry : ZoneGeometry, optional
        Default :func:`~rczone.construction.office_241`.
    keep_dc : bool
        See :func:`band_matched`.
    **options
        ``split`` and ``door`` of the full model the values are matched to.

    Returns
    -------
    RCNetwork
        The declared network of :func:`rczone.models.paper.get_model` with new parameter values.
    """
    from rczone.models.paper import get_model  # paper builds its networks from this package's values

    _check_structure(name)
    g = office_241() if geometry is None else geometry
    split, door = options.get("split", "matched"), options.get("door", "fold")
    fit = band_matched(
        g.room_capacity, g.window.resistance, surface_elements(g, split, door), name, keep_dc=keep_dc
    )
    net = get_model(name, g, split=split, door=door)
    return net.replace_parameters(
        [replace(p, value=fit.values[k]) if k in fit.values else p for k, p in net.parameters.items()]
    )
