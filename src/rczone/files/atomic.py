"""Writing results: atomic, inside the folder asked for, all or nothing.

Every result rczone writes (JSON, Parquet parts, reports, saved models, schedules) goes through
these functions, so that

* a result file is either complete or absent, never half written: it is written to a temporary
  file beside it and renamed over the name;
* nothing is written outside an output folder: the files of a folder (a report, a batch's
  ``--out``) are written by :func:`write_bytes_in`, which follows no symbolic link below the
  folder (a link planted at a file's name is replaced, not followed; a link in place of a
  subfolder is refused with one line), and the batch lock is opened by :func:`open_in` with
  ``O_NOFOLLOW``;
* a file the user names (``--json out.json``) that is a symbolic link stays a link: the file
  it points to is replaced. One that is not a regular file is written through, not replaced:
  ``/dev/stdout``, ``/dev/fd/N`` (a shell's ``>(...)``) and a named pipe (FIFO) receive the
  bytes as a stream (a pipe that no program reads is one line, not a hang);
* the outputs of one command are all or nothing (:func:`all_or_nothing`): they appear only
  when the command succeeds, so a failing ``--report`` leaves no ``--json`` behind.

A place that cannot take the result (a folder where a file is expected, a file where a folder
is expected, a read-only folder, a full disk) raises :class:`~rczone.errors.OutputError` with
one line naming the path, and leaves nothing behind. This module imports nothing of rczone but
its errors; every layer may use it.
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import os
import re
import secrets
import stat
import sys
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rczone.errors import OutputError

_REASONS = {
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "the file system is read-only",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.ENAMETOOLONG: "the name is too long",
    errno.ELOOP: "a symbolic link loops or is not followed",
}

NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
BINARY = getattr(os, "O_BINARY", 0)
#: Directory descriptors (POSIX): a folder's files are opened relative to the folder, with no race.
DIR_FD = (
    hasattr(os, "O_DIRECTORY")
    and NOFOLLOW != 0
    and {os.open, os.mkdir, os.replace, os.unlink, os.stat} <= os.supports_dir_fd
)
MAX_LINKS = 40
"""Symbolic links followed at most from a name the user gives (as the operating system does)."""


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def output_error(path: str | os.PathLike, exc: OSError, what: str = "write") -> OutputError:
    """One line saying why ``path`` cannot take a result, from the operating system's error."""
    reason = _REASONS.get(exc.errno or 0) or (exc.strerror or type(exc).__name__).lower()
    return OutputError(f"cannot {what} {os.fspath(path)!r}: {reason}")


# ---------------------------------------------------------------------------------------------
# all or nothing


@dataclass
class _Batch:
    """Outputs staged by one command: committed together, or none of them."""

    commits: list[Callable[[], None]] = field(default_factory=list)
    rollbacks: list[Callable[[], None]] = field(default_factory=list)


_STATE = threading.local()


def _batch() -> _Batch | None:
    return getattr(_STATE, "batch", None)


@contextlib.contextmanager
def immediate() -> Iterator[None]:
    """Write at once inside the block, even within :func:`all_or_nothing` (a batch's results are
    kept as they arrive, so an interrupted run resumes)."""
    saved = _batch()
    _STATE.batch = None
    try:
        yield
    finally:
        _STATE.batch = saved


@contextlib.contextmanager
def all_or_nothing(success: Callable[[BaseException], bool] | None = None) -> Iterator[None]:
    """Stage every output written inside the block; make them appear only if the block succeeds.

    Each file is written in full (to a temporary file beside its name) when it is asked for,
    so a place that cannot take it fails there, with one line; the renames that make the files
    appear happen when the block ends without an exception. On an exception (a failing
    ``--report``, a user error, Ctrl-C) the temporary files and the folders created for them
    are removed, and no output of the block appears. Streams (stdout, a pipe) are written at
    the end too. Blocks do not nest: an inner block joins the outer one.
    """
    if _batch() is not None:
        yield
        return
    batch = _Batch()
    _STATE.batch = batch
    try:
        yield
    except BaseException as exc:
        _STATE.batch = None
        if success is not None and success(exc):  # an exit that still means "outputs written"
            _commit(batch)
            raise
        for undo in reversed(batch.rollbacks):
            with contextlib.suppress(OSError):
                undo()
        raise
    _STATE.batch = None
    _commit(batch)


def _commit(batch: _Batch) -> None:
    try:
        for commit in batch.commits:
            commit()
    except BaseException:
        for undo in reversed(batch.rollbacks):
            with contextlib.suppress(OSError):
                undo()
        raise


def _defer(commit: Callable[[], None], rollback: Callable[[], None] | None = None) -> None:
    """Run ``commit`` now, or at the end of the :func:`all_or_nothing` block."""
    batch = _batch()
    if batch is None:
        commit()
        return
    batch.commits.append(commit)
    if rollback is not None:
        batch.rollbacks.append(rollback)


def _created_folder(path: Path) -> None:
    """Remember a folder made for a staged output (removed again if the block fails)."""
    batch = _batch()
    if batch is not None:
        batch.rollbacks.append(lambda: path.rmdir())  # only if still empty: rmdir refuses otherwise


# ---------------------------------------------------------------------------------------------
# folders


def ensure_folder(path: str | os.PathLike) -> Path:
    """Create the folder ``path`` (and its parents) for results, or raise :class:`OutputError`.

    An existing file at ``path``, or at one of its parents, is an error naming it.
    """
    path = Path(path)
    for p in (path, *path.parents):
        if p.exists() and not p.is_dir():
            raise OutputError(
                f"cannot write results into {os.fspath(path)!r}: {os.fspath(p)!r} is a file, not a folder;"
                " give a folder name"
            )
    missing = [p for p in (path, *path.parents) if not p.exists()]
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise output_error(path, exc, "create the folder") from None
    for p in missing:  # deepest first: removed in that order when the block fails
        _created_folder(p)
    return path


def _is_link(path: Path) -> bool:
    try:
        return stat.S_ISLNK(os.lstat(path).st_mode)
    except OSError:
        return False


def _link_error(folder: Path, where: Path) -> OutputError:
    return OutputError(
        f"cannot write into {os.fspath(folder)!r}: {os.fspath(where)!r} is a symbolic link, and rczone"
        " writes nothing outside the output folder; remove the link"
    )


def _split(name: str | os.PathLike) -> list[str]:
    parts = [p for p in re.split(r"[\\/]+", os.fspath(name)) if p not in ("", ".")]
    if not parts or ".." in parts:
        raise OutputError(f"cannot write {os.fspath(name)!r}: not a file name inside the output folder")
    return parts


@contextlib.contextmanager
def _folder_fd(folder: Path, subfolders: list[str]) -> Iterator[int | None]:
    """A descriptor of ``folder/sub/...`` (None without directory descriptors).

    ``folder`` (the user's) is created if absent and may be a link; every subfolder below it is
    created if absent and must be a real folder: a link there is refused.
    """
    ensure_folder(folder)
    if not DIR_FD:
        here = folder
        for s in subfolders:
            here = here / s
            if _is_link(here):
                raise _link_error(folder, here)
            ensure_folder(here)
        yield None
        return
    flags = os.O_RDONLY | os.O_DIRECTORY
    try:
        fd = os.open(folder, flags)
    except OSError as exc:
        raise output_error(folder, exc) from None
    try:
        here = folder
        for s in subfolders:
            here = here / s
            try:
                os.mkdir(s, 0o777, dir_fd=fd)
                _created_folder(here)
            except FileExistsError:
                pass
            except OSError as exc:
                raise output_error(here, exc, "create the folder") from None
            try:
                sub = os.open(s, flags | NOFOLLOW, dir_fd=fd)
            except OSError as exc:
                if exc.errno in (errno.ELOOP, errno.ENOTDIR) and _is_link(here):
                    raise _link_error(folder, here) from None
                if exc.errno == errno.ENOTDIR:
                    raise OutputError(
                        f"cannot write results into {os.fspath(here)!r}: it is a file, not a folder;"
                        " remove it or give another folder"
                    ) from None
                raise output_error(here, exc) from None
            os.close(fd)
            fd = sub
        yield fd
    finally:
        os.close(fd)


def ensure_folder_in(folder: str | os.PathLike, name: str) -> Path:
    """Create the subfolder ``folder/name`` (a real folder: a symbolic link there is refused)."""
    folder = Path(folder)
    parts = _split(name)
    with _folder_fd(folder, parts):
        pass
    return folder.joinpath(*parts)


def refuse_link_in(folder: str | os.PathLike, name: str) -> None:
    """Refuse now a symbolic link at ``folder/name``, a subfolder a command writes into when it ends.

    The writing refuses it too (:func:`write_bytes_in`); this says so before the work, not after.
    """
    folder = Path(folder)
    here = folder.joinpath(*_split(name))
    if _is_link(here):
        raise _link_error(folder, here)


def open_in(folder: str | os.PathLike, name: str, flags: int = os.O_RDWR | os.O_CREAT) -> int:
    """Open the regular file ``folder/name`` (a lock file) without following a symbolic link.

    The file must be a regular file with one name: a symbolic link, a hard link to a file
    elsewhere, a pipe or a device at its place is refused with one line, so nothing outside
    ``folder`` is ever opened for writing. Returns an open descriptor (the caller closes it).
    """
    folder = Path(folder)
    parts = _split(name)
    path = folder.joinpath(*parts)
    flags |= NOFOLLOW | BINARY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    with _folder_fd(folder, parts[:-1]) as dfd:
        if not NOFOLLOW and _is_link(path):
            raise _link_error(folder, path)
        try:
            fd = (
                os.open(parts[-1], flags, 0o644, dir_fd=dfd)
                if dfd is not None
                else os.open(path, flags, 0o644)
            )
        except OSError as exc:
            if exc.errno in (errno.ELOOP, errno.EMLINK) or _is_link(path):
                raise _link_error(folder, path) from None
            raise output_error(path, exc, "open") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode) or st.st_nlink > 1:
        os.close(fd)
        what = "has another name (a hard link)" if stat.S_ISREG(st.st_mode) else "is not a regular file"
        raise OutputError(
            f"cannot open {os.fspath(path)!r}: it {what}; rczone writes nothing outside the output folder;"
            " remove it"
        )
    with contextlib.suppress(OSError, AttributeError):
        os.set_blocking(fd, True)
    return fd


# ---------------------------------------------------------------------------------------------
# atomic files


def _temp_name(name: str) -> str:
    return f".{name[:200]}.{secrets.token_hex(4)}.tmp"


def _create_temp(folder: Path, dfd: int | None, tmp: str) -> int:
    """A new file ``tmp`` in the folder, created exclusively (never through a link)."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | NOFOLLOW | BINARY
    return os.open(tmp, flags, 0o644, dir_fd=dfd) if dfd is not None else os.open(folder / tmp, flags, 0o644)


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _atomic(folder: Path, dfd: int | None, name: str, data: bytes, shown: Path) -> Path:
    """Write ``data`` to ``name`` in the folder (descriptor ``dfd``, or path ``folder``) atomically."""
    final = folder / name
    try:
        st = os.stat(name, dir_fd=dfd, follow_symlinks=False) if dfd is not None else os.lstat(final)
    except OSError:
        st = None
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise OutputError(f"cannot write {os.fspath(shown)!r}: it is a folder; give a file name")
    tmp = _temp_name(name)
    try:
        fd = _create_temp(folder, dfd, tmp)
    except OSError as exc:
        raise output_error(shown, exc) from None
    keep = None if dfd is None else os.dup(dfd)  # the folder, until the rename (staged: later)

    def unlink_tmp() -> None:
        if keep is not None:
            os.unlink(tmp, dir_fd=keep)
        else:
            os.unlink(folder / tmp)

    def close_keep() -> None:
        if keep is not None:
            with contextlib.suppress(OSError):
                os.close(keep)

    try:
        try:
            _write_all(fd, data)
            if hasattr(os, "fchmod"):
                os.fchmod(fd, 0o644)  # readable by all, like a file written by open (whatever the umask)
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError as exc:
        with contextlib.suppress(OSError):
            unlink_tmp()
        close_keep()
        raise output_error(shown, exc) from None
    except BaseException:
        with contextlib.suppress(OSError):
            unlink_tmp()
        close_keep()
        raise

    def commit() -> None:
        try:
            if keep is not None:
                os.replace(tmp, name, src_dir_fd=keep, dst_dir_fd=keep)
            else:
                os.replace(folder / tmp, final)
        except OSError as exc:
            with contextlib.suppress(OSError):
                unlink_tmp()
            if exc.errno in (errno.EISDIR, errno.ENOTEMPTY, errno.EEXIST):
                raise OutputError(
                    f"cannot write {os.fspath(shown)!r}: it is a folder; give a file name"
                ) from None
            raise output_error(shown, exc) from None
        finally:
            close_keep()

    def rollback() -> None:
        try:
            unlink_tmp()
        finally:
            close_keep()

    _defer(commit, rollback)
    return shown


def write_bytes_in(folder: str | os.PathLike, name: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``folder/name`` atomically, never outside ``folder``.

    ``name`` may name subfolders (``parts/x.json``); they are created, and a symbolic link in
    their place is refused with one line. A symbolic link at the file's own name is replaced by
    the file (the file it pointed to is not touched). ``folder`` itself is the user's and may
    be a link.

    Raises
    ------
    OutputError
        The folder cannot take the file; no file (temporary or partial) is left behind.
    """
    folder = Path(folder)
    parts = _split(name)
    shown = folder.joinpath(*parts)
    with _folder_fd(folder, parts[:-1]) as dfd:
        where = folder.joinpath(*parts[:-1])
        return _atomic(where, dfd, parts[-1], data, shown)


_STD = {"/dev/stdout": 1, "/dev/stderr": 2}
_FD_NAME = re.compile(r"^/(?:dev/fd|proc/self/fd)/(\d+)$")


def _stream_fd(path: str) -> int | None:
    """The descriptor a name like ``/dev/stdout`` or ``/dev/fd/63`` stands for in this process."""
    if path in _STD:
        return _STD[path]
    m = _FD_NAME.match(path)
    return int(m.group(1)) if m else None


def _follow(path: Path) -> tuple[Path, int | None]:
    """``path`` with the symbolic links of its last name followed; or the stream it names."""
    for _ in range(MAX_LINKS):
        fd = _stream_fd(os.path.normpath(os.fspath(path)))
        if fd is not None:
            return path, fd
        try:
            target = os.readlink(path)
        except OSError:  # not a link (or absent): this is the file
            return path, None
        path = path.parent / target
    raise OutputError(
        f"cannot write {os.fspath(path)!r}: more than {MAX_LINKS} symbolic links (a loop?); give a file name"
    )


def write_stdout(text: str) -> None:
    """``text`` to standard output (``--json -``): at the end of the :func:`all_or_nothing` block."""
    _defer(lambda: _write_stream(1, text.encode("utf-8"), Path("-")))


def is_stream(path: str | os.PathLike) -> bool:
    """True if ``path`` (``-``, ``/dev/stdout``, or a link to it) names standard output."""
    if os.fspath(path) == "-":
        return True
    try:
        return _follow(Path(path))[1] == 1
    except OutputError:
        return False


def _write_stream(fd: int, data: bytes, shown: Path) -> None:
    if fd in (1, 2):
        stream = sys.stdout if fd == 1 else sys.stderr
        stream.flush()
        buffer = getattr(stream, "buffer", None)
        if buffer is not None:
            buffer.write(data)
        else:
            stream.write(data.decode("utf-8"))
        stream.flush()
        return
    try:
        _write_all(fd, data)
    except OSError as exc:
        raise output_error(shown, exc) from None


def _write_through(path: Path, st: os.stat_result, data: bytes, shown: Path) -> None:
    """Write into a pipe or a device as a stream (it is not a file to replace)."""
    if stat.S_ISSOCK(st.st_mode):
        raise OutputError(f"cannot write {os.fspath(shown)!r}: it is a socket, not a file; give a file name")
    flags = os.O_WRONLY | getattr(os, "O_NOCTTY", 0) | BINARY
    if stat.S_ISFIFO(st.st_mode):
        flags |= getattr(os, "O_NONBLOCK", 0)  # a pipe without a reader fails now instead of waiting
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        if exc.errno == errno.ENXIO:
            raise OutputError(
                f"cannot write {os.fspath(shown)!r}: it is a named pipe that no program reads; start the"
                " reader first, or give a file name"
            ) from None
        raise output_error(shown, exc) from None
    try:
        with contextlib.suppress(OSError, AttributeError):
            os.set_blocking(fd, True)
        _write_all(fd, data)
    except OSError as exc:
        raise output_error(shown, exc) from None
    finally:
        os.close(fd)


def write_bytes_atomic(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to the file ``path`` a user named, through a temporary file and a rename.

    The file is made readable by all (``0644``) like a file written by ``open``. A symbolic link
    at ``path`` is followed (the file it points to is replaced, the link stays). A pipe or a
    device (``/dev/stdout``, ``/dev/fd/N``, a named pipe, ``/dev/null``) is written through as
    a stream; a pipe that no program reads is an error, not a wait.

    Raises
    ------
    OutputError
        If ``path`` is a folder, its folder cannot be created or written, or the disk is full;
        no file (temporary or partial) is left behind.
    """
    shown = Path(path)
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise TypeError(f"data must be bytes, got {type(data).__name__}")
    target, fd = _follow(shown)
    if fd is not None:
        _defer(lambda: _write_stream(fd, bytes(data), shown))
        return shown
    try:
        st = os.stat(target)
    except OSError:
        st = None
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise OutputError(f"cannot write {os.fspath(shown)!r}: it is a folder; give a file name")
    if st is not None and not stat.S_ISREG(st.st_mode):
        _defer(lambda: _write_through(target, st, bytes(data), shown))
        return shown
    folder = target.parent
    with _folder_fd(folder, []) as dfd:
        return _atomic(folder, dfd, target.name, bytes(data), shown)


def write_text_atomic(path: str | os.PathLike, text: str) -> Path:
    """Write UTF-8 text atomically."""
    return write_bytes_atomic(path, text.encode("utf-8"))


def write_json_atomic(path: str | os.PathLike, obj: Any) -> Path:
    """Write ``obj`` as JSON atomically; numpy values become plain numbers, NaN becomes null."""
    return write_text_atomic(path, json_text(obj))


def json_text(obj: Any) -> str:
    """``obj`` as the JSON rczone writes (indented; numpy values plain; NaN and inf null)."""
    return json.dumps(_jsonable(obj), indent=2, allow_nan=False) + "\n"


def write_text_in(folder: str | os.PathLike, name: str, text: str) -> Path:
    """UTF-8 text to ``folder/name`` (see :func:`write_bytes_in`)."""
    return write_bytes_in(folder, name, text.encode("utf-8"))


def write_json_in(folder: str | os.PathLike, name: str, obj: Any) -> Path:
    """JSON to ``folder/name`` (see :func:`write_bytes_in` and :func:`json_text`)."""
    return write_text_in(folder, name, json_text(obj))
