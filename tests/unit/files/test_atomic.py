"""Atomic writes: a place that cannot take a result is one line naming it, and nothing is left behind."""

from __future__ import annotations

import errno
import os

import pytest

import rczone.files.atomic as atomic
from rczone.errors import OutputError, RczoneError
from rczone.files.atomic import ensure_folder, write_json_atomic, write_text_atomic


def test_a_folder_where_a_file_is_expected(tmp_path):
    (tmp_path / "r.json").mkdir()
    with pytest.raises(OutputError, match=r"cannot write '.*r.json': it is a folder; give a file name"):
        write_json_atomic(tmp_path / "r.json", {"a": 1})


def test_a_file_where_a_folder_is_expected(tmp_path):
    (tmp_path / "report").write_text("an existing file")
    with pytest.raises(OutputError, match=r"'.*report' is a file, not a folder"):
        write_text_atomic(tmp_path / "report" / "report.html", "<html>")
    with pytest.raises(OutputError, match=r"'.*report' is a file, not a folder"):
        ensure_folder(tmp_path / "report" / "deeper")
    assert (tmp_path / "report").read_text() == "an existing file"


@pytest.mark.parametrize(
    ("code", "reason"),
    [
        (errno.ENOSPC, "no space left on the device"),
        (errno.EROFS, "the file system is read-only"),
        (errno.EACCES, "permission denied"),
        (errno.EDQUOT, "disk quota exceeded"),
    ],
)
@pytest.mark.parametrize("step", ["mkstemp", "write", "replace"])
def test_operating_system_refusals_leave_nothing(tmp_path, monkeypatch, code, reason, step):
    """EACCES and EROFS cannot be provoked as root (the tests' user), so the OS call is made to fail."""

    def fail(*args, **kwargs):
        raise OSError(code, os.strerror(code))

    if step == "mkstemp":
        monkeypatch.setattr(atomic, "_create_temp", fail)
    elif step == "write":
        monkeypatch.setattr(atomic.os, "fsync", fail)
    else:
        monkeypatch.setattr(atomic.os, "replace", fail)
    with pytest.raises(OutputError, match=rf"cannot write '.*out.json': {reason}$") as info:
        write_json_atomic(tmp_path / "out.json", {"a": 1})
    assert isinstance(info.value, RczoneError) and isinstance(info.value, OSError)
    assert list(tmp_path.iterdir()) == []  # no temporary or partial file


def test_a_read_only_file_system(tmp_path):
    """A real read-only mount where the test runs as root; skipped elsewhere."""
    import subprocess

    ro = tmp_path / "ro"
    ro.mkdir()
    if (
        os.geteuid() != 0
        or subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(ro)]).returncode
    ):
        pytest.skip("mounting needs root")
    try:
        with pytest.raises(OutputError, match=r"the file system is read-only"):
            write_json_atomic(ro / "out.json", {"a": 1})
    finally:
        subprocess.run(["umount", "-l", str(ro)])
