"""A minimal measured data set for estimation: time, inputs, flows and outputs as arrays.

This is deliberately small (arrays + names); loading files and converting units is the
job of the data package. Inputs and flows must be finite; outputs may contain NaN
(missing measurements, skipped by the costs).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rczone.errors import DataError, InputShapeError, did_you_mean
from rczone.network import RCNetwork
from rczone.simulation.intervals import interval_groups, interval_keys, unique_rows
from rczone.simulation.simulate import check_inputs, check_time


@dataclass(frozen=True, eq=False)
class Dataset:
    """Sampled measurements in SI units, time-first.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sample times, s, strictly increasing (irregular spacing allowed).
    u : ndarray, shape (N, p)
        Inputs (temperatures in degC or K, heat flows in W), columns ``input_names``.
    m : ndarray, shape (N, n_flows)
        Mass flows, kg/s, held constant from ``t[k]`` to ``t[k+1]``, columns ``flow_names``
        (``None`` when there are no flows).
    y : ndarray, shape (N, ny)
        Measured outputs; NaN marks a missing sample.
    input_names, flow_names, output_names : tuple of str
    """

    t: np.ndarray
    u: np.ndarray
    m: np.ndarray
    y: np.ndarray
    input_names: tuple[str, ...]
    flow_names: tuple[str, ...] = ()
    output_names: tuple[str, ...] = ("Ti",)

    def __post_init__(self) -> None:
        t = check_time(self.t)
        n = t.size
        u = check_inputs(self.u, n, tuple(self.input_names), "u")
        no_flows = len(self.flow_names) == 0 and (self.m is None or np.size(self.m) == 0)
        m = np.zeros((n, 0)) if no_flows else self.m
        m = check_inputs(m, n, tuple(self.flow_names), "m")
        y = np.asarray(self.y, dtype=float)
        if y.ndim == 1 and len(self.output_names) == 1:
            y = y[:, None]
        if y.shape != (n, len(self.output_names)):
            raise InputShapeError(
                f"y must have shape (n_samples, {len(self.output_names)}) = ({n}, {len(self.output_names)})"
                f" for outputs {list(self.output_names)}, got {y.shape}"
            )
        if np.isinf(y).any():
            raise InputShapeError("y has infinite values; mark missing samples with NaN")
        if np.isnan(y).all():
            raise DataError("y has no measured value (all NaN)")
        for name, arr in (("t", t), ("u", u), ("m", m), ("y", y)):
            arr = arr.copy()
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        for name in ("input_names", "flow_names", "output_names"):
            object.__setattr__(self, name, tuple(getattr(self, name)))

    @property
    def n_samples(self) -> int:
        return self.t.size

    @cached_property
    def interval_groups(self) -> np.ndarray | None:
        """Intervals sharing length and flows (:func:`rczone.simulation.intervals.interval_groups`)."""
        return interval_groups(self.t, self.m)

    @cached_property
    def intervals(self) -> tuple[np.ndarray, np.ndarray]:
        """``(keys, which)``: the distinct ``(dt, m)`` rows, shape (K, 1 + n_flows), and the row of each interval.

        Every interval's discrete matrices depend only on its key, so each is computed once.
        """
        keys, _, which = unique_rows(interval_keys(self.t, self.m))
        for arr in (keys, which):
            arr.setflags(write=False)
        return np.ascontiguousarray(keys), np.ascontiguousarray(which, dtype=np.int64)

    def check_against(self, network: RCNetwork) -> None:
        """Raise :class:`InputShapeError` unless the columns match the network's signals."""
        for what, mine, theirs in (
            ("inputs", self.input_names, network.input_names),
            ("flows", self.flow_names, network.flow_names),
            ("outputs", self.output_names, network.outputs),
        ):
            if mine != tuple(theirs):
                raise InputShapeError(
                    f"data {what} {list(mine)} do not match network {network.name!r} {what} {list(theirs)}"
                    " (same names, same order expected); build the data with Dataset.from_frame(df, network)"
                )

    def subset(self, start: int, stop: int) -> Dataset:
        """Samples ``start:stop`` as a new data set."""
        sl = slice(start, stop)
        return Dataset(
            self.t[sl],
            self.u[sl],
            self.m[sl],
            self.y[sl],
            self.input_names,
            self.flow_names,
            self.output_names,
        )

    @classmethod
    def from_frame(cls, df, network: RCNetwork, time: str | None = None) -> Dataset:
        """Pick the network's signals out of a :class:`pandas.DataFrame`.

        Parameters
        ----------
        df : pandas.DataFrame
            One column per input, flow and output (named as in the network), SI units.
        network : RCNetwork
        time : str, optional
            Column holding the time in s; default the index (numeric seconds, or a
            DatetimeIndex converted to seconds since the first sample).
        """
        import pandas as pd

        needed = (*network.input_names, *network.flow_names, *network.outputs)
        cols = list(df.columns)
        for c in needed:
            if c not in cols:
                raise DataError(
                    f"data frame has no column {c!r} needed by network {network.name!r}; "
                    + did_you_mean(c, cols)
                )
        if time is not None:
            if time not in cols:
                raise DataError(f"no time column {time!r}; " + did_you_mean(time, cols))
            t = df[time].to_numpy(dtype=float)
        elif isinstance(df.index, pd.DatetimeIndex):
            t = (df.index - df.index[0]).total_seconds().to_numpy()
        else:
            t = df.index.to_numpy(dtype=float)
        return cls(
            t=t,
            u=df[list(network.input_names)].to_numpy(dtype=float),
            m=df[list(network.flow_names)].to_numpy(dtype=float).reshape(len(df), len(network.flow_names)),
            y=df[list(network.outputs)].to_numpy(dtype=float),
            input_names=network.input_names,
            flow_names=network.flow_names,
            output_names=network.outputs,
        )
