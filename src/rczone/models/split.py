"""The 3R2C lumping of a layered construction, and the wall's exact frequency response.

A surface of the paper's full-scale model (Lin et al. 2012, section II) is a 3R-2C element between the room
air and the far-side temperature::

    Ti --R1-- T1 --R2-- T2 --R3-- T_far
              |         |
              C1        C2

``R1`` is on the room side. Two rules turn a :class:`~rczone.construction.Construction`
(per m2) into ``(R1, R2, R3, C1, C2)``; both keep the DC behaviour exact
(``R1 + R2 + R3 = r_total`` and ``C1 + C2 = c_total``):

``"symmetric"``
    With ``R`` the layer resistance (no films) and ``C`` the layer capacity:
    ``R3 = film_out + R/4``, ``R2 = R/2``, ``R1 = R/4 + film_in``, ``C1 = C2 = C/2``: the
    two capacities sit at the quarter points of the layers. This is the split of the shared
    file ``reference/ashrae/derived_RC_per_m2.csv``.

``"matched"``
    The five values that best reproduce the wall's *exact* frequency response over
    ``1e-6 .. 1e-3`` Hz (:data:`FIT_BAND_HZ`), in the spirit of Gouda, Danaher & Underwood [1]_
    (who fitted 3R2C elements to the response of a fine wall model by constrained nonlinear
    optimization). The exact response is the product of the layers' transmission matrices
    (:func:`exact_wall_response`; homogeneous layer: ``cosh``/``sinh`` of
    ``sqrt(j w rho c / k) d`` [2]_). Constraints: the totals are fixed as above; the films
    stay outside the capacities (``R1 >= film_in``, ``R3 >= film_out``), i.e. the layer
    resistance ``R`` is shared out as ``R1 = film_in + s1 R``, ``R2 = s2 R``,
    ``R3 = film_out + s3 R`` with ``s1 + s2 + s3 = 1``, and ``C1 = f C``, ``C2 = (1 - f) C``.
    The cost (:func:`split_residuals`) is the sum over a log-spaced grid of the squared
    complex errors of

    * the room-side admittance ``Y_room`` (heat flow into the wall per kelvin of room
      temperature, far side held), relative to its exact value at each frequency, and
    * the transfer admittance ``Y_tr`` (heat flow delivered to the room per kelvin of far-side
      temperature), relative to its DC value ``1/r_total`` (so the tiny transfer of a heavy
      wall at high frequency is matched in absolute terms, which is what the room feels).

    The far-side admittance is not fitted: the far side of every surface is a prescribed
    temperature in the paper's model, so it never affects ``Ti``. The fit runs once per
    construction (cached); the result is never worse on this cost than the symmetric split,
    which is its starting point.

References
----------
.. [1] M. M. Gouda, S. Danaher, C. P. Underwood, "Building thermal model reduction using
   nonlinear constrained optimization", Building and Environment 37 (2002) 1255-1265.
.. [2] H. S. Carslaw, J. C. Jaeger, *Conduction of Heat in Solids*, 2nd ed., Oxford 1959,
   section 1.15 (the quadrupole / transmission-matrix form of a slab).
.. [3] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented thermal models
   of zones in multi-zone buildings", Proc. 51st IEEE Conference on Decision and Control, 2012
   ("Lin et al. 2012").
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from rczone.construction.materials import Construction
from rczone.errors import ParameterError, did_you_mean

#: Band (Hz) over which the matched split reproduces the exact wall response.
FIT_BAND_HZ = (1e-6, 1e-3)
#: Number of log-spaced frequencies of the fit.
FIT_POINTS = 40
#: Names of the split rules.
SPLIT_METHODS = ("matched", "symmetric")


@dataclass(frozen=True)
class WallSplit:
    """The five values of a 3R2C element; room side first.

    Per m2 (m2 K/W and J/(m2 K)) from :func:`split_construction`, or for a whole surface
    (K/W and J/K) after :meth:`scaled`.

    Attributes
    ----------
    r1, r2, r3 : float
        Room-side, middle and far-side resistances.
    c1, c2 : float
        Room-side and far-side capacities.
    """

    r1: float
    r2: float
    r3: float
    c1: float
    c2: float

    @property
    def r_total(self) -> float:
        """``r1 + r2 + r3``."""
        return self.r1 + self.r2 + self.r3

    @property
    def c_total(self) -> float:
        """``c1 + c2``."""
        return self.c1 + self.c2

    @property
    def r_centroid(self) -> float:
        """Resistance from the room to the capacity-weighted centre of the two capacities."""
        return (self.c1 * self.r1 + self.c2 * (self.r1 + self.r2)) / self.c_total

    def scaled(self, area: float) -> WallSplit:
        """The element of a surface of ``area`` m2: resistances / area, capacities * area."""
        if not area > 0:
            raise ParameterError(f"area must be > 0 m2, got {area!r}")
        return WallSplit(self.r1 / area, self.r2 / area, self.r3 / area, self.c1 * area, self.c2 * area)

    def scaled_resistances(self, factor: float) -> WallSplit:
        """The element with every resistance multiplied by ``factor`` (> 0)."""
        return WallSplit(self.r1 * factor, self.r2 * factor, self.r3 * factor, self.c1, self.c2)


def _check_capacity(construction: Construction) -> None:
    if not construction.c_total > 0:
        raise ParameterError(
            f"construction {construction.name!r} has no heat capacity; a 3R2C element needs C > 0"
            " (model a massless element such as a window as a single resistor instead)"
        )


def symmetric_split(construction: Construction) -> WallSplit:
    """The symmetric 3R2C split (per m2): capacities at the quarter points of the layers.

    ``R1 = R/4 + film_in``, ``R2 = R/2``, ``R3 = film_out + R/4``, ``C1 = C2 = C/2``.
    """
    _check_capacity(construction)
    r, c = construction.r_layers, construction.c_total
    return WallSplit(r / 4 + construction.film_in, r / 2, construction.film_out + r / 4, c / 2, c / 2)


# ----------------------------------------------------------------------------- exact response
def _series(r: float, n: int) -> np.ndarray:
    m = np.zeros((n, 2, 2), dtype=complex)
    m[:, 0, 0] = m[:, 1, 1] = 1.0
    m[:, 0, 1] = r
    return m


def _shunt(c: float, w: np.ndarray) -> np.ndarray:
    m = np.zeros((w.size, 2, 2), dtype=complex)
    m[:, 0, 0] = m[:, 1, 1] = 1.0
    m[:, 1, 0] = 1j * w * c
    return m


def _slab(d: float, k: float, rho_c: float, w: np.ndarray) -> np.ndarray:
    g = np.sqrt(1j * w * rho_c / k) * d  # gamma * d
    kg = k * g / d
    m = np.empty((w.size, 2, 2), dtype=complex)
    m[:, 0, 0] = m[:, 1, 1] = np.cosh(g)
    m[:, 0, 1] = np.sinh(g) / kg
    m[:, 1, 0] = kg * np.sinh(g)
    return m


def _admittances(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # (T_room, q_room) = t (T_far, q_far), q positive from the room towards the far side.
    a, b, d = t[:, 0, 0], t[:, 0, 1], t[:, 1, 1]
    return d / b, 1.0 / b, a / b


def _omega(freq_hz: np.ndarray) -> np.ndarray:
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    if f.ndim != 1 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ParameterError("freq_hz must be a 1-D array of finite frequencies > 0 Hz")
    return 2 * np.pi * f


def exact_wall_response(
    construction: Construction, freq_hz: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact per-m2 admittances of a layered wall (films included) at ``freq_hz``.

    Each homogeneous layer contributes the transmission matrix
    ``[[cosh g, sinh g / (k g/d)], [(k g/d) sinh g, cosh g]]`` with ``g = sqrt(j w rho c / k) d``;
    air spaces and films contribute ``[[1, R], [0, 1]]`` [2]_.

    Parameters
    ----------
    construction : Construction
    freq_hz : ndarray, shape (K,)
        Frequencies > 0, Hz.

    Returns
    -------
    y_room, y_transfer, y_far : ndarray of complex, shape (K,)
        W/(m2 K). With the far side held at 0, ``y_room`` is the heat flow into the wall per
        kelvin of room temperature; with the room held at 0, ``y_transfer`` is the heat flow
        into the room per kelvin of far-side temperature; ``y_far`` is the far-side analogue
        of ``y_room``. At DC ``y_room = y_transfer = y_far = 1 / r_total``.

    References
    ----------
    .. [2] H. S. Carslaw, J. C. Jaeger, *Conduction of Heat in Solids*, 2nd ed., Oxford 1959.
    """
    w = _omega(freq_hz)
    t = _series(construction.film_in, w.size)
    for layer in reversed(construction.layers):  # layers are stored far side first
        if layer.fixed_r is not None or layer.c == 0.0:
            t = t @ _series(layer.r, w.size)
        else:
            t = t @ _slab(layer.thickness, layer.conductivity, layer.density * layer.specific_heat, w)  # type: ignore[arg-type]
    t = t @ _series(construction.film_out, w.size)
    return _admittances(t)


def lumped_wall_response(split: WallSplit, freq_hz: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The admittances of a 3R2C element, same meaning and order as :func:`exact_wall_response`."""
    w = _omega(freq_hz)
    n = w.size
    t = _series(split.r1, n) @ _shunt(split.c1, w) @ _series(split.r2, n) @ _shunt(split.c2, w)
    return _admittances(t @ _series(split.r3, n))


def fit_frequencies() -> np.ndarray:
    """The log-spaced frequency grid of the matched fit, Hz."""
    return np.logspace(np.log10(FIT_BAND_HZ[0]), np.log10(FIT_BAND_HZ[1]), FIT_POINTS)


def split_residuals(
    split: WallSplit,
    freq_hz: np.ndarray,
    y_room: np.ndarray,
    y_transfer: np.ndarray,
    r_total: float,
) -> np.ndarray:
    """The residual vector of the matched fit (see the module docstring).

    Returns
    -------
    ndarray, shape (4 K,)
        Real and imaginary parts of ``(Y_room - y_room) / |y_room|`` and of
        ``(Y_tr - y_transfer) * r_total``, where ``Y`` are the 3R2C element's admittances.
    """
    ly_room, ly_tr, _ = lumped_wall_response(split, freq_hz)
    e_room = (ly_room - y_room) / np.abs(y_room)
    e_tr = (ly_tr - y_transfer) * r_total
    return np.concatenate([e_room.real, e_room.imag, e_tr.real, e_tr.imag])


def _from_x(x: np.ndarray, construction: Construction) -> WallSplit:
    e = np.exp(np.array([x[0], x[1], 0.0]) - max(x[0], x[1], 0.0))
    s = e / e.sum()
    f = 1.0 / (1.0 + np.exp(-x[2]))
    r, c = construction.r_layers, construction.c_total
    return WallSplit(
        construction.film_in + s[0] * r, s[1] * r, construction.film_out + s[2] * r, f * c, (1 - f) * c
    )


@cache
def matched_split(construction: Construction) -> WallSplit:
    """The frequency-matched 3R2C split (per m2) of ``construction`` (cached per construction).

    See the module docstring for the cost and constraints. Starts from the symmetric split and
    returns it unchanged if the optimizer cannot improve on it.
    """
    sym = symmetric_split(construction)
    f = fit_frequencies()
    y_room, y_tr, _ = exact_wall_response(construction, f)
    rt = construction.r_total

    def res(x: np.ndarray) -> np.ndarray:
        return split_residuals(_from_x(x, construction), f, y_room, y_tr, rt)

    # x = (log s1 - log s3, log s2 - log s3, logit of C1/C): the symmetric split is (0, log 2, 0)
    x0 = np.array([0.0, np.log(2.0), 0.0])
    from scipy.optimize import least_squares  # imported here: scipy.optimize costs 0.2 s at start-up

    sol = least_squares(res, x0, bounds=([-12.0, -12.0, -9.0], [12.0, 12.0, 9.0]), xtol=1e-10, ftol=1e-10)
    best = _from_x(sol.x, construction)
    cost_sym = float(np.sum(res(x0) ** 2))
    return best if float(np.sum(sol.fun**2)) < cost_sym else sym


def split_construction(construction: Construction, method: str = "matched") -> WallSplit:
    """The per-m2 3R2C split of ``construction`` by ``method`` (``"matched"`` or ``"symmetric"``)."""
    if method == "matched":
        return matched_split(construction)
    if method == "symmetric":
        return symmetric_split(construction)
    raise ParameterError(
        f"unknown split method {method!r}; expected one of {', '.join(SPLIT_METHODS)}; "
        + did_you_mean(method, SPLIT_METHODS)
    )
