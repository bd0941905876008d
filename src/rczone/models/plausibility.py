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
and a ``UA`` or time constant more than ``factor`` (10) times from the construction guess, the
model's values before the fit. They inform; they do not change a fit's verdict.

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

#: A UA or time constant this many times from the construction guess (either way) is warned about.
FACTOR = 10.0


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
    """

    ua: float
    time_constants: tuple[float, ...]
    solar_aperture: float | None
    guess_ua: float = math.nan
    guess_time_constants: tuple[float, ...] = ()
    warnings: tuple[str, ...] = ()

    def line(self) -> str:
        """The one line ``rczone fit`` prints (``UA 250 W/K; time constants 41 h, 2.1 h; ...``)."""
        parts = [f"UA {self.ua:.4g} W/K" if math.isfinite(self.ua) else "UA n/a"]
        if math.isfinite(self.guess_ua):
            parts[0] += f" (guess {self.guess_ua:.3g})"
        parts.append("time constants " + ", ".join(_duration(t) for t in self.time_constants))
        if self.solar_aperture is not None:
            parts.append(f"solar aperture {self.solar_aperture:.3g} m2")
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


def plausibility(
    fitted: ZoneModel,
    guess: ZoneModel | None = None,
    *,
    flow: float | Sequence[float] | None = None,
    factor: float = FACTOR,
) -> Plausibility:
    """The plausibility line of ``fitted``, against the construction ``guess`` (see the module notes).

    Parameters
    ----------
    fitted : ZoneModel
        The fitted model.
    guess : ZoneModel, optional
        The model before the fit (same network): its values are the construction guess.
    flow : float or sequence of float, optional
        Operating supply-air flow(s), kg/s, e.g. the mean flow of the data (required when the
        model has supply air).
    factor : float
        A UA or time constant more than ``factor`` times from the guess is warned about.

    Returns
    -------
    Plausibility
    """
    ua, tau = heat_loss_coefficient(fitted, flow), time_constants(fitted, flow)
    warnings = [w for w in (_envelope_warning(fitted),) if w]
    g_ua, g_tau = math.nan, ()
    if guess is not None:
        g_ua, g_tau = heat_loss_coefficient(guess, flow), time_constants(guess, flow)
        if _far(ua, g_ua, factor):
            warnings.append(f"UA {ua:.3g} W/K is {ua / g_ua:.2g} times the construction guess {g_ua:.3g} W/K")
        for k, (t, g) in enumerate(zip(tau, g_tau)):
            if _far(t, g, factor):
                warnings.append(
                    f"time constant {k + 1} ({_duration(t)}) is {t / g:.2g} times the construction guess ({_duration(g)})"
                )
    return Plausibility(ua, tau, solar_aperture(fitted), g_ua, tuple(g_tau), tuple(warnings))


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
