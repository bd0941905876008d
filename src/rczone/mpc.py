"""Models ready for model-predictive control: save, load, and matrices for a sample time.

A :class:`ZoneModel` is a network with parameter values and the provenance of those values
(construction data, or a fit: data, method, cost, standard errors). It writes to and reads
from a small JSON file, and gives the continuous or discrete LTI matrices at a chosen
mass flow (the bilinear model is LTI for constant flow), as plain numpy arrays or as a
python-control ``StateSpace`` (optional extra ``rczone[control]``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rczone import __version__
from rczone.atomic import write_json_atomic
from rczone.errors import DataError, RczoneError
from rczone.network import BilinearStateSpace, LinearStateSpace, RCNetwork
from rczone.network.serialize import network_from_dict, network_to_dict
from rczone.simulation import SimulationResult, foh, simulate, zoh

FORMAT = "rczone-model/1"


@dataclass(frozen=True, eq=False)
class DiscreteModel:
    """``x[k+1] = Ad x[k] + Bd u[k] (+ Bd1 u[k+1] for FOH)``, ``y[k] = C x[k] + D u[k]``."""

    Ad: np.ndarray
    Bd: np.ndarray
    Bd1: np.ndarray | None
    C: np.ndarray
    D: np.ndarray
    dt: float
    m: np.ndarray
    hold: str
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class ZoneModel:
    """A network with parameter values and where they came from."""

    network: RCNetwork
    theta: Mapping[str, float]
    provenance: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.network.values(self.theta)  # validate names and ranges now

    # ------------------------------------------------------------ matrices
    def state_space(self) -> BilinearStateSpace:
        """The bilinear state space at these parameter values."""
        return self.network.state_space(self.theta)

    def continuous(self, m: float | np.ndarray = 0.0) -> LinearStateSpace:
        """Continuous-time LTI model at constant flow ``m`` (kg/s)."""
        return self.state_space().lti(m)

    def discrete(self, dt: float, m: float | np.ndarray = 0.0, hold: str = "zoh") -> DiscreteModel:
        """Exact discrete-time model for sample time ``dt`` (s) at constant flow ``m``."""
        if not dt > 0:
            raise RczoneError("sample time dt must be > 0 s")
        c = self.continuous(m)
        if hold == "zoh":
            Ad, Bd = zoh(c.A, c.B, dt)
            Bd1 = None
        elif hold == "foh":
            Ad, Bd, Bd1 = foh(c.A, c.B, dt)
        else:
            raise RczoneError(f"hold must be 'zoh' or 'foh', got {hold!r}")
        return DiscreteModel(
            Ad,
            Bd,
            Bd1,
            c.C,
            c.D,
            float(dt),
            np.atleast_1d(np.asarray(m, float)),
            hold,
            c.state_names,
            c.input_names,
            c.output_names,
        )

    def arrays(self, m: float | np.ndarray = 0.0) -> dict[str, np.ndarray]:
        """Plain arrays ``A, B, C, D`` of the continuous model at flow ``m`` and ``N, M`` of the bilinear one."""
        ss = self.state_space()
        A, B = ss.matrices(m) if ss.n_flows else (ss.A, ss.B)
        return {"A": A, "B": B, "C": ss.C, "D": ss.D, "N": ss.N, "M": ss.M}

    def to_control(self, m: float | np.ndarray = 0.0, dt: float | None = None) -> Any:
        """A ``control.StateSpace`` (continuous, or discrete ZOH when ``dt`` is given)."""
        try:
            import control
        except ImportError:
            raise RczoneError(
                "python-control is not installed; install the extra: pip install 'rczone[control]'"
            ) from None
        c = self.continuous(m)
        kw = {"states": list(c.state_names), "inputs": list(c.input_names), "outputs": list(c.output_names)}
        if dt is None:
            return control.ss(c.A, c.B, c.C, c.D, **kw)
        d = self.discrete(dt, m)
        return control.ss(d.Ad, d.Bd, d.C, d.D, dt, **kw)

    def simulate(
        self, t: np.ndarray, u: np.ndarray, m: np.ndarray | None = None, x0: np.ndarray | None = None
    ) -> SimulationResult:
        """Simulate the model (see :func:`rczone.simulation.simulate`)."""
        return simulate(self.state_space(), t, u, m, x0)

    # ------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        units = {n: p.unit for n, p in self.network.parameters.items()}
        return {
            "format": FORMAT,
            "rczone_version": __version__,
            "network": network_to_dict(self.network),
            "theta": {k: float(v) for k, v in self.theta.items()},
            "units": units,
            "signals": {
                "states": list(self.network.state_names),
                "inputs": list(self.network.input_names),
                "flows": list(self.network.flow_names),
                "outputs": list(self.network.outputs),
            },
            "provenance": dict(self.provenance),
        }

    def save(self, path: str | os.PathLike) -> Path:
        """Write the model as JSON (atomically)."""
        return write_json_atomic(path, self.to_dict())

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> ZoneModel:
        if d.get("format") != FORMAT:
            raise DataError(f"not an rczone model file (format {d.get('format')!r}, expected {FORMAT!r})")
        return cls(network_from_dict(d["network"]), dict(d["theta"]), dict(d.get("provenance", {})))

    @classmethod
    def load(cls, path: str | os.PathLike) -> ZoneModel:
        """Read a model written by :meth:`save`."""
        p = Path(path)
        if not p.exists():
            raise DataError(f"model file {str(p)!r} does not exist")
        try:
            d = json.loads(p.read_text())
        except json.JSONDecodeError as exc:
            raise DataError(
                f"model file {str(p)!r} is not valid JSON: {exc.msg} at line {exc.lineno}"
            ) from None
        return cls.from_dict(d)
