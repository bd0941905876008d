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

MIN_MEASURED = 30
"""Fewest measured output samples a fit accepts (see :meth:`Dataset.check_fit_size`): the
residual whiteness test after a fit looks at up to 20 lags, and a fit of a few samples would
match anything."""


def time_text(t: float) -> str:
    """A time for messages: ``t = 420 s``, with the UTC date when ``t`` is an epoch time."""
    if 3.15e8 <= t <= 9.2e9:  # 1980 to 2261: Unix seconds
        stamp = np.datetime64(int(t), "s").astype(str)
        return f"t = {t:.10g} s ({stamp}Z)"
    return f"t = {t:g} s"


def _check_gaps(t: np.ndarray, arr: object, names: tuple[str, ...], what: str) -> None:
    """A missing input value is an error naming the channel, its first time and what to do."""
    a = np.asarray(arr, dtype=float)
    if a.ndim == 1 and len(names) == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape != (t.size, len(names)):
        return  # the shape error is check_inputs' to report
    bad = ~np.isfinite(a)
    for j in np.flatnonzero(bad.any(axis=0)):
        k = int(np.flatnonzero(bad[:, j])[0])
        raise DataError(
            f"{what} {names[j]!r} is missing (NaN or infinite) at {int(bad[:, j].sum())} of {t.size}"
            f" samples, first at {time_text(float(t[k]))} (sample {k}); inputs must be complete: fill the"
            " gap in the data, or fit a gap-free stretch (rczone.data.ZoneData.complete_segments)"
        )


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
    warnings : tuple of str
        Signals outside their plausible range in SI units (degF read as degC, ...), found where
        the data set was built (:func:`rczone.data.units.signal_warnings`); a fit to them is flagged.
    """

    t: np.ndarray
    u: np.ndarray
    m: np.ndarray
    y: np.ndarray
    input_names: tuple[str, ...]
    flow_names: tuple[str, ...] = ()
    output_names: tuple[str, ...] = ("Ti",)
    warnings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        t = check_time(self.t)
        n = t.size
        _check_gaps(t, self.u, tuple(self.input_names), "input")
        u = check_inputs(self.u, n, tuple(self.input_names), "u")
        no_flows = len(self.flow_names) == 0 and (self.m is None or np.size(self.m) == 0)
        m = np.zeros((n, 0)) if no_flows else self.m
        _check_gaps(t, m, tuple(self.flow_names), "flow")
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

    @property
    def n_measured(self) -> int:
        """Samples with every output measured (finite)."""
        return int(np.isfinite(self.y).all(axis=1).sum())

    def check_fit_size(self, n_free: int = 0) -> None:
        """Raise :class:`DataError` unless the data can support a fit of ``n_free`` parameters.

        A fit needs at least :data:`MIN_MEASURED` measured samples and more than twice as many
        as free parameters; fewer (a record of a few samples, or one almost all missing) would
        fit anything and then fail in the residual tests.
        """
        need = max(MIN_MEASURED, 2 * n_free + 1)
        if self.n_measured < need:
            raise DataError(
                f"only {self.n_measured} of {self.n_samples} samples have a measured"
                f" {', '.join(self.output_names)}; a fit of {n_free} parameter(s) needs at least {need}"
                " (rczone.estimation.data.MIN_MEASURED); use a longer record with fewer gaps"
            )

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
