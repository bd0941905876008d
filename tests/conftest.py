"""Tests run the BLAS libraries on one thread, as the command line does (:mod:`rczone.kernels.blas`).

Set here, before any test module imports numpy: the unit tests call the optimizers and kernels
below the API's own limit, and on a loaded 2-core machine a threaded BLAS made each small
L-BFGS-B step wait milliseconds. A count set in the environment is kept.
"""

import os

from rczone.kernels.blas import BLAS_THREADS

for _var in BLAS_THREADS:
    os.environ.setdefault(_var, "1")
