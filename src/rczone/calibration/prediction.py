"""Predictions of a fitted model on data: open loop or k steps ahead, with a band.

The path of ``rczone predict``: the unmeasured nodes' start (estimated or steady), the
parameters' and the noise's contributions to the band, and the scores against the data.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pandas as pd

from rczone import validation
from rczone.calibration.calibration import (
    estimated_start,
)
from rczone.calibration.dataset import (
    EPOCH_SECONDS,
    ModelLike,
    PreparedData,
    as_model,
    ignored_channels,
    prepare,
    time_index,
)
from rczone.errors import DataError
from rczone.estimation.data import Dataset
from rczone.estimation.forecast import parameter_sd
from rczone.estimation.initial import InitialStateEstimate
from rczone.estimation.methods import REGISTRY
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
from rczone.postfit.openloop import OpenLoopError, open_loop_error, per_output_errors
from rczone.results import Result
from rczone.results.accessors import PredictionFrames
from rczone.simulation.simulate import HOLDS


def predict(
    model: ModelLike, frame: pd.DataFrame | PreparedData, constants: Mapping[str, float] | None = None
) -> OpenLoopError:
    """Open-loop simulation of a model on data (the measured states start at their first measurement).

    ``frame`` may be data prepared for the model (:func:`~rczone.calibration.dataset.prepare`).
    """
    zm = as_model(model)
    return open_loop_error(zm.network, dict(zm.theta), prepare(zm, frame, constants).dataset)


class HiddenStates(NamedTuple):
    """Every node's estimated temperature at the scored samples.

    Attributes
    ----------
    names : tuple of str
        The states (nodes).
    x, sd : ndarray, shape (N, n)
        Estimate and its standard deviation, K (NaN: none).
    method : str
        ``"smoothed"`` (Rauch-Tung-Striebel smoother) or ``"simulated"`` (open loop); the column suffix.
    """

    names: tuple[str, ...]
    x: np.ndarray
    sd: np.ndarray
    method: str


@dataclass(frozen=True, eq=False, repr=False)
class Prediction(PredictionFrames, Result):
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
    states : HiddenStates, optional
        Every node's estimated temperature (written with the series).
    start_note : str
        Open loop: where the prediction starts, in words.
    warmup_samples : int
        Samples before the first scored one that the start used (not scored).
    lower, upper : ndarray, shape (N, ny), optional
        A posterior predictive band (a model fitted by sampling:
        :func:`~rczone.estimation.forecast.posterior_band`), of the probability of plus or minus two
        standard deviations; None: the band is ``predicted -+ 2 sd``.
    ignored_channels : tuple of str
        Channels the data's column map mapped that the model does not use.

    ``summary_frame(alpha)`` and ``predicted_mean`` are statsmodels'
    (:class:`rczone.results.accessors.PredictionFrames`).
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
    states: HiddenStates | None = None
    start_note: str = ""
    warmup_samples: int = 0
    lower: np.ndarray | None = None
    upper: np.ndarray | None = None
    ignored_channels: tuple[str, ...] = ()

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
    def has_band(self) -> bool:
        """Whether the prediction has a 2-sigma band at a measured sample of every output.

        A model without noise levels, an LS fit's RMSE or saved standard errors has none
        (:attr:`band_source` says so); its :attr:`coverage` is then None, never NaN.
        """
        lo, hi = self.band
        ok = np.isfinite(self.measured) & np.isfinite(lo) & np.isfinite(hi)
        return bool(ok.any(axis=0).all())

    @property
    def coverage(self) -> np.ndarray | None:
        """Fraction of measured samples inside the band, per output; None without a band (:attr:`has_band`)."""
        if not self.has_band:
            return None
        lo, hi = self.band
        ok = np.isfinite(self.measured) & np.isfinite(lo) & np.isfinite(hi)
        inside = (self.measured >= lo) & (self.measured <= hi) & ok
        return inside.sum(axis=0) / ok.sum(axis=0)

    @property
    def no_band_note(self) -> str:
        """Why the prediction has no band, in words (empty when it has one)."""
        if self.has_band:
            return ""
        return (
            "no 2-sigma band: the model has no noise levels or standard errors (a model fitted with rczone fit"
            " --save-model has them)"
        )

    def _columns(self) -> dict[str, np.ndarray]:
        cols: dict[str, np.ndarray] = {}
        lo, hi = self.band
        band = self.has_band  # without one, no column of NaN bounds: the note says why
        parts = {
            part: a
            for part, a in (("sd_noise", self.sd_noise), ("sd_parameters", self.sd_parameters))
            if a is not None and np.isfinite(a).any()
        }
        for j, o in enumerate(self.outputs):
            cols[f"{o}_measured"] = self.measured[:, j]
            cols[f"{o}_predicted"] = self.predicted[:, j]
            if band:
                cols[f"{o}_lower"] = lo[:, j]
                cols[f"{o}_upper"] = hi[:, j]
            for part, a in parts.items():
                cols[f"{o}_{part}"] = a[:, j]
        st = self.states
        if st is not None:
            for i, name in enumerate(st.names):
                cols[f"{name}_{st.method}"] = st.x[:, i]
                if np.isfinite(st.sd[:, i]).any():
                    cols[f"{name}_{st.method}_sd"] = st.sd[:, i]
        return cols

    def to_frame(self) -> pd.DataFrame:
        """Per output measured, predicted, lower and upper (2 sigma), then every node's estimate.

        Without a band (:attr:`has_band`) there are no ``lower`` and ``upper`` columns.
        Indexed by the data's time stamps.
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
        if self.start_note:
            lines.append(f"open-loop start: {esc(self.start_note)}")
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
        cover = self.coverage
        for j, o in enumerate(self.outputs):
            band = (
                f"{cover[j]:.0%} of the measurements inside the 2-sigma band ({esc(self.band_source)})"
                if cover is not None
                else self.no_band_note
            )
            lines.append(
                f"{esc(self.data_label)}: {esc(o)} {self.horizon} RMSE {self.rmse_K[j]:.3f} K, max error"
                f" {self.max_abs_K[j]:.3f} K; {band}"
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
            "start": self.start_note or None,
            "warmup_samples": self.warmup_samples,
            "hidden_states": self.states.method if self.states is not None else None,
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
            "coverage_2sigma": None
            if (cover := self.coverage) is None
            else {o: float(c) for o, c in zip(self.outputs, cover)},
            "coverage_note": self.no_band_note or None,
            "mean_sd_K": {
                part: {o: float(np.nanmean(a[:, j])) for j, o in enumerate(self.outputs)}
                for part, a in (("noise", self.sd_noise), ("estimates", self.sd_parameters))
                if a is not None and np.isfinite(a).any()
            },
            "ignored_channels": list(self.ignored_channels),
        }

    def write(self, path: str | os.PathLike) -> None:
        """Write :meth:`series_frame` as ``.csv`` or ``.parquet`` (atomically).

        Parameters
        ----------
        path : str or path
            Ends in ``.csv`` or ``.parquet``.
        """
        write_series(self.series_frame(), path)


def write_series(frame: pd.DataFrame, path: str | os.PathLike) -> None:
    """Write a series frame as ``.csv`` or ``.parquet`` (atomically, :mod:`rczone.files.atomic`).

    Parameters
    ----------
    frame : DataFrame
        The series.
    path : str or path
        Ends in ``.csv`` or ``.parquet``; any other suffix is a DataError.
    """
    import io

    from rczone.files.atomic import write_bytes_atomic, write_text_atomic

    p = os.fspath(path)
    low = p.lower()
    if low.endswith(".csv"):
        write_text_atomic(p, frame.to_csv(index=False))
    elif low.endswith((".parquet", ".pq")):
        buf = io.BytesIO()
        frame.to_parquet(buf, index=False)
        write_bytes_atomic(p, buf.getvalue())
    else:
        raise DataError(f"the series file must end in .csv or .parquet, got {p!r}")


@dataclass(frozen=True, eq=False)
class PredictionSetup:
    """A model, its data (warm-up included) and where its predictions start: shared by every horizon.

    Attributes
    ----------
    model : ZoneModel
    data : Dataset
        Every sample the predictions may use: the warm-up (``data.t < data.t[first]``), then the
        scored samples.
    first : int
        Index of the first scored sample (0: no warm-up).
    values : dict
        Parameter values, noise levels and, open loop, the start's ``x0_*``.
    has_noise : bool
        Whether the model has noise levels (a likelihood fit): its predictions come from the Kalman filter.
    start : InitialStateEstimate or None
        The unmeasured nodes' start estimated from data (None: steady state or the filter's).
    start_note : str
        Where the open-loop prediction starts, in words.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the inputs (the fit's, recorded with the model).
    """

    model: ZoneModel
    data: Dataset
    first: int
    values: dict
    has_noise: bool
    start: InitialStateEstimate | None
    start_note: str
    hold: str = "zoh"

    @property
    def dt(self) -> float:
        """The median sample interval, s."""
        return float(np.median(np.diff(self.data.t))) if self.data.n_samples > 1 else float("nan")

    def predictor(self, horizons: Sequence[int | None]) -> Callable[[Mapping[str, float]], np.ndarray]:
        """Values to the predictions of every horizon (steps ahead; None for open loop), shape (H, N, ny)."""
        from rczone.estimation.forecast import k_step_bands, noise_band

        net, data, known = self.model.network, self.data, max(self.first, 1)
        ks = [h for h in horizons if h is not None]

        def run(v: Mapping[str, float]) -> np.ndarray:
            bands = k_step_bands(net, v, data, ks, self.hold) if ks else {}
            out = []
            for h in horizons:
                if h is not None:
                    out.append(bands[h].y_hat)
                elif self.has_noise:
                    out.append(noise_band(net, v, data, hold=self.hold, known=known)[0])
                else:
                    out.append(open_loop_error(net, v, data, self.hold).y_hat)
            return np.stack(out)

        return run

    def noise_sd(
        self, horizons: Sequence[int | None], calibrated: bool = True
    ) -> tuple[np.ndarray, list[str]]:
        """The noise part of each horizon's band, shape (H, N, ny), and where it comes from, in words.

        With noise levels: the Kalman filter's k-step (or open-loop) standard deviation, times the
        per-horizon factor calibrated on the fit's data (:mod:`rczone.calibration.bands`) when the
        model has one and ``calibrated``; without: the LS fit's open-loop RMSE, open loop only.
        """
        from rczone.calibration.bands import BandScale
        from rczone.estimation.forecast import k_step_bands, noise_band

        zm, net, data = self.model, self.model.network, self.data
        shape = (len(horizons), *data.y.shape)
        if not self.has_noise:
            fitted_by = REGISTRY.get(str(zm.provenance.get("method")))
            rmse = zm.provenance.get("rmse_K") if fitted_by is not None and not fitted_by.stochastic else None
            if isinstance(rmse, (int, float)) and np.isfinite(rmse):
                sd = np.full(shape, np.nan)
                sd[[h is None for h in horizons]] = float(rmse)
                return sd, ["the open-loop RMSE of the least-squares fit"]
            return np.full(shape, np.nan), []
        ks = [h for h in horizons if h is not None]
        bands = k_step_bands(net, self.values, data, ks, self.hold) if ks else {}
        known = max(self.first, 1)
        sd = np.stack(
            [
                bands[h].sd
                if h is not None
                else noise_band(net, self.values, data, hold=self.hold, known=known)[1]
                for h in horizons
            ]
        )
        saved = zm.provenance.get("band_scale")
        if not calibrated or saved is None:
            return sd, ["the model's noise levels"]
        scale = BandScale.from_dict(saved)
        factors = [scale.at(None if h is None else h * self.dt) for h in horizons]
        sd = sd * np.array(factors)[:, None, None]
        what = ", ".join(f"{f:.2f}" for f in factors)
        return sd, [f"the model's noise levels times {what}, calibrated on the fit's own errors"]


def prediction_setup(
    model: ModelLike,
    frame: pd.DataFrame,
    constants: Mapping[str, float] | None = None,
    *,
    start: float | None = None,
    initial_state: str = "warmup",
    hold: str | None = None,
) -> PredictionSetup:
    """The data and start of a model's predictions; the samples before ``start`` only warm the filter up.

    Parameters
    ----------
    model : ZoneModel, RCNetwork, str or path
    frame : DataFrame or PreparedData
        The data, warm-up included (or prepared for the model: :func:`~rczone.calibration.dataset.prepare`).
    constants : mapping, optional
        Inputs held constant (SI units).
    start : float, optional
        Time (s, on the data's axis) of the first scored sample; default the first sample.
    initial_state : {"warmup", "steady", "estimated"}
        Open loop: where the unmeasured nodes start (see :func:`prediction`).
    hold : {"zoh", "foh"}, optional
        Inter-sample behaviour of the inputs; default the one the model was fitted with (its
        provenance), else ``"zoh"``.
    """
    zm = as_model(model)
    hold = model_hold(zm) if hold is None else hold
    if hold not in HOLDS:
        raise DataError(f"hold must be one of {', '.join(HOLDS)}, got {hold!r}")
    if initial_state not in INITIAL_STATES:
        raise DataError(f"initial_state must be one of {', '.join(INITIAL_STATES)}, got {initial_state!r}")
    raw = frame.frame if isinstance(frame, PreparedData) else frame
    validation.measured_outputs(raw, zm.network.outputs)  # a measurement of 1e308 degC starts nothing
    data = prepare(zm, frame, constants).dataset
    first = 0 if start is None else int(np.searchsorted(data.t, start))
    if first >= data.n_samples:
        raise DataError("the warm-up covers every sample: nothing is left to predict; give a shorter warm-up")
    if initial_state != "warmup" and first:
        data, first = window(data, first), 0
    values = {**zm.theta, **noise_values(zm)}
    has_noise = any(is_noise_name(k) for k in zm.noise)
    begin = None
    if initial_state == "estimated":
        begin = estimated_start(zm, values, data, has_noise)
        note = "the unmeasured nodes start where the scored data say (fitted to them: not a held-out score)"
    elif first == 0:
        note = (
            "the first sample only: the measured nodes at their measurement, the others at the steady"
            " state for its inputs"
        )
    elif has_noise:
        note = f"the Kalman filter's estimate after {first} warm-up samples"
    else:
        y = np.array(data.y)
        y[first:] = np.nan
        masked = Dataset(data.t, data.u, data.m, y, data.input_names, data.flow_names, data.output_names)
        begin = estimated_start(zm, values, masked, has_noise)
        note = f"the unmeasured nodes' start fitted to the {first} warm-up samples"
    if begin is not None:
        values.update(begin.values)
        if has_noise:
            values.update({initial_spread_name(target_of(k)): v for k, v in begin.sd.items()})
    return PredictionSetup(zm, data, first, values, has_noise, begin, note, hold)


def model_hold(zm: ZoneModel) -> str:
    """The inter-sample behaviour a model was fitted with (``provenance["hold"]``), else ``"zoh"``.

    Parameters
    ----------
    zm : ZoneModel
    """
    hold = zm.provenance.get("hold")
    return hold if isinstance(hold, str) and hold in HOLDS else "zoh"


def window(data: Dataset, first: int) -> Dataset:
    """The samples of ``data`` from index ``first`` on.

    Parameters
    ----------
    data : Dataset
    first : int
        Index of the first sample kept.
    """
    return Dataset(
        data.t[first:],
        data.u[first:],
        data.m[first:] if data.m is not None and data.m.size else None,
        data.y[first:],
        data.input_names,
        data.flow_names,
        data.output_names,
    )


def prediction(
    model: ModelLike,
    frame: pd.DataFrame,
    constants: Mapping[str, float] | None = None,
    steps: int | None = None,
    parameters: bool = True,
    initial_state: str = "warmup",
    label: str = "data",
    *,
    start: float | None = None,
    calibrated: bool = True,
    hold: str | None = None,
) -> Prediction:
    """Open-loop (or ``steps``-ahead) prediction of ``model`` on data with a two-sigma band.

    The band has two parts (:mod:`rczone.estimation.forecast`):

    * the noise: from the model's noise levels when it has them (a likelihood fit: process noise
      accumulated along the prediction plus measurement noise), widened or narrowed per horizon by
      the factors the fit calibrated on its own data (:mod:`rczone.calibration.bands`), else, open
      loop, from the open-loop RMSE of the least-squares fit that produced the model (constant),
      else none;
    * the estimates: their covariance saved with a fitted model (``provenance["covariance"]``),
      carried to the prediction by the delta method (``parameters=False`` leaves it out).

    No prediction uses a measurement after its origin: k steps ahead, the filter's state at
    ``j - k``; open loop, the warm-up's (or the first sample's) measurements only.

    Parameters
    ----------
    model : ZoneModel, RCNetwork, str or path
    frame : DataFrame or PreparedData
        The data, warm-up included (or prepared for the model: :func:`~rczone.calibration.dataset.prepare`).
    constants : mapping, optional
        Inputs held constant (SI units).
    steps : int, optional
        Predict ``y[j]`` from the measurements up to ``j - steps`` (Kalman filter; needs the
        model's noise levels). Default: open loop.
    parameters : bool
        Include the estimates' uncertainty in the band.
    initial_state : {"warmup", "steady", "estimated"}
        Open loop: where the unmeasured nodes start. ``"warmup"`` (default): the Kalman filter's
        estimate at the end of the warm-up (the samples before ``start``), as a controller has it (a
        model without noise levels: their start fitted to the warm-up's measurements, then simulated
        through it); without a warm-up, from the first sample only: the measured nodes at their
        measurement, the others at the steady state for its inputs. ``"steady"``: that, ignoring
        any warm-up. ``"estimated"``: their start fitted to the scored data themselves
        (:func:`~rczone.estimation.initial.estimate_initial_state`): it uses the samples it then
        scores, so it is a check of the model's dynamics, not a held-out score.
    label : str
        The data's name, for titles.
    start : float, optional
        Time (s, on the data's axis) of the first scored sample; the samples before it warm the
        filter up and are not scored.
    calibrated : bool
        Apply the fit's per-horizon band factors (when the model has them).
    hold : {"zoh", "foh"}, optional
        Inter-sample behaviour of the inputs; default the one the model was fitted with.

    Returns
    -------
    Prediction
    """
    zm = as_model(model)
    if steps is not None and not any(is_noise_name(k) for k in zm.noise):
        raise DataError(
            f"a {steps}-step prediction needs the model's noise levels; fit the model by ML"
            " (rczone fit --method ml --save-model ...) or predict open loop"
        )
    with filter_failure(zm):
        setup = prediction_setup(zm, frame, constants, start=start, initial_state=initial_state, hold=hold)
        if steps is not None:
            validation.steps_ahead(steps, len(setup.data.t) - setup.first)
        raw = frame.frame if isinstance(frame, PreparedData) else frame
        return setup_prediction(
            setup, steps, parameters=parameters, calibrated=calibrated, frame=raw, label=label
        )


def setup_prediction(
    setup: PredictionSetup,
    steps: int | None,
    *,
    parameters: bool = True,
    calibrated: bool = True,
    frame: pd.DataFrame | None = None,
    label: str = "data",
) -> Prediction:
    """The prediction of one horizon from a :class:`PredictionSetup` (see :func:`prediction`).

    Parameters
    ----------
    setup : PredictionSetup
    steps : int or None
        Steps ahead; None for open loop.
    parameters : bool
        Include the estimates' uncertainty in the band.
    calibrated : bool
        Apply the fit's per-horizon band factors.
    frame : DataFrame, optional
        The data's frame, for its time stamps.
    label : str
        The data's name.
    """
    zm, data, first = setup.model, setup.data, setup.first
    y_hat = setup.predictor([steps])(setup.values)[0]
    sd, sources = setup.noise_sd([steps], calibrated)
    sd = sd[0]
    if not np.all(np.isfinite(y_hat[max(first, steps or 0) :])):
        raise DataError("the model's prediction is not finite; its values are not usable on these data")
    what = "the open-loop prediction" if steps is None else f"the {steps}-step prediction"
    validation.scored_samples(data.y[first:], y_hat[first:], zm.network.outputs, what)
    sd_par = lower = upper = None
    kept = saved_draws(zm) if parameters else None
    cov = saved_covariance(zm) if parameters and kept is None else None
    if kept is not None:
        from rczone.estimation.forecast import k_step_bands, noise_band, posterior_band

        net, known, sd_ls = zm.network, max(first, 1), sd

        def band(v: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
            if not setup.has_noise:
                return open_loop_error(net, v, data, setup.hold).y_hat, sd_ls
            if steps is None:
                return noise_band(net, v, data, hold=setup.hold, known=known)
            one = k_step_bands(net, v, data, [steps], setup.hold)[steps]
            return one.y_hat, one.sd

        lower, upper, sd_par = posterior_band(band, setup.values, *kept, np.random.default_rng(0))
        lower, upper, sd_par = lower[first:], upper[first:], sd_par[first:]
        sources.append(f"{kept[1].shape[0]} posterior draws")
    if cov is not None:
        names, matrix = cov
        predictor = setup.predictor([steps])
        sd_par = parameter_sd(lambda v: predictor(v)[0], setup.values, names, matrix)[first:]
        sources.append("the estimates' covariance")
    sd = sd[first:]
    total = sd if sd_par is None else np.sqrt(np.where(np.isfinite(sd), sd**2, 0.0) + sd_par**2)
    source = (
        " and ".join(sources) if sources else "none: the model has no noise levels (fit it by ML for a band)"
    )
    return Prediction(
        data.t[first:],
        data.y[first:],
        y_hat[first:],
        total,
        zm.network.outputs,
        source,
        sd,
        sd_par,
        steps,
        setup.start,
        index=time_index(frame, data.t[first:]) if frame is not None else None,
        model_label=zm.label,
        data_label=label,
        states=hidden_states(setup),
        start_note=setup.start_note if steps is None else "",
        warmup_samples=first,
        lower=lower,
        upper=upper,
        ignored_channels=ignored_channels(frame) if frame is not None else (),
    )


def hidden_states(setup: PredictionSetup) -> HiddenStates:
    """Every node's estimated temperature over the scored samples, with its standard deviation.

    A model with noise levels: the Rauch-Tung-Striebel smoother's estimates ``x[j | N]`` (from
    every measurement of the record, before and after the sample:
    :func:`rczone.estimation.smoother.smooth_states`), the best estimate to compare with an
    embedded sensor; without: the open-loop simulation from the prediction's start (no standard
    deviation). The scores never use them.

    Parameters
    ----------
    setup : PredictionSetup
    """
    from rczone.estimation.costs import simulate_output
    from rczone.estimation.smoother import smooth_states

    net, first = setup.model.network, setup.first
    if setup.has_noise:
        est = smooth_states(net, setup.values, setup.data, hold=setup.hold)
        sd = np.sqrt(np.maximum(np.einsum("kii->ki", est.P), 0.0))
        return HiddenStates(net.state_names, est.x[first:], sd[first:], "smoothed")
    x, _ = simulate_output(net, setup.values, setup.data, setup.hold)
    return HiddenStates(net.state_names, x[first:], np.full_like(x[first:], np.nan), "simulated")


#: Where an open-loop prediction starts its unmeasured nodes (:func:`prediction`).
INITIAL_STATES = ("warmup", "steady", "estimated")


@contextlib.contextmanager
def filter_failure(zm: ZoneModel) -> Iterator[None]:
    """Turn the Kalman filter's refusal of the model's noise levels into one line naming them.

    A saved model whose noise levels leave an innovation variance that is not positive (every
    level zero) cannot weigh a measurement (Durbin & Koopman 2012, sec. 4.3: the gain needs
    ``F_t > 0``); the prediction is refused, not a traceback.
    """
    try:
        yield
    except np.linalg.LinAlgError as exc:
        levels = ", ".join(f"{k} = {v:g}" for k, v in zm.noise.items() if is_noise_name(k)) or "none"
        raise DataError(
            f"the Kalman filter cannot use the noise levels of model {zm.label!r} ({levels}): {exc};"
            " refit the model by ML (rczone fit --method ml --save-model ...)"
        ) from None


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
