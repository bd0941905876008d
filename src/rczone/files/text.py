"""Reading the files a user hands in: column maps, manifests, model files (and the checks of data files).

Only regular files are read: :func:`regular_file` checks a name before anything opens it, so a
named pipe (which would wait forever for a writer), a device (``/dev/zero`` never ends), a
socket or a symbolic link that loops is one :class:`~rczone.errors.DataError` line, not a hang
or a ``MemoryError``. Files are then opened without blocking and checked again on the open
descriptor, and read up to a size limit.

Every such file is untrusted. Whatever is wrong with it (a folder in its place, not UTF-8,
not valid TOML or JSON, nested deeper than any real file, far too large) becomes one
:class:`~rczone.errors.DataError` line naming the file and saying what to do; the parsers'
own exceptions (``UnicodeDecodeError``, ``RecursionError``, ``IsADirectoryError``...) never
reach the user. This module imports nothing of rczone but its errors.
"""

from __future__ import annotations

import errno
import json
import os
import stat
import tomllib
import unicodedata
from typing import Any

from rczone.errors import DataError

MAX_BYTES = 16 * 1024 * 1024
"""Largest configuration file read (bytes); real maps, manifests and model files are kilobytes."""

MAX_DEPTH = 32
"""Deepest nesting of tables and arrays accepted; real files nest three or four levels."""


def not_regular(path: str | os.PathLike, what: str, st: os.stat_result) -> DataError | None:
    """The error for a name that is not a regular file (None if it is one)."""
    mode = st.st_mode
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return DataError(f"{what} {os.fspath(path)!r} is a folder, not a file")
    kind = (
        "a named pipe (FIFO)"
        if stat.S_ISFIFO(mode)
        else "a device"
        if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
        else "a socket"
        if stat.S_ISSOCK(mode)
        else "not a regular file"
    )
    return DataError(
        f"{what} {os.fspath(path)!r} is {kind}, not a regular file; rczone reads only regular files"
        " (save the data to a file first)"
    )


def regular_file(path: str | os.PathLike, what: str) -> os.stat_result:
    """Check, before opening it, that ``path`` names a regular file; return its status.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist (a dangling link included).
    DataError
        If it is a folder, a pipe, a device or a socket, a symbolic link loop, or cannot be
        examined.
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise FileNotFoundError(errno.ENOENT, "No such file", os.fspath(path)) from None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise DataError(
                f"{what} {os.fspath(path)!r} is a symbolic link that loops (or a chain of more than 40);"
                " point it at a file"
            ) from None
        raise DataError(f"{what} {os.fspath(path)!r} cannot be read: {exc.strerror or exc}") from None
    except ValueError:  # a NUL byte in the name
        raise DataError(f"{what} {os.fspath(path)!r}: not a valid file name") from None
    problem = not_regular(path, what, st)
    if problem is not None:
        raise problem
    return st


def read_limited(path: str | os.PathLike, what: str, limit: int, hint: str) -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` of them (``hint``: the limit's name).

    Checked by :func:`regular_file` first, then opened without blocking (a file swapped for a
    pipe in between cannot hang) and checked again on the descriptor.
    """
    regular_file(path, what)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise FileNotFoundError(errno.ENOENT, "No such file", os.fspath(path)) from None
    except OSError as exc:
        raise DataError(f"{what} {os.fspath(path)!r} cannot be read: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        problem = not_regular(path, what, st)
        if problem is not None:
            raise problem
        if st.st_size > limit:
            raise _too_large(path, what, st.st_size, limit, hint)
        chunks, total = [], 0
        while True:
            block = os.read(fd, min(1 << 20, limit + 1 - total))
            if not block:
                break
            chunks.append(block)
            total += len(block)
            if total > limit:  # grew while being read
                raise _too_large(path, what, total, limit, hint)
        return b"".join(chunks)
    except OSError as exc:
        raise DataError(f"{what} {os.fspath(path)!r} cannot be read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def _too_large(path, what: str, size: int, limit: int, hint: str) -> DataError:
    return DataError(
        f"{what} {os.fspath(path)!r} has {'more than ' if size > limit else ''}{size:,} bytes, more than the"
        f" limit of {limit:,} ({hint}); is it the right file?"
    )


def read_text(path: str | os.PathLike, what: str) -> str:
    """The UTF-8 text of the file ``path``, described as ``what`` in messages.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    DataError
        If it is not a regular file (a folder, a pipe, a device, a link loop), unreadable,
        larger than :data:`MAX_BYTES` or not UTF-8.
    """
    raw = read_limited(path, what, MAX_BYTES, "rczone.files.text.MAX_BYTES")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise DataError(
            f"{what} {os.fspath(path)!r} is not UTF-8 text (byte 0x{raw[exc.start]:02x} on line {line});"
            " save it as UTF-8"
        ) from None


INT_LIMIT = 2**63
"""Integers in a file must lie in [-2**63, 2**63) (64-bit, as the TOML standard requires): a
larger one (``10**400``) cannot become a float and is an error naming its key."""


def nfkc(obj: Any) -> Any:
    """``obj`` with every string (and dict key) in Unicode NFKC form: the one form of a name.

    Python reads identifiers in NFKC (a tie ``"µ*2"`` names ``μ``), so names are normalized once,
    where they enter (model files, column maps, data headers, names on the command line and in a
    manifest): ``µ`` (micro sign) and ``μ`` (Greek mu) are one name, never two parameters.
    """
    if isinstance(obj, str):
        return unicodedata.normalize("NFKC", obj)
    if isinstance(obj, dict):
        return {nfkc(k): nfkc(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [nfkc(v) for v in obj]
    return obj


def _depth(obj: Any) -> tuple[int, str | None]:
    """Nesting depth of dicts and lists, and the key of the first integer beyond 64 bits.

    Without recursion (a hostile file may be deep).
    """
    deepest, stack = 0, [(obj, 1, "")]
    while stack:
        node, d, key = stack.pop()
        if isinstance(node, dict):
            children = [(v, f"{key}.{k}" if key else str(k)) for k, v in node.items()]
        elif isinstance(node, list):
            children = [(v, f"{key}[{i}]") for i, v in enumerate(node)]
        else:
            if isinstance(node, int) and not isinstance(node, bool) and not -INT_LIMIT <= node < INT_LIMIT:
                return deepest, key or "the document"
            continue
        deepest = max(deepest, d)
        if deepest > MAX_DEPTH:
            return deepest, None
        stack.extend((c, d + 1, k) for c, k in reversed(children))
    return deepest, None


def _nesting_hint(text: str) -> int:
    """Brackets open at the deepest point of ``text`` (an upper bound of its nesting)."""
    depth = deepest = 0
    for ch in text:
        if ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth -= 1
    return deepest


def _parsed(text: str, path: str | os.PathLike, what: str, kind: str, parse) -> Any:
    # The parsers recurse once per nesting level; refuse absurd nesting before they run.
    if _nesting_hint(text) > 4 * MAX_DEPTH:
        raise DataError(
            f"{what} {os.fspath(path)!r}: nested more than {MAX_DEPTH} levels deep (rczone.files.text.MAX_DEPTH)"
        )
    try:
        doc = parse(text)
    except RecursionError:
        raise DataError(
            f"{what} {os.fspath(path)!r}: nested more than {MAX_DEPTH} levels deep (rczone.files.text.MAX_DEPTH)"
        ) from None
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, ValueError) as exc:
        first = " ".join(str(exc).split())
        raise DataError(f"{what} {os.fspath(path)!r}: not valid {kind}: {first}") from None
    depth, huge = _depth(doc)
    if depth > MAX_DEPTH:
        raise DataError(
            f"{what} {os.fspath(path)!r}: nested more than {MAX_DEPTH} levels deep (rczone.files.text.MAX_DEPTH)"
        )
    if huge is not None:
        raise DataError(
            f"{what} {os.fspath(path)!r}: {huge}: an integer beyond 64 bits (rczone.files.text.INT_LIMIT);"
            " write a number in range (with an exponent for a float: 1e6)"
        )
    return doc


def read_toml(path: str | os.PathLike, what: str) -> dict[str, Any]:
    """Parse the TOML file ``path`` (see :func:`read_text` for the checks)."""
    return _parsed(read_text(path, what), path, what, "TOML", tomllib.loads)


def read_json(path: str | os.PathLike, what: str) -> Any:
    """Parse the JSON file ``path`` (see :func:`read_text` for the checks)."""
    return _parsed(read_text(path, what), path, what, "JSON", json.loads)
