"""The report of ``rczone predict``: measured and predicted outputs with the two-sigma band."""

from __future__ import annotations

import html

import numpy as np
from matplotlib.figure import Figure

from rczone.calibration import Prediction
from rczone.calibration.horizons import HorizonScores
from rczone.network.stochastic import target_of
from rczone.report.html import Report, literal


def prediction_figure(pred: Prediction, title: str = "") -> Figure:
    """One panel per output: measurement, open-loop prediction and its band, and the error below."""
    ny = len(pred.outputs)
    fig = Figure(figsize=(8.5, 2.8 * ny + 1.8))
    axes = fig.subplots(ny + 1, 1, squeeze=False, sharex=True)[:, 0]
    h = (pred.t - pred.t[0]) / 3600.0
    band_lo, band_hi = pred.band
    posterior = pred.lower is not None
    for j, (ax, o) in enumerate(zip(axes[:-1], pred.outputs, strict=True)):
        lo, hi = band_lo[:, j], band_hi[:, j]
        if np.isfinite(lo).any():
            label = "posterior predictive 95.4 %" if posterior else "±2 σ"
            ax.fill_between(h, lo, hi, color="#90cdf4", alpha=0.5, lw=0, label=label)
        if (
            pred.sd_parameters is not None
            and pred.sd_noise is not None
            and np.isfinite(pred.sd_noise[:, j]).any()
        ):
            # the part of the band the estimates' uncertainty alone would give
            sp = pred.sd_parameters[:, j]
            ax.fill_between(
                h,
                pred.predicted[:, j] - 2 * sp,
                pred.predicted[:, j] + 2 * sp,
                color="#2c5282",
                alpha=0.35,
                lw=0,
                label="±2 σ from the estimates",
            )
        ax.plot(h, pred.measured[:, j], color="black", lw=1.0, label="measured")
        ax.plot(
            h, pred.predicted[:, j], color="#2b6cb0", lw=1.3, label=literal(f"predicted ({pred.horizon})")
        )
        ax.set_ylabel(literal(f"{o} (°C)"))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    ax = axes[-1]
    for j, o in enumerate(pred.outputs):
        ax.plot(h, pred.error[:, j], lw=1.0, label=literal(o))
    ax.axhline(0.0, color="grey", lw=0.8)
    ax.set_ylabel("error (K)")
    ax.set_xlabel("hours from start")
    ax.grid(alpha=0.3)
    if title:
        fig.suptitle(literal(title))
    fig.tight_layout()
    return fig


def prediction_report(pred: Prediction, data_name: str, model_name: str) -> Report:
    """A report with the prediction plot and its error statistics."""
    rep = Report(f"Prediction of {model_name} on {data_name}")
    what = (
        "Open-loop simulation from the first measurement"
        if pred.steps is None
        else f"Each sample predicted {pred.horizon} from the Kalman filter's estimate of the state"
    )
    rep.paragraph(f"{what}; band: {html.escape(pred.band_source)}.")
    start = pred.initial_state
    if start is not None and start.sd:
        rep.table(
            [
                {
                    "node": target_of(k),
                    "initial temperature (°C)": start.values[k],
                    "steady state (°C)": start.steady[k],
                    "std. error (K)": sd,
                }
                for k, sd in start.sd.items()
            ],
            "Initial temperatures of the unmeasured nodes, estimated from these data (the measured ones"
            " start at their first measurement)",
            digits=3,
        )
    rows = []
    cover = pred.coverage
    for j, o in enumerate(pred.outputs):
        row = {
            "output": o,
            "RMSE (K)": float(pred.rmse_K[j]),
            "max error (K)": float(pred.max_abs_K[j]),
            "inside ±2σ": f"{cover[j]:.0%}" if cover is not None else "no band",
        }
        for key, part in (
            ("mean σ, noise (K)", pred.sd_noise),
            ("mean σ, estimates (K)", pred.sd_parameters),
        ):
            if part is not None and np.isfinite(part[:, j]).any():
                row[key] = float(np.nanmean(part[:, j]))
        rows.append(row)
    rep.table(rows, f"Prediction error ({pred.horizon})", digits=3)
    rep.figure(
        "prediction", prediction_figure(pred, f"{model_name} on {data_name}"), "Measured and predicted"
    )
    return rep


def horizons_figure(scores: HorizonScores) -> Figure:
    """RMSE and 2-sigma coverage against the horizon: the model, persistence and ARX (open loop at the right)."""
    from rczone.postfit.evidence import MODEL

    fig = Figure(figsize=(8.5, 5.6))
    ax_rmse, ax_cov = fig.subplots(2, 1, sharex=True)
    table = scores.table
    labels = list(dict.fromkeys(table["horizon"]))
    pos = np.arange(len(labels))
    styles = {"model": ("#2b6cb0", "o"), "persistence": ("#718096", "s"), "arx": ("#c05621", "^")}
    for (name, output), rows in table.groupby(["predictor", "output"], sort=False):
        if not rows["stable"].all():  # an unstable baseline is not ranked (issue 38)
            continue
        x = [labels.index(h) for h in rows["horizon"]]
        colour, marker = styles.get(name, ("black", "x"))
        tag = name if len(scores.outputs) == 1 else f"{name} ({output})"
        ax_rmse.plot(x, rows["rmse_K"], marker=marker, color=colour, label=literal(tag))
        if name == MODEL:
            ax_cov.plot(x, 100 * rows["coverage_2sigma"], marker=marker, color=colour, label=literal(tag))
    ax_rmse.set_ylabel("RMSE (K)")
    ax_rmse.grid(alpha=0.3)
    ax_rmse.legend(fontsize=8, loc="best")
    ax_cov.axhspan(90, 98, color="#c6f6d5", alpha=0.6, lw=0, label="90-98 %")
    ax_cov.axhline(95.45, color="grey", lw=0.8, ls="--", label="nominal 95.45 %")
    ax_cov.set_ylabel("inside ±2σ (%)")
    ax_cov.set_ylim(0, 102)
    ax_cov.grid(alpha=0.3)
    ax_cov.legend(fontsize=8, loc="lower left")
    ax_cov.set_xticks(pos, [literal(x) for x in labels], rotation=20, fontsize=8)
    ax_cov.set_xlabel("horizon")
    fig.suptitle(literal(f"{scores.model_label} on {scores.data_label}: error against horizon"))
    fig.tight_layout()
    return fig


def horizons_report(scores: HorizonScores) -> Report:
    """A report with the scores table per horizon and the figure of error against horizon."""
    rep = Report(
        f"Prediction of {scores.model_label} on {scores.data_label} at {len(scores.horizons)} horizons"
    )
    rep.paragraph(
        f"{len(scores.t)} samples scored"
        + (f" after {scores.warmup_samples} warm-up samples (not scored)" if scores.warmup_samples else "")
        + f". Open-loop start: {html.escape(scores.start_note)}. Band: {html.escape(scores.band_source)}."
        f" Baselines: {html.escape(scores.baseline_note)}."
    )
    rows = [
        {
            "horizon": r.horizon,
            **({"output": r.output} if len(scores.outputs) > 1 else {}),
            "predictor": r.predictor,
            "RMSE (K)": r.rmse_K if r.stable else "unstable",
            "MAE (K)": r.mae_K if r.stable else "",
            "bias (K)": r.bias_K if r.stable else "",
            "inside ±2σ": f"{r.coverage_2sigma:.0%}" if np.isfinite(r.coverage_2sigma) else "",
            "interval score (K)": r.interval_score_K,
        }
        for r in scores.table.itertuples()
    ]
    rep.table(rows, "Scores per horizon (bias: measured minus predicted)", digits=3)
    rep.figure("horizons", horizons_figure(scores), "Error and band coverage against the horizon")
    if scores.drift is not None:
        rep.paragraph(f"Drift: {html.escape(scores.drift.describe())}.")
        if scores.drift.traces:
            rep.figure("drift", drift_figure(scores), "CUSUM statistics of the innovations")
    return rep


def drift_figure(scores: HorizonScores) -> Figure:
    """The CUSUM statistics of each output's innovations per block, the decision interval and the drift's start."""
    from rczone.calibration.drift import CUSUM_H

    check = scores.drift
    traces = check.traces
    fig = Figure(figsize=(8.5, 2.6 * len(traces) + 1.0))
    axes = fig.subplots(len(traces), 1, squeeze=False, sharex=True)[:, 0]
    t0 = scores.t[0]
    for ax, (o, tr) in zip(axes, traces.items(), strict=True):
        h = (tr.t - t0) / 3600.0
        ax.plot(h, tr.mean_up, color="#c05621", label="mean up")
        ax.plot(h, tr.mean_down, color="#2b6cb0", label="mean down")
        ax.plot(h, tr.variance_up, color="#2f855a", label="variance up")
        ax.axhline(CUSUM_H, color="black", lw=0.8, ls="--", label="decision interval")
        if check.since_s is not None:
            ax.axvline((check.since_s - t0) / 3600.0, color="red", lw=1.0, label="drift since")
        ax.set_ylabel(f"{o}: CUSUM")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    axes[-1].set_xlabel("hours from the first scored sample")
    fig.suptitle(f"{scores.model_label}: drift tests")
    fig.tight_layout()
    return fig
