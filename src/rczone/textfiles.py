"""Reading the small text files a user hands in: column maps, manifests, model files.

Every such file is untrusted. Whatever is wrong with it (a folder in its place, not UTF-8,
not valid TOML or JSON, nested deeper than any real file, far too large) becomes one
:class:`~rczone.errors.DataError` line naming the file and saying what to do; the parsers'
own exceptions (``UnicodeDecodeError``, ``RecursionError``, ``IsADirectoryError``...) never
reach the user. This module imports nothing of rczone but its errors.
"""

from __future__ import annotations

import json
import os
import tomllib
from pathlib import Path
from typing import Any

from rczone.errors import DataError

MAX_BYTES = 16 * 1024 * 1024
"""Largest configuration file read (bytes); real maps, manifests and model files are kilobytes."""

MAX_DEPTH = 32
"""Deepest nesting of tables and arrays accepted; real files nest three or four levels."""


def read_text(path: str | os.PathLike, what: str) -> str:
    """The UTF-8 text of the file ``path``, described as ``what`` in messages.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    DataError
        If it is a folder, unreadable, larger than :data:`MAX_BYTES` or not UTF-8.
    """
    path = Path(path)
    if path.is_dir():
        raise DataError(f"{what} {os.fspath(path)!r} is a folder, not a file")
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise DataError(
                f"{what} {os.fspath(path)!r} has {size:,} bytes, more than the limit of {MAX_BYTES:,}"
                " (rczone.textfiles.MAX_BYTES); is it the right file?"
            )
        raw = path.read_bytes()
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise DataError(f"{what} {os.fspath(path)!r} cannot be read: {exc.strerror or exc}") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise DataError(
            f"{what} {os.fspath(path)!r} is not UTF-8 text (byte 0x{raw[exc.start]:02x} on line {line});"
            " save it as UTF-8"
        ) from None


def _depth(obj: Any) -> int:
    """Nesting depth of dicts and lists, without recursion (a hostile file may be deep)."""
    deepest, stack = 0, [(obj, 1)]
    while stack:
        node, d = stack.pop()
        if isinstance(node, dict):
            children = node.values()
        elif isinstance(node, list):
            children = node
        else:
            continue
        deepest = max(deepest, d)
        if deepest > MAX_DEPTH:
            return deepest
        stack.extend((c, d + 1) for c in children)
    return deepest


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
            f"{what} {os.fspath(path)!r}: nested more than {MAX_DEPTH} levels deep (rczone.textfiles.MAX_DEPTH)"
        )
    try:
        doc = parse(text)
    except RecursionError:
        raise DataError(
            f"{what} {os.fspath(path)!r}: nested more than {MAX_DEPTH} levels deep (rczone.textfiles.MAX_DEPTH)"
        ) from None
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, ValueError) as exc:
        first = " ".join(str(exc).split())
        raise DataError(f"{what} {os.fspath(path)!r}: not valid {kind}: {first}") from None
    if _depth(doc) > MAX_DEPTH:
        raise DataError(
            f"{what} {os.fspath(path)!r}: nested more than {MAX_DEPTH} levels deep (rczone.textfiles.MAX_DEPTH)"
        )
    return doc


def read_toml(path: str | os.PathLike, what: str) -> dict[str, Any]:
    """Parse the TOML file ``path`` (see :func:`read_text` for the checks)."""
    return _parsed(read_text(path, what), path, what, "TOML", tomllib.loads)


def read_json(path: str | os.PathLike, what: str) -> Any:
    """Parse the JSON file ``path`` (see :func:`read_text` for the checks)."""
    return _parsed(read_text(path, what), path, what, "JSON", json.loads)
