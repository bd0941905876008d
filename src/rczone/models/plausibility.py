"""Is a fitted model physically plausible? Its heat-loss coefficient, time constants and solar aperture.

A fit can reach the data's best likelihood with values no building has (Lin et al. 2012 show
closed-loop data doing exactly that). Three numbers a building engineer can judge at a glance
summarize the fitted network:

* the **overall heat-loss coefficient** ``UA`` (W/K): the heat that must enter the measured
  node(s) to hold them 1 K above every boundary temperature at steady state, the other nodes
  settling where they will. With the conductance matrix ``L = -diag(C) A`` of the states (``A`` at
  the operating supply-air flow, so ventilation ``m cp`` counts) and ``S`` selecting the measured
  states, ``UA = 1' (S L^-1 S')^-1 1``; for one measured node ``UA = 1 / (L^-1)_kk`` (``1 / Ria``
  for ``Ti``, ``1 / (Rie + Rea)`` for ``TiTe``: the series and parallel rules);
* the **time constants** ``tau_i = -1 / Re(lambda_i)`` of the eigenvalues ``lambda_i`` of ``A``
  at the operating flow, slowest first (Ljung 1999, sec. 4.1, on the modes of a linear system);
* the **solar aperture** (m2): the sum of the gains of the irradiance inputs (W/m2) over the
  nodes they heat (the paper's ``Aw``, plus ``Ae`` and ``As`` in Bacher & Madsen's family).

Warnings name what is implausible: a measured room node holding more heat than the envelope it
sits in (its capacity above the summed capacity of the unmeasured nodes joined to a boundary),
and a ``UA`` or time constant judged against a *reference* that the message names:

* with a **floor area** (``rczone fit --floor-area``): the documented ranges per m2 of floor,
  :data:`UA_PER_AREA` (0.15 to 10 W/(m2 K): from half a passive house's 0.3 to twice an
  uninsulated house's 5, heat loss by transmission and ventilation, ISO 13790 sec. 8) and
  :data:`CAPACITY_PER_AREA` (40 to 740 kJ/(m2 K): half the "very light" 80 to twice the "very
  heavy" 370 of ISO 13790 Table 12) for the summed capacity; the slowest time constant must lie
  between their ratios (:func:`reference_ranges`);
* else the values **the user declared** (a model file, a saved model, or a built-in model whose
  values were changed): ``UA`` or a time constant more than ``factor`` (10) times from them;
* else (a built-in model at rczone's generic starting values, which describe no building) no UA or
  time constant is judged, and the line says how to give a reference.

They inform; they do not change a fit's verdict.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal
   models of zones in multi-zone buildings", IEEE CDC 2012 (physically wrong estimates that fit).
.. [2] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall, 1999.
.. [3] ISO 13790:2008, section 8 (the heat transfer coefficient by transmission and ventilation).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rczone.models.zone import ZoneModel

#: A UA or time constant this many times from the declared values (either way) is warned about.
FACTOR = 10.0
#: Plausible overall heat-loss coefficient per m2 of floor, W/(m2 K) (module notes).
UA_PER_AREA = (0.15, 10.0)
#: Plausible summed heat capacity per m2 of floor, J/(m2 K) (module notes).
CAPACITY_PER_AREA = (4.0e4, 7.4e5)


@dataclass(frozen=True)
class Plausibility:
    """The plausibility line of a fitted model (see the module notes).

    Attributes
    ----------
    ua : float
        Overall heat-loss coefficient, W/K (NaN when a measured node is massless or the network
        has no path to a boundary).
    time_constants : tuple of float
        Seconds, slowest first.
    solar_aperture : float or None
        m2; None when the model has no irradiance input.
    guess_ua : float
        The same of the construction guess (NaN without one).
    guess_time_constants : tuple of float
        The same of the construction guess (empty without one).
    warnings : tuple of str
        What is implausible, in words.
    reference : str
        What UA and the time constants were judged against, in words (module notes).
    """

    ua: float
    time_constants: tuple[float, ...]
    solar_aperture: float | None
    guess_ua: float = math.nan
    guess_time_constants: tuple[float, ...] = ()
    warnings: tuple[str, ...] = ()
    reference: str = ""

    def line(self) -> str:
        """The one line ``rczone fit`` prints (``UA 250 W/K; time constants 41 h, 2.1 h; ...``)."""
        parts = [f"UA {self.ua:.4g} W/K" if math.isfinite(self.ua) else "UA n/a"]
        if math.isfinite(self.guess_ua):
            parts[0] += f" (guess {self.guess_ua:.3g})"
        parts.append("time constants " + ", ".join(_duration(t) for t in self.time_constants))
        if self.solar_aperture is not None:
            parts.append(f"solar aperture {self.solar_aperture:.3g} m2")
        if self.reference:
            parts.append(self.reference)
        return "plausibility: " + "; ".join(parts)

    def to_dict(self) -> dict:
        """JSON-ready fields (NaN becomes None)."""
        return {
            "ua_W_per_K": _num(self.ua),
            "time_constants_s": [_num(t) for t in self.time_constants],
            "solar_aperture_m2": _num(self.solar_aperture) if self.solar_aperture is not None else None,
            "guess_ua_W_per_K": _num(self.guess_ua),
            "guess_time_constants_s": [_num(t) for t in self.guess_time_constants],
            "warnings": list(self.warnings),
            "reference": self.reference,
        }


def _num(x: float) -> float | None:
    return float(x) if x is not None and math.isfinite(x) else None


def _duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "inf"
    if seconds >= 86400 * 2:
        return f"{seconds / 86400:.3g} d"
    if seconds >= 3600:
        return f"{seconds / 3600:.3g} h"
    return f"{seconds / 60:.3g} min"


def _capacities(zm: ZoneModel) -> dict[str, float]:
    """Capacity (J/K) of every state at the model's values."""
    ss = zm.state_space()
    return dict(zip(ss.state_names, map(float, ss.capacities), strict=True))


def heat_loss_coefficient(zm: ZoneModel, flow: float | Sequence[float] | None = None) -> float:
    """Overall heat-loss coefficient ``UA`` (W/K) of the measured nodes (see the module notes).

    Parameters
    ----------
    zm : ZoneModel
        The model at its values.
    flow : float or sequence of float, optional
        Operating supply-air flow(s), kg/s (required when the model has supply air).

    Returns
    -------
    float
        NaN when a measured node is massless or the conductance matrix is singular.
    """
    net = zm.network
    a = zm.continuous(flow).A
    caps = _capacities(zm)
    states = net.state_names
    if any(o not in states for o in net.outputs):
        return math.nan
    lap = -np.diag([caps[s] for s in states]) @ a
    try:
        inv = np.linalg.inv(lap)
    except np.linalg.LinAlgError:
        return math.nan
    idx = [states.index(o) for o in net.outputs]
    sub = inv[np.ix_(idx, idx)]
    try:
        return float(np.linalg.inv(sub).sum())
    except np.linalg.LinAlgError:
        return math.nan


def time_constants(zm: ZoneModel, flow: float | Sequence[float] | None = None) -> tuple[float, ...]:
    """Time constants ``-1 / Re(lambda)`` of the state matrix at the operating flow, seconds, slowest first.

    Parameters
    ----------
    zm : ZoneModel
        The model at its values.
    flow : float or sequence of float, optional
        Operating supply-air flow(s), kg/s (required when the model has supply air).

    Returns
    -------
    tuple of float
        ``inf`` for a mode that does not decay.
    """
    lam = np.linalg.eigvals(zm.continuous(flow).A)
    tau = [(-1.0 / r if r < 0 else math.inf) for r in np.real(lam)]
    return tuple(sorted((float(t) for t in tau), reverse=True))


def solar_aperture(zm: ZoneModel) -> float | None:
    """Sum of the gains (m2) of the irradiance inputs (unit W/m2) at the model's values; None without one.

    Parameters
    ----------
    zm : ZoneModel
        The model at its values.

    Returns
    -------
    float or None
    """
    values = zm.network.values(dict(zm.theta))
    solar = [h for h in zm.network.heat_inputs if h.unit == "W/m2"]
    if not solar:
        return None
    return float(sum(values[g] if isinstance(g, str) else float(g) for h in solar for _, g in h.split))


def _envelope_warning(zm: ZoneModel) -> str | None:
    """The measured node's capacity above the summed capacity of the unmeasured nodes joined to a boundary."""
    net = zm.network
    caps = _capacities(zm)
    bounds = set(net.boundaries)
    envelope = {
        x
        for r in net.resistors
        for x, y in ((r.a, r.b), (r.b, r.a))
        if y in bounds and x in caps and x not in net.outputs
    }
    if not envelope:
        return None
    total = sum(caps[n] for n in envelope)
    for o in net.outputs:
        if o in caps and caps[o] > total:
            return (
                f"the room node {o} holds more heat ({caps[o]:.3g} J/K) than the envelope"
                f" {', '.join(sorted(envelope))} ({total:.3g} J/K): the room and envelope may have swapped roles"
            )
    return None


def _far(value: float, guess: float, factor: float) -> bool:
    return (
        math.isfinite(value)
        and math.isfinite(guess)
        and guess > 0
        and not 1 / factor <= value / guess <= factor
    )


def generic_values(zm: ZoneModel) -> bool:
    """Whether ``zm`` is a built-in model at rczone's generic starting values (they describe no building).

    Parameters
    ----------
    zm : ZoneModel
    """
    from rczone.errors import RczoneError

    source = str(zm.source or "")
    if not source or source.lower().endswith((".toml", ".json")):
        return False
    from rczone.models import load_model

    try:
        builtin = load_model(source)
    except (RczoneError, OSError, ValueError):
        return False
    return dict(builtin.theta) == dict(zm.theta)


def reference_ranges(floor_area: float) -> dict[str, tuple[float, float]]:
    """The plausible UA (W/K), summed capacity (J/K) and slowest time constant (s) of ``floor_area`` m2.

    Parameters
    ----------
    floor_area : float
        Heated floor area, m2 (positive, finite).

    Returns
    -------
    dict
        ``{"ua": (lo, hi), "capacity": (lo, hi), "time_constant": (lo, hi)}``.
    """
    from rczone.errors import ParameterError

    if not (isinstance(floor_area, (int, float)) and math.isfinite(floor_area) and floor_area > 0):
        raise ParameterError(f"the floor area must be a positive number of m2, got {floor_area!r}")
    ua = (UA_PER_AREA[0] * floor_area, UA_PER_AREA[1] * floor_area)
    cap = (CAPACITY_PER_AREA[0] * floor_area, CAPACITY_PER_AREA[1] * floor_area)
    return {"ua": ua, "capacity": cap, "time_constant": (cap[0] / ua[1], cap[1] / ua[0])}


def _against_area(fitted: ZoneModel, ua: float, tau: tuple[float, ...], floor_area: float) -> list[str]:
    ranges = reference_ranges(floor_area)
    total = sum(_capacities(fitted).values())
    where = f"the reference range for {floor_area:g} m2 of floor"
    out = []
    for what, value, (lo, hi), unit in (
        ("UA", ua, ranges["ua"], "W/K"),
        ("the summed heat capacity", total, ranges["capacity"], "J/K"),
    ):
        if math.isfinite(value) and not lo <= value <= hi:
            out.append(f"{what} {value:.3g} {unit} is outside {where}, {lo:.3g} to {hi:.3g} {unit}")
    lo, hi = ranges["time_constant"]
    if tau and math.isfinite(tau[0]) and not lo <= tau[0] <= hi:
        out.append(
            f"the slowest time constant ({_duration(tau[0])}) is outside {where}, {_duration(lo)} to {_duration(hi)}"
        )
    return out


def plausibility(
    fitted: ZoneModel,
    guess: ZoneModel | None = None,
    *,
    flow: float | Sequence[float] | None = None,
    factor: float = FACTOR,
    floor_area: float | None = None,
) -> Plausibility:
    """The plausibility line of ``fitted``, judged against the reference the module notes give.

    Parameters
    ----------
    fitted : ZoneModel
        The fitted model.
    guess : ZoneModel, optional
        The model before the fit (same network): its values are the user's declared ones unless it
        is a built-in model at its generic values (:func:`generic_values`).
    flow : float or sequence of float, optional
        Operating supply-air flow(s), kg/s, e.g. the mean flow of the data (required when the
        model has supply air).
    factor : float
        A UA or time constant more than ``factor`` times from the declared values is warned about.
    floor_area : float, optional
        Heated floor area, m2: UA, the capacity and the slowest time constant are judged against
        :func:`reference_ranges` instead.

    Returns
    -------
    Plausibility
    """
    ua, tau = heat_loss_coefficient(fitted, flow), time_constants(fitted, flow)
    warnings = [w for w in (_envelope_warning(fitted),) if w]
    g_ua, g_tau = math.nan, ()
    if guess is not None:
        g_ua, g_tau = heat_loss_coefficient(guess, flow), time_constants(guess, flow)
    if floor_area is not None:
        warnings += _against_area(fitted, ua, tau, floor_area)
        reference = f"judged against the reference ranges for {floor_area:g} m2 of floor"
    elif guess is not None and not generic_values(guess):
        declared = f"the values declared in {guess.label}"
        if _far(ua, g_ua, factor):
            warnings.append(f"UA {ua:.3g} W/K is {ua / g_ua:.2g} times {declared} ({g_ua:.3g} W/K)")
        for k, (t, g) in enumerate(zip(tau, g_tau)):
            if _far(t, g, factor):
                warnings.append(
                    f"time constant {k + 1} ({_duration(t)}) is {t / g:.2g} times {declared} ({_duration(g)})"
                )
        reference = f"judged against {declared}"
    else:
        reference = (
            "UA and time constants not judged: the model's values are rczone's generic start, no building's"
            " (give --floor-area, or a model file with your values)"
            if guess is not None
            else ""
        )
    return Plausibility(ua, tau, solar_aperture(fitted), g_ua, tuple(g_tau), tuple(warnings), reference)


def operating_flow(m: np.ndarray | None, names: Sequence[str]) -> np.ndarray | None:
    """The mean of each flow column (kg/s, missing samples skipped); None for a model without flows.

    Parameters
    ----------
    m : ndarray, shape (N, n_flows), or None
        The data's mass flows.
    names : sequence of str
        The flow names (empty: no flow).

    Returns
    -------
    ndarray or None
    """
    if not names or m is None or np.size(m) == 0:
        return None
    mean = np.nanmean(np.asarray(m, dtype=float), axis=0)
    return np.where(np.isfinite(mean), np.maximum(mean, 0.0), 0.0)
