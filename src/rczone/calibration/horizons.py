"""Scores of a model per prediction horizon, next to persistence and an ARX model: ``rczone predict --horizons``.

One call scores every horizon: the k-step predictions of all horizons come from one Kalman
filter pass (the k-step predictor from each filtered state,
:func:`rczone.estimation.forecast.k_step_bands`), the open-loop one from the warm-up's estimate.
The baselines (:mod:`rczone.estimation.baselines`) use the same information: persistence repeats
the measurement at the origin; the ARX model is the one fitted by least squares on the model's
own calibration data and saved with it (or, for a model saved without one, fitted on the
warm-up). Each row has RMSE, MAE, bias (mean of measured minus predicted) and, for the model, the
share of measurements inside its 2-sigma band (Ljung 1999, section 16.6: a model is validated
against simple ones on data it has not seen).

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   sections 7.3 (k-step predictors) and 16.6 (model validation).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rczone import validation
from rczone.calibration.conformal import (
    ALPHA,
    ConformalBand,
    ConformalSettings,
    conformal_band,
    interval_score,
)
from rczone.calibration.dataset import ModelLike, as_model, ignored_channels
from rczone.calibration.drift import DriftCheck, check_drift
from rczone.calibration.prediction import (
    PredictionSetup,
    filter_failure,
    prediction_setup,
    saved_covariance,
    write_series,
)
from rczone.errors import DataError, ParameterError
from rczone.estimation.baselines import ARX, fit_arx, k_step_baselines, open_loop_baselines
from rczone.estimation.forecast import parameter_sd
from rczone.network.stochastic import is_noise_name
from rczone.postfit.evidence import ARX_NAME, MODEL, PERSISTENCE
from rczone.results import Result
from rczone.results.protocol import json_number

#: The word for an open-loop horizon in ``--horizons``.
OPEN = "open"


def parse_horizons(text: str) -> list[int | None]:
    """``"1,12,72,open"`` -> ``[1, 12, 72, None]`` (steps ahead; None for open loop).

    Parameters
    ----------
    text : str
        Comma-separated positive step counts and ``open``.
    """
    out: list[int | None] = []
    for part in (p.strip().lower() for p in text.split(",")):
        if part == OPEN:
            value = None
        else:
            try:
                value = int(part)
            except ValueError:
                value = 0
            if value < 1:
                raise ParameterError(
                    f"--horizons must be comma-separated positive step counts or 'open', e.g. 1,12,72,open;"
                    f" got {part!r} in {text!r}"
                )
        if value not in out:
            out.append(value)
    return out


def horizon_label(steps: int | None, dt: float) -> str:
    """``"12 steps (1 h)"`` or ``"open loop"``.

    Parameters
    ----------
    steps : int or None
        Steps ahead; None for open loop.
    dt : float
        Sample interval, s.
    """
    if steps is None:
        return "open loop"
    s = steps * dt
    when = f"{s / 3600:g} h" if s >= 3600 else f"{s / 60:g} min" if s >= 60 else f"{s:g} s"
    return f"{steps} step{'s' * (steps != 1)} ({when})"


@dataclass(frozen=True, eq=False, repr=False)
class HorizonScores(Result):
    """Scores per horizon of a model and its baselines on the scored samples.

    Attributes
    ----------
    table : DataFrame
        One row per horizon, predictor and output: ``horizon`` (label), ``steps`` (None: open
        loop), ``horizon_s``, ``predictor``, ``output``, ``n``, ``rmse_K``, ``mae_K``, ``bias_K``
        (measured minus predicted), ``coverage_2sigma`` and ``interval_score_K`` (model only; NaN
        without a band; the interval score of Gneiting & Raftery 2007 of the band at its nominal
        95.45 %, :func:`~rczone.calibration.conformal.interval_score`), ``stable`` (False for an ARX
        baseline with a pole on or outside the unit circle: its scores are shown as "unstable" and
        never ranked).
    t : ndarray, shape (N,)
        The scored samples' times, s.
    measured : ndarray, shape (N, ny)
    predicted : dict
        Predictor name to its predictions, shape (H, N, ny), horizons in :attr:`horizons` order.
    sd : ndarray, shape (H, N, ny)
        The model's band (total standard deviation).
    horizons : tuple
        Steps ahead (None: open loop).
    outputs : tuple of str
    band_source, start_note, baseline_note : str
        Where the band, the open-loop start and the ARX model come from, in words.
    model_label, data_label : str
    warmup_samples : int
    ignored_channels : tuple of str
        Channels the data's column map mapped that the model does not use.
    conformal : ConformalBand, optional
        The conformal band's quantiles when the band is conformal (``sd`` is then half its
        half-width, so that ``+-2 sd`` is the band).
    drift : DriftCheck, optional
        The drift tests, with a conformal band.
    unstable : dict of str to float
        Baselines whose predictor is unstable, with the largest modulus of their poles.
    """

    table: pd.DataFrame
    t: np.ndarray
    measured: np.ndarray
    predicted: dict
    sd: np.ndarray
    horizons: tuple
    outputs: tuple[str, ...]
    band_source: str
    start_note: str
    baseline_note: str
    model_label: str = "model"
    data_label: str = "data"
    warmup_samples: int = 0
    ignored_channels: tuple[str, ...] = ()
    conformal: ConformalBand | None = None
    drift: DriftCheck | None = None
    unstable: dict = field(default_factory=dict)

    def _repr_line(self) -> str:
        return (
            f"{self.model_label} on {self.data_label}: {len(self.horizons)} horizons, {len(self.t)} samples"
        )

    def to_frame(self) -> pd.DataFrame:
        """The scores table (a copy); a score that does not exist is missing (``pd.NA``), never NaN.

        A baseline has no band, a model without noise levels none either (:attr:`band_source`
        says so): their ``coverage_2sigma`` and ``interval_score_K`` are missing, as are the
        scores of a row with no scored sample (``n`` 0) and of an unstable baseline.
        """
        table = self.table.copy()
        unstable = ~table["stable"].astype(bool)
        table.loc[unstable, ["rmse_K", "mae_K", "bias_K"]] = np.nan
        for col in table.columns:
            if table[col].dtype.kind == "f" and table[col].isna().any():
                table[col] = table[col].astype("Float64")
        return table

    def summary_lines(self) -> list:
        """What ``rczone predict --horizons`` prints: the table, then where the start, band and ARX come from."""
        from rich.table import Table

        from rczone.results.fit_text import esc

        many = len(self.outputs) > 1
        table = Table(
            title=f"{esc(self.model_label)} on {esc(self.data_label)}: {len(self.t)} samples scored"
            + (f" after {self.warmup_samples} warm-up samples" if self.warmup_samples else "")
        )
        for col in ("horizon", *(["output"] if many else []), "predictor", "RMSE (K)", "MAE (K)", "bias (K)"):
            table.add_column(col)
        table.add_column("inside ±2σ")
        for _, r in self.table.iterrows():
            cov = (
                f"{r.coverage_2sigma:.0%}"
                if math.isfinite(r.coverage_2sigma)
                else "no band"
                if r.predictor == MODEL
                else ""
            )
            if not math.isnan(r.interval_score_K):
                cov += f" (score {r.interval_score_K:.3f})"
            scores = (
                (f"{r.rmse_K:.3f}", f"{r.mae_K:.3f}", f"{r.bias_K:+.3f}")
                if r.stable
                else (f"[yellow]unstable[/] (pole {self.unstable[r.predictor]:.4g})", "", "")
            )
            table.add_row(r.horizon, *([esc(r.output)] if many else []), r.predictor, *scores, cov)
        lines: list = [table]
        if None in self.horizons:
            lines.append(f"open-loop start: {esc(self.start_note)}")
        lines.append(f"band: {esc(self.band_source)}")
        lines.append(
            "score: the band's interval score (Gneiting & Raftery 2007), its width plus 2/alpha times"
            " each miss's distance, K; lower is better"
        )
        lines.append(f"baselines: {esc(self.baseline_note)}")
        if self.drift is not None:
            lines.append(f"drift: {esc(self.drift.describe())}")
        for name, pole in self.unstable.items():
            lines.append(
                f"[yellow]{esc(name)} is unstable[/] (a pole of modulus {pole:.4g}, outside the unit circle):"
                " its predictions grow without bound, so it is shown but not ranked"
            )
        return lines

    def to_dict(self) -> dict:
        """What ``rczone predict --horizons --json`` writes."""
        rows = [
            {k: (json_number(v) if isinstance(v, float) else v) for k, v in row.items()}
            for row in self.table.to_dict(orient="records")
        ]
        for row in rows:
            if not row["stable"]:  # an unstable baseline's numbers are no score
                row.update(rmse_K=None, mae_K=None, bias_K=None)
            row["steps"] = None if row["steps"] is None or row["steps"] != row["steps"] else int(row["steps"])
            row["n"] = int(row["n"])
        return {
            "model": self.model_label,
            "data": self.data_label,
            "samples": len(self.t),
            "warmup_samples": self.warmup_samples,
            "start": self.start_note,
            "band": self.band_source,
            "baselines": self.baseline_note,
            "scores": rows,
            "conformal": None if self.conformal is None else self.conformal.to_dict(),
            "drift": None if self.drift is None else self.drift.to_dict(),
            "ignored_channels": list(self.ignored_channels),
            "unstable": {k: float(v) for k, v in self.unstable.items()},
        }

    def series_frame(self) -> pd.DataFrame:
        """The series file: ``time``, then per output the measurement and, per horizon, each predictor's prediction.

        The model's columns are ``<output>_<horizon>`` with ``_lower`` and ``_upper`` (2 sigma);
        a baseline's ``<output>_<horizon>_<predictor>``; ``<horizon>`` is ``k<steps>`` or ``open``.
        """
        cols: dict[str, np.ndarray] = {"time": self.t}
        for j, o in enumerate(self.outputs):
            cols[f"{o}_measured"] = self.measured[:, j]
            for h, steps in enumerate(self.horizons):
                tag = OPEN if steps is None else f"k{steps}"
                model = self.predicted[MODEL][h, :, j]
                cols[f"{o}_{tag}"] = model
                cols[f"{o}_{tag}_lower"] = model - 2 * self.sd[h, :, j]
                cols[f"{o}_{tag}_upper"] = model + 2 * self.sd[h, :, j]
                for name, pred in self.predicted.items():
                    if name != MODEL:
                        cols[f"{o}_{tag}_{name}"] = pred[h, :, j]
        return pd.DataFrame(cols)

    def write(self, path) -> None:
        """Write :meth:`series_frame` as ``.csv`` or ``.parquet`` (atomically).

        Parameters
        ----------
        path : str or path
            Ends in ``.csv`` or ``.parquet``.
        """
        write_series(self.series_frame(), path)


def _scores(e: np.ndarray, sd: np.ndarray | None) -> dict:
    ok = np.isfinite(e)
    n = int(ok.sum())
    if n == 0:
        return {
            "n": 0,
            "rmse_K": math.nan,
            "mae_K": math.nan,
            "bias_K": math.nan,
            "coverage_2sigma": math.nan,
            "interval_score_K": math.nan,
        }
    v = e[ok]
    cover = score = math.nan
    if sd is not None and not np.isnan(sd[ok]).any():
        cover = float(np.mean(np.abs(v) <= 2 * sd[ok]))
        score = float(np.mean(interval_score(v, -2 * sd[ok], 2 * sd[ok], ALPHA)))
    return {
        "n": n,
        "rmse_K": float(np.sqrt(np.mean(v**2))),
        "mae_K": float(np.mean(np.abs(v))),
        "bias_K": float(np.mean(v)),
        "coverage_2sigma": cover,
        "interval_score_K": score,
    }


def saved_arx(setup: PredictionSetup) -> tuple[ARX | None, str]:
    """The ARX baseline: the one saved with the model's fit, else one fitted on the warm-up, and where it came from.

    Parameters
    ----------
    setup : PredictionSetup
    """
    data, prov = setup.data, setup.model.provenance
    saved = (prov.get("baselines") or {}).get("arx") if isinstance(prov.get("baselines"), Mapping) else None
    dt = setup.dt
    if saved is not None:
        arx = ARX.from_dict(saved)
        same_inputs = list(saved.get("inputs", [])) == list(data.input_names)
        same_dt = math.isclose(float(saved.get("dt_s", math.nan)), dt, rel_tol=0.01)
        if same_inputs and same_dt:
            return arx, f"ARX({arx.na},{arx.nb}) fitted by least squares on the model's calibration data"
        why = "other inputs" if not same_inputs else f"another sample interval ({saved.get('dt_s')} s)"
        note = f"the saved ARX model has {why}; "
    else:
        note = "the model has no saved ARX model; "
    if setup.first:
        try:
            y = np.array(data.y[: setup.first])
            arx = fit_arx(y, data.u[: setup.first])
            return (
                arx,
                note + f"ARX({arx.na},{arx.nb}) fitted by least squares on the {setup.first} warm-up samples",
            )
        except DataError:
            pass
    return (
        None,
        note + "no ARX baseline (fit the model with rczone fit to save one, or give a longer --warmup)",
    )


def horizon_scores(
    model: ModelLike,
    frame: pd.DataFrame,
    constants: Mapping[str, float] | None = None,
    *,
    horizons: Sequence[int | None],
    baselines: bool = True,
    start: float | None = None,
    parameters: bool = True,
    label: str = "data",
    hold: str | None = None,
    conformal: ConformalSettings | None = None,
) -> HorizonScores:
    """Score a model at several horizons at once, with persistence and ARX next to it.

    Parameters
    ----------
    model : ZoneModel, RCNetwork, str or path
    frame : DataFrame
        The data, warm-up included.
    constants : mapping, optional
        Inputs held constant (SI units).
    horizons : sequence
        Steps ahead (positive integers; k-step needs the model's noise levels) and None for open loop.
    baselines : bool
        Score persistence and the ARX model too.
    start : float, optional
        Time (s, on the data's axis) of the first scored sample; the samples before it warm up.
    parameters : bool
        Include the estimates' uncertainty in the band.
    label : str
        The data's name.
    hold : {"zoh", "foh"}, optional
        Inter-sample behaviour of the inputs; default the one the model was fitted with.
    conformal : ConformalSettings, optional
        Replace the model's band by a conformal one calibrated on the last warm-up samples
        (:mod:`rczone.calibration.conformal`; needs ``start``); the model is then also tested for
        drift on the same window (:mod:`rczone.calibration.drift`).

    Returns
    -------
    HorizonScores
    """
    zm = as_model(model)
    horizons = tuple(horizons)
    if not horizons:
        raise ParameterError("give at least one horizon")
    if any(h is not None for h in horizons) and not any(is_noise_name(k) for k in zm.noise):
        raise DataError(
            "k-step predictions need the model's noise levels; fit the model by ML (rczone fit --method ml"
            " --save-model ...) or score open loop only (--horizons open)"
        )
    with filter_failure(zm):
        setup = prediction_setup(zm, frame, constants, start=start, hold=hold)
        data, first = setup.data, setup.first
        for h in horizons:
            if h is not None:
                validation.steps_ahead(h, len(data.t) - first, "horizon")
        predictor = setup.predictor(horizons)
        y_hat = predictor(setup.values)
        for h, steps in zip(y_hat, horizons):
            what = "the open-loop prediction" if steps is None else f"the {steps}-step prediction"
            if not np.isfinite(h[max(first, steps or 0) :]).all():
                raise DataError(f"{what} is not finite; the model's values are not usable on these data")
            validation.scored_samples(data.y[first:], h[first:], zm.network.outputs, what)
        sd, sources = setup.noise_sd(horizons)
    cov = saved_covariance(zm) if parameters else None
    if cov is not None:
        sd_par = parameter_sd(predictor, setup.values, *cov)
        sd = np.sqrt(np.where(np.isfinite(sd), sd**2, 0.0) + sd_par**2)
        sources.append("the estimates' covariance")
    cband = drift = None
    if conformal is not None:
        cband, sd, window = _conformal(conformal, data, y_hat, sd, horizons, first)
        drift = _drift(setup, horizons, cband, window)
        sources = [
            f"{conformal.describe()}, on the band of "
            + " and ".join(sources or ["no noise"])
            + (
                " (open loop and horizons with too few errors in the window keep the model's band)"
                if np.isnan(cband.quantile).any()
                else ""
            )
        ]
    predicted = {MODEL: y_hat}
    note = "not asked for"
    unstable: dict[str, float] = {}
    if baselines:
        arx, note = saved_arx(setup)
        if arx is not None and not arx.stable:
            unstable[ARX_NAME] = arx.largest_pole()
        ks = [h for h in horizons if h is not None]
        kb = k_step_baselines(data.y, data.u, ks, arx) if ks else {}
        ol = open_loop_baselines(data.y, data.u, max(first, 1), arx)
        parts = [kb[h] if h is not None else ol for h in horizons]
        predicted[PERSISTENCE] = np.stack([p.persistence for p in parts])
        if arx is not None:
            predicted[ARX_NAME] = np.stack([p.arx for p in parts])
    rows = []
    dt = setup.dt
    y = data.y[first:]
    for h, steps in enumerate(horizons):
        for name, pred in predicted.items():
            for j, o in enumerate(zm.network.outputs):
                e = y[:, j] - pred[h, first:, j]
                rows.append(
                    {
                        "horizon": horizon_label(steps, dt),
                        "steps": steps,
                        "horizon_s": None if steps is None else steps * dt,
                        "predictor": name,
                        "output": o,
                        **_scores(e, sd[h, first:, j] if name == MODEL else None),
                        "stable": name not in unstable,
                    }
                )
    return HorizonScores(
        pd.DataFrame(rows),
        data.t[first:],
        y,
        {k: v[:, first:] for k, v in predicted.items()},
        sd[:, first:],
        horizons,
        zm.network.outputs,
        " and ".join(sources) if sources else "none (the model has no noise levels)",
        setup.start_note,
        note,
        model_label=zm.label,
        data_label=label,
        warmup_samples=first,
        ignored_channels=ignored_channels(frame),
        unstable=unstable,
        conformal=cband,
        drift=drift,
    )


def _conformal(
    settings: ConformalSettings, data, y_hat: np.ndarray, sd: np.ndarray, horizons: tuple, first: int
) -> tuple[ConformalBand, np.ndarray]:
    """The conformal band over the model's own, and the standard deviation whose ``+-2 sd`` is that band."""
    t0 = data.t[first] if first < data.n_samples else data.t[-1]
    window = int(np.sum(data.t[:first] >= t0 - settings.window_s))
    band = conformal_band(data.y[None] - y_hat, sd, horizons, first, window, settings)
    # open loop and horizons the window has too few errors for keep the model's band
    keep = np.isnan(band.quantile)[:, None, :]
    return band, np.where(keep, sd, band.half_width / 2.0), window


def _drift(setup: PredictionSetup, horizons: tuple, band: ConformalBand, window: int) -> DriftCheck:
    """The drift tests (:mod:`rczone.calibration.drift`) on the filter's standardized innovations and the band."""
    from rczone.estimation.engines import run_filter

    net, data = setup.model.network, setup.data
    out = run_filter(net, setup.values, data, setup.hold)
    with np.errstate(invalid="ignore"):
        z = out.innovations / np.sqrt(np.einsum("kii->ki", out.S))
    reference = max(window, setup.first - setup.first // 4)  # the warm-up after the filter's start
    return check_drift(
        z, data.t, setup.first, reference, net.outputs, widening=band.widening(), horizons=horizons
    )


#: Horizons a held-out part is scored at (``--holdout``), s: one step, 1 h, 6 h and 24 h, then open loop.
HOLDOUT_HORIZONS_S = (3600.0, 21600.0, 86400.0)


def holdout_horizons(dt: float, n_samples: int, stochastic: bool) -> list[int | None]:
    """The horizons ``--holdout`` scores: one step, 1 h, 6 h and 24 h (those shorter than the part), open loop.

    Parameters
    ----------
    dt : float
        Sample interval, s.
    n_samples : int
        Samples of the held-out part.
    stochastic : bool
        Whether the model has noise levels (k-step predictions need them); without, open loop only.
    """
    if not stochastic:
        return [None]
    steps = [1, *(round(h / dt) for h in HOLDOUT_HORIZONS_S)]
    return [*dict.fromkeys(k for k in steps if 1 <= k < n_samples), None]


def holdout_scores(
    model: ModelLike,
    frame: pd.DataFrame,
    start: float,
    constants: Mapping[str, float] | None = None,
    *,
    label: str = "data",
) -> HorizonScores:
    """Scores of a model fitted on the samples before ``start`` on those after, with the baselines.

    The calibration part warms the filter up (:func:`horizon_scores` with ``start``); the horizons
    are :func:`holdout_horizons`.

    Parameters
    ----------
    model : ZoneModel, str or path
        The model fitted on the calibration part.
    frame : DataFrame
        Every sample, calibration and held-out.
    start : float
        Time (s, on the data's axis) of the first held-out sample.
    constants : mapping, optional
        Inputs held constant (SI units).
    label : str
        The data's name.
    """
    zm = as_model(model)
    t = frame["time"].to_numpy(float)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    stochastic = any(is_noise_name(k) for k in zm.noise)
    horizons = holdout_horizons(dt, int((t >= start).sum()), stochastic)
    return horizon_scores(zm, frame, constants, horizons=horizons, start=start, label=label)
