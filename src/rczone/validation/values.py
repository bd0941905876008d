"""Checks of the values a user hands in, shared by the command line and the Python API.

The command line parses an option and the API takes a keyword; both then call the function here,
so a value the command refuses is refused by the API with the same line (issue 39 found the API
passing negative seeds to NumPy, a trillion prediction steps to the filter and non-finite initial
temperatures to the simulation, all of which the command refused). Each function returns the
value it checked, converted (an ``int``, a ``float``, a float array), or raises an
:class:`~rczone.errors.RczoneError` naming the argument, what was expected and what was given.

The limits are physical, not statistical: a temperature above absolute zero and below
:data:`MAX_TEMPERATURE`, a mass flow, a power and an irradiance below magnitudes no building
reaches by orders of magnitude (:data:`INPUT_LIMITS`), and a record shorter than
:data:`MAX_SPAN` (past these the discretization's exponentials overflow, Moler & Van Loan 2003,
and the results are NaN without a word). This module imports nothing of rczone but its errors, so
every layer may call it.

References
----------
Moler, C. & Van Loan, C. (2003). Nineteen dubious ways to compute the exponential of a matrix,
twenty-five years later. *SIAM Review* 45(1), 3-49.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rczone.errors import DataError, ParameterError, printable

#: Seeds NumPy's generators take: 0 <= seed < 2**63.
SEED_LIMIT = 2**63

#: Absolute zero, degC.
ABSOLUTE_ZERO = -273.15

#: Highest temperature (degC) rczone computes with: far above any building's, far below overflow.
MAX_TEMPERATURE = 1.0e4

#: Largest magnitude of an input, SI units, by quantity (a constant, an initial state).
INPUT_LIMITS = {"temperature": MAX_TEMPERATURE, "flow": 1.0e4, "power": 1.0e9, "irradiance": 1.0e5}

#: Largest noise level (a standard deviation, SI units) a model may carry: its square stays finite.
MAX_NOISE = 1.0e6

#: Longest record, s (a century): a longer time axis is a unit mistake or a corrupt stamp.
MAX_SPAN = 100 * 365.25 * 86400.0


def integer(
    value: object, name: str, *, low: int | None = None, high: int | None = None, besides: str = ""
) -> int:
    """``value`` as an ``int`` within ``[low, high]``; bools, floats and text are refused.

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        The argument's name as the user wrote it (``"seed"``, ``"--steps"``).
    low, high : int, optional
        Inclusive limits.
    besides : str
        What else the argument may be, for the message (``"None (automatic) or "``).

    Returns
    -------
    int
    """
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    n = int(value) if ok else 0  # type: ignore[arg-type]
    if not ok or (low is not None and n < low) or (high is not None and n > high):
        top = "2**63 - 1" if high == SEED_LIMIT - 1 else f"{high:,}" if high is not None else ""
        span = (
            f"from {low} to {top}"
            if low is not None and high is not None
            else f">= {low}"
            if low is not None
            else f"<= {high}"
        )
        shown = printable(repr(value))[:60]
        raise ParameterError(f"{name} must be {besides}an integer {span}, got {shown}")
    return n


def seed(value: object, name: str = "seed") -> int:
    """A seed of a random generator: an integer from 0 to 2**63 - 1 (NumPy takes no negative seed).

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        The argument's name (``"seed"``, ``"--seed"``).
    """
    return integer(value, name, low=0, high=SEED_LIMIT - 1)


def ascii_count(text: str) -> int | None:
    """``text`` as a count when it is ASCII digits only (``"3"``), else None (``"²"``, ``"٣"``, ``"a,b"``).

    ``str.isdigit`` is true for superscripts and other scripts' digits, which ``int`` then refuses
    or reads as a number the user did not type.
    """
    t = text.strip()
    return int(t) if t and t.isascii() and t.isdigit() else None


def steps_ahead(steps: object, n_samples: int, name: str = "steps") -> int:
    """A prediction horizon in samples: a positive integer less than the ``n_samples`` of the data.

    Parameters
    ----------
    steps : object
        What the user gave.
    n_samples : int
        Samples the prediction scores; a horizon as long leaves none to predict.
    name : str
        The argument's name.
    """
    k = integer(steps, name, low=1)
    if k >= n_samples:
        raise ParameterError(
            f"{name} {k} is not less than the {n_samples} samples scored: no sample would be predicted;"
            " give fewer steps"
        )
    return k


def number(value: object, name: str) -> float:
    """``value`` as a float (NaN and infinities pass, for the caller's own check); bools and text are refused.

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        The argument's name, for the message.
    """
    try:
        if isinstance(value, (bool, np.bool_, str, bytes)):
            raise TypeError
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{name} must be a number, got {printable(repr(value))[:60]}") from None


def finite(value: object, name: str, *, low: float = -math.inf, high: float = math.inf) -> float:
    """``value`` as a finite float within ``[low, high]`` (a number, not a bool or text).

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        The argument's name, for the message.
    low, high : float
        Inclusive limits.
    """
    x = number(value, name)
    if not math.isfinite(x) or not low <= x <= high:
        span = f" from {low:g} to {high:g}" if math.isfinite(low) or math.isfinite(high) else ""
        raise ParameterError(f"{name} must be a finite number{span}, got {x:g}")
    return x


def temperature(value: object, name: str) -> float:
    """A temperature, degC: above absolute zero and below :data:`MAX_TEMPERATURE`.

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        What it is, for the message (``"x0 of Ti"``).
    """
    t = finite(value, name, low=ABSOLUTE_ZERO, high=MAX_TEMPERATURE)
    if t == ABSOLUTE_ZERO:
        raise ParameterError(f"{name} must be above absolute zero ({ABSOLUTE_ZERO} degC), got {t:g}")
    return t


def input_value(value: object, name: str, quantity: str) -> float:
    """A value of an input of ``quantity`` (a key of :data:`INPUT_LIMITS`, else ``"power"``'s limit), SI.

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        What it is, for the message (``"constant m"``).
    quantity : str
        ``"temperature"``, ``"flow"``, ``"power"`` or ``"irradiance"``.
    """
    if quantity == "temperature":
        return temperature(value, name)
    limit = INPUT_LIMITS.get(quantity, INPUT_LIMITS["power"])
    return finite(value, name, low=-limit, high=limit)


def mapping(value: object, name: str) -> Mapping[str, Any]:
    """``value`` if it is a mapping with text keys (``{"Ti": 20}``), else one line.

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        The argument's name.
    """
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise ParameterError(
            f"{name} must map names to values, e.g. {{'Ti': 20.0}}; got {type(value).__name__}"
        )
    return value


def numeric_column(frame: Any, column: str) -> np.ndarray:
    """The column ``column`` of a frame as floats, or one line naming it when it holds no numbers.

    Text (``"x"``, ``"21.5"``), booleans, dates and complex numbers are refused: rczone converts
    units and text at the data boundary (``rczone.load_data``), never in silence inside a fit.

    Parameters
    ----------
    frame : DataFrame
        The data.
    column : str
        The column's name.
    """
    col = frame[column]
    if getattr(col, "ndim", 1) != 1:
        raise DataError(f"column {printable(str(column))!r} appears more than once in the data; rename one")
    kind = getattr(col.dtype, "kind", "O")
    if kind not in "iuf":
        sample = next((v for v in col.to_numpy(object) if v is not None), None)
        raise DataError(
            f"column {printable(str(column))!r} holds {col.dtype} values (e.g. {printable(repr(sample))[:40]}),"
            " not numbers; convert it (pandas.to_numeric) or read the file with rczone.load_data"
        )
    return col.to_numpy(float)


def time_axis(t: np.ndarray) -> np.ndarray:
    """A time axis, s: finite, strictly increasing and shorter than :data:`MAX_SPAN`.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Time, s.
    """
    t = np.asarray(t, dtype=float)
    if t.size == 0:
        raise DataError("the data have no samples")
    if not np.isfinite(t).all():
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise DataError(f"'time' is not finite at sample {i + 1}; every sample needs a time (s)")
    steps = np.diff(t)
    if steps.size and not (steps > 0).all():
        i = int(np.flatnonzero(steps <= 0)[0])
        raise DataError(
            f"'time' does not increase at sample {i + 2} ({t[i + 1]:g} s after {t[i]:g} s); sort the data"
            " and drop repeated times"
        )
    if t[-1] - t[0] > MAX_SPAN:
        i = int(np.argmax(steps))
        raise DataError(
            f"'time' spans {t[-1] - t[0]:.3g} s, more than a century (a step of {steps[i]:.3g} s after sample"
            f" {i + 1}); check the time unit (seconds) and the time stamps"
        )
    return t


def sampling_period(t: np.ndarray) -> float:
    """The median time step of a time axis, s (1 for a single sample).

    Parameters
    ----------
    t : ndarray, shape (N,)
        Time, s, increasing.
    """
    return float(np.median(np.diff(t))) if len(t) > 1 else 1.0


def finite_inputs(t: np.ndarray, values: np.ndarray, channels: Sequence[str]) -> None:
    """Refuse inputs with a missing (NaN) or infinite sample, naming the channel and the first time.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Time, s.
    values : ndarray, shape (N, p)
        The inputs, a column per channel.
    channels : sequence of str
        The channels' names.
    """
    bad = ~np.isfinite(values)
    if bad.any():
        j = int(np.flatnonzero(bad.any(axis=0))[0])
        rows = np.flatnonzero(bad[:, j])
        raise DataError(
            f"input {printable(str(channels[j]))!r} is missing or not finite at {rows.size} sample(s), first at"
            f" t = {t[rows[0]]:g} s; fill or drop those samples, or hold the input constant"
        )


def finite_result(frame: Any, what: str) -> Any:
    """``frame`` (temperatures, degC) if every value is finite and below :data:`MAX_TEMPERATURE`, else one line.

    A NaN or an overflow in a result is never returned as a number: it is said where it starts.

    Parameters
    ----------
    frame : DataFrame
        The result, a column per node.
    what : str
        What computed it, for the message.
    """
    values = frame.to_numpy(float)
    bad = ~np.isfinite(values) | (np.abs(np.where(np.isfinite(values), values, 0.0)) > MAX_TEMPERATURE)
    if bad.any():
        i, j = (int(k[0]) for k in np.nonzero(bad))
        raise DataError(
            f"{what} leaves the range of temperatures at sample {i + 1} of {printable(str(frame.columns[j]))!r}"
            f" ({values[i, j]:g}); check the initial state, the inputs and the model's values"
        )
    return frame


def measured_outputs(frame: Any, outputs: Sequence[str], *, label: str = "data", minimum: int = 1) -> None:
    """Refuse measured outputs that are infinite, measured fewer than ``minimum`` times, or constant.

    A constant output (a column map that maps it to a value, a stuck sensor) carries nothing to fit
    or score; an output never measured leaves every score NaN.

    Parameters
    ----------
    frame : DataFrame
        The data; outputs it lacks are left to the caller.
    outputs : sequence of str
        The model's measured outputs.
    label : str
        The data's name, for the message.
    minimum : int
        Fewest measured samples of each output.
    """
    for name in outputs:
        if name not in frame:
            continue
        values = within_limits(numeric_column(frame, name), name, "temperature")
        measured = int(np.isfinite(values).sum())
        if measured < minimum:
            raise DataError(
                f"{label}: only {measured} of {len(values)} samples have a measured {name}; at least {minimum}"
                " are needed: use a longer record with fewer gaps"
            )
        if measured >= 2 and np.nanmin(values) == np.nanmax(values):
            raise DataError(
                f"{label}: the measured {name} is {np.nanmin(values):g} at every sample: a constant carries"
                " nothing to fit (a column map that maps it to a value, or a stuck sensor); map the"
                " measured column"
            )


def scored_samples(measured: np.ndarray, predicted: np.ndarray, outputs: Sequence[str], what: str) -> None:
    """Refuse a score of nothing: every output needs a sample both measured and predicted.

    A prediction whose warm-up, horizon or gaps leave an output no such sample would report its
    RMSE, maximum error and coverage as NaN; it is one line instead.

    Parameters
    ----------
    measured, predicted : ndarray, shape (N, ny)
        The scored samples (NaN: not measured, not predicted).
    outputs : sequence of str
        The outputs' names.
    what : str
        What is scored, for the message (``"the 12-step prediction"``).
    """
    counts = (np.isfinite(measured) & np.isfinite(predicted)).sum(axis=0)
    for j, name in enumerate(outputs):
        if counts[j] == 0:
            raise DataError(
                f"{what} scores no sample of {printable(str(name))!r}: none of the {len(measured)} scored"
                " samples is both measured and predicted; give data that measure it after the warm-up and"
                " horizon"
            )


def name_list(value: object, name: str) -> list[str]:
    """A sequence of names (``["Ci", "Rw"]``), not a single string or a number.

    Parameters
    ----------
    value : object
        What the user gave.
    name : str
        The argument's name.
    """
    if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, set, frozenset)):
        raise ParameterError(f"{name} must be a sequence of names, got {printable(repr(value))[:60]}")
    bad = [v for v in value if not isinstance(v, str)]
    if bad:
        raise ParameterError(f"{name} must hold names (text), got {printable(repr(bad[0]))[:60]}")
    return list(value)


def within_limits(values: np.ndarray, name: str, quantity: str) -> np.ndarray:
    """``values`` of a channel if every finite one is within :data:`INPUT_LIMITS` (missing ones may be NaN).

    Parameters
    ----------
    values : ndarray
        The channel's samples, SI units.
    name : str
        The channel, for the message.
    quantity : str
        ``"temperature"``, ``"flow"``, ``"power"`` or ``"irradiance"``.
    """
    limit = INPUT_LIMITS.get(quantity, INPUT_LIMITS["power"])
    low = ABSOLUTE_ZERO if quantity == "temperature" else -limit
    finite_values = np.where(np.isfinite(values), values, 0.0)
    bad = np.isinf(values) | (finite_values <= low) | (finite_values > limit)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"column {printable(str(name))!r} ({quantity}) is {values[i]:g} at sample {i + 1}, beyond what a"
            f" building reaches ({low:g} to {limit:g} in SI units); check the unit and the sensor"
        )
    return values
