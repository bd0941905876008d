"""Smoothed node temperatures of a fitted model on data: ``rczone.smooth``.

The hidden nodes of a model (an envelope, a slab) are estimated from every measurement, before
and after each sample, by the Rauch-Tung-Striebel smoother over the model's Kalman filter
(:mod:`rczone.estimation.smoother`): the estimate to compare with an embedded sensor, or to start
a prediction or a controller from.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import pandas as pd

from rczone.calibration import ModelLike, as_model, noise_values, prepare, time_index
from rczone.calibration.prediction import model_hold
from rczone.errors import DataError
from rczone.estimation.smoother import SmoothedStates, smooth_states
from rczone.kernels.blas import single_threaded
from rczone.network.stochastic import INITIAL_STATE, kind_of
from rczone.workflow.datasource import DataSource, frame_and_label

PathLike = str | os.PathLike


@single_threaded
def smooth(
    model: ModelLike,
    data: pd.DataFrame | PathLike | DataSource,
    *,
    constants: Mapping[str, float] | None = None,
    columns: PathLike | None = None,
    label: str | None = None,
) -> SmoothedStates:
    """Smoothed temperature of every node of ``model`` on ``data``, with its standard deviation.

    Parameters
    ----------
    model : ZoneModel, str or path
        A model with noise levels (fitted by ML or MAP and saved, or given them).
    data : DataFrame, str, path or DataSource
        As for :func:`rczone.fit`.
    constants : mapping, optional
        Inputs held constant (SI units).
    columns : str or path, optional
        A column map for ``data`` given as a file.
    label : str, optional
        The data's name in titles and the JSON.

    Returns
    -------
    SmoothedStates
        ``to_frame()``: one column per node and ``<node>_sd``, indexed by the data's time stamps.

    Raises
    ------
    DataError
        The model has no noise levels.
    """
    zm = as_model(model)
    frame, name = frame_and_label(data, columns, zm)
    # the initial state a fit found is that of its own data, not of these
    values = {k: v for k, v in noise_values(zm).items() if kind_of(k) != INITIAL_STATE}
    if not values:
        raise DataError(
            f"smoothing needs the model's noise levels and {zm.label} has none; fit it by ML"
            " (rczone fit --method ml --save-model ...)"
        )
    data_set = prepare(zm, frame, constants).dataset
    out = smooth_states(zm.network, {**zm.theta, **values}, data_set, hold=model_hold(zm))
    return SmoothedStates(
        data_set.t,
        zm.network.state_names,
        out.x,
        out.sd,
        out.filtered_sd,
        out.P,
        index=time_index(frame, data_set.t),
        model_label=zm.label,
        data_label=label or name,
    )
