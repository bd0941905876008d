"""Sphinx configuration of rczone's documentation site (``make docs``; warnings are errors, in the tests too).

One site: the Markdown guides of ``docs/`` read by MyST, and the API reference (``docs/api``)
written by autodoc and laid out by numpydoc, because rczone's docstrings are numpydoc with Sphinx
roles (``:func:``, ``:mod:``), which Sphinx resolves as they are written.
"""

from __future__ import annotations

import rczone

project = "rczone"
author = "the rczone developers"
copyright = "the rczone developers"  # noqa: A001 - Sphinx's name
release = version = rczone.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser"]
root_doc = "index"
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_heading_anchors = 3  # the guides link to each other's sections (validation.md#...)
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False  # autodoc's :members: lists them once
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
exclude_patterns = ["_build", "api/_build"]
html_theme = "alabaster"
html_static_path: list[str] = []


def _skip_data_attributes(app, what, name, obj, skip, options):
    """Leave out a class's data attributes: its numpydoc ``Attributes`` section lists each once.

    autodoc would list a dataclass's fields a second time, bare (``result``, ``model`` ...), below
    the section that describes them; properties, methods and nested classes stay.
    """
    import functools
    import inspect

    if what != "class" or skip:
        return None
    kept = (property, functools.cached_property, classmethod, staticmethod)
    if isinstance(obj, kept) or inspect.isroutine(obj) or inspect.isclass(obj) or callable(obj):
        return None
    return True


def setup(app):
    app.connect("autodoc-skip-member", _skip_data_attributes)
