"""Checks of the values a user hands in, one layer the command line and the Python API share.

:mod:`rczone.validation.values` holds the checks (seeds, counts, horizons, temperatures, inputs,
columns, time axes); they are re-exported here, so callers write ``validation.seed(value)``.
"""

from rczone.validation.values import (
    ABSOLUTE_ZERO,
    INPUT_LIMITS,
    MAX_NOISE,
    MAX_SPAN,
    MAX_TEMPERATURE,
    SEED_LIMIT,
    ascii_count,
    finite,
    finite_inputs,
    finite_result,
    input_value,
    integer,
    mapping,
    measured_outputs,
    numeric_column,
    sampling_period,
    seed,
    steps_ahead,
    temperature,
    time_axis,
)

__all__ = [
    "ABSOLUTE_ZERO",
    "INPUT_LIMITS",
    "MAX_NOISE",
    "MAX_SPAN",
    "MAX_TEMPERATURE",
    "SEED_LIMIT",
    "ascii_count",
    "finite",
    "finite_inputs",
    "finite_result",
    "input_value",
    "integer",
    "mapping",
    "measured_outputs",
    "numeric_column",
    "sampling_period",
    "seed",
    "steps_ahead",
    "temperature",
    "time_axis",
]
