"""Compare model orders in the time and frequency domain (Lin et al. 2012 [1]_, section III).

Time domain (the paper's Fig. 4): every model is simulated open loop on the measured inputs of
a data set and compared with the measured room temperature. Frequency domain (Figs. 5, 6): the
LTI case at a fixed flow; gains from the supply temperature ``Ts`` and from the surroundings
(for a model with separate surroundings, the sum of their responses, eq. 6), and the weighted
gain error of each low-order model against the reference model (eq. 7).

Analyses return data objects; plotting lives in :mod:`rczone.report.figures`.

References
----------
.. [1] Lin, Middelkoop, Barooah, IEEE CDC 2012, section III.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.errors import DataError, did_you_mean
from rczone.models.paper import SURROUNDINGS
from rczone.network import RCNetwork
from rczone.simulation import simulate
from rczone.simulation.frequency import FrequencyResponse, frequency_response, gain_error
from rczone.simulation.initial import output_consistent_state


def model_arrays(
    network: RCNetwork, frame: pd.DataFrame, constants: Mapping[str, float] | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time (s), inputs and flows of ``network`` taken by name from a data frame.

    Parameters
    ----------
    constants : mapping, optional
        Inputs held at a constant value instead of read from the frame (the paper's Q = 50 W).
    """
    constants = dict(constants or {})
    cols = {}
    for name in (*network.input_names, *network.flow_names):
        if name in constants:
            cols[name] = np.full(len(frame), float(constants[name]))
        elif name == "Tsd" and name not in frame and all(s in frame for s in SURROUNDINGS):
            cols[name] = frame[list(SURROUNDINGS)].to_numpy(float).mean(axis=1)
        elif name in frame:
            cols[name] = frame[name].to_numpy(float)
        else:
            raise DataError(
                f"model {network.name!r} needs input {name!r}, not in the data; "
                + did_you_mean(name, frame.columns)
            )
    t = frame["time"].to_numpy(float)
    u = np.column_stack([cols[n] for n in network.input_names])
    m = (
        np.column_stack([cols[n] for n in network.flow_names])
        if network.flow_names
        else np.zeros((len(t), 0))
    )
    return t, u, m


@dataclass(frozen=True, eq=False)
class TimeComparison:
    """Open-loop predictions of several models on one data set.

    Attributes
    ----------
    t : ndarray, shape (N,)
    measured : ndarray, shape (N,)
    predicted : dict of model name to ndarray, shape (N,)
    """

    label: str
    t: np.ndarray
    measured: np.ndarray
    predicted: dict[str, np.ndarray]

    def rmse(self) -> dict[str, float]:
        """Root-mean-square error of each model, K."""
        return {k: float(np.sqrt(np.nanmean((v - self.measured) ** 2))) for k, v in self.predicted.items()}

    def max_error(self) -> dict[str, float]:
        """Largest absolute error of each model, K."""
        return {k: float(np.nanmax(np.abs(v - self.measured))) for k, v in self.predicted.items()}

    def max_difference_to(self, reference: str) -> dict[str, float]:
        """Largest absolute difference of each model's prediction from ``reference``'s, K."""
        ref = self.predicted[reference]
        return {k: float(np.max(np.abs(v - ref))) for k, v in self.predicted.items() if k != reference}


def compare_time(
    models: Mapping[str, RCNetwork],
    frame: pd.DataFrame,
    label: str = "",
    constants: Mapping[str, float] | None = None,
    thetas: Mapping[str, Mapping[str, float]] | None = None,
) -> TimeComparison:
    """Simulate each model open loop on the inputs of ``frame`` and compare with its ``Ti``.

    Each simulation starts with ``Ti`` at its first measured value and the walls in
    equilibrium (:func:`rczone.simulation.initial.output_consistent_state`).
    """
    y = frame["Ti"].to_numpy(float)
    preds = {}
    for name, net in models.items():
        t, u, m = model_arrays(net, frame, constants)
        ss = net.state_space((thetas or {}).get(name))
        x0 = output_consistent_state(ss, u[0], m[0] if m.shape[1] else 0.0, y[0])
        preds[name] = simulate(ss, t, u, m if m.shape[1] else None, x0=x0).y[:, 0]
    return TimeComparison(label, frame["time"].to_numpy(float), y, preds)


@dataclass(frozen=True, eq=False)
class FrequencyComparison:
    """Gains and weighted gain errors of models against a reference (Lin et al. 2012, eqs. (6)-(7)).

    Attributes
    ----------
    freq_hz : ndarray, shape (K,)
    gains : dict model -> dict input -> ndarray (K,)
        ``|H|`` from ``Ts``, ``Tsd`` (summed surroundings) and ``To``.
    errors : dict model -> dict input -> ndarray (K,)
        ``e_i(w)`` in K for every model but the reference.
    du : dict input -> float
        Largest variation of each input used as weight, K.
    """

    freq_hz: np.ndarray
    m: float
    reference: str
    gains: dict[str, dict[str, np.ndarray]]
    errors: dict[str, dict[str, np.ndarray]]
    du: dict[str, float]

    def max_errors(self) -> dict[str, dict[str, float]]:
        """Largest error over the band for each model and input, K."""
        return {k: {i: float(e.max()) for i, e in v.items()} for k, v in self.errors.items()}


def _common_inputs(fr: FrequencyResponse) -> FrequencyResponse:
    if all(s in fr.input_names for s in SURROUNDINGS):
        return fr.summed({"Tsd": list(SURROUNDINGS)})
    return fr


def compare_frequency(
    models: Mapping[str, RCNetwork],
    reference: str,
    du: Mapping[str, float],
    m: float = 0.12,
    freq_hz: np.ndarray | None = None,
) -> FrequencyComparison:
    """Gains and the paper's weighted error (eq. 7) of every model against ``reference``.

    Parameters
    ----------
    du : mapping of input name ("Ts", "Tsd", "To") to its largest variation in the data, K.
    m : float
        Constant flow of the LTI case, kg/s (the paper: the largest, 0.12 kg/s).
    freq_hz : ndarray, optional
        Default: 200 points log-spaced over 1e-5..1e-3 Hz.
    """
    if reference not in models:
        raise DataError(f"reference model {reference!r} is not among {list(models)}")
    f = np.logspace(-5, -3, 200) if freq_hz is None else np.asarray(freq_hz, float)
    frs = {k: _common_inputs(frequency_response(net.state_space().lti(m), f)) for k, net in models.items()}
    gains = {k: {i: np.abs(fr.to_input(i)) for i in du} for k, fr in frs.items()}
    errors = {k: gain_error(frs[reference], fr, du) for k, fr in frs.items() if k != reference}
    return FrequencyComparison(f, m, reference, gains, errors, {k: float(v) for k, v in du.items()})


def input_variation(
    frames: Sequence[pd.DataFrame], inputs: Sequence[str] = ("Ts", "Tsd", "To")
) -> dict[str, float]:
    """Largest variation of each input within any one data set, the paper's ``du`` (eq. 7).

    For ``Tsd``, when the frames hold the five surroundings, the largest range of any one of
    them is used, since each surrounding input can move by that much.
    """
    out = {}
    for name in inputs:
        ranges = []
        for f in frames:
            cols = list(SURROUNDINGS) if name == "Tsd" and all(s in f for s in SURROUNDINGS) else [name]
            for c in cols:
                v = f[c].to_numpy(float)
                ranges.append(np.nanmax(v) - np.nanmin(v))
        out[name] = float(max(ranges))
    return out
