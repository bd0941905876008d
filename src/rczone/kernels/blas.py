"""One BLAS thread while rczone computes: its matrices are a few states wide.

scipy's L-BFGS-B and numba's ``np.linalg`` calls go through OpenBLAS (or MKL), which by default
starts a thread per core. On matrices of a few rows the threads only wait for each other: on a
2-core machine at load 3-6, a 2-state ML fit of the built-in night C took 4.9-8.8 s with two BLAS
threads and 0.65-0.8 s with one (the optimizer's ``setulb`` step waited ~8 ms per call). The
command line sets the thread count before numpy loads (:func:`rczone.cli.run`); a Python user has
usually imported numpy already, so the API limits the threads for the duration of each call
instead, through threadpoolctl (as scikit-learn does), and leaves them as they were afterwards.
A user who set one of :data:`BLAS_THREADS` keeps that choice.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

#: The variables that set the BLAS libraries' thread counts (OpenBLAS, OpenMP, MKL).
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")

F = TypeVar("F", bound=Callable[..., Any])


@functools.cache
def _controller():
    """threadpoolctl's view of the loaded BLAS libraries (read once: ~10 ms; a limit then ~0.1 ms)."""
    import scipy.linalg  # noqa: F401  (its OpenBLAS serves scipy's optimizers and numba's LAPACK)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block with one BLAS thread, unless the user set a thread count in the environment."""
    if any(os.environ.get(var) for var in BLAS_THREADS):
        yield
        return
    with _controller().limit(limits=1, user_api="blas"):
        yield


def single_threaded(function: F) -> F:
    """``function`` run under :func:`one_blas_thread`."""

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with one_blas_thread():
            return function(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
