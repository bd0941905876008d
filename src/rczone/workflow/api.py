"""The functions :mod:`rczone` exports: load, fit, predict, with the command line's defaults.

Each takes the data first and its options by keyword only, builds the same settings as the
command (:class:`~rczone.estimation.settings.FitSettings`) and returns a result that prints what the
command prints (``summary()``) and serializes to what its ``--json`` writes (``to_dict()``).
"""

from __future__ import annotations

import dataclasses
import datetime
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rczone import validation
from rczone.calibration import Calibration, Prediction, as_model, frame_from, prediction
from rczone.calibration.dataset import time_index
from rczone.errors import ParameterError
from rczone.estimation.methods import DEFAULT_METHOD, MethodOptions
from rczone.estimation.settings import FitSettings
from rczone.kernels.blas import single_threaded
from rczone.models import ZoneModel
from rczone.workflow.checks import defer_checks, fit_and_check
from rczone.workflow.datasource import DataSource, data_source, frame_and_label
from rczone.workflow.holdout import before, conformal_settings, score_held_out, split_time

PathLike = str | os.PathLike
ModelLike = ZoneModel | PathLike


def load_data(
    source: PathLike | DataSource, *, columns: PathLike | None = None, model: ModelLike | None = None
) -> pd.DataFrame:
    """A zone's data as a frame, read exactly as the command line reads them.

    Parameters
    ----------
    source : str, path or DataSource
        A CSV or Parquet trend log, a built-in data set's name (``"A"``, ``"B"``, ``"C"``) or a
        :class:`~rczone.workflow.datasource.DataSource` (a virtual night, for one).
    columns : str or path, optional
        A TOML column map (``--columns``; ``docs/data.md``).
    model : ZoneModel, str or path, optional
        The model the data are for: its signal names are read from a file without a map, and a
        map may name them (a heater ``Ph``).

    Returns
    -------
    DataFrame
        SI units, a column per signal and ``time`` (s). A trend log is indexed by its time stamps
        in the column map's time zone (UTC without a map); a built-in set by sample number.
        ``attrs["name"]`` is the file's (or set's) name, which :func:`fit` and :func:`predict`
        use as the data's name.
    """
    zm = as_model(model) if model is not None else None
    return data_source(source, columns).frame(zm)


@single_threaded
def fit(
    model: ModelLike,
    data: pd.DataFrame | PathLike,
    *,
    method: str = DEFAULT_METHOD,
    free: Sequence[str] | None = None,
    optimizer: str = "auto",
    n_starts: int | None = None,
    seed: int = 0,
    noise: str = "measured",
    constants: Mapping[str, float] | None = None,
    columns: PathLike | None = None,
    check_on: Sequence[pd.DataFrame | PathLike | tuple[PathLike, PathLike]] = (),
    checks: bool = True,
    profiles: bool = True,
    hold: str = "zoh",
    bounds: Mapping[str, tuple[float, float]] | None = None,
    fixed: Mapping[str, float | None] | None = None,
    label: str | None = None,
    options: MethodOptions | Mapping[str, Any] | None = None,
    holdout: str | float | None = None,
    floor_area: float | None = None,
) -> Calibration:
    """Fit a model to data: ``rczone fit`` in Python.

    Parameters
    ----------
    model : ZoneModel, str or path
        A built-in name, a model file, a saved model (its values are the start) or a model.
    data : DataFrame, str or path
        A frame (``time`` in s or a DatetimeIndex, a column per signal), a trend log or a built-in
        data set's name.
    method : str
        ``"ml"`` (default, as the command line), ``"ls"``, ``"map"`` or ``"mcmc"`` (posterior
        sampling; :data:`rczone.estimation.methods.REGISTRY`).
    free : sequence of str, optional
        Free parameters; default the model's, plus noise levels for ML and MAP. ``"+NAME"`` adds
        ``NAME`` to the default set (``--free +sigma_w_Te``).
    optimizer : str
        ``"auto"``, ``"nelder-mead"``, ``"powell"`` or ``"lbfgs"``.
    n_starts : int, optional
        Local searches; default the global search, 1 for one local search.
    seed : int
        Seed of the global search.
    noise : {"measured", "all"}
        ML and MAP: process noise on the measured states or on every state.
    constants : mapping, optional
        Inputs held constant (SI units), e.g. ``{"Q": 50}``.
    columns : str or path, optional
        A column map for ``data`` and ``check_on`` given as files.
    check_on : sequence, optional
        Other data: fitted too, their estimates compared, and predicted with this fit. An item
        ``(file, column_map)`` reads the file with its own map (``--check-on FILE:MAP``).
    checks : bool
        Make the checks after the fit (identifiability at the estimates, profiles), as
        ``rczone fit --json`` does; they enter the one verdict. They are made when first read
        (``verdict``, ``checks``, ``identifiability``, ``summary()``, ``to_dict()``), so that a
        user who wants the estimates pays for the estimates (:attr:`Calibration.pending`).
    profiles : bool
        With ``checks``: profile each R and C over a factor of ten.
    hold : {"zoh", "foh"}
        Inputs between samples: held (default) or linear (``--hold``).
    bounds : mapping of str to (float, float), optional
        Search bounds in the parameter's SI unit (``--bounds NAME=LO,HI``).
    fixed : mapping of str to float or None, optional
        Parameters held at a value, None for the model's (``--fix NAME[=VALUE]``).
    label : str, optional
        The data's name in titles and the JSON; default the file name (or ``"data"``).
    options : MethodOptions or mapping, optional
        The method's own options (``--option NAME=VALUE``): ``{"draws": 500, "tune": 500,
        "chains": 4}`` for ``"mcmc"`` (``seed`` seeds the sampler), ``{"prior_spread": 0.5}`` for
        ``"map"``; an option the method does not have is refused.
    holdout : str or float, optional
        Fit on the data before this time (``"2009-02-09T12:00"``, in the column map's time zone)
        or all but this last fraction of the samples (``0.25``), then score the rest at one step,
        1 h, 6 h, 24 h and open loop next to persistence and ARX (``--holdout``;
        :attr:`Calibration.holdout`).
    floor_area : float, optional
        Heated floor area, m2 (``--floor-area``): the plausibility is judged against reference
        ranges per m2 (:func:`rczone.models.plausibility.reference_ranges`).

    Returns
    -------
    Calibration
        ``summary()`` is what ``rczone fit`` prints, ``to_dict()`` what ``--json`` writes.
    """
    zm = as_model(model)
    settings = FitSettings(
        method=method,
        free=free,
        optimizer=optimizer,
        n_starts=n_starts,
        seed=seed,
        noise=noise,
        constants=validation.mapping(constants or {}, "constants"),
        checks=checks,
        profiles=profiles,
        options=options,
        hold=hold,
        bounds=dict(bounds or {}),
        fixed=dict(fixed or {}),
    )
    frame, name = frame_and_label(data, columns, zm)
    validation.measured_outputs(frame, zm.network.outputs, label=label or name)
    others = {}
    for k, other in enumerate(check_on):
        other, own = other if isinstance(other, tuple) else (other, columns)  # (file, its own map)
        f, other_name = frame_and_label(other, own, zm)
        others[other_name if other_name not in others and other_name != "data" else f"data {k + 1}"] = f
    at = None
    if holdout is not None:  # a split needs the time axis
        frame = frame_from(frame)
        at = split_time(frame, holdout, model=zm, columns=columns)
    now = dataclasses.replace(settings, checks=False)  # the checks are made when first read
    cal = fit_and_check(zm, frame, now, label=label or name, holdout=at)
    if floor_area is not None and cal.plausibility is not None:
        from rczone.calibration.reference import with_floor_area

        cal = with_floor_area(cal, zm, before(frame, at), floor_area)
    if checks or others:
        cal = defer_checks(cal, before(frame, at), settings, others=others)
    return cal


@single_threaded
def predict(
    model: ModelLike,
    data: pd.DataFrame | PathLike,
    *,
    steps: int | None = None,
    initial_state: str = "warmup",
    constants: Mapping[str, float] | None = None,
    columns: PathLike | None = None,
    parameters: bool = True,
    label: str | None = None,
    hold: str | None = None,
    warmup: str | None = None,
) -> Prediction:
    """Predict data with a model, open loop or ``steps`` ahead, with a 2-sigma band: ``rczone predict``.

    Parameters
    ----------
    model : ZoneModel, str or path
        A fitted model (or any model: its values are used).
    data : DataFrame, str or path
        As for :func:`fit`.
    steps : int, optional
        Steps ahead from the Kalman filter (a model fitted by ML); default open loop.
    initial_state : {"warmup", "steady", "estimated"}
        Open loop: where the unmeasured nodes start (:func:`rczone.calibration.prediction`; the
        default uses no sample it scores).
    constants : mapping, optional
        Inputs held constant (SI units).
    columns : str or path, optional
        A column map for ``data`` given as a file.
    parameters : bool
        Include the estimates' uncertainty in the band.
    label : str, optional
        The data's name in titles and the JSON.
    hold : {"zoh", "foh"}, optional
        Inputs between samples; default the one the model was fitted with.
    warmup : str, optional
        The first part of the data only warms the filter up and is not scored: a duration
        (``"1d"``, ``"6h"``, ``"30min"``) or the time the scored part starts (``--warmup``).

    Returns
    -------
    Prediction
        ``to_frame()`` is indexed by the data's time stamps.
    """
    if steps is not None:
        validation.integer(steps, "steps", low=1)
    zm = as_model(model)
    frame, name = frame_and_label(data, columns, zm)
    validation.measured_outputs(frame, zm.network.outputs, label=label or name)
    start = None
    if warmup is not None:  # a split needs the time axis
        frame = frame_from(frame)
        start = split_time(frame, warmup, model=zm, columns=columns, warmup=True)
    if steps is not None:
        validation.steps_ahead(steps, len(frame))
    return prediction(
        zm,
        frame,
        dict(constants) if constants else None,
        steps=steps,
        parameters=parameters,
        initial_state=initial_state,
        label=label or name,
        hold=hold,
        start=start,
    )


@single_threaded
def score_horizons(
    model: ModelLike,
    data: pd.DataFrame | PathLike,
    *,
    horizons: Sequence[int | str] | str = "1,12,72,open",
    baselines: bool = False,
    warmup: str | None = None,
    constants: Mapping[str, float] | None = None,
    columns: PathLike | None = None,
    label: str | None = None,
    hold: str | None = None,
    conformal: str | None = None,
    online: bool = False,
):
    """Score a model at several horizons at once, with baselines: ``rczone predict --horizons --baselines``.

    Parameters
    ----------
    model : ZoneModel, str or path
        A fitted model (a model fitted by ML for the k-step horizons).
    data : DataFrame, str or path
        As for :func:`fit`.
    horizons : sequence or str
        Steps ahead and ``"open"`` (open loop), e.g. ``[1, 12, 72, "open"]`` or ``"1,12,72,open"``.
    baselines : bool
        Score persistence and the ARX(2,2) model saved with the fitted model beside it.
    warmup : str, optional
        A duration (``"1d"``) or time: the data before it warm the filter up and are not scored.
    constants : mapping, optional
        Inputs held constant (SI units).
    columns : str or path, optional
        A column map for ``data`` given as a file.
    label : str, optional
        The data's name in titles and the JSON.
    hold : {"zoh", "foh"}, optional
        Inputs between samples; default the one the model was fitted with.
    conformal : str, optional
        Replace the k-step bands by split conformal ones calibrated on the last part of the
        warm-up, this long (``"1d"``; needs ``warmup``), as ``--conformal``.
    online : bool
        With ``conformal``: update the bands while predicting and watch for drift (``--online``).

    Returns
    -------
    HorizonScores
        ``summary()`` is what ``rczone predict --horizons`` prints, one row per horizon (RMSE,
        MAE, bias and 2-sigma coverage).
    """
    from rczone.calibration.horizons import horizon_scores, parse_horizons

    zm = as_model(model)
    frame, name = frame_and_label(data, columns, zm)
    frame = frame_from(frame)
    start = split_time(frame, warmup, model=zm, columns=columns, warmup=True)
    settings = conformal_settings(conformal, online, start)
    if not isinstance(horizons, (str, list, tuple)):  # an int or a set: one line, not a TypeError
        raise ParameterError(
            f"horizons must be a list such as [1, 12, 'open'] or text such as '1,12,open', got {horizons!r}"
        )
    text = horizons if isinstance(horizons, str) else ",".join(str(h) for h in horizons)
    return horizon_scores(
        zm,
        frame,
        dict(constants) if constants else None,
        horizons=parse_horizons(text),
        baselines=baselines,
        start=start,
        label=label or name,
        hold=hold,
        conformal=settings,
    )


@single_threaded
def simulate(
    model: ModelLike,
    data: pd.DataFrame | PathLike,
    *,
    x0: Mapping[str, float] | None = None,
    hold: str = "zoh",
    constants: Mapping[str, float] | None = None,
    columns: PathLike | None = None,
) -> pd.DataFrame:
    """Simulate a model exactly on the inputs of data: every node's temperature over time.

    The bilinear supply-air term m cp (Ts - Ti) is kept: the model is discretized exactly on each
    sampling interval with the inputs held as ``hold`` says (Lin, Middelkoop and Barooah 2012,
    eq. 2). Measured outputs in ``data`` are used only for the start: a measured node starts at its
    first measurement.

    Parameters
    ----------
    model : ZoneModel, str or path
        The model and its values.
    data : DataFrame, str or path
        As for :func:`fit` (only the model's inputs are read).
    x0 : mapping of str to float, optional
        Initial temperature of each node, degC. Nodes not named start at their first measurement
        when the data measure them (an output with a first value), else at the steady state for the
        first inputs.
    hold : {"zoh", "foh"}
        Inputs held constant (zero-order) or linear (first-order) between samples.
    constants : mapping, optional
        Inputs held constant (SI units).
    columns : str or path, optional
        A column map for ``data`` given as a file.

    Returns
    -------
    DataFrame
        One column per node (and per output that is not a node), indexed by the data's time
        stamps in their time zone, or by ``time_s`` when the data have no clock time.

    Examples
    --------
    >>> import rczone
    >>> states = rczone.simulate("second-order-paper", "C", constants={"Q": 50.0})
    >>> list(states.columns)
    ['Ti', 'Tw']
    """
    from rczone.simulation import simulate as simulate_state_space
    from rczone.simulation.simulate import steady_state

    zm = as_model(model)
    frame, _ = frame_and_label(data, columns, zm)
    given = frame_from(frame)
    missing = [o for o in zm.network.outputs if o not in given]  # a simulation needs no measurement
    given = given.assign(**{o: float("nan") for o in missing}) if missing else given
    t, u, m, _ = zm.signals(given, dict(constants) if constants else None)
    validation.finite_inputs(t, np.column_stack([u, m]), [*zm.network.input_names, *zm.network.flow_names])
    m = m if m.shape[1] else None
    ss = zm.state_space()
    start = None
    given_x0 = {
        k: validation.temperature(v, f"x0 of {k}") for k, v in validation.mapping(x0 or {}, "x0").items()
    }
    first = {o: given[o].iloc[0] for o in zm.network.outputs if o not in missing and o in ss.state_names}
    x0 = {**{o: float(v) for o, v in first.items() if pd.notna(v)}, **given_x0}
    if x0:
        unknown = sorted(set(x0) - set(ss.state_names))
        if unknown:
            raise ParameterError(
                f"x0 names {', '.join(map(repr, unknown))}, not a node of model {zm.label!r}"
                f" (its nodes: {', '.join(ss.state_names)})"
            )
        start = steady_state(ss, u[0], 0.0 if m is None else m[0])
        for i, name in enumerate(ss.state_names):
            if name in x0:
                start[i] = float(x0[name])
    res = simulate_state_space(ss, t, u, m, start, hold)
    out = validation.finite_result(res.to_frame(), f"the simulation of {zm.label!r}")
    index = time_index(frame, t)
    if index is not None:
        out.index = index
    return out


@single_threaded
def diagnose(
    model: ModelLike,
    data: pd.DataFrame | PathLike,
    *,
    free: Sequence[str] | None = None,
    sigma: float = 0.1,
    model_error: float = 0.2,
    operating_point: str = "auto",
    seed: int = 0,
    constants: Mapping[str, float] | None = None,
    columns: PathLike | None = None,
    label: str | None = None,
    hold: str | None = None,
):
    """Can these data identify the model's parameters, and why: ``rczone diagnose`` in Python.

    Parameters
    ----------
    model : ZoneModel, str or path
        The model; the analysis is made at its values if they reproduce the data, else at a quick
        least-squares fit's (:func:`rczone.diagnostics.diagnose`).
    data : DataFrame, str or path
        As for :func:`fit`.
    free : sequence of str, optional
        Parameters to diagnose; default the model's free R, C and gains.
    sigma : float
        Error level a fit must see through (sensor noise and model error), K.
    model_error : float
        Structural model error the verdicts allow for, K RMS (0: none).
    operating_point : {"auto", "model", "fit"}
        Where the analysis is made.
    seed : int
        Seed of the quick fit's global search.
    constants : mapping, optional
        Inputs held constant (SI units).
    columns : str or path, optional
        A column map for ``data`` given as a file.
    label : str, optional
        The data's name in titles and the JSON.
    hold : {"zoh", "foh"}, optional
        Inputs between samples; default the one the model was fitted with, else ``"zoh"``.

    Returns
    -------
    IdentifiabilityReport
        ``summary()`` is what ``rczone diagnose`` prints, ``to_dict()`` what its ``--json`` writes.
    """
    import dataclasses

    from rczone.diagnostics import diagnose as run

    validation.seed(seed)
    free = validation.name_list(free, "free") if free is not None else None
    sigma = validation.finite(sigma, "sigma")
    model_error = validation.finite(model_error, "model_error")
    zm = as_model(model)
    frame, name = frame_and_label(data, columns, zm)
    rep = run(
        zm,
        frame,
        free=list(free) if free else None,
        sigma_K=sigma,
        model_error_K=model_error,
        constants=dict(constants) if constants else None,
        operating_point=operating_point,
        hold=hold,
        seed=seed,
    )
    return dataclasses.replace(rep, data_label=label or name)


def read_for_models(
    source: PathLike,
    columns: PathLike | None,
    models: Sequence[ZoneModel],
    required: Sequence[str] | None = None,
) -> pd.DataFrame:
    """Data with every candidate's signals, read as ``rczone select`` reads them.

    Parameters
    ----------
    source : str or path
        A trend log or a built-in data set's name.
    columns : str or path, optional
        A column map.
    models : sequence of ZoneModel
        The candidates: the union of their signals is read.
    required : sequence of str, optional
        Columns that must exist; default every candidate's required signals.

    Returns
    -------
    DataFrame
    """
    from rczone.workflow.reader import read_frame

    signals: dict[str, str] = {}
    needed: list[str] = []
    for zm in models:
        signals.update(zm.signal_quantities())
        needed += [s for s in zm.required_signals() if s not in needed]
    outputs = list(dict.fromkeys(o for zm in models for o in zm.network.outputs))
    return read_frame(source, columns, signals, needed if required is None else list(required), outputs)


@single_threaded
def select_models(
    models: Sequence[ModelLike],
    data: pd.DataFrame | PathLike,
    *,
    criterion: str = "bic",
    forward: bool = False,
    alpha: float = 0.05,
    noise: str = "all",
    n_starts: int | None = None,
    seed: int = 0,
    constants: Mapping[str, float] | None = None,
    columns: PathLike | None = None,
    hold: str = "zoh",
    bounds: Mapping[str, tuple[float, float]] | None = None,
    free: Sequence[str] | None = None,
    fixed: Mapping[str, float | None] | None = None,
    label: str | None = None,
    holdout: str | float | None = None,
):
    """Fit candidate models to the same data by ML and choose one: ``rczone select`` in Python.

    Parameters
    ----------
    models : sequence of ZoneModel, str or path
        At least two candidates.
    data : DataFrame, str or path
        As for :func:`fit`; a file is read with every candidate's signals.
    criterion : {"bic", "aic"}
        Without ``forward``: the criterion to minimize.
    forward : bool
        Forward selection by likelihood-ratio tests along the nesting of the candidates.
    alpha : float
        Level of the tests.
    noise : {"all", "measured"}
        Process noise on every state (default, as the command) or on the measured ones.
    n_starts : int, optional
        Local searches per fit; default the global search.
    seed : int
        Seed of the global searches.
    constants : mapping, optional
        Inputs held constant (SI units).
    columns : str or path, optional
        A column map for ``data`` given as a file.
    hold : {"zoh", "foh"}
        Inputs between samples in every fit (``--hold``).
    bounds : mapping of str to (float, float), optional
        Search bounds (SI units) for the candidates that have the parameter (``--bounds``).
    free : sequence of str, optional
        ``"+NAME"`` entries added to every candidate's free set that has the parameter (``--free``).
    fixed : mapping of str to float or None, optional
        Parameters held at a value (None: the model's) in every candidate that has them (``--fix``).
    label : str, optional
        The data's name in titles and the JSON.
    holdout : str or float, optional
        Select on the data before this time or all but this last fraction, then score the selected
        model on the rest (``--holdout``; :attr:`Selection.holdout`); the held-out checks enter the
        selected fit's verdict and :attr:`Selection.exit_code`, as in :func:`fit`.

    Returns
    -------
    Selection
        ``summary()`` is what ``rczone select`` prints, ``to_dict()`` what its ``--json`` writes.
    """
    import dataclasses

    from rczone.selection import select_models as run
    from rczone.selection.text import fit_arguments

    validation.seed(seed)
    validation.finite(alpha, "alpha", low=0.0, high=1.0)
    if n_starts is not None:
        validation.integer(n_starts, "n_starts", low=1, besides="None (automatic) or ")
    if not isinstance(criterion, str):
        raise ParameterError(f"criterion must be 'bic' or 'aic', got {criterion!r}")
    zms = [as_model(m) for m in models]
    if isinstance(data, pd.DataFrame):
        frame, name, source = data, str(data.attrs.get("name", "data")), ""
    else:
        frame, name, source = read_for_models(data, columns, zms), Path(str(data)).name, str(data)
    settings = FitSettings(
        method="ml",
        free=free,
        fixed=dict(fixed or {}),
        bounds=dict(bounds or {}),
        hold=hold,
        n_starts=n_starts,
        seed=seed,
        noise=noise,
        constants=dict(constants or {}),
    )
    full, at = frame, None
    if holdout is not None:  # a split needs the time axis
        full = frame_from(frame)
        at = split_time(full, holdout, model=zms[0], columns=columns)
        frame = before(full, at)
    sel = run(zms, frame, settings, rule=criterion.strip().lower(), forward=forward, alpha=alpha)
    args = fit_arguments(sel, settings, columns=columns)
    if at is not None:  # the held-out checks enter the selected fit's verdict, as in fit
        from rczone.selection.compare import with_held_out

        sel = with_held_out(
            sel, score_held_out(sel.best.calibration.model, full, at, settings.constants, label or name)
        )
    return dataclasses.replace(sel, data_label=label or name, source=source, noise=noise, fit_args=args)


@single_threaded
def design_test(
    model: ModelLike,
    *,
    actuate: Mapping[str, tuple[float, float]],
    conditions: Mapping[str, float] | None = None,
    free: Sequence[str] | None = None,
    hours: float = 12.0,
    band: tuple[float, float] = (17.0, 28.0),
    min_hold: float = 30.0,
    initial: float | None = None,
    start: datetime.time | pd.Timestamp | None = datetime.time(18, 0),
):
    """A D-optimal forced-response test the building can run: ``rczone design`` in Python, SI units.

    Parameters
    ----------
    model : ZoneModel, str or path
        The zone's model; its values are the prior.
    actuate : mapping of str to (float, float)
        The inputs the test may drive and their ranges, SI units, e.g.
        ``{"Ts": (12, 35), "m": (0.02, 0.12)}`` or ``{"Ph": (0, 2000)}``.
    conditions : mapping of str to float, optional
        Expected values of the other inputs during the test, e.g. ``{"To": 18, "Tsd": 22}``.
    free : sequence of str, optional
        Parameters the test should identify; default the model's free R and C.
    hours : float
        Length of the test, h.
    band : (float, float)
        Allowed zone temperature, degC.
    min_hold : float
        Shortest hold of a command, min.
    initial : float, optional
        Zone temperature at the start, degC (default: the middle of the band).
    start : datetime.time or Timestamp, optional
        When the test starts (the schedule's clock column); default 18:00.

    Returns
    -------
    DesignResult
        ``summary()`` is what ``rczone design`` prints, ``to_frame()`` the schedule for the BMS.
    """
    import dataclasses

    from rczone.diagnostics.design import SI_UNIT, DesignLimits
    from rczone.diagnostics.design import design_test as run

    hours = validation.finite(hours, "hours", low=0.0)
    min_hold = validation.finite(min_hold, "min_hold", low=0.0)
    initial = None if initial is None else validation.temperature(initial, "initial")
    band = _pair(band, "band", validation.temperature)
    actuate = {
        k: _pair(v, f"actuate[{k!r}]", validation.finite)
        for k, v in validation.mapping(actuate, "actuate").items()
    }
    conditions = {
        k: validation.finite(v, f"conditions[{k!r}]")
        for k, v in validation.mapping(conditions or {}, "conditions").items()
    }
    free = validation.name_list(free, "free") if free is not None else None
    zm = as_model(model)
    net = zm.network
    names = (
        list(free)
        if free
        else [n for n in net.default_free if net.parameters[n].kind in ("resistance", "capacitance")]
    )
    limits = DesignLimits(dict(actuate), tuple(band), min_hold * 60.0)
    res = run(zm, names, hours * 3600.0, limits, conditions=conditions, ti0=initial)
    units = {a: SI_UNIT[res.quantities.get(a, "temperature")] for a in res.actuated}
    return dataclasses.replace(
        res, model_label=zm.label, start=start, display_units={**units, res.output: "degC"}
    )


def _pair(value: object, name: str, check) -> tuple[float, float]:
    """Two numbers ``(low, high)``, each passed through ``check(value, name)``."""
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or len(value) != 2:
        raise ParameterError(f"{name} must be a pair (low, high), got {value!r}")
    return check(value[0], name), check(value[1], name)
