"""The first-run notice: printed once when numba compiles one of rczone's kernels, never otherwise.

Real compilations are minutes of CPU, so numba's ``numba:compile`` events are broadcast here by
hand, as numba's dispatcher does on a cache miss; ``bench/first_run.py`` checks the notice on a real
first and second run.
"""

from __future__ import annotations

import io
from contextlib import nullcontext
from types import SimpleNamespace

from numba.core import event

from rczone.cli.compile_notice import NOTICE, compile_notice
from rczone.cli.main import _notice_for, main


def _compiling(module: str) -> None:
    """Broadcast the start and end of a compilation of a function defined in ``module``."""
    func = SimpleNamespace(__module__=module)
    data = {"dispatcher": SimpleNamespace(py_func=func), "args": (), "return_type": None}
    for status in (event.EventStatus.START, event.EventStatus.END):
        event.broadcast(event.Event("numba:compile", status, data=data))


def test_the_notice_is_printed_once_however_many_kernels_compile() -> None:
    out = io.StringIO()
    with compile_notice(out):
        _compiling("rczone.kernels.kalman")
        _compiling("rczone.kernels.problem")
    assert out.getvalue() == NOTICE + "\n"


def test_no_notice_without_a_compilation_or_for_code_that_is_not_rczones() -> None:
    out = io.StringIO()
    with compile_notice(out):
        _compiling("numba.np.arrayobj")
        _compiling("someone_else.kernels")
    assert out.getvalue() == ""


def test_the_listener_is_gone_after_the_block() -> None:
    out = io.StringIO()
    with compile_notice(out):
        pass
    _compiling("rczone.kernels.kalman")
    assert out.getvalue() == ""


def test_only_computing_commands_listen(capsys) -> None:
    for argv in ([], ["models"], ["version"], ["fit", "C", "--help"]):
        assert isinstance(_notice_for(argv), nullcontext), argv
    for argv in (["fit", "C"], ["demo"], ["fit-many", "m.toml"]):
        assert not isinstance(_notice_for(argv), nullcontext), argv
    assert main(["models"]) == 0
    assert NOTICE not in capsys.readouterr().err
