"""Baseline predictors a grey-box model must beat: persistence and an ARX model fitted by least squares.

A held-out score means little alone: a model of a room that predicts 1 h ahead with 0.3 K RMSE is
good only if "the temperature stays as it is" (persistence) does worse, and worth its physics
only if a black-box linear model of the same inputs, fitted on the same calibration data, does
worse too. Both baselines use the same information as the model's k-step predictor: the
measurements up to the origin and the known inputs up to the target.

The ARX model (AutoRegressive with eXogenous inputs, Ljung 1999, section 4.2) of every output is

``y_t = sum_i a_i y_{t-i} + sum_j b_j u_{t-j} + c``,  ``i = 1..na``, ``j = 1..nb``,

with the lags of every output and input on the right (a multi-output ARX, one equation per
output), fitted by ordinary least squares on the calibration samples where every regressor is
known (:func:`numpy.linalg.lstsq`). Its k-step predictor substitutes its own predictions for the
outputs after the origin (Ljung 1999, section 3.2). The default order ``na = nb = 2`` is that of the
input-output difference equation of a 2-state RC model discretized with the inputs held over a
sample (Madsen 2007, section 5.9).

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   sections 3.2 (k-step predictors), 4.2 (ARX models) and 16.6 (model validation against simple models).
.. [2] H. Madsen, *Time Series Analysis*, Chapman & Hall 2007, section 5.9 (transfer function models).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from rczone.errors import DataError, ParameterError

#: Default ARX orders (output lags, input lags): a 2-state RC model's difference equation.
ARX_ORDERS = (2, 2)


class ARX(NamedTuple):
    """A fitted multi-output ARX model.

    Attributes
    ----------
    na, nb : int
        Output and input lags.
    coef : ndarray, shape (na * ny + nb * nu + 1, ny)
        Coefficients of the regressors ``[y_{t-1}, ..., y_{t-na}, u_{t-1}, ..., u_{t-nb}, 1]``
        (each lag a block of every output or input), one column per output.
    """

    na: int
    nb: int
    coef: np.ndarray

    def to_dict(self) -> dict:
        """JSON-ready: ``{"na", "nb", "coef"}``."""
        return {"na": self.na, "nb": self.nb, "coef": self.coef.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> ARX:
        """The inverse of :meth:`to_dict`; a malformed entry (a model file is untrusted) is a DataError.

        Parameters
        ----------
        d : dict
            ``{"na", "nb", "coef"}``.
        """
        try:
            na, nb = int(d["na"]), int(d["nb"])
            coef = np.array(d["coef"], dtype=float)
            if na < 1 or nb < 1 or coef.ndim != 2 or not np.isfinite(coef).all():
                raise ValueError
        except (KeyError, TypeError, ValueError):
            raise DataError(
                "the saved ARX baseline is malformed (expected na, nb and a finite coefficient matrix);"
                " fit the model again to save a new one"
            ) from None
        return cls(na, nb, coef)

    def poles(self) -> np.ndarray:
        """Poles of the autoregressive part: eigenvalues of its block companion matrix.

        With ``A_i`` the ``(ny, ny)`` coefficients of ``y_{t-i}``, the homogeneous recursion
        ``y_t = sum_i A_i y_{t-i}`` is ``z_t = F z_{t-1}`` for ``z_t = [y_t, ..., y_{t-na+1}]`` and the
        block companion matrix ``F`` (Ljung 1999, section 4.2); its eigenvalues are the poles.

        Returns
        -------
        ndarray of complex, shape (na * ny,)
        """
        ny = self.coef.shape[1]
        F = np.zeros((self.na * ny, self.na * ny))
        for i in range(self.na):
            F[:ny, i * ny : (i + 1) * ny] = self.coef[i * ny : (i + 1) * ny].T
        F[ny:, :-ny] = np.eye((self.na - 1) * ny)
        return np.linalg.eigvals(F)

    def largest_pole(self) -> float:
        """Largest modulus of the poles; at least 1 means the predictor is unstable."""
        return float(np.max(np.abs(self.poles())))

    @property
    def stable(self) -> bool:
        """Every pole strictly inside the unit circle: its open-loop and long-horizon predictions stay bounded."""
        return self.largest_pole() < 1.0


def _regressors(y: np.ndarray, u: np.ndarray, t: np.ndarray, na: int, nb: int) -> np.ndarray:
    """The regressor rows of samples ``t`` (NaN where a lag falls before the data)."""
    rows = [_lag(y, t, i) for i in range(1, na + 1)] + [_lag(u, t, j) for j in range(1, nb + 1)]
    return np.column_stack([*rows, np.ones(len(t))])


def _lag(a: np.ndarray, t: np.ndarray, i: int) -> np.ndarray:
    out = np.full((len(t), a.shape[1]), np.nan)
    ok = t - i >= 0
    out[ok] = a[t[ok] - i]
    return out


def fit_arx(y: np.ndarray, u: np.ndarray, *, na: int = ARX_ORDERS[0], nb: int = ARX_ORDERS[1]) -> ARX:
    """Fit an ARX model by least squares on the samples where every regressor and output is known.

    Parameters
    ----------
    y : ndarray, shape (N, ny)
        Outputs (NaN: not measured).
    u : ndarray, shape (N, nu)
        Inputs.
    na, nb : int
        Output and input lags, at least 1.

    Returns
    -------
    ARX
    """
    y = np.asarray(y, dtype=float)
    u = np.asarray(u, dtype=float)
    if na < 1 or nb < 1:
        raise ParameterError(f"the ARX orders must be at least 1, got na={na}, nb={nb}")
    t = np.arange(max(na, nb), y.shape[0])
    X = _regressors(y, u, t, na, nb)
    ok = np.isfinite(X).all(axis=1) & np.isfinite(y[t]).all(axis=1)
    if ok.sum() <= X.shape[1]:
        raise DataError(
            f"too few complete samples ({int(ok.sum())}) to fit the ARX baseline's {X.shape[1]} coefficients"
        )
    coef = np.linalg.lstsq(X[ok], y[t][ok], rcond=None)[0]
    return ARX(na, nb, coef)


def arx_rollout(arx: ARX, y: np.ndarray, u: np.ndarray, origins: np.ndarray, n_steps: int) -> np.ndarray:
    """ARX predictions of the ``n_steps`` samples after each origin, from the measurements up to it.

    Parameters
    ----------
    arx : ARX
    y : ndarray, shape (N, ny)
    u : ndarray, shape (N, nu)
    origins : ndarray of int, shape (M,)
        Index of the last measurement each prediction uses.
    n_steps : int
        Steps ahead.

    Returns
    -------
    ndarray, shape (M, n_steps, ny)
        ``[m, s - 1]`` predicts sample ``origins[m] + s`` (NaN beyond the data).
    """
    ny, nu = y.shape[1], u.shape[1]
    if arx.coef.shape != (arx.na * ny + arx.nb * nu + 1, ny):
        raise DataError(
            f"the ARX baseline has {arx.coef.shape[0]} coefficients per output, not the"
            f" {arx.na * ny + arx.nb * nu + 1} of {ny} outputs and {nu} inputs: it was fitted to other signals"
        )
    origins = np.asarray(origins, dtype=int)
    hist = np.stack([_lag(y, origins, i) for i in range(0, arx.na)], axis=1)  # (M, na, ny), newest first
    out = np.full((len(origins), n_steps, ny), np.nan)
    for s in range(1, n_steps + 1):
        t = origins + s
        inside = t < y.shape[0]
        tt = np.minimum(t, y.shape[0] - 1)
        ulags = np.concatenate([_lag(u, tt, j) for j in range(1, arx.nb + 1)], axis=1)
        X = np.column_stack([hist.reshape(len(origins), -1), ulags, np.ones(len(origins))])
        pred = X @ arx.coef
        pred[~inside] = np.nan
        out[:, s - 1] = pred
        hist = np.concatenate([pred[:, None, :], hist[:, :-1]], axis=1)
    return out


class Baselines(NamedTuple):
    """Predictions of the baselines for one horizon, each shape (N, ny) (NaN: no prediction)."""

    persistence: np.ndarray
    arx: np.ndarray | None


def k_step_baselines(
    y: np.ndarray, u: np.ndarray, steps: Sequence[int], arx: ARX | None = None
) -> dict[int, Baselines]:
    """Persistence ``y[j - k]`` and the ARX model's k-step prediction of every sample ``j``.

    Parameters
    ----------
    y : ndarray, shape (N, ny)
    u : ndarray, shape (N, nu)
    steps : sequence of int
        Steps ahead (positive).
    arx : ARX, optional
        Without it, only persistence.

    Returns
    -------
    dict
        Steps ahead to :class:`Baselines`.
    """
    N = y.shape[0]
    kmax = max(steps)
    origins = np.arange(N)
    roll = arx_rollout(arx, y, u, origins, kmax) if arx is not None else None
    out = {}
    for k in steps:
        per = np.full(y.shape, np.nan)
        model = None if roll is None else np.full(y.shape, np.nan)
        if k < N:
            per[k:] = y[: N - k]
            if model is not None:
                model[k:] = roll[: N - k, k - 1]
        out[k] = Baselines(per, model)
    return out


def open_loop_baselines(y: np.ndarray, u: np.ndarray, known: int, arx: ARX | None = None) -> Baselines:
    """Persistence of the last known measurement and the ARX simulation from it, for every later sample.

    Parameters
    ----------
    y : ndarray, shape (N, ny)
    u : ndarray, shape (N, nu)
    known : int
        The first ``known`` samples' measurements are used (a warm-up, or the first sample).
    arx : ARX, optional

    Returns
    -------
    Baselines
        NaN before ``known``.
    """
    N = y.shape[0]
    last = y[:known]
    held = np.full(y.shape, np.nan)
    if N > known:
        # the last measured value of each output before the prediction starts
        idx = [np.flatnonzero(np.isfinite(last[:, j])) for j in range(y.shape[1])]
        held[known:] = [last[i[-1], j] if i.size else np.nan for j, i in enumerate(idx)]
    model = None
    if arx is not None:
        model = np.full(y.shape, np.nan)
        if N > known:
            model[known:] = arx_rollout(arx, y, u, np.array([known - 1]), N - known)[0]
    return Baselines(held, model)
