"""Compiled (numba) hot loops.

Each kernel is a small ``@njit(cache=True)`` function over contiguous float64 / int64
arrays, with a plain NumPy reference elsewhere in the package that the tests compare it
with (:mod:`rczone.simulation.simulate`, :mod:`rczone.estimation.kalman`). Kernels are few
and short because their compile time (paid once per machine, then cached on disk) counts
against the test suite and the CLI start-up.
"""

from rczone.kernels.cache import use_writable_cache

# before any kernel module decorates its functions: numba picks each one's cache folder then
use_writable_cache()
