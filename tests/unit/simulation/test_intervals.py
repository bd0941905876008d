"""Distinct intervals: the fast row grouping against numpy's own."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rczone.simulation.intervals import interval_keys, unique_rows


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 60), st.integers(0, 3))
def test_unique_rows_matches_numpy_unique(seed, n, c):
    rng = np.random.default_rng(seed)
    levels = np.array([-0.0, 0.0, 0.5, 1e-300, -2.0, 60.0])
    key = rng.choice(levels, (n, c)) if c else np.zeros((n, 0))
    uniq, first, inverse = unique_rows(key)
    if n and c:
        ref, ref_first, ref_inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
        np.testing.assert_array_equal(uniq, ref)
        np.testing.assert_array_equal(first, ref_first)
        np.testing.assert_array_equal(inverse, ref_inverse.reshape(-1))
    np.testing.assert_array_equal(uniq[inverse] if n else key, key)
    assert first.dtype == inverse.dtype == np.int64


def test_interval_keys_and_bad_shapes():
    t = np.array([0.0, 60.0, 120.0, 240.0])
    m = np.array([[0.1], [0.1], [0.2], [0.3]])
    np.testing.assert_array_equal(interval_keys(t, m), [[60, 0.1], [60, 0.1], [120, 0.2]])
    uniq, first, inverse = unique_rows(interval_keys(t, m))
    assert uniq.shape == (2, 2) and list(first) == [0, 2] and list(inverse) == [0, 0, 1]
    with pytest.raises(ValueError, match="2-D"):
        unique_rows(np.zeros(3))
