"""The ``rczone`` command-line interface."""

from __future__ import annotations

import os
import sys

from rczone.kernels.blas import BLAS_THREADS  # numpy-free: the counts are set before numpy loads

#: Exit code of an interrupted command (Ctrl-C), as a shell reports a SIGINT.
INTERRUPTED = 130


def run() -> int:
    """The console script: :func:`rczone.cli.main.main`, with Ctrl-C during start-up giving 130 too.

    Importing the command modules (typer, rich, and the numerical stack they pull in) takes a
    moment; an interrupt then would otherwise end in a traceback or a signal exit instead of the
    documented 130. After an interrupt the process ends at once: worker pools that the same Ctrl-C
    tore down would otherwise print "Exception ignored" noise from their exit handlers, and every
    output is already whole or absent (:func:`rczone.files.atomic.all_or_nothing`).

    The BLAS libraries run on one thread unless the user set otherwise: rczone's matrices are a
    few states wide, and a multi-threaded BLAS on a busy machine made each of scipy's L-BFGS-B
    steps wait milliseconds for its threads (4 ms instead of 30 us measured on a loaded 2-core
    machine; :mod:`rczone.kernels.blas`). Set before numpy is first imported; worker processes
    inherit it.
    """
    for var in BLAS_THREADS:
        os.environ.setdefault(var, "1")
    from rczone.cli.interrupt import noting_ctrl_c

    with noting_ctrl_c() as ctrl_c:  # from here on, a Ctrl-C that Python drops still counts
        try:
            from rczone.cli.main import main

            code = INTERRUPTED if ctrl_c() else main()
        except KeyboardInterrupt:
            code = INTERRUPTED
        if ctrl_c():  # dropped on the way, and the command ended as if not
            code = INTERRUPTED
    if code == INTERRUPTED:
        import multiprocessing

        for child in multiprocessing.active_children():  # a worker pool's processes end with us
            child.terminate()
            child.join(timeout=5)
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):  # a closed pipe: nothing more to say
                pass
        os._exit(INTERRUPTED)
    return code
