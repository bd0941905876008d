"""Smoothed states of a stochastic RC model: the filter forward, the Rauch-Tung-Striebel pass back.

The filter gives the best estimate of every state from the measurements up to each sample; the
smoother [1]_ from all of them. For a node without a sensor (an envelope, a slab) this is the
estimate to compare with an embedded sensor, or to start a prediction from. The forward pass is
the compiled filter of :mod:`rczone.kernels.kalman` (it keeps the predicted and filtered means
and covariances); the backward pass is :func:`rczone.kernels.smoother.rts_smoother` with the
filter's own transition matrices.

References
----------
.. [1] H. E. Rauch, F. Tung, C. T. Striebel, "Maximum likelihood estimates of linear dynamic
   systems", AIAA Journal 3(8), 1965, 1445-1450.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.estimation.data import Dataset
from rczone.estimation.engines import filter_arrays
from rczone.estimation.kalman import FilterOutput, FilterProblem, kalman_filter_arrays
from rczone.kernels.arrays import StateMoments, writable
from rczone.kernels.smoother import rts_smoother
from rczone.network import RCNetwork
from rczone.results.protocol import Result, json_number


@dataclass(frozen=True, eq=False)
class SmootherOutput:
    """Smoothed means and covariances of every state, with the filter run they come from.

    Attributes
    ----------
    x : ndarray, shape (N, n)
        Smoothed means ``x_k|N``, K.
    P : ndarray, shape (N, n, n)
        Smoothed covariances ``P_k|N``, K^2.
    filtered : FilterOutput
        The forward pass (its ``x_filt``, ``P_filt`` are the filtered estimates).
    """

    x: np.ndarray
    P: np.ndarray
    filtered: FilterOutput

    @property
    def sd(self) -> np.ndarray:
        """Standard deviations of the smoothed states, shape (N, n), K."""
        return state_sd(self.P)

    @property
    def filtered_sd(self) -> np.ndarray:
        """Standard deviations of the filtered states, shape (N, n), K."""
        return state_sd(self.filtered.P_filt)


def state_sd(P: np.ndarray) -> np.ndarray:
    """Standard deviations of the states from covariances of shape (N, n, n); shape (N, n)."""
    return np.sqrt(np.clip(np.diagonal(P, axis1=1, axis2=2), 0.0, None))


def rts_smooth(problem: FilterProblem) -> SmootherOutput:
    """The compiled filter over ``problem``, then the Rauch-Tung-Striebel backward pass.

    Parameters
    ----------
    problem : FilterProblem
        As for :func:`rczone.estimation.kalman.kalman_filter_arrays`.

    Returns
    -------
    SmootherOutput
    """
    out = kalman_filter_arrays(problem)
    smoothed = rts_smoother(
        writable(problem.Phi),  # read-only arrays would compile a second specialization
        writable(problem.which, np.int64),
        StateMoments(out.x_pred, out.P_pred),
        StateMoments(out.x_filt, out.P_filt),
    )
    return SmootherOutput(smoothed.x, smoothed.P, out)


def smooth_states(
    network: RCNetwork, values: Mapping[str, float], data: Dataset, *, hold: str = "zoh"
) -> SmootherOutput:
    """Smoothed states of ``network`` with the parameter and noise values ``values`` on ``data``.

    Parameters
    ----------
    network : RCNetwork
    values : mapping of str to float
        The network's parameters and every noise level (``sigma_v``, process noise, initial
        spread), SI units; initial states where given, else those of the filter's prior.
    data : Dataset
    hold : {"zoh", "foh"}
        How the inputs vary between samples.

    Returns
    -------
    SmootherOutput
    """
    return rts_smooth(filter_arrays(network, values, data, hold))


@dataclass(frozen=True, eq=False, repr=False)
class SmoothedStates(Result):
    """The smoothed temperature of every node of a model on data, with its standard deviation.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time, s (as in the data).
    states : tuple of str
        The nodes (capacitive states).
    mean, sd : ndarray, shape (N, n)
        Smoothed means and standard deviations, K (degC for a mean).
    filtered_sd : ndarray, shape (N, n)
        The filter's standard deviations at the same samples, K.
    covariance : ndarray, shape (N, n, n)
        Smoothed covariances, K^2.
    index : DatetimeIndex, optional
        The samples' time stamps in the data's time zone (None without clock time).
    model_label, data_label : str
        Names of the model and the data.
    """

    t: np.ndarray
    states: tuple[str, ...]
    mean: np.ndarray
    sd: np.ndarray
    filtered_sd: np.ndarray
    covariance: np.ndarray
    index: pd.DatetimeIndex | None = None
    model_label: str = "model"
    data_label: str = "data"

    def to_frame(self) -> pd.DataFrame:
        """One column per node and one for its standard deviation (``<node>_sd``), by time stamp.

        Indexed by the data's time stamps; without clock time, a ``time`` column in seconds.
        """
        cols: dict[str, np.ndarray] = {}
        for i, s in enumerate(self.states):
            cols[s] = self.mean[:, i]
            cols[f"{s}_sd"] = self.sd[:, i]
        if self.index is not None:
            return pd.DataFrame(cols, index=self.index)
        return pd.DataFrame({"time": self.t, **cols})

    def _repr_line(self) -> str:
        return (
            f"{self.model_label} on {self.data_label}, {len(self.t)} samples, nodes {', '.join(self.states)}"
        )

    def summary_lines(self) -> list:
        """A line per node: its mean smoothed and filtered standard deviations."""
        from rczone.results.fit_text import esc

        return [
            f"{esc(self.data_label)}: {esc(s)} smoothed from {self.mean[:, i].min():.2f} to"
            f" {self.mean[:, i].max():.2f} degC, mean sd {np.mean(self.sd[:, i]):.3f} K (filtered"
            f" {np.mean(self.filtered_sd[:, i]):.3f} K)"
            for i, s in enumerate(self.states)
        ]

    def to_dict(self) -> dict:
        """The nodes' mean standard deviations, smoothed and filtered (the series are in :meth:`to_frame`)."""
        return {
            "model": self.model_label,
            "data": self.data_label,
            "samples": len(self.t),
            "mean_sd_K": {s: json_number(np.mean(self.sd[:, i])) for i, s in enumerate(self.states)},
            "mean_filtered_sd_K": {
                s: json_number(np.mean(self.filtered_sd[:, i])) for i, s in enumerate(self.states)
            },
        }
