"""A one-line notice on stderr while numba compiles rczone's kernels (the first run after an install).

numba compiles a kernel on its first call and caches the machine code on disk (``cache=True``);
later runs load it in milliseconds. The notice is driven by numba's own ``numba:compile`` event,
which fires only on a cache miss: a warm run never prints it, and nothing has to guess whether
the cache is empty or stale (a new numba, an edited kernel, another CPU). Importing this module
imports numba, so the CLI does it only for the commands that compute.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO

from numba.core import event

NOTICE = "compiling kernels (first run only)…"


class _Notice(event.Listener):
    """Prints :data:`NOTICE` once, when numba starts compiling a function of :mod:`rczone.kernels`."""

    def __init__(self, stream: TextIO | None) -> None:
        self.stream = stream
        self.shown = False

    def on_start(self, ev: event.Event) -> None:
        if self.shown:
            return
        dispatcher = (ev.data or {}).get("dispatcher")
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        if module.startswith("rczone.kernels"):
            self.shown = True
            print(NOTICE, file=self.stream or sys.stderr, flush=True)

    def on_end(self, ev: event.Event) -> None:
        pass


@contextmanager
def compile_notice(stream: TextIO | None = None) -> Iterator[None]:
    """Within the block, announce the first compilation of a kernel on ``stream`` (default: stderr)."""
    listener = _Notice(stream)
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)
