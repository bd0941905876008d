"""A plug-in package on a path, as pip leaves one: a module and a dist-info declaring its entry point."""

from __future__ import annotations

from pathlib import Path


def install(site: Path, module: str, text: str, group: str, entry: str) -> Path:
    """Write ``module``.py (``text``) and a distribution whose entry point ``entry`` is in ``group``.

    Parameters
    ----------
    site : Path
        The folder to put on ``sys.path`` (or ``PYTHONPATH``).
    module, text : str
        The module's name and source.
    group, entry : str
        The entry-point group (``rczone.controllers``) and line (``name = module:object``).

    Returns
    -------
    Path
        ``site``.
    """
    site.mkdir(parents=True, exist_ok=True)
    (site / f"{module}.py").write_text(text, encoding="utf-8")
    dist = site / f"{module}-1.0.dist-info"
    dist.mkdir()
    name = module.replace("_", "-")
    (dist / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n", encoding="utf-8")
    (dist / "entry_points.txt").write_text(f"[{group}]\n{entry}\n", encoding="utf-8")
    return site
