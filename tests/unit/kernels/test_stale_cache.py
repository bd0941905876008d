"""A kernel cache index written by an older rczone, naming a class it no longer has, is a cache miss."""

from __future__ import annotations

import pickle
import sys
import types

import numpy as np
from numba.core import caching

import rczone.kernels.arrays  # noqa: F401  (applies the tolerance)
from rczone.kernels.cache import tolerate_stale_indexes


def _index_naming_a_vanished_class(path, version) -> None:
    """An index as numba writes one, whose overloads name ``gone_module.Renamed``."""
    module = types.ModuleType("gone_module")

    class Renamed(tuple):
        pass

    Renamed.__module__, Renamed.__qualname__ = "gone_module", "Renamed"
    module.Renamed = Renamed
    sys.modules["gone_module"] = module
    try:
        payload = pickle.dumps((("stamp", 1), {(Renamed(), "cpu"): "f-1.nbc"}), protocol=-1)
    finally:
        del module.Renamed  # the class is renamed in the new version
    with open(path, "wb") as f:
        pickle.dump(version, f, protocol=-1)
        f.write(payload)


def test_an_index_naming_a_renamed_class_reads_as_empty(tmp_path) -> None:
    index = caching.IndexDataCacheFile.__new__(caching.IndexDataCacheFile)
    index._index_path = str(tmp_path / "kernel.nbi")
    index._version = "0.61"
    index._source_stamp = ("stamp", 1)
    _index_naming_a_vanished_class(index._index_path, index._version)
    try:
        with open(index._index_path, "rb") as f:  # what numba alone does with it
            pickle.load(f)
            raised = None
            try:
                pickle.loads(f.read())
            except AttributeError as exc:
                raised = exc
        assert raised is not None
        tolerate_stale_indexes()  # a second call changes nothing
        assert index._load_index() == {}
    finally:
        sys.modules.pop("gone_module", None)


def test_a_fresh_index_still_loads() -> None:
    from rczone.kernels.smoother import smoother_gain

    P = np.eye(2)
    np.testing.assert_allclose(smoother_gain(P, 0.5 * np.eye(2), 2 * np.eye(2)), 0.25 * np.eye(2))
