"""The checks after a fit, and the fit that makes them: what ``rczone fit`` and :func:`rczone.fit` run.

After the estimates, :func:`check_fit` asks whether they can be trusted: the identifiability
analysis at the estimates (:func:`rczone.diagnostics.diagnose`), each R and C profiled over a
factor of ten, the estimates at a bound or far from the construction values, and the same model
fitted to other data (their estimates compared, and this fit predicting them). The answers enter
the one verdict of the returned :class:`~rczone.calibration.Calibration`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

import pandas as pd

from rczone.calibration import Calibration, PreparedData, calibrate, predict, prepare
from rczone.calibration.calibration import stamped, verdict_fit, with_holdout
from rczone.estimation.settings import FitSettings
from rczone.models import ZoneModel
from rczone.workflow.holdout import before, score_held_out


def _quiet(_: str) -> None:
    """No progress messages."""


def fit_and_check(
    model: ZoneModel,
    frame: pd.DataFrame,
    settings: FitSettings,
    *,
    label: str = "data",
    others: Mapping[str, pd.DataFrame] | None = None,
    progress: Callable[[str], None] = _quiet,
    analyses: bool = True,
    holdout: float | None = None,
) -> Calibration:
    """Fit ``model`` to ``frame`` with ``settings``, then (``settings.checks``) check the fit.

    Parameters
    ----------
    model : ZoneModel
        The model; its values are the start.
    frame : DataFrame or PreparedData
        The data (``time`` in s or a DatetimeIndex, a column per signal), or the data set the
        caller prepared (:func:`rczone.calibration.prepare`; the methods of one zone in a batch
        share one).
    settings : FitSettings
        How to fit and what to check.
    label : str
        The data's name, recorded in the fitted model's provenance.
    others : mapping of name to DataFrame, optional
        Other data to fit and predict in the checks.
    progress : callable
        Called with a short message before each long step; when it also has ``advance(done, total)``
        (:class:`rczone.cli.progress.Reporter`), the fit tells it how far its search is.
    analyses : bool
        The analyses after the fit that a reader looks at (:func:`rczone.calibration.calibrate`);
        batch calibration, which stores estimates and errors only, skips them.
    holdout : float, optional
        Where a held-out part of ``frame`` starts (:func:`rczone.workflow.holdout.split_time`): the
        model is fitted and checked on the data before it and scored on the rest
        (:attr:`Calibration.holdout`).

    Returns
    -------
    Calibration
    """
    progress(f"fitting {model.label} to {label} ({settings.method})")
    full = frame.frame if isinstance(frame, PreparedData) else frame
    frame = frame if holdout is None else before(full, holdout)
    cal = calibrate(
        model,
        frame,
        settings,
        provenance={"data": label, "model": model.label},
        analyses=analyses,
        progress=progress if hasattr(progress, "advance") else None,  # a bar that counts the searches
    )
    if settings.checks or others:
        cal = check_fit(cal, frame, settings, others=others, progress=progress)
    if holdout is not None:
        progress("scoring the held-out data")
        held = score_held_out(cal.model, full, holdout, settings.constants, label)
        cal = with_holdout(dataclasses.replace(cal, holdout=held), held)
    return cal


def check_fit(
    cal: Calibration,
    frame: pd.DataFrame,
    settings: FitSettings,
    *,
    others: Mapping[str, pd.DataFrame] | None = None,
    progress: Callable[[str], None] = _quiet,
) -> Calibration:
    """The calibration with its post-fit checks, identifiability analysis and verdict, made now.

    Parameters
    ----------
    cal : Calibration
        A fit of :func:`rczone.calibration.calibrate`.
    frame : DataFrame
        The data it was fitted to.
    settings : FitSettings
        The fit's settings (the other data are fitted with them; ``profiles`` says whether to
        profile).
    others : mapping of name to DataFrame, optional
        Other data: fitted too (the estimates compared) and predicted with this fit.
    progress : callable
        Called with a short message before each long step.

    Returns
    -------
    Calibration
        A new calibration; its model's provenance carries the verdict.
    """
    checks, diag = PostFitChecks(frame, settings, others or {}, progress)(cal)
    checked = dataclasses.replace(cal, checks=checks, identifiability=diag)
    return dataclasses.replace(checked, model=stamped(checked.model, checked.verdict))


def defer_checks(
    cal: Calibration,
    frame: pd.DataFrame,
    settings: FitSettings,
    *,
    others: Mapping[str, pd.DataFrame] | None = None,
) -> Calibration:
    """The calibration whose post-fit checks are made on the first read of a result that needs them.

    The profiles and the identifiability analysis cost several times the fit (a 2-state ML fit of
    night C: 0.9 s, its checks 6 s); :func:`rczone.fit` returns at once and
    :attr:`Calibration.verdict`, ``checks``, ``identifiability``, ``summary()``, ``to_dict()`` make
    them when first read (:attr:`Calibration.pending`).

    Parameters
    ----------
    cal : Calibration
        A fit of :func:`rczone.calibration.calibrate` (held-out scores and plausibility included).
    frame, settings, others
        As for :func:`check_fit`.

    Returns
    -------
    Calibration
    """
    return dataclasses.replace(cal, pending=PostFitChecks(frame, settings, dict(others or {})))


@dataclasses.dataclass(frozen=True)
class PostFitChecks:
    """The checks after a fit, as one call: ``(checks, identifiability)`` of a calibration.

    Parameters
    ----------
    frame : DataFrame
        The data the calibration was fitted to.
    settings : FitSettings
        The fit's settings (the other data are fitted with them; ``profiles`` says whether to
        profile).
    others : mapping of name to DataFrame
        Other data: fitted too (the estimates compared) and predicted with this fit.
    progress : callable
        Called with a short message before each long step.
    """

    frame: pd.DataFrame
    settings: FitSettings
    others: Mapping[str, pd.DataFrame]
    progress: Callable[[str], None] = _quiet

    def __call__(self, cal: Calibration) -> tuple[dict, object]:
        """The JSON-ready checks and the identifiability report (None without an R or C) of ``cal``.

        Reads only what a calibration holds before its checks (result, model, innovations), so
        that a calibration with pending checks can call it on itself.
        """
        from rczone.diagnostics import diagnose
        from rczone.postfit.profiles import compare_fits, far_from_construction, profile_checks

        settings, progress = self.settings, self.progress
        r, zm = cal.result, cal.model
        # the fit's own data set (a calibration made elsewhere: the frame, as it was fitted)
        data = (
            cal.data
            if cal.data is not None
            else prepare(zm, self.frame, zm.provenance.get("constants") or None)
        )
        label = cal.data_label
        prof = {}
        if settings.profiles and len(zm.network.outputs) == 1:
            progress("profiling the estimates")
            prof = profile_checks(zm, data, r)
            prof = {k: v.to_dict() for k, v in prof.items()}
        fits = {label: verdict_fit(cal)}  # robust errors when the innovations are not white (issue 38)
        validation = {}
        for name, f in self.others.items():
            progress(f"fitting {name} for comparison")
            fits[name] = verdict_fit(
                calibrate(zm, f, settings, progress=progress if hasattr(progress, "advance") else None)
            )
            ol = predict(zm, f, settings.constants or None)
            validation[name] = {"rmse_K": ol.rmse_K, "max_error_K": ol.max_abs_K}
        checks = {
            "profiles": prof,
            "at_bound": [n for n, e in r.parameters.items() if e.at_bound],
            "far_from_construction": far_from_construction(r),
            "other_fits": {k: dict(v.estimates) for k, v in fits.items() if k != label},
            "disagreements": [{"name": d.name, **d.to_dict()} for d in compare_fits(fits)],
            "validation": validation,
        }
        rc = [n for n in r.names if n in zm.network.parameters and zm.theta[n] > 0]
        diag = None
        if rc:
            progress("diagnosing identifiability at the estimates")
            diag = diagnose(zm, data, free=rc, heat_input=None, operating_point="model")
        return checks, diag
