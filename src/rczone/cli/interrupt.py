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

Python runs a signal's handler only when the main thread returns to the interpreter, which a
numba compile (LLVM) does not do for tens of seconds on a first run. The signal is also written,
by the C-level handler, to a wake-up pipe (:func:`signal.set_wakeup_fd`) that a watchdog thread
reads: when the handler has not run :data:`CTRL_C_STUCK_S` after the signal, the main thread is
stuck in compiled code and the process ends at once, exit 130 (outputs are written atomically, so
an interrupted command leaves none half written).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator

#: After a Ctrl-C, the seconds a command has to wind down before its process ends at once (exit 130).
CTRL_C_GRACE_S = 30.0

#: After a Ctrl-C, the seconds Python has to run its handler; longer, the main thread is stuck in
#: compiled code (a numba compile) and the process ends at once (exit 130).
CTRL_C_STUCK_S = 3.0

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
    hook = sys.unraisablehook
    sys.unraisablehook = _quiet_ctrl_c(hook)
    signal.signal(signal.SIGINT, on_ctrl_c)
    term = signal.getsignal(signal.SIGTERM)
    if term == signal.SIG_DFL:  # SIGTERM (kill, a job scheduler) ends a command as Ctrl-C does
        signal.signal(signal.SIGTERM, on_ctrl_c)
    watchdog = _Watchdog.start({signal.SIGINT, *([signal.SIGTERM] if term == signal.SIG_DFL else [])})
    try:
        yield _arrived
    finally:
        if watchdog is not None:
            watchdog.stop()
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if term == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
        sys.unraisablehook = hook
        _depth[0] = 0
        for timer in timers:  # the command ended: nothing is left to end (nor a caller's process)
            timer.cancel()
            timer.join(timeout=5)


def _quiet_ctrl_c(hook: Callable) -> Callable:
    """``hook`` for every unraisable exception but a Ctrl-C: that one is noted, not printed.

    A Ctrl-C that lands in a finalizer or a ctypes callback (llvmlite's object cache, while numba
    compiles) cannot be raised there; Python prints it as "Exception ignored ..." with a traceback.
    It is already noted (the command ends 130, "aborted"), so the traceback is noise.
    """

    def quiet(unraisable) -> None:
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            return
        hook(unraisable)

    return quiet


class _Watchdog:
    """Ends the process when a signal's Python handler does not run in time (module notes)."""

    def __init__(self, read_fd: int, write_fd: int, previous: int, watched: set[int]):
        self.read_fd, self.write_fd, self.previous = read_fd, write_fd, previous
        self.watched = watched
        self.thread = threading.Thread(target=self._watch, name="rczone-ctrl-c", daemon=True)

    @classmethod
    def start(cls, signals: set[int]) -> _Watchdog | None:
        """Watch ``signals`` (those handled by :func:`noting_ctrl_c`) from now on.

        None where the wake-up descriptor is another's (an event loop's) or there is none.
        """
        try:
            read_fd, write_fd = os.pipe()
            os.set_blocking(write_fd, False)
            previous = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
        except (OSError, ValueError, AttributeError):  # pragma: no cover - no pipes or not the main thread
            return None
        if previous != -1:  # someone else's: give it back and do without
            signal.set_wakeup_fd(previous)
            os.close(read_fd)
            os.close(write_fd)
            return None
        dog = cls(read_fd, write_fd, previous, {int(n) for n in signals})
        dog.thread.start()
        return dog

    def _watch(self) -> None:
        while True:
            try:
                got = os.read(self.read_fd, 64)
            except OSError:
                return
            if not got:  # the pipe was closed: the command ended
                return
            if self.watched & set(got) and not _seen:
                deadline = time.monotonic() + CTRL_C_STUCK_S
                while not _seen and time.monotonic() < deadline:
                    time.sleep(0.05)
                if not _seen and _depth[0]:
                    _end_now()

    def stop(self) -> None:
        """Give the wake-up descriptor back and end the thread."""
        with contextlib.suppress(OSError, ValueError):
            signal.set_wakeup_fd(self.previous)
        with contextlib.suppress(OSError):
            os.close(self.write_fd)  # the reader sees the end of the pipe
        self.thread.join(timeout=5)
        with contextlib.suppress(OSError):
            os.close(self.read_fd)


def _end_now() -> None:  # pragma: no cover - runs in a subprocess of the tests
    """End the process now, as interrupted: a Ctrl-C the command did not end on in time."""
    import multiprocessing

    with contextlib.suppress(OSError, ValueError):
        sys.stderr.write("aborted\n")
        sys.stderr.flush()
    for child in multiprocessing.active_children():  # a worker pool's processes end with us
        child.terminate()
    os._exit(130)
