"""Where numba keeps rczone's compiled kernels: beside the package, or in the user's cache folder.

numba caches a kernel compiled with ``cache=True`` in the ``__pycache__`` folder beside its source
file. An installed package may sit where the user cannot write (a system-wide or read-only
site-packages, an installed wheel in a shared environment); every process would then compile
every kernel again unless the cache goes elsewhere. :func:`use_writable_cache` (called once, when
:mod:`rczone.kernels` is imported, before any kernel is decorated) keeps numba's own folder when it
is writable, respects a ``NUMBA_CACHE_DIR`` the user set, and otherwise points numba at the
platform's user cache folder: ``$XDG_CACHE_HOME/rczone/numba`` (default ``~/.cache/rczone/numba``)
on Linux, ``~/Library/Caches/rczone/numba`` on macOS, ``%LOCALAPPDATA%\\rczone\\Cache\\numba`` on
Windows (numba's own rule for its user-wide folder [1]_).

References
----------
.. [1] numba documentation, "Cache sharing" and "NUMBA_CACHE_DIR" (environment variables).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

#: numba's environment variable for the folder that holds every cached kernel.
CACHE_VARIABLE = "NUMBA_CACHE_DIR"


def writable(folder: Path) -> bool:
    """Whether numba can keep cache files in ``folder`` (created if missing), by writing one.

    The same test numba makes: a permission check says nothing for a read-only file system or a
    privileged user, a temporary file does.
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        return False
    return True


def user_cache_folder() -> Path:
    """The platform's user cache folder for rczone's kernels (``.../rczone/numba``).

    numba's rule for its own user-wide folder, written out so that choosing it does not import
    numba (commands that compute nothing do not load it).
    """
    home = Path.home()
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or home / "AppData" / "Local") / "rczone" / "Cache"
    elif sys.platform == "darwin":
        base = home / "Library" / "Caches" / "rczone"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or home / ".cache") / "rczone"
    return base / "numba"


def use_writable_cache(package: Path | None = None) -> Path | None:
    """Point numba at the user cache folder when the kernels' own folder cannot be written.

    Parameters
    ----------
    package : Path, optional
        The folder of the kernels' source files (default: this package's).

    Returns
    -------
    Path or None
        The folder numba now caches in when rczone chose it; None when numba keeps its own choice
        (a writable ``__pycache__`` beside the sources, or the user's ``NUMBA_CACHE_DIR``).
    """
    if os.environ.get(CACHE_VARIABLE):
        return None
    here = Path(__file__).resolve().parent if package is None else package
    if writable(here / "__pycache__"):
        return None
    folder = user_cache_folder()
    if not writable(folder):  # nowhere to write: numba's own fallbacks decide
        return None
    # numba reads the variable when it is imported (and again when its configuration reloads);
    # if it was imported already, its setting is changed too
    os.environ[CACHE_VARIABLE] = str(folder)
    config = sys.modules.get("numba.core.config")
    if config is not None:
        config.CACHE_DIR = str(folder)
    return folder


#: What unpickling a cache index written by another version of rczone can raise: a named-array
#: class renamed or removed since (AttributeError), a module moved (ImportError), a truncated file.
STALE_INDEX_ERRORS = (AttributeError, ImportError, EOFError, TypeError, ValueError, IndexError)


def tolerate_stale_indexes() -> None:
    """Read a cache index that names a class rczone no longer has as an empty index (a cache miss).

    numba unpickles a kernel's index before it compares the index's source stamp with the source
    file, so an index written by an older rczone whose signatures name a renamed named-array
    class (``kernels.arrays.Prior`` became ``FilterStart``) ends the first call of the kernel in
    an ``AttributeError`` instead of a recompilation. An installed package's folder keeps such
    files across upgrades (pip removes only the files it installed). Called once by
    :mod:`rczone.kernels.arrays`, which every kernel with named arrays in its signature imports.
    """
    from numba.core import caching

    load = caching.IndexDataCacheFile._load_index
    if getattr(load, "tolerates_stale", False):
        return

    def _load_index(self):
        try:
            return load(self)
        except STALE_INDEX_ERRORS:
            return {}

    _load_index.tolerates_stale = True
    caching.IndexDataCacheFile._load_index = _load_index
