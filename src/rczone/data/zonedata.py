"""The loaded record of one zone: SI channels on one time axis, with metadata.

:class:`ZoneData` is frozen and its arrays are read-only; selecting a segment returns a
new object. Everything inside is SI (degC, kg/s, W, s); ``t`` is UTC epoch seconds,
uniform when the column map asked for resampling, else as given. Missing values are NaN
and are listed in ``gaps``; :meth:`ZoneData.arrays` refuses them unless asked, because
the simulator and the costs need finite inputs (pick a gap-free stretch with
:meth:`ZoneData.complete_segments` and :meth:`ZoneData.select`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np

from rczone.data.quality import Gap
from rczone.data.segments import Segment, constant_segments, finite_segments, night_segments
from rczone.data.timestamps import to_local
from rczone.errors import DataError, did_you_mean


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class ZoneData:
    """Measured channels of one zone in SI units on one time axis.

    Attributes
    ----------
    t : ndarray, shape (N,)
        UTC epoch seconds, strictly increasing.
    values : ndarray, shape (N, k)
        Channel values in SI units; NaN where missing.
    channels : tuple of str, length k
        Channel names (``"Ti"``, ``"To"``, ``"Ts"``, ``"m"``, ``"Q"``, surroundings, ``"Tsd"``).
    units : mapping
        SI unit of each channel (``"degC"``, ``"kg/s"``, ``"W"``).
    source_units : mapping
        Unit each channel was declared in (``"degF"``, ``"cfm"``...); ``"derived"`` for Tsd.
    quantities : mapping
        ``"temperature"``, ``"flow"`` or ``"power"`` per channel.
    source : str
        Where the data came from (file name).
    timezone : str
        IANA time zone of the site (for night windows and display).
    night : tuple of str
        Local night window ``(start, end)``, ``"HH:MM"``.
    step : float or None
        Grid step (s) when resampled, else None.
    max_gaps : mapping
        Gap threshold used for each channel (s); ``inf`` for a constant.
    surroundings : tuple of str
        Channels whose mean is ``Tsd``.
    gaps : tuple of Gap
        Stretches without values, per channel.
    warnings : tuple of str
        Suspicious-but-usable findings (also emitted as :class:`RczoneWarning`).
    ignored : tuple of str
        Channels of the column map that the model the data were read for does not use (not loaded).
    """

    t: np.ndarray
    values: np.ndarray
    channels: tuple[str, ...]
    units: Mapping[str, str]
    source_units: Mapping[str, str]
    quantities: Mapping[str, str]
    source: str = "<data>"
    timezone: str = "UTC"
    night: tuple[str, str] = ("18:00", "06:00")
    step: float | None = None
    max_gaps: Mapping[str, float] = field(default_factory=dict)
    surroundings: tuple[str, ...] = ()
    gaps: tuple[Gap, ...] = ()
    warnings: tuple[str, ...] = field(default=())
    ignored: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        t = _readonly(self.t)
        v = _readonly(self.values)
        if t.ndim != 1 or v.ndim != 2 or v.shape != (t.size, len(self.channels)):
            raise DataError(
                f"ZoneData: values must have shape (len(t), len(channels)) = ({t.size}, {len(self.channels)}),"
                f" got {v.shape}"
            )
        if t.size > 1 and np.any(np.diff(t) <= 0):
            raise DataError("ZoneData: t must be strictly increasing")
        set_ = object.__setattr__
        set_(self, "t", t)
        set_(self, "values", v)
        for name in ("units", "source_units", "quantities", "max_gaps"):
            set_(self, name, MappingProxyType(dict(getattr(self, name))))
        set_(self, "gaps", tuple(self.gaps))
        set_(self, "warnings", tuple(self.warnings))

    def __len__(self) -> int:
        return int(self.t.size)

    def __repr__(self) -> str:
        span = f"{self.t[-1] - self.t[0]:g} s" if len(self) else "empty"
        return (
            f"ZoneData({self.source!r}, {len(self)} samples over {span}, channels={list(self.channels)},"
            f" gaps={len(self.gaps)}, warnings={len(self.warnings)})"
        )

    # ------------------------------------------------------------------ access
    def _index(self, name: str) -> int:
        if name in self.channels:
            return self.channels.index(name)
        raise DataError(
            f"channel {name!r} is not in the data from {self.source}; {did_you_mean(name, self.channels)}"
            f" (channels: {', '.join(self.channels)}); map it in the column map"
        )

    def channel(self, name: str) -> np.ndarray:
        """Values of one channel (read-only view), SI units, shape (N,)."""
        return self.values[:, self._index(name)]

    @property
    def is_uniform(self) -> bool:
        """True if the time steps are all equal (to 1e-9 relative)."""
        if len(self) < 3:
            return True
        dt = np.diff(self.t)
        return bool(np.all(np.abs(dt - dt[0]) <= 1e-9 * abs(dt[0])))

    def times(self):
        """The time axis as a time-zone-aware :class:`pandas.DatetimeIndex` in local time."""
        return to_local(self.t, self.timezone)

    def to_frame(self):
        """A copy as a :class:`pandas.DataFrame` in rczone's default columns.

        Column ``time`` (UTC epoch seconds) followed by the channels in SI units -- the
        layout :func:`~rczone.data.columnmap.default_column_map` reads, so the frame can be
        written to CSV and loaded again without a column map. ``attrs["ignored_channels"]`` lists
        :attr:`ignored`, when there are any.
        """
        import pandas as pd

        cols = {"time": np.array(self.t)}
        cols.update({n: np.array(self.values[:, k]) for k, n in enumerate(self.channels)})
        frame = pd.DataFrame(cols)
        if self.ignored:
            frame.attrs["ignored_channels"] = list(self.ignored)
        return frame

    def arrays(
        self,
        input_names: Sequence[str],
        flow_names: Sequence[str] = (),
        output: str | Sequence[str] = "Ti",
        *,
        min_samples: int = 2,
        allow_nan: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Time-first float arrays ordered as a model asks for them.

        Parameters
        ----------
        input_names : sequence of str
            E.g. ``net.input_names`` (``("To", "Tsd", "Ts", "Q")``).
        flow_names : sequence of str
            E.g. ``net.flow_names`` (``("m",)``).
        output : str or sequence of str
            Measured output channel(s), default ``"Ti"``.
        min_samples : int
            Fewer samples than this is an error (e.g. more than the number of parameters).
        allow_nan : bool
            Return NaN where values are missing instead of raising.

        Returns
        -------
        t : ndarray, shape (N,)
            UTC epoch seconds.
        u : ndarray, shape (N, len(input_names))
        m : ndarray, shape (N, len(flow_names))
        y : ndarray, shape (N, n_outputs)

        Raises
        ------
        DataError
            A requested channel is missing (close names suggested), values are missing
            and ``allow_nan`` is False, or there are fewer than ``min_samples`` samples.
        """
        outputs = (output,) if isinstance(output, str) else tuple(output)
        groups = (("input", tuple(input_names)), ("flow", tuple(flow_names)), ("output", outputs))
        idx = {what: [self._index(n) for n in names] for what, names in groups}
        if len(self) < min_samples:
            raise DataError(
                f"{self.source}: only {len(self)} samples, the model needs at least {min_samples};"
                " use a longer record or a larger segment"
            )
        if not allow_nan:
            for _, names in groups:
                for n in names:
                    x = self.channel(n)
                    bad = np.flatnonzero(~np.isfinite(x))
                    if bad.size:
                        first = self.times()[bad[0]]
                        raise DataError(
                            f"{self.source}: channel {n!r} has {bad.size} missing sample(s), first at"
                            f" {first.isoformat()}; select a gap-free stretch (complete_segments + select)"
                            " or pass allow_nan=True"
                        )
        t = np.array(self.t)
        u, m, y = (np.array(self.values[:, idx[w]]).reshape(len(self), -1) for w, _ in groups)
        return t, u, m, y

    # ---------------------------------------------------------------- segments
    def select(self, segment: Segment) -> ZoneData:
        """A new :class:`ZoneData` with the samples inside ``segment`` (inclusive)."""
        keep = segment.mask(self.t)
        gaps = tuple(g for g in self.gaps if g.end >= segment.start and g.start <= segment.end)
        return replace(self, t=self.t[keep], values=self.values[keep], gaps=gaps)

    def nights(self, start: str | None = None, end: str | None = None) -> list[Segment]:
        """Night windows of the record (default: the column map's, 18:00 to 06:00 local)."""
        if len(self) == 0:
            return []
        return night_segments(
            float(self.t[0]), float(self.t[-1]), self.timezone, start or self.night[0], end or self.night[1]
        )

    def constant_flow_segments(
        self, flow: str = "m", tolerance: float = 1e-3, min_duration: float = 3600.0
    ) -> list[Segment]:
        """Stretches where ``flow`` (kg/s) varies by at most ``tolerance`` for ``min_duration`` s or more."""
        return constant_segments(self.t, self.channel(flow), tolerance, min_duration)

    def complete_segments(self, names: Sequence[str], min_duration: float = 0.0) -> list[Segment]:
        """Gap-free stretches of the channels ``names``, at least ``min_duration`` s long.

        A stretch ends at a missing value or at a time step longer than the channels'
        gap threshold (``max_gaps``).
        """
        cols = [self._index(n) for n in names]
        step = min((self.max_gaps.get(n, np.inf) for n in names), default=np.inf)
        return finite_segments(self.t, self.values[:, cols], min_duration, max_step=step)
