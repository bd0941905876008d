"""The plausibility of a fit judged against a floor area (``rczone fit --floor-area``).

:func:`rczone.calibration.calibrate` judges the fitted UA and time constants against the values
the user declared (:mod:`rczone.models.plausibility`); with the zone's heated floor area they are
judged against documented ranges per m2 instead, and the message says so.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from rczone.models import ZoneModel
from rczone.models.plausibility import operating_flow, plausibility


def with_floor_area(cal, guess: ZoneModel, frame: pd.DataFrame, floor_area: float):
    """``cal`` with its plausibility judged against the reference ranges of ``floor_area`` m2.

    Parameters
    ----------
    cal : Calibration
        A fit with its analyses (``cal.plausibility`` set).
    guess : ZoneModel
        The model before the fit.
    frame : DataFrame
        The data it was fitted to (the mean supply-air flow is the operating point).
    floor_area : float
        Heated floor area, m2.

    Returns
    -------
    Calibration
    """
    net = cal.model.network
    m = np.column_stack([frame[f].to_numpy(float) for f in net.flow_names]) if net.flow_names else None
    flow = operating_flow(m, net.flow_names)
    judged = plausibility(cal.model, guess, flow=flow, floor_area=floor_area)
    return dataclasses.replace(cal, plausibility=judged)
