"""The calibration workflow: data frame in, fitted model and its checks out.

This is the path shared by ``rczone fit``, ``rczone predict``, the demo and batch
calibration: pick the model's signals from a frame (deriving ``Tsd`` from the five
surroundings, holding ``Q`` constant when the data have none), fit, and validate the fitted
model open loop. The network is never modified; the fitted values live in a
:class:`~rczone.mpc.ZoneModel`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rczone.comparison import model_arrays
from rczone.estimation import Dataset, FitResult, fit
from rczone.estimation.validation import OpenLoopError, ResidualTest, ljung_box, open_loop_error
from rczone.mpc import ZoneModel
from rczone.network import RCNetwork

#: Free parameters by method when the user names none: the paper's reduced set, plus the
#: measurement and process noise for the likelihood methods.
DEFAULT_FREE = {
    "ls": ("Cr", "Rw"),
    "ml": ("Cr", "Rw", "sigma_v", "sigma_w_Ti"),
    "map": ("Cr", "Rw", "sigma_v", "sigma_w_Ti"),
}


def dataset(network: RCNetwork, frame: pd.DataFrame, constants: Mapping[str, float] | None = None) -> Dataset:
    """The network's signals from a frame in rczone's default columns."""
    t, u, m = model_arrays(network, frame, constants)
    y = frame[list(network.outputs)].to_numpy(float)
    return Dataset(
        t, u, m if m.shape[1] else None, y, network.input_names, network.flow_names, network.outputs
    )


def default_constants(frame: pd.DataFrame, network: RCNetwork) -> dict[str, float]:
    """The paper's Q = 50 W when the data carry no internal-gain column."""
    return {"Q": 50.0} if "Q" in network.input_names and "Q" not in frame else {}


def default_free(network: RCNetwork, method: str) -> tuple[str, ...]:
    """Default free parameters: the paper's set if the model has it, else every base R and C."""
    base = DEFAULT_FREE.get(method, DEFAULT_FREE["ls"])
    if all(n in network.parameters for n in ("Cr", "Rw")):
        return tuple(n for n in base if n in network.parameters or n.startswith("sigma_"))
    rc = tuple(
        n for n, p in network.parameters.items() if not p.is_tied and p.kind in ("resistance", "capacitance")
    )
    return rc + (("sigma_v", f"sigma_w_{network.state_names[0]}") if method != "ls" else ())


@dataclass(frozen=True, eq=False)
class Calibration:
    """A fit and its open-loop check on the calibration data."""

    result: FitResult
    model: ZoneModel
    open_loop: OpenLoopError
    residuals: ResidualTest


def calibrate(
    network: RCNetwork,
    frame: pd.DataFrame,
    method: str = "ls",
    free: Sequence[str] | None = None,
    optimizer: str = "nelder-mead",
    n_starts: int = 1,
    seed: int = 0,
    constants: Mapping[str, float] | None = None,
    provenance: Mapping[str, object] | None = None,
    uncertainty: bool = True,
) -> Calibration:
    """Fit ``network`` to ``frame`` and check the fitted model open loop."""
    constants = dict(default_constants(frame, network) if constants is None else constants)
    data = dataset(network, frame, constants)
    free = tuple(free) if free else default_free(network, method)
    rng = np.random.default_rng(seed)
    res = fit(
        network,
        data,
        free,
        method=method,
        optimizer=optimizer,
        n_starts=n_starts,
        rng=rng,
        uncertainty=uncertainty,
    )
    theta = {k: v for k, v in {**res.fixed, **res.estimates}.items() if k in network.parameters}
    noise = {k: v for k, v in {**res.fixed, **res.estimates}.items() if k not in network.parameters}
    model = ZoneModel(
        network,
        theta,
        {
            "method": method,
            "optimizer": optimizer,
            "free": list(free),
            "cost": res.cost,
            "rmse_K": res.rmse_K,
            "std_errors": {k: float(v) for k, v in res.std_errors.items()},
            "noise_and_initial_state": noise,
            "constants": constants,
            **dict(provenance or {}),
        },
    )
    ol = open_loop_error(network, theta, data)
    return Calibration(res, model, ol, ljung_box(ol.error[:, 0], n_lags=min(20, data.n_samples // 5)))


def predict(
    model: ZoneModel, frame: pd.DataFrame, constants: Mapping[str, float] | None = None
) -> OpenLoopError:
    """Open-loop simulation of a saved model on other data (starting at the measured Ti)."""
    if constants is None:
        constants = model.provenance.get("constants") or default_constants(frame, model.network)
    data = dataset(model.network, frame, constants)
    return open_loop_error(model.network, dict(model.theta), data)
