"""Sphinx configuration of rczone's API reference (``make docs``; built with warnings as errors in the tests).

Sphinx with numpydoc, because rczone's docstrings are numpydoc with Sphinx roles (``:func:``,
``:mod:``), which Sphinx resolves and numpydoc lays out as they are written.
"""

from __future__ import annotations

import rczone

project = "rczone"
author = "the rczone developers"
copyright = "the rczone developers"  # noqa: A001 - Sphinx's name
release = version = rczone.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc"]
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False  # autodoc's :members: lists them once
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
exclude_patterns = ["_build"]
html_theme = "alabaster"
html_static_path: list[str] = []
