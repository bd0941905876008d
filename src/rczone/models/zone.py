"""A zone model: an RC network with parameter values, input conventions and provenance.

A :class:`ZoneModel` is what a user hands to every command: a built-in model, a model file
(:mod:`rczone.models.modelfile`) or a model saved by a fit. It holds

* the frozen :class:`~rczone.network.RCNetwork` (its declared values are the construction
  values that priors and ratios refer to);
* ``theta``, the values of its base parameters (the declared ones, or a fit's estimates; a fit
  starts from them);
* :class:`ModelInputs`: how the model's inputs are found in data besides by name (a constant
  when the data have no such column, such as the paper's ``Q = 50 W``; a mean of several
  columns, such as ``Tsd`` of the surrounding rooms);
* ``noise``: noise levels a likelihood fit found (start values of a later fit);
* ``provenance``: where the values came from.

It gives the continuous or exact discrete LTI matrices at a chosen mass flow (the bilinear
model is LTI for constant flow), as plain numpy arrays or a python-control ``StateSpace``,
and reads and writes a small JSON file. Everything read from a file is validated: a model
with a non-finite element value, a malformed field or an impossible tie is an error that
names the field, never a model that predicts NaN.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
import pandas as pd

from rczone import __version__, validation
from rczone.errors import (
    DataError,
    InputShapeError,
    ModelFileError,
    ParameterError,
    RczoneError,
    did_you_mean,
)
from rczone.files.atomic import write_json_atomic
from rczone.network import BilinearStateSpace, LinearStateSpace, RCNetwork
from rczone.network.serialize import network_from_dict, network_to_dict
from rczone.network.stochastic import is_noise_name, is_reserved
from rczone.simulation import SimulationResult, simulate
from rczone.simulation.discretize import interval_discretization

FORMAT = "rczone-model/1"
#: What a controller does with an input (:attr:`ModelInputs.roles`).
INPUT_ROLES = ("actuator", "measured", "unmeasured")


@dataclass(frozen=True)
class ModelInputs:
    """How a model's inputs are found in data, besides a column of the same name.

    Attributes
    ----------
    defaults : mapping of input name to float
        Constant (SI units) used when the data have no such column, e.g. ``{"Q": 50.0}``.
    mean_of : mapping of input name to tuple of str
        Input computed as the mean of several columns when the data have no such column,
        e.g. ``{"Tsd": ("Tf", "Tc", "Tn1", "Tn2", "Thw")}``.
    descriptions : mapping of input name to str
        What the input is, used in messages when the data lack it.
    roles : mapping of input name to str
        What a controller does with the input (:data:`INPUT_ROLES`): ``actuator`` (it decides
        it: a heater's power, a supply flow), ``measured`` (a disturbance it measures or is
        forecast: outdoor temperature, irradiance) or ``unmeasured`` (a disturbance nobody
        measures: the model's default is used). Inputs not named have no declared role.
    """

    defaults: Mapping[str, float] = field(default_factory=dict)
    mean_of: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    descriptions: Mapping[str, str] = field(default_factory=dict)
    roles: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        d = {}
        for k, v in dict(self.defaults).items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
                raise ModelFileError(f"input {k!r}: default must be a finite number, got {v!r}")
            d[str(k)] = float(v)
        mo = {}
        for k, cols in dict(self.mean_of).items():
            if isinstance(cols, str) or not isinstance(cols, Sequence) or not cols:
                raise ModelFileError(f"input {k!r}: mean_of must be a non-empty list of column names")
            if not all(isinstance(c, str) and c for c in cols):
                raise ModelFileError(f"input {k!r}: mean_of must list column names (text)")
            mo[str(k)] = tuple(cols)
        object.__setattr__(self, "defaults", MappingProxyType(d))
        object.__setattr__(self, "mean_of", MappingProxyType(mo))
        object.__setattr__(self, "descriptions", MappingProxyType(dict(self.descriptions)))
        roles = dict(self.roles) if isinstance(self.roles, Mapping) else None
        if roles is None or not all(isinstance(r, str) and r in INPUT_ROLES for r in roles.values()):
            raise ModelFileError(
                f"input roles must map input names to one of {', '.join(INPUT_ROLES)}, got {self.roles!r}"
            )
        object.__setattr__(self, "roles", MappingProxyType({str(k): v for k, v in roles.items()}))

    def check_against(self, network: RCNetwork) -> None:
        """Every convention must name an input or flow of ``network``."""
        signals = (*network.input_names, *network.flow_names)
        for k in (*self.defaults, *self.mean_of, *self.roles):
            if k not in signals:
                raise ModelFileError(
                    f"input convention for {k!r}: model {network.name!r} has no such input; "
                    + did_you_mean(k, signals)
                )

    def to_dict(self) -> dict[str, Any]:
        return {
            "defaults": dict(self.defaults),
            "mean_of": {k: list(v) for k, v in self.mean_of.items()},
            "descriptions": dict(self.descriptions),
            "roles": dict(self.roles),
        }


def _describe(name: str, inputs: ModelInputs, network: RCNetwork) -> str:
    """A hint saying how to provide a missing input."""
    what = inputs.descriptions.get(name, "")
    parts = [f"model {network.name!r} needs input {name!r}" + (f" ({what})" if what else "")]
    if name in inputs.mean_of:
        cols = ", ".join(inputs.mean_of[name])
        parts.append(
            f"give a {name!r} column, or the columns {cols} (their mean is used), or map them in a"
            " column map's [surroundings] table"
        )
    elif name in network.flow_names:
        parts.append(f"give a {name!r} column (supply mass flow, kg/s; a column map converts cfm or L/s)")
    else:
        parts.append(
            f"give a {name!r} column, map one in a column map, or set a constant (--const {name}=...)"
        )
    return "; ".join(parts)


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


def _finite_matrices(what: str, *arrays: np.ndarray) -> None:
    for a in arrays:
        if a is not None and not np.all(np.isfinite(a)):
            raise RczoneError(f"{what} has non-finite entries; the model's values are not usable")


@dataclass(frozen=True, eq=False)
class ZoneModel:
    """A network with parameter values, input conventions and where the values came from.

    Parameters
    ----------
    network : RCNetwork
    theta : mapping, optional
        Base parameter values (SI); default the declared values.
    provenance : mapping, optional
        Where the values came from (method, data, cost...).
    inputs : ModelInputs, optional
    noise : mapping, optional
        Noise levels (``sigma_*``) a likelihood fit found.
    source : str
        Where the model was read from (a built-in name or a file), for reports.
    """

    network: RCNetwork
    theta: Mapping[str, float] = field(default_factory=dict)
    provenance: Mapping[str, Any] = field(default_factory=dict)
    inputs: ModelInputs = field(default_factory=ModelInputs)
    noise: Mapping[str, float] = field(default_factory=dict)
    source: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.network, RCNetwork):
            raise ModelFileError(f"network must be an RCNetwork, got {type(self.network).__name__}")
        theta = {
            n: p.value for n, p in self.network.parameters.items() if not p.is_tied and p.value is not None
        }
        given = validation.mapping(self.theta, "theta")
        theta.update({str(k): validation.number(v, f"parameter {k}") for k, v in given.items()})
        vals = self.network.values(theta)  # validates names, ranges and ties now
        self.inputs.check_against(self.network)
        for k, v in dict(self.noise).items():
            if not is_reserved(k) or not (
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            ):
                raise ModelFileError(f"noise value {k!r} = {v!r}: expected sigma_*/x0_* with a finite number")
            if is_noise_name(k) and not 0.0 <= v <= validation.MAX_NOISE:
                raise ModelFileError(
                    f"noise level {k!r} = {v:g}: expected a standard deviation from 0 to {validation.MAX_NOISE:g}"
                )
        object.__setattr__(self, "theta", MappingProxyType({k: float(vals[k]) for k in theta if k in vals}))
        object.__setattr__(self, "provenance", MappingProxyType(dict(self.provenance)))
        object.__setattr__(
            self, "noise", MappingProxyType({k: float(v) for k, v in dict(self.noise).items()})
        )
        # every element value must be usable: assemble once (raises on non-positive R, C)
        ss = self.network.state_space(self.theta)
        _finite_matrices(f"model {self.network.name!r}", ss.A, ss.B, ss.N, ss.M, ss.C, ss.D)

    @property
    def name(self) -> str:
        """The model's name (the network's)."""
        return self.network.name

    @property
    def label(self) -> str:
        """Short label for titles: the file name (not its folder), or the built-in name."""
        return Path(self.source).name if self.source else self.network.name

    def with_values(
        self, theta: Mapping[str, float], noise: Mapping[str, float] | None = None, **provenance: Any
    ) -> ZoneModel:
        """A copy with other parameter values (a fit's), same structure and conventions."""
        theta = validation.mapping(theta, "theta")
        noise = None if noise is None else validation.mapping(noise, "noise")
        return ZoneModel(
            self.network,
            {**self.theta, **theta},
            {**self.provenance, **provenance},
            self.inputs,
            dict(self.noise if noise is None else noise),
            self.source,
        )

    # ------------------------------------------------------------ data
    def signals(
        self, frame: pd.DataFrame, constants: Mapping[str, float] | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(t, u, m, y)`` of this model taken from a frame by name.

        Each input is, in this order of preference: a constant from ``constants``, the frame's
        column of that name, the mean of the columns of :attr:`ModelInputs.mean_of`, or the
        model's default constant (:attr:`ModelInputs.defaults`). Outputs are the columns named as
        the output nodes (NaN marks missing samples).

        Returns
        -------
        t : ndarray, shape (N,), s
        u : ndarray, shape (N, p), columns ``network.input_names``
        m : ndarray, shape (N, n_flows)
        y : ndarray, shape (N, ny)
        """
        net = self.network
        constants = self.check_constants(constants)
        if "time" not in frame:
            raise DataError(
                "the data have no 'time' column (seconds); " + did_you_mean("time", frame.columns)
            )
        cols = {}
        quantities = self.signal_quantities()
        for name in (*net.input_names, *net.flow_names):
            if name in constants:
                cols[name] = np.full(len(frame), float(constants[name]))
            elif name in frame:
                cols[name] = validation.within_limits(
                    validation.numeric_column(frame, name), name, quantities.get(name, "power")
                )
            elif name in self.inputs.mean_of and all(c in frame for c in self.inputs.mean_of[name]):
                means = [validation.numeric_column(frame, c) for c in self.inputs.mean_of[name]]
                cols[name] = np.mean(means, axis=0)
            elif name in self.inputs.defaults:
                cols[name] = np.full(len(frame), self.inputs.defaults[name])
            else:
                raise DataError(_describe(name, self.inputs, net) + "; " + did_you_mean(name, frame.columns))
        for o in net.outputs:
            if o not in frame:
                raise DataError(
                    f"model {net.name!r} measures {o!r}, but the data have no such column; "
                    + did_you_mean(o, frame.columns)
                    + " (map it in a column map)"
                )
        t = validation.time_axis(validation.numeric_column(frame, "time"))
        self.check_time_scales(validation.sampling_period(t))
        u = np.column_stack([cols[n] for n in net.input_names]) if net.input_names else np.zeros((len(t), 0))
        m = np.column_stack([cols[n] for n in net.flow_names]) if net.flow_names else np.zeros((len(t), 0))
        y = (
            np.column_stack([validation.numeric_column(frame, o) for o in net.outputs])
            if net.outputs
            else np.zeros((len(t), 0))
        )
        return t, u, m, y

    def check_time_scales(self, dt: float) -> None:
        """Refuse a latent force whose period is shorter than the sampling interval ``dt`` (s).

        A period below the interval is aliased (Shannon's sampling theorem): the data cannot tell it
        from a slower one, and the filter's discretization of a resonator that turns millions of
        times per sample takes minutes for a meaningless answer.
        """
        params = self.network.parameters
        for d in self.network.disturbances:
            if d.period is None:
                continue
            value = params[d.period].value if isinstance(d.period, str) else float(d.period)
            if not value >= dt:
                raise ParameterError(
                    f"disturbance {d.name!r}: period {value:g} s is shorter than the sampling interval"
                    f" {dt:g} s; the data cannot resolve it (give a period of at least two samples)"
                )

    def signal_quantities(self) -> dict[str, str]:
        """Quantity of every signal the model reads from data (for loading a trend log).

        Outputs, boundaries, supply temperatures and the columns of ``mean_of`` are temperatures,
        flows are flows, heat inputs powers (``W``) or irradiances (``W/m2``).
        """
        net = self.network
        out = {o: "temperature" for o in net.outputs}
        out.update({b: "temperature" for b in net.boundaries})
        out.update({s.temperature: "temperature" for s in net.supply_air})
        out.update({f: "flow" for f in net.flow_names})
        out.update({h.name: "power" if h.unit == "W" else "irradiance" for h in net.heat_inputs})
        for cols in self.inputs.mean_of.values():
            out.update({c: "temperature" for c in cols})
        return out

    def signal_roles(self) -> dict[str, str]:
        """Plausibility role (:data:`rczone.data.units.PLAUSIBLE`) of every signal the model reads.

        Outputs are room temperatures, supply temperatures supply-air temperatures, the channels
        rczone knows by name (:data:`rczone.data.columnmap.KNOWN_CHANNELS`) their own role (``To``
        outdoor, -60 to 60 degC), other boundaries any temperature (-60 to 100 degC): they are
        adjacent spaces as often as outdoor air, and an unconditioned attic under a desert sun
        reaches 61 degC (the EnergyPlus small office in Phoenix's July).
        """
        from rczone.data.columnmap import KNOWN_CHANNELS

        net = self.network
        roles = {b: KNOWN_CHANNELS.get(b, ("temperature", "temperature"))[1] for b in net.boundaries}
        roles.update({s.temperature: "supply" for s in net.supply_air})
        roles.update({o: "room" for o in net.outputs})
        roles.update({f: "flow" for f in net.flow_names})
        roles.update({h.name: "power" if h.unit == "W" else "irradiance" for h in net.heat_inputs})
        return roles

    def implausible_signals(self, u: np.ndarray, m: np.ndarray, y: np.ndarray) -> tuple[str, ...]:
        """One line per signal of :meth:`signals` outside its plausible range in SI units.

        Parameters
        ----------
        u, m, y : ndarray
            Inputs, flows and outputs as :meth:`signals` returns them.

        Returns
        -------
        tuple of str
            The findings of :func:`rczone.data.units.signal_warnings` (degF read as degC, ...).
        """
        from rczone.data.units import signal_warnings

        net = self.network
        named = {n: u[:, j] for j, n in enumerate(net.input_names)}
        named.update({n: m[:, j] for j, n in enumerate(net.flow_names)})
        named.update({n: y[:, j] for j, n in enumerate(net.outputs)})
        return signal_warnings(named, self.signal_roles())

    def required_signals(self) -> tuple[str, ...]:
        """Signals the data must have as columns: outputs, and inputs without a default or a mean."""
        net = self.network
        inputs = (*net.input_names, *net.flow_names)
        optional = {*self.inputs.defaults, *self.inputs.mean_of}
        return (*net.outputs, *(n for n in inputs if n not in optional))

    def check_constants(self, constants: Mapping[str, float] | None) -> dict[str, float]:
        """``constants`` if each names an input of the model; else one line naming the first that does not.

        A constant of an unknown name (a typo) or of an output would otherwise be ignored in silence.
        """
        constants = dict(validation.mapping(constants or {}, "constants"))
        inputs = (*self.network.input_names, *self.network.flow_names)
        quantities = self.signal_quantities()
        for name in constants:
            if name in inputs:
                constants[name] = validation.input_value(
                    constants[name], f"constant {name}", quantities.get(name, "power")
                )
                continue
            if name in self.network.outputs or name in self.network.state_names:
                raise ParameterError(
                    f"cannot hold {name!r} constant: it is a node or output of the model {self.label!r};"
                    f" constants are inputs ({', '.join(inputs) or 'none'})"
                )
            raise ParameterError(
                f"constant {name!r} is not an input of the model {self.label!r}; "
                + did_you_mean(name, inputs)
            )
        return constants

    def constants_used(
        self, frame: pd.DataFrame, constants: Mapping[str, float] | None = None
    ) -> dict[str, float]:
        """The inputs :meth:`signals` holds constant on ``frame`` (given or defaults), with their values."""
        constants = self.check_constants(constants)
        out = {}
        for name in (*self.network.input_names, *self.network.flow_names):
            if name in constants:
                out[name] = float(constants[name])
            elif (
                name not in frame
                and name in self.inputs.defaults
                and not (name in self.inputs.mean_of and all(c in frame for c in self.inputs.mean_of[name]))
            ):
                out[name] = self.inputs.defaults[name]
        return out

    # ------------------------------------------------------------ matrices
    def state_space(self) -> BilinearStateSpace:
        """The bilinear state space at these parameter values (built once: the model is immutable)."""
        ss = self.__dict__.get("_state_space")
        if ss is None:
            ss = self.__dict__["_state_space"] = self.network.state_space(self.theta)
        return ss

    def _flows(self, m: float | np.ndarray | None) -> np.ndarray:
        if m is None:
            if self.network.flow_names:
                raise InputShapeError(
                    f"model {self.name!r} has supply-air flow(s) {', '.join(self.network.flow_names)}: give the"
                    " operating flow m in kg/s (its matrices depend on it; zero would be a closed damper)"
                )
            m = 0.0
        arr = np.atleast_1d(np.asarray(m, dtype=float))
        nf = len(self.network.flow_names)
        if arr.shape != (nf,) and not (nf == 0 and arr.shape == (1,) and arr[0] == 0.0):
            raise InputShapeError(
                f"flow m must have {nf} value(s) for {list(self.network.flow_names)}, got {arr.tolist()}"
            )
        if not np.all(np.isfinite(arr)) or np.any(arr < 0):
            raise InputShapeError(f"flow m must be finite and >= 0 kg/s, got {arr.tolist()}")
        return arr

    def continuous(self, m: float | np.ndarray | None = None) -> LinearStateSpace:
        """Continuous-time LTI model at constant flow ``m`` (kg/s, finite, >= 0; required with a supply-air element)."""
        mm = self._flows(m)
        return self.state_space().lti(mm if self.network.flow_names else 0.0)

    def discrete(self, dt: float, m: float | np.ndarray | None = None, hold: str = "zoh") -> DiscreteModel:
        """Exact discrete-time model for sample time ``dt`` (s, finite, > 0) at constant flow ``m``.

        ``m`` (kg/s) is required when the model has a supply-air element, and ignored without one.
        """
        try:
            dt = float(dt)
        except (TypeError, ValueError):
            raise InputShapeError(f"sample time dt must be a number of seconds, got {dt!r}") from None
        if not (math.isfinite(dt) and dt > 0):
            raise InputShapeError(f"sample time dt must be finite and > 0 s, got {dt!r}")
        if hold not in ("zoh", "foh"):
            raise InputShapeError(f"hold must be 'zoh' or 'foh', got {hold!r}")
        c = self.continuous(m)
        # the exact spectral formulas of an RC network (a matrix exponential otherwise), on the kept state space
        ss = self.state_space()
        flows = self._flows(m) if self.network.flow_names else ()
        Phi, G0, G1, _ = interval_discretization(
            ss.A, ss.N, ss.B, ss.M, ss.capacities, np.array([[dt, *flows]]), hold
        )
        Ad, Bd, Bd1 = Phi[0], G0[0], (G1[0] if hold == "foh" else None)
        _finite_matrices(f"the discretization of {self.name!r} at dt = {dt:g} s", Ad, Bd, Bd1)
        return DiscreteModel(
            Ad,
            Bd,
            Bd1,
            c.C,
            c.D,
            dt,
            self._flows(m),
            hold,
            c.state_names,
            c.input_names,
            c.output_names,
        )

    def arrays(self, m: float | np.ndarray = 0.0) -> dict[str, np.ndarray]:
        """Plain arrays ``A, B, C, D`` of the continuous model at flow ``m`` and ``N, M`` of the bilinear one."""
        ss = self.state_space()
        A, B = ss.matrices(self._flows(m)) if ss.n_flows else (ss.A, ss.B)
        return {"A": A, "B": B, "C": ss.C, "D": ss.D, "N": ss.N, "M": ss.M}

    def to_control(self, m: float | np.ndarray | None = None, dt: float | None = None) -> Any:
        """A ``control.StateSpace`` (continuous, or discrete ZOH when ``dt`` is given).

        Parameters
        ----------
        m : float or array, optional
            The operating supply-air flow, kg/s, one per flow of the model: required when the model
            has a supply-air element (the bilinear term ``m cp (Ts - T)`` makes the linear model
            depend on it; a silent zero would be a closed damper). Ignored without one.
        dt : float, optional
            Sample time, s, for the exact ZOH discretization; None for continuous time.

        Returns
        -------
        control.StateSpace
            With the state, input and output names.
        """
        self._flows(
            m
        )  # the operating flow first: a missing one is the user's to fix, with or without control
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
            "noise": dict(self.noise),
            "inputs": self.inputs.to_dict(),
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
    def from_dict(cls, d: object, source: str = "") -> ZoneModel:
        """A model from the JSON form of :meth:`to_dict` (untrusted: every field is checked)."""
        where = f"model file {source}" if source else "model"
        if not isinstance(d, Mapping):
            raise ModelFileError(
                f"{where}: not an rczone model file (expected a JSON object, got {type(d).__name__})"
            )
        if d.get("format") != FORMAT:
            raise ModelFileError(
                f"{where}: not an rczone model file (format {d.get('format')!r}, expected {FORMAT!r})"
            )
        if "network" not in d:
            raise ModelFileError(f"{where}: has no 'network' (the model's structure)")
        theta = d.get("theta", {})
        if not isinstance(theta, Mapping) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in theta.values()
        ):
            raise ModelFileError(f"{where}: 'theta' must be an object of parameter values (numbers)")
        prov = d.get("provenance", {})
        if not isinstance(prov, Mapping):
            raise ModelFileError(f"{where}: 'provenance' must be an object")
        noise = d.get("noise")
        if noise is None:
            legacy = prov.get("noise_and_initial_state", {})
            noise = (
                {k: v for k, v in legacy.items() if is_reserved(k, noise_only=True)}
                if isinstance(legacy, Mapping)
                else {}
            )
        if not isinstance(noise, Mapping):
            raise ModelFileError(f"{where}: 'noise' must be an object")
        inp = d.get("inputs")
        try:
            if inp is None:  # files of rczone <= 0.1: constants used by the fit became defaults
                const = prov.get("constants") or {}
                inputs = ModelInputs(defaults=dict(const) if isinstance(const, Mapping) else {})
            elif isinstance(inp, Mapping):
                inputs = ModelInputs(
                    defaults=dict(inp.get("defaults") or {}),
                    mean_of={
                        k: tuple(v) if isinstance(v, list) else v
                        for k, v in (inp.get("mean_of") or {}).items()
                    },
                    descriptions=dict(inp.get("descriptions") or {}),
                    roles=dict(inp.get("roles") or {}),
                )
            else:
                raise ModelFileError("'inputs' must be an object")
            return cls(network_from_dict(d["network"]), dict(theta), dict(prov), inputs, dict(noise), source)
        except ModelFileError as exc:
            raise ModelFileError(f"{where}: {str(exc).removeprefix('model: ')}") from None
        except RczoneError as exc:
            raise ModelFileError(f"{where}: {exc}") from None
        except (TypeError, AttributeError, ValueError) as exc:
            raise ModelFileError(f"{where}: malformed ({exc})") from None

    @classmethod
    def load(cls, path: str | os.PathLike) -> ZoneModel:
        """Read a model written by :meth:`save` (any model file: :func:`rczone.models.load_model`)."""
        p = Path(path)
        return cls.from_dict(read_model_document(p, "JSON"), str(p))


def read_model_document(path: Path, kind: str) -> object:
    """The parsed document of a model file (``kind`` "TOML" or "JSON"), every read problem one line.

    The checks of :mod:`rczone.files.text` (a folder in place of the file, not UTF-8, too large,
    nested too deeply, not valid TOML or JSON) become :class:`ModelFileError`.
    """
    from rczone.files.text import nfkc, read_json, read_toml

    try:
        # names in one Unicode form (NFKC), as Python reads the ties' identifiers
        return nfkc(read_toml(path, "model file") if kind == "TOML" else read_json(path, "model file"))
    except FileNotFoundError:
        raise ModelFileError(f"model file {str(path)!r} does not exist") from None
    except ModelFileError:
        raise
    except DataError as exc:
        raise ModelFileError(str(exc)) from None
