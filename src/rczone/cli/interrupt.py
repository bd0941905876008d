"""Ctrl-C, noted as it arrives: a command interrupted is one that ends 130, whatever Python drops.

Python raises ``KeyboardInterrupt`` where a SIGINT finds the interpreter. One that lands in a
finalizer is printed and dropped, and one that lands while numba compiles can leave a kernel half
built, whose next use fails with an error that does not carry the interrupt (``no compiled object
yet``); either way the command goes on, or fails with a traceback, instead of ending as
interrupted. :func:`noting_ctrl_c` notes every Ctrl-C as it arrives, from the first line of the
console script on (a Ctrl-C dropped while the command modules import counts too), and then
raises as Python's own handler does. A SIGTERM is taken as a Ctrl-C: the command ends 130 and
ends its worker processes (a process killed outright runs no handler; fit-many's workers then end
by themselves, :func:`rczone.batch.runner._end_with_parent`).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator

#: After a Ctrl-C, the seconds a command has to wind down before its process ends at once (exit 130).
CTRL_C_GRACE_S = 30.0

_seen: list[bool] = []  # a Ctrl-C arrived while the outermost block was active
_depth = [0]  # blocks active now (the console script's and main()'s nest)


def _arrived() -> bool:
    return bool(_seen)


@contextlib.contextmanager
def noting_ctrl_c() -> Iterator[Callable[[], bool]]:
    """Note every Ctrl-C as it arrives; yields whether one arrived.

    A command that goes on after one is ended :data:`CTRL_C_GRACE_S` later (:func:`_end_now`,
    exit 130); the timer ends with the outermost block, so a caller that runs a command in its
    own process lives on. Only where Python's default handler is in place, in the main thread;
    restored on the way out. Blocks nest: an inner one shares the outer one's note.
    """
    if _depth[0]:
        _depth[0] += 1
        try:
            yield _arrived
        finally:
            _depth[0] -= 1
        return
    if threading.current_thread() is not threading.main_thread() or (
        signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield lambda: False
        return
    timers: list[threading.Timer] = []

    def on_ctrl_c(signum, frame):
        if not _seen:
            timer = threading.Timer(CTRL_C_GRACE_S, _end_now)
            timer.daemon = True
            timers.append(timer)
            timer.start()
        _seen.append(True)
        signal.default_int_handler(signum, frame)

    _seen.clear()
    _depth[0] = 1
    signal.signal(signal.SIGINT, on_ctrl_c)
    term = signal.getsignal(signal.SIGTERM)
    if term == signal.SIG_DFL:  # SIGTERM (kill, a job scheduler) ends a command as Ctrl-C does
        signal.signal(signal.SIGTERM, on_ctrl_c)
    try:
        yield _arrived
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if term == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
        _depth[0] = 0
        for timer in timers:  # the command ended: nothing is left to end (nor a caller's process)
            timer.cancel()
            timer.join(timeout=5)


def _end_now() -> None:  # pragma: no cover - runs in a subprocess of the tests
    """End the process now, as interrupted: a Ctrl-C the command did not end on in time."""
    import multiprocessing

    with contextlib.suppress(OSError, ValueError):
        sys.stderr.write("aborted\n")
        sys.stderr.flush()
    for child in multiprocessing.active_children():  # a worker pool's processes end with us
        child.terminate()
    os._exit(130)
