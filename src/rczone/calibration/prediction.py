"""Predictions of a fitted model on data: open loop or k steps ahead, with a band.

The path of ``rczone predict``: the unmeasured nodes' start (estimated or steady), the
parameters' and the noise's contributions to the band, and the scores against the data.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.calibration.calibration import (
    estimated_start,
)
from rczone.calibration.dataset import (
    EPOCH_SECONDS,
    ModelLike,
    as_model,
    dataset,
    time_index,
)
from rczone.errors import DataError
from rczone.estimation.methods import REGISTRY
from rczone.estimation.openloop import (
    InitialStateEstimate,
    OpenLoopError,
    open_loop_error,
    per_output_errors,
)
from rczone.models import ZoneModel
from rczone.network.stochastic import (
    INITIAL_SPREAD,
    INITIAL_STATE,
    KINDS,
    initial_spread_name,
    is_noise_name,
    kind_of,
    target_of,
)
from rczone.results import Result


def predict(
    model: ModelLike, frame: pd.DataFrame, constants: Mapping[str, float] | None = None
) -> OpenLoopError:
    """Open-loop simulation of a model on data (the measured states start at their first measurement)."""
    zm = as_model(model)
    data = dataset(zm, frame, constants)
    return open_loop_error(zm.network, dict(zm.theta), data)


@dataclass(frozen=True, eq=False, repr=False)
class Prediction(Result):
    """An open-loop or k-step-ahead prediction with a band of plus or minus two standard deviations.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time, s (as in the data: UTC epoch seconds for a loaded trend log).
    measured, predicted, sd : ndarray, shape (N, ny)
        ``sd`` is the total: ``sqrt(sd_noise^2 + sd_parameters^2)``.
    outputs : tuple of str
    band_source : str
        Where the standard deviation comes from, in words.
    sd_noise, sd_parameters : ndarray, shape (N, ny), optional
        The parts from the noise (or the fit's RMSE) and from the estimates' covariance (NaN: none).
    steps : int, optional
        Steps ahead; None for open loop.
    initial_state : InitialStateEstimate, optional
        Open loop: the unmeasured nodes' initial temperatures estimated from the data (None when
        they start at the steady state).
    index : DatetimeIndex, optional
        The samples' time stamps in the data's time zone (None when the data have no clock time).
    model_label, data_label : str
        Names of the model and the data, for titles.
    lower, upper : ndarray, shape (N, ny), optional
        A posterior predictive band (a model fitted by sampling:
        :func:`~rczone.estimation.forecast.posterior_band`), of the probability of plus or minus two
        standard deviations; None: the band is ``predicted -+ 2 sd``.
    """

    t: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    sd: np.ndarray
    outputs: tuple[str, ...]
    band_source: str
    sd_noise: np.ndarray | None = None
    sd_parameters: np.ndarray | None = None
    steps: int | None = None
    initial_state: InitialStateEstimate | None = None
    index: pd.DatetimeIndex | None = None
    model_label: str = "model"
    data_label: str = "data"
    lower: np.ndarray | None = None
    upper: np.ndarray | None = None

    @property
    def band(self) -> tuple[np.ndarray, np.ndarray]:
        """The band's lower and upper ends, shape (N, ny) each."""
        if self.lower is not None and self.upper is not None:
            return self.lower, self.upper
        return self.predicted - 2 * self.sd, self.predicted + 2 * self.sd

    @property
    def horizon(self) -> str:
        """``"open loop"`` or ``"k steps ahead"``, in words."""
        return "open loop" if self.steps is None else f"{self.steps} step{'s' * (self.steps != 1)} ahead"

    @property
    def error(self) -> np.ndarray:
        return self.measured - self.predicted

    @property
    def rmse_K(self) -> np.ndarray:
        """Per output, K (NaN where nothing is measured)."""
        return per_output_errors(self.error)[0]

    @property
    def max_abs_K(self) -> np.ndarray:
        """Per output, K (NaN where nothing is measured)."""
        return per_output_errors(self.error)[1]

    @property
    def coverage(self) -> np.ndarray:
        """Fraction of measured samples inside the band, per output (NaN without a band)."""
        lo, hi = self.band
        ok = np.isfinite(self.measured) & np.isfinite(lo) & np.isfinite(hi)
        inside = (self.measured >= lo) & (self.measured <= hi) & ok
        return np.where(ok.sum(axis=0) > 0, inside.sum(axis=0) / np.maximum(ok.sum(axis=0), 1), np.nan)

    def _columns(self) -> dict[str, np.ndarray]:
        cols: dict[str, np.ndarray] = {}
        lo, hi = self.band
        for j, o in enumerate(self.outputs):
            cols[f"{o}_measured"] = self.measured[:, j]
            cols[f"{o}_predicted"] = self.predicted[:, j]
            cols[f"{o}_lower"] = lo[:, j]
            cols[f"{o}_upper"] = hi[:, j]
            if self.sd_noise is not None:
                cols[f"{o}_sd_noise"] = self.sd_noise[:, j]
            if self.sd_parameters is not None:
                cols[f"{o}_sd_parameters"] = self.sd_parameters[:, j]
        return cols

    def to_frame(self) -> pd.DataFrame:
        """Per output measured, predicted, lower and upper (2 sigma), indexed by the data's time stamps.

        Without clock time (seconds from the start), a ``time`` column in seconds instead.
        """
        if self.index is not None:
            return pd.DataFrame(self._columns(), index=self.index)
        return pd.DataFrame({"time": self.t, **self._columns()})

    def series_frame(self) -> pd.DataFrame:
        """The layout of the series file: ``time`` (s), ``timestamp_utc`` for epoch times, then the columns."""
        cols: dict[str, np.ndarray] = {"time": self.t}
        if self.t.size and self.t[0] > EPOCH_SECONDS:  # epoch seconds: also a readable UTC time stamp
            cols["timestamp_utc"] = pd.to_datetime(self.t, unit="s", utc=True).strftime("%Y-%m-%dT%H:%M:%SZ")
        return pd.DataFrame({**cols, **self._columns()})

    def _repr_line(self) -> str:
        rmse = ", ".join(f"{o} RMSE {v:.3f} K" for o, v in zip(self.outputs, self.rmse_K))
        return f"{self.model_label} on {self.data_label}, {self.horizon}, {len(self.t)} samples, {rmse}"

    def summary_lines(self) -> list:
        """What ``rczone predict`` prints (before the files it writes)."""
        from rczone.results.fit_text import esc

        lines = []
        start = self.initial_state
        if start is not None and start.sd:
            lines.append(
                "initial temperatures of the unmeasured nodes, estimated from the data (steady state for the"
                " first sample in brackets): "
                + ", ".join(
                    f"{esc(target_of(k))} {start.values[k]:.2f} ({start.steady[k]:.2f}) ± {sd:.2f} K"
                    for k, sd in start.sd.items()
                )
            )
        for j, o in enumerate(self.outputs):
            lines.append(
                f"{esc(self.data_label)}: {esc(o)} {self.horizon} RMSE {self.rmse_K[j]:.3f} K, max error"
                f" {self.max_abs_K[j]:.3f} K; {self.coverage[j]:.0%} of the measurements inside the 2-sigma band"
                f" ({esc(self.band_source)})"
            )
        return lines

    def to_dict(self) -> dict:
        """What ``rczone predict --json`` writes."""
        start = self.initial_state
        one = len(self.outputs) == 1
        return {
            "model": self.model_label,
            "data": self.data_label,
            "rmse_K": float(self.rmse_K[0]) if one else dict(zip(self.outputs, map(float, self.rmse_K))),
            "max_error_K": float(self.max_abs_K[0])
            if one
            else dict(zip(self.outputs, map(float, self.max_abs_K))),
            "band": self.band_source,
            "horizon": self.horizon,
            "steps": self.steps,
            "initial_state": {
                target_of(k): {
                    "estimate_degC": v,
                    "steady_degC": start.steady[k],
                    "sd_K": start.sd[k],
                }
                for k, v in start.values.items()
                if k in start.sd
            }
            if start is not None
            else None,
            "coverage_2sigma": dict(zip(self.outputs, map(float, self.coverage))),
            "mean_sd_K": {
                part: {o: float(np.nanmean(a[:, j])) for j, o in enumerate(self.outputs)}
                for part, a in (("noise", self.sd_noise), ("estimates", self.sd_parameters))
                if a is not None and np.isfinite(a).any()
            },
        }

    def write(self, path: str | os.PathLike) -> None:
        """Write :meth:`series_frame` as ``.csv`` or ``.parquet`` (atomically)."""
        import io

        from rczone.files.atomic import write_bytes_atomic, write_text_atomic

        p = os.fspath(path)
        low = p.lower()
        if low.endswith(".csv"):
            write_text_atomic(p, self.series_frame().to_csv(index=False))
        elif low.endswith((".parquet", ".pq")):
            buf = io.BytesIO()
            self.series_frame().to_parquet(buf, index=False)
            write_bytes_atomic(p, buf.getvalue())
        else:
            raise DataError(f"the series file must end in .csv or .parquet, got {p!r}")


def prediction(
    model: ModelLike,
    frame: pd.DataFrame,
    constants: Mapping[str, float] | None = None,
    steps: int | None = None,
    parameters: bool = True,
    initial_state: str = "estimated",
    label: str = "data",
) -> Prediction:
    """Open-loop (or ``steps``-ahead) prediction of ``model`` on data with a two-sigma band.

    The band has two parts (:mod:`rczone.estimation.forecast`):

    * the noise: from the model's noise levels when it has them (a likelihood fit: process noise
      accumulated along the prediction plus measurement noise), else, open loop, from the
      open-loop RMSE of the least-squares fit that produced the model (constant), else none;
    * the estimates: their covariance saved with a fitted model (``provenance["covariance"]``),
      carried to the prediction by the delta method (``parameters=False`` leaves it out).

    Parameters
    ----------
    steps : int, optional
        Predict ``y[j]`` from the measurements up to ``j - steps`` (Kalman filter; needs the
        model's noise levels). Default: open loop from the first measurement.
    initial_state : {"estimated", "steady"}
        Open loop: where the unmeasured nodes start. ``"estimated"`` (default): their initial
        temperatures estimated from these data around the conditional steady state
        (:func:`~rczone.estimation.openloop.estimate_initial_state`, prior standard deviation
        the model's ``sigma_x0`` or 1 K), and the band starts from the estimate's uncertainty;
        ``"steady"``: at the steady state for the first sample's inputs, which shows a slow node's
        unknown start as a bias lasting its time constant.
    label : str
        The data's name, for titles.
    """
    from rczone.estimation.forecast import noise_band, parameter_sd

    zm = as_model(model)
    data = dataset(zm, frame, constants)
    net = zm.network
    values = {**zm.theta, **noise_values(zm)}
    has_noise = any(is_noise_name(k) for k in zm.noise)
    if steps is not None and not has_noise:
        raise DataError(
            f"a {steps}-step prediction needs the model's noise levels; fit the model by ML"
            " (rczone fit --method ml --save-model ...) or predict open loop"
        )
    if initial_state not in INITIAL_STATES:
        raise DataError(f"initial_state must be one of {', '.join(INITIAL_STATES)}, got {initial_state!r}")
    start = None
    if steps is None and initial_state == "estimated":
        start = estimated_start(zm, values, data, has_noise)
        values.update(start.values)
        if has_noise:
            values.update({initial_spread_name(target_of(k)): v for k, v in start.sd.items()})
    sources = []
    if has_noise:
        y_hat, sd = noise_band(net, values, data, steps)
        sources.append("the model's noise levels")
    else:
        y_hat = open_loop_error(net, {**zm.theta, **values}, data).y_hat
        fitted_by = REGISTRY.get(str(zm.provenance.get("method")))
        rmse = zm.provenance.get("rmse_K") if fitted_by is not None and not fitted_by.stochastic else None
        if isinstance(rmse, (int, float)) and np.isfinite(rmse):
            sd = np.full_like(y_hat, float(rmse))
            sources.append("the open-loop RMSE of the least-squares fit")
        else:
            sd = np.full_like(y_hat, np.nan)
    if not np.all(np.isfinite(y_hat[steps or 0 :])):
        raise DataError("the model's prediction is not finite; its values are not usable on these data")
    sd_par = lower = upper = None
    kept = saved_draws(zm) if parameters else None
    cov = saved_covariance(zm) if parameters and kept is None else None
    if kept is not None:
        from rczone.estimation.forecast import posterior_band

        def band(v: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
            if has_noise:
                return noise_band(net, v, data, steps)
            return open_loop_error(net, v, data).y_hat, sd

        lower, upper, sd_par = posterior_band(band, values, *kept, np.random.default_rng(0))
        sources.append(f"{kept[1].shape[0]} posterior draws")
    if cov is not None:
        names, matrix = cov
        if has_noise:

            def predictor(v: Mapping[str, float]) -> np.ndarray:
                return noise_band(net, v, data, steps)[0]
        else:

            def predictor(v: Mapping[str, float]) -> np.ndarray:
                return open_loop_error(net, v, data).y_hat

        sd_par = parameter_sd(predictor, values, names, matrix)
        sources.append("the estimates' covariance")
    total = sd if sd_par is None else np.sqrt(np.where(np.isfinite(sd), sd**2, 0.0) + sd_par**2)
    source = (
        " and ".join(sources) if sources else "none: the model has no noise levels (fit it by ML for a band)"
    )
    return Prediction(
        data.t,
        data.y,
        y_hat,
        total,
        net.outputs,
        source,
        sd,
        sd_par,
        steps,
        start,
        index=time_index(frame, data.t),
        model_label=zm.label,
        data_label=label,
        lower=lower,
        upper=upper,
    )


#: Where an open-loop prediction starts its unmeasured nodes (:func:`prediction`).
INITIAL_STATES = ("estimated", "steady")


def noise_values(zm: ZoneModel) -> dict[str, float]:
    """The model's noise levels completed with the defaults for those it has none of (empty without any)."""
    if not any(is_noise_name(k) for k in zm.noise):
        return {}
    from rczone.estimation.parameters import noise_parameter_names

    values = dict(zm.noise)
    for n in noise_parameter_names(zm.network):
        kind = kind_of(n)
        if n in values or kind == INITIAL_STATE:
            continue
        values[n] = KINDS[INITIAL_SPREAD].default if kind == INITIAL_SPREAD else 0.0
    return values


def saved_draws(zm: ZoneModel) -> tuple[list[str], np.ndarray] | None:
    """The posterior draws a sampled fit saved with the model, restricted to what moves a prediction.

    As :func:`saved_covariance`: only base parameters and noise levels are kept. None when the
    model has none. A malformed entry (a model file is untrusted) is an error.
    """
    kept = zm.provenance.get("posterior_draws")
    if kept is None:
        return None
    try:
        names = [str(n) for n in kept["names"]]
        matrix = np.array(kept["values"], dtype=float)
        if matrix.ndim != 2 or matrix.shape[1] != len(names) or matrix.shape[0] < 2:
            raise ValueError
        if not np.isfinite(matrix).all():
            raise ValueError
    except (KeyError, TypeError, ValueError):
        raise DataError(
            f"model {zm.label!r}: its saved posterior draws are malformed (expected names and a table of"
            " at least two finite rows, one column per name)"
        ) from None
    known = {*zm.theta, *noise_values(zm)}
    keep = [i for i, n in enumerate(names) if n in known]
    if not keep:
        return None
    return [names[i] for i in keep], matrix[:, keep]


def saved_covariance(zm: ZoneModel) -> tuple[list[str], np.ndarray] | None:
    """The estimates' covariance a fit saved with the model, restricted to what moves a prediction.

    Only the model's base parameters and noise levels are kept (the initial state of the
    calibration data says nothing about other data). None when the model has none, or none of
    its entries is usable. A malformed entry (a model file is untrusted) is an error.
    """
    cov = zm.provenance.get("covariance")
    if cov is None:
        return None
    try:
        names = [str(n) for n in cov["names"]]
        matrix = np.array(
            [[np.nan if v is None else float(v) for v in row] for row in cov["matrix"]], dtype=float
        )
        if matrix.shape != (len(names), len(names)):
            raise ValueError
    except (KeyError, TypeError, ValueError):
        raise DataError(
            f"model {zm.label!r}: its saved covariance is malformed (expected names and a square matrix)"
        ) from None
    known = {*zm.theta, *noise_values(zm)}
    keep = [i for i, n in enumerate(names) if n in known and np.isfinite(matrix[i, i])]
    if not keep:
        return None
    return [names[i] for i in keep], matrix[np.ix_(keep, keep)]
