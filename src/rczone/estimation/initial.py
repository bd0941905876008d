"""The initial temperatures of a model's unmeasured nodes, estimated from the data it is to predict.

References
----------
.. [1] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999,
   section 16.6 (model validation: the initial condition of a simulation on validation data).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rczone.estimation.costs import initial_state, measured_states, network_theta
from rczone.estimation.data import Dataset
from rczone.network import RCNetwork
from rczone.network.stochastic import initial_state_names
from rczone.simulation.simulate import propagate, transition_matrices

#: Prior standard deviation (K) of an unmeasured node's initial temperature around its conditional
#: steady state, for a model without its own ``sigma_x0_<state>``.
INITIAL_STATE_PRIOR_K = 1.0


@dataclass(frozen=True)
class InitialStateEstimate:
    """Initial temperatures of a model's nodes estimated from the data it is to predict.

    Attributes
    ----------
    values : dict
        ``x0_<state>`` of every state: measured states at their first measurement, the others
        estimated.
    steady : dict
        The conditional steady state the unmeasured ones would otherwise start at (``x0_<state>``).
    sd : dict
        Posterior standard deviation of each estimated one (``x0_<state>``), K.
    """

    values: dict[str, float]
    steady: dict[str, float]
    sd: dict[str, float]


def estimate_initial_state(
    network: RCNetwork,
    values: Mapping[str, float],
    data: Dataset,
    noise_sd: Sequence[float],
    prior_sd: Mapping[str, float],
    hold: str = "zoh",
) -> InitialStateEstimate:
    """The unmeasured nodes' initial temperatures that best explain the open-loop error.

    The open-loop output is affine in the initial state, so its response to each unmeasured
    node's initial temperature is exact from one simulation per node. The estimate is the
    maximum a posteriori one under the Gaussian prior ``N(x_ss, prior_sd^2)`` around the
    conditional steady state of :func:`~rczone.estimation.engines.auto_initial_state` and
    measurement errors of ``noise_sd`` per output, neglecting process noise: regularized linear
    least squares. The prior keeps directions the data do not determine (two boards of one wall
    moving in opposite directions) at the steady state. The open-loop error is mostly model error
    and accumulated process noise, not measurement noise, so a second pass weighs each output by
    the larger of ``noise_sd`` and the RMS error the first estimate leaves (the standard deviations
    stay optimistic where that error is autocorrelated). Estimating the initial condition of an
    open-loop simulation on validation data is the usual practice of model validation
    (Ljung 1999, section 16.6): a slow node's unknown starting temperature otherwise shows as a
    bias that lasts its time constant.

    Parameters
    ----------
    network : RCNetwork
    values : mapping
        Base parameter values (``x0_*`` entries are ignored).
    data : Dataset
    noise_sd : sequence of float
        Standard deviation of each output's error around the simulation, K.
    prior_sd : mapping
        State name to the prior standard deviation of its initial temperature, K.
    """
    ss = network.state_space(network_theta(network, values))
    x_ss = initial_state(ss, {}, data)
    names = initial_state_names(ss.state_names)
    measured = measured_states(ss)
    free = [i for i in range(ss.n_states) if i not in measured]
    steady = {names[i]: float(x_ss[i]) for i in free}
    if not free:
        return InitialStateEstimate(dict(zip(names, map(float, x_ss), strict=True)), steady, {})
    # discretized once: the output from x_ss, and the response to each unit initial temperature
    # (inputs zero; the flows still set the matrices)
    Phi, G0, G1, which = transition_matrices(ss, data.t, data.m, hold)
    y0 = propagate(Phi, G0, G1, which, data.u, x_ss) @ ss.C.T + data.u @ ss.D.T
    zero = np.zeros_like(data.u)
    eye = np.eye(ss.n_states)
    psi = np.stack(
        [propagate(Phi, G0, G1, which, zero, eye[i]) @ ss.C.T for i in free], axis=-1
    )  # (N, ny, k)
    p = np.array([1.0 / prior_sd[ss.state_names[i]] for i in free])
    level = np.asarray(noise_sd, dtype=float)
    for _ in range(2):  # the second pass weighs the outputs by what the start leaves unexplained
        w = 1.0 / level
        e = (data.y - y0) * w
        ok = np.isfinite(e)
        lhs = np.vstack([(psi * w[None, :, None])[ok], np.diag(p)])
        rhs = np.concatenate([e[ok], np.zeros(len(free))])
        delta = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
        rest = data.y - y0 - psi @ delta
        level = np.maximum(level, np.sqrt(np.nanmean(rest**2, axis=0)))
    cov = np.linalg.pinv(lhs.T @ lhs)
    x = x_ss.copy()
    x[free] += delta
    sd = {names[i]: float(math.sqrt(max(cov[j, j], 0.0))) for j, i in enumerate(free)}
    return InitialStateEstimate(dict(zip(names, map(float, x), strict=True)), steady, sd)
