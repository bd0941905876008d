"""Latent-force disturbances: unmeasured heat inputs with a Gaussian-process prior.

An unmeasured heat flow ``d(t)`` (W), e.g. the internal and solar gains a data set lacks, is
modelled as a stationary Gaussian process whose covariance function is a Matérn or a
quasi-periodic kernel. Such a process is the output of a small linear SDE (Hartikainen & Särkkä
2010; Särkkä & Solin 2019, ch. 12.3), so appending its states to the RC network's states keeps
the model linear and Gaussian: the Kalman filter estimates the disturbance together with the
temperatures, and the GP's hyper-parameters are estimated like any other parameter. This is the
latent-force model of Alvarez, Luengo & Lawrence (2009) in the state-space form used by pySIP.

The SDE of one disturbance (``s`` its latent state, ``beta`` a standard Wiener process)::

    ds = F s dt + diag(sqrt(qc)) dbeta,     d(t) = sigma * s_1(t)

is written for a process of unit variance: its stationary covariance ``P_inf`` has a unit first
diagonal entry, and the magnitude ``sigma`` (W, the standard deviation of the heat flow) scales
the state where it enters the network. The states are scaled so that ``P_inf`` is the identity
(Matérn-3/2, quasi-periodic) or close to it (Matérn-5/2), which makes the filter's default
initial spread of one unit the stationary one.

==============  ======  =======================================================  ==========================
kind            states  covariance ``k(tau) / sigma^2``                          hyper-parameters
==============  ======  =======================================================  ==========================
``matern32``    2       ``(1 + lam tau) exp(-lam tau)``, ``lam = sqrt(3)/ell``   sigma (W), ell (s)
``matern52``    3       ``(1 + lam tau + (lam tau)^2/3) exp(-lam tau)``,         sigma (W), ell (s)
                        ``lam = sqrt(5)/ell``
``periodic``    2       ``exp(-tau/ell) cos(2 pi tau / period)``                 sigma, ell, period (s)
==============  ======  =======================================================  ==========================

State-space forms (``lam`` as in the table)::

    matern32:  F = lam [[0, 1], [-1, -2]],                       qc = (0, 4 lam)
    matern52:  F = lam [[0, 1, 0], [0, 0, 1], [-1, -3, -3]],     qc = (0, 0, 16 lam / 3)
    periodic:  F = [[-1/ell, -w], [w, -1/ell]], w = 2 pi/period, qc = (2/ell, 2/ell)

The Matérn forms are the companion forms of Hartikainen & Särkkä (2010, eq. 12-14) with the
``k``-th state divided by ``lam**k``; the quasi-periodic one is a damped stochastic resonator
(Särkkä & Solin 2019, ex. 12.12 with an exponential envelope). Their diffusion is diagonal, so it is
a per-state intensity like the network's process noise, and it follows from the hyper-parameters,
never from the ``sigma_w_`` parameters of :mod:`rczone.network.stochastic`.

How a disturbance enters the network: it is delivered to one or several nodes with dimensionless
gains, as a :class:`~rczone.network.network.HeatInput` is (``{"Ti": 1.0}`` puts all of it into
``Ti``; gains may be parameter names). The magnitude carries the unit W, so ``sigma = 0`` removes
the disturbance exactly: a model with a disturbance nests the model without one.

References
----------
.. [1] J. Hartikainen, S. Särkkä, "Kalman filtering and smoothing solutions to temporal Gaussian
   process regression models", IEEE Int. Workshop on Machine Learning for Signal Processing, 2010.
.. [2] S. Särkkä, A. Solin, *Applied Stochastic Differential Equations*, Cambridge University Press,
   2019, ch. 12.3.
.. [3] M. A. Alvarez, D. Luengo, N. D. Lawrence, "Latent force models", Proc. AISTATS 2009,
   JMLR W&CP 5, 9-16.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rczone.errors import NetworkError, ParameterError, did_you_mean

Value = str | float

#: kind -> number of latent states.
KINDS = {"matern32": 2, "matern52": 3, "periodic": 2}

#: Suffixes of the latent state names after the disturbance's name (``Qx``, ``Qx_d1``, ...).
STATE_SUFFIXES = {"matern32": ("", "_d1"), "matern52": ("", "_d1", "_d2"), "periodic": ("", "_q")}


class LatentSDE(NamedTuple):
    """The SDE of a unit-variance disturbance: ``ds = F s dt + diag(sqrt(qc)) dbeta``.

    Attributes
    ----------
    F : ndarray, shape (k, k), 1/s
        Drift matrix.
    qc : ndarray, shape (k,), 1/s
        Diagonal diffusion intensity (variance per second of each state).
    """

    F: np.ndarray
    qc: np.ndarray


def _check_kind(kind: str) -> None:
    if kind not in KINDS:
        raise NetworkError(
            f"disturbance kind {kind!r} is not one of {', '.join(KINDS)}; " + did_you_mean(kind, KINDS)
        )


def latent_sde(kind: str, length_scale: float | complex, period: float | complex | None = None) -> LatentSDE:
    """The drift and diffusion of a unit-variance disturbance (see the module table).

    Pure and analytic in its arguments, so the network's complex-step derivatives pass through it.

    Parameters
    ----------
    kind : {"matern32", "matern52", "periodic"}
        Covariance family.
    length_scale : float
        Length scale ``ell`` (s) of a Matérn kernel, decay time of the periodic one; > 0.
    period : float, optional
        Period (s) of the ``periodic`` kind; unused by the others.

    Returns
    -------
    LatentSDE

    References
    ----------
    .. [1] J. Hartikainen, S. Särkkä (2010), eq. 12-14 (the Matérn SDEs).
    .. [2] S. Särkkä, A. Solin (2019), ch. 12.3.
    """
    _check_kind(kind)
    dtype = complex if isinstance(length_scale, complex) or isinstance(period, complex) else float
    if kind == "matern32":
        lam = math.sqrt(3.0) / length_scale
        F = lam * np.array([[0.0, 1.0], [-1.0, -2.0]], dtype)
        return LatentSDE(F, np.array([0.0, 4.0 * lam], dtype))
    if kind == "matern52":
        lam = math.sqrt(5.0) / length_scale
        F = lam * np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -3.0, -3.0]], dtype)
        return LatentSDE(F, np.array([0.0, 0.0, 16.0 * lam / 3.0], dtype))
    if period is None:
        raise NetworkError("a periodic disturbance needs a period (s)")
    lam, w = 1.0 / length_scale, 2.0 * math.pi / period
    F = np.array([[-lam, -w], [w, -lam]], dtype)
    return LatentSDE(F, np.array([2.0 * lam, 2.0 * lam], dtype))


def covariance_function(
    kind: str, lag: np.ndarray | float, *, magnitude: float, length_scale: float, period: float | None = None
) -> np.ndarray:
    """The kernel ``k(lag)`` (W^2) of a disturbance, in closed form (the module table).

    Parameters
    ----------
    kind : {"matern32", "matern52", "periodic"}
        Covariance family.
    lag : float or ndarray
        Time lags (s).
    magnitude : float
        Standard deviation ``sigma`` of the heat flow, W.
    length_scale : float
        ``ell`` (s).
    period : float, optional
        Period (s) of the ``periodic`` kind.

    Returns
    -------
    ndarray
        ``k(lag)``, the shape of ``lag``.

    References
    ----------
    .. [1] C. E. Rasmussen, C. K. I. Williams, *Gaussian Processes for Machine Learning*, MIT Press,
       2006, eq. 4.17 (Matérn kernels with half-integer order).
    """
    _check_kind(kind)
    tau = np.abs(np.asarray(lag, dtype=float))
    s2 = magnitude**2
    if kind == "matern32":
        r = math.sqrt(3.0) * tau / length_scale
        return s2 * (1.0 + r) * np.exp(-r)
    if kind == "matern52":
        r = math.sqrt(5.0) * tau / length_scale
        return s2 * (1.0 + r + r * r / 3.0) * np.exp(-r)
    if period is None:
        raise NetworkError("a periodic disturbance needs a period (s)")
    return s2 * np.exp(-tau / length_scale) * np.cos(2.0 * math.pi * tau / period)


@dataclass(frozen=True)
class LatentForce:
    """An unmeasured heat input with a Gaussian-process prior (a latent force).

    Parameters
    ----------
    name : str
        Name of the disturbance; its latent states are named after it (``name``, ``name_d1``, ...,
        see :data:`STATE_SUFFIXES`).
    kind : {"matern32", "matern52", "periodic"}
        Covariance family (the module table).
    gains : mapping of node name to gain
        Dimensionless gain (a number or a parameter name) with which the heat flow enters each
        node; a node name alone means ``{node: 1.0}``.
    magnitude : str or float
        Standard deviation of the heat flow, W (parameter name or value); 0 removes it.
    length_scale : str or float
        ``ell``, s (parameter name or value): the Matérn length scale or the periodic decay time.
    period : str or float, optional
        Period, s, of the ``periodic`` kind (a day is 86400 s).
    """

    name: str
    kind: str
    gains: tuple[tuple[str, Value], ...]
    magnitude: Value
    length_scale: Value
    period: Value | None = None

    def __init__(
        self,
        name: str,
        kind: str,
        gains: Mapping[str, Value] | str,
        *,
        magnitude: Value,
        length_scale: Value,
        period: Value | None = None,
    ) -> None:
        if not isinstance(name, str) or not name.isidentifier():
            raise NetworkError(f"disturbance name {name!r} is not a valid identifier")
        _check_kind(kind)
        if isinstance(gains, str):
            gains = {gains: 1.0}
        elif isinstance(gains, tuple) and all(isinstance(g, tuple) and len(g) == 2 for g in gains):
            gains = dict(gains)  # the stored form (dataclasses.replace passes it back)
        if not isinstance(gains, Mapping) or not gains:
            raise NetworkError(f"disturbance {name!r}: gains must map node names to gains, got {gains!r}")
        if kind == "periodic" and period is None:
            raise NetworkError(f"disturbance {name!r}: the periodic kind needs a period (s), e.g. 86400")
        if kind != "periodic" and period is not None:
            raise NetworkError(
                f"disturbance {name!r}: a {kind} disturbance has no period (only 'periodic' has)"
            )
        for what, v in (
            *((f"gain at {k!r}", g) for k, g in gains.items()),
            ("magnitude", magnitude),
            ("length_scale", length_scale),
            ("period", period),
        ):
            if v is None and what == "period":
                continue
            if isinstance(v, bool) or not isinstance(v, (str, int, float)):
                raise NetworkError(
                    f"disturbance {name!r}: {what} must be a number or a parameter name, got {v!r}"
                )
            _check_number(name, what, v)
        set_ = object.__setattr__
        set_(self, "name", name)
        set_(self, "kind", kind)
        set_(self, "gains", tuple(gains.items()))
        set_(self, "magnitude", magnitude)
        set_(self, "length_scale", length_scale)
        set_(self, "period", period)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the latent states, the first being the unit-variance force."""
        return tuple(self.name + s for s in STATE_SUFFIXES[self.kind])

    @property
    def hyperparameters(self) -> tuple[tuple[str, Value], ...]:
        """``(role, value)`` of ``magnitude``, ``length_scale`` and (periodic) ``period``."""
        out: tuple[tuple[str, Value], ...] = (
            ("magnitude", self.magnitude),
            ("length_scale", self.length_scale),
        )
        return out + ((("period", self.period),) if self.period is not None else ())


def _check_number(name: str, what: str, v: object) -> None:
    """A hyper-parameter given as a number: finite; a magnitude >= 0, a length scale or period > 0 s.

    The same values a model file refuses when the network is built (:meth:`RCNetwork.state_space`),
    refused when the disturbance is declared.
    """
    if isinstance(v, str):
        return
    x = float(v)  # type: ignore[arg-type]
    positive = what in ("length_scale", "period")
    signed = not positive and what != "magnitude"  # a gain
    if not math.isfinite(x) or (not signed and x < 0) or (positive and x == 0):
        expected = "> 0 s" if positive else ">= 0 W" if what == "magnitude" else "finite"
        raise ParameterError(f"disturbance {name!r}: {what} must be {expected}, got {x:g}")


#: Parameter kind each hyper-parameter role must have when given by name.
ROLE_KINDS = {"magnitude": "magnitude", "length_scale": "time", "period": "time"}
