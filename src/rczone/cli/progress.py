"""Progress of long work, told as it goes: a bar on a terminal, a line every 10 s elsewhere.

A fit search, a selection's candidates, a batch or the demo's steps can run for minutes; silence
for that long reads as a hang. A command makes one :class:`Reporter` (:func:`reporter`) and hands
it down as a plain callback: ``report("fitting the second-order model")`` names the stage,
``report.advance(done, total)`` counts its steps. The work never asks where the words go:

* on a terminal, rich's live bar with the stage, the count, the elapsed time and an estimate of
  the time left (:class:`TerminalReporter`);
* elsewhere (a CI log, a redirected run) one plain line on stderr at most every
  :data:`INTERVAL_S` seconds with the stage, the count and the elapsed time, and a heartbeat line
  when the stage is long and says nothing (:class:`LineReporter`);
* with ``--quiet``, nothing (:class:`QuietReporter`).

The work below the CLI (the global search, the sampler, the closed loop, the demo's study) takes
the reporter as one keyword, ``progress=None``, and only calls it: ``progress.advance(done, total)``
after each local search, as the chains' draws come in, per simulated hour; the caller names the
stage. None (the API's default) tells nothing. :class:`Steps` numbers stages of a known count (the
candidates of ``select``, the runs of ``control-test --compare``).

No state is global: each reporter holds its own clock, stream and last line, so two commands (or
two tests) never share one. The interval of the lines can be set by the environment variable
:data:`INTERVAL_ENV` (seconds; a test sets it near zero to see lines at once).
"""

from __future__ import annotations

import math
import os
import sys
import threading
import time
from collections.abc import Callable
from typing import IO, Protocol, runtime_checkable

#: Seconds between two lines of a reporter that does not write to a terminal.
INTERVAL_S = 10.0
#: Environment variable overriding :data:`INTERVAL_S` (seconds, >= 0; anything else is ignored).
INTERVAL_ENV = "RCZONE_PROGRESS_INTERVAL"


def interval_s() -> float:
    """Seconds between two progress lines: :data:`INTERVAL_ENV` when it is a number >= 0, else :data:`INTERVAL_S`."""
    text = os.environ.get(INTERVAL_ENV, "").strip()
    try:
        value = float(text)
    except ValueError:
        return INTERVAL_S
    return value if math.isfinite(value) and value >= 0 else INTERVAL_S


@runtime_checkable
class Reporter(Protocol):
    """What long work calls: the stage's name, and how far the stage is."""

    def __call__(self, message: str) -> None:
        """A new stage, in a few words (``"fitting TiTe to C"``)."""
        ...

    def advance(self, done: int, total: int | None = None) -> None:
        """``done`` of ``total`` steps of the current stage are finished (None: total unknown)."""
        ...

    def close(self) -> None:
        """The work is over (a bar is removed, a thread stopped)."""
        ...


class QuietReporter:
    """Says nothing (``--quiet``, and the API's default)."""

    def __call__(self, message: str) -> None:
        """Ignored."""

    def advance(self, done: int, total: int | None = None) -> None:
        """Ignored."""

    def close(self) -> None:
        """Nothing to close."""

    def __enter__(self) -> QuietReporter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _clock_text(seconds: float) -> str:
    s = int(max(seconds, 0.0))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class LineReporter:
    """One line on ``stream`` at most every ``interval`` seconds: ``[0:01:20] stage (3/8)``.

    Parameters
    ----------
    stream : file
        Where the lines go (stderr).
    interval : float, optional
        Least seconds between two lines (default :func:`interval_s`); a stage that starts is written at once if the last
        line is that old, a long silent stage gets a heartbeat line from :meth:`tick`.
    clock : callable
        Seconds, monotonic (a fake clock in tests).
    """

    def __init__(
        self,
        stream: IO[str],
        *,
        interval: float | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.stream, self.clock = stream, clock
        self.interval = interval_s() if interval is None else float(interval)
        self.start = self.last = clock()
        self.stage, self.done, self.total = "", 0, None
        self._lock = threading.Lock()
        self._stop: threading.Event | None = None

    def __call__(self, message: str) -> None:
        """A new stage; written when the last line is at least ``interval`` old."""
        with self._lock:
            self.stage, self.done, self.total = str(message), 0, None
        self.tick()

    def advance(self, done: int, total: int | None = None) -> None:
        """Progress of the stage; written when the last line is at least ``interval`` old."""
        with self._lock:
            self.done, self.total = int(done), total
        self.tick()

    def line(self) -> str:
        """The line that would be written now."""
        count = f" ({self.done}/{self.total})" if self.total else f" ({self.done})" if self.done else ""
        return f"[{_clock_text(self.clock() - self.start)}] {self.stage or 'working'}{count}"

    def tick(self) -> bool:
        """Write the current line if the last is at least ``interval`` old; True if written."""
        with self._lock:
            now = self.clock()
            if now - self.last < self.interval:
                return False
            self.last = now
            self.stream.write(self.line() + "\n")
            self.stream.flush()
            return True

    def start_heartbeat(self, poll: float = 1.0) -> LineReporter:
        """Call :meth:`tick` every ``poll`` seconds from a daemon thread until :meth:`close`."""
        self._stop = stop = threading.Event()

        def beat() -> None:
            while not stop.wait(poll):
                self.tick()

        threading.Thread(target=beat, name="rczone-progress", daemon=True).start()
        return self

    def close(self) -> None:
        """Stop the heartbeat thread."""
        if self._stop is not None:
            self._stop.set()

    def __enter__(self) -> LineReporter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class TerminalReporter:
    """rich's live bar on a terminal: the stage, a bar and count, the elapsed time, the time left.

    Parameters
    ----------
    console : rich.console.Console
        The terminal's console (stderr).
    """

    def __init__(self, console) -> None:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.bar = Progress(
            SpinnerColumn(),
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("elapsed"),
            TimeElapsedColumn(),
            TextColumn("left"),
            TimeRemainingColumn(),
            console=console,
            transient=True,
        )
        self.task = self.bar.add_task("starting", total=None)
        self.bar.start()

    def __call__(self, message: str) -> None:
        """A new stage: the description changes, the count starts again."""
        from rich.markup import escape

        self.bar.reset(self.task, description=escape(str(message)), total=None)

    def advance(self, done: int, total: int | None = None) -> None:
        """The stage's count."""
        self.bar.update(self.task, completed=done, total=total)

    def close(self) -> None:
        """Remove the bar."""
        self.bar.stop()

    def __enter__(self) -> TerminalReporter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class Steps:
    """Stages of a known count on a reporter: ``steps(name)`` starts ``template`` for the next one.

    Parameters
    ----------
    report : Reporter
        Where the stages go.
    total : int
        How many stages there are.
    template : str
        The stage's words, with ``{name}``, ``{i}`` (from 1) and ``{n}``.

    The count of a stage (``advance``) is the work inside it (a fit's local searches), passed on.
    """

    def __init__(self, report: Reporter, total: int, template: str) -> None:
        self.report, self.total, self.template, self.started = report, int(total), template, 0

    def __call__(self, name: str) -> None:
        """The next stage, ``name``."""
        self.started += 1
        self.report(self.template.format(name=name, i=self.started, n=self.total))

    def advance(self, done: int, total: int | None = None) -> None:
        """How far the current stage is."""
        self.report.advance(done, total)

    def close(self) -> None:
        """The reporter is the caller's to close."""


def reporter(*, quiet: bool = False, stream: IO[str] | None = None, heartbeat: bool = True):
    """The reporter for a command: quiet, a bar on a terminal, or periodic lines on ``stream``.

    Parameters
    ----------
    quiet : bool
        Say nothing (``--quiet``).
    stream : file, optional
        Where progress goes; default stderr.
    heartbeat : bool
        Off a terminal, also write a line when a long stage says nothing for ``INTERVAL_S``.

    Returns
    -------
    Reporter
        Also a context manager that closes it.
    """
    if quiet:
        return QuietReporter()
    stream = sys.stderr if stream is None else stream
    if getattr(stream, "isatty", lambda: False)():
        from rich.console import Console

        return TerminalReporter(Console(file=stream, stderr=stream is sys.stderr))
    lines = LineReporter(stream)
    return lines.start_heartbeat() if heartbeat else lines
