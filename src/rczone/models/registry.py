"""Choosing a model: a built-in name, a model file a person wrote, or a model rczone saved.

:func:`load_model` is the one entry point the command line, batch manifests and the Python API
share. It returns a :class:`~rczone.models.zone.ZoneModel`: the network, the values a fit starts
from (the declared ones, or a saved fit's estimates), and the model's input conventions.

Built-in models are the paper's (:mod:`rczone.models.paper`) and the standard single-zone family
(:mod:`rczone.models.library`, e.g. ``TiTe+heater+solar``).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from rczone.errors import ModelFileError, ParameterError, RczoneError, did_you_mean
from rczone.models import library
from rczone.models.modelfile import read_model_file
from rczone.models.paper import model_names as paper_names
from rczone.models.paper import paper_model
from rczone.models.zone import ZoneModel
from rczone.network import RCNetwork

#: Model-file suffixes: a TOML file written by a person, a JSON file saved by rczone.
SUFFIXES = {".toml": "model file", ".json": "saved model"}


def builtin_names() -> tuple[str, ...]:
    """Names of the built-in models (the family's bases; options are added with ``+``)."""
    return (*paper_names(), *library.FAMILY)


def builtin_models() -> list[tuple[str, str]]:
    """``(name, description)`` of every built-in model (family models without options)."""
    out = [(n, paper_model(n).network.description) for n in paper_names()]
    out += [(n, library.family_network(n).description) for n in library.FAMILY]
    return out


def _builtin(name: str) -> ZoneModel | None:
    if name in paper_names():
        return paper_model(name)
    if library.is_family_name(name):
        return library.family_model(name)
    return None


def load_model(
    spec: str | os.PathLike | ZoneModel | RCNetwork, base_dir: str | os.PathLike | None = None
) -> ZoneModel:
    """The model named by ``spec``.

    Parameters
    ----------
    spec : str, path, ZoneModel or RCNetwork
        A built-in name (``second-order-paper``, ``TiTe+heater+solar``...), a model file
        (``.toml``), or a model saved by ``rczone fit --save-model`` / :meth:`ZoneModel.save`
        (``.json``, whose fitted values become the start of a new fit). A network is wrapped as
        it is.
    base_dir : path, optional
        Folder that relative file names are relative to (a manifest's folder); default the
        current folder.

    Returns
    -------
    ZoneModel

    Raises
    ------
    ModelFileError, ParameterError
        One line: the file's problem, or an unknown name with the closest built-in names.
    """
    if isinstance(spec, ZoneModel):
        return spec
    if isinstance(spec, RCNetwork):
        return ZoneModel(spec, source=spec.name)
    if not isinstance(spec, (str, os.PathLike)):
        raise ParameterError(f"a model is a built-in name or a model file, got {type(spec).__name__}")
    text = os.fspath(spec)
    if not text.strip():
        raise ParameterError("the model name is empty; give a built-in name or a model file (.toml or .json)")
    path = Path(text)
    if base_dir is not None and not path.is_absolute():
        path = Path(base_dir) / path
    suffix = path.suffix.lower()
    if suffix in SUFFIXES or path.exists():
        if suffix not in SUFFIXES:
            raise ModelFileError(
                f"model file {text!r}: unknown type {suffix or '(no suffix)'!r}; expected a model file"
                " (.toml) or a saved model (.json)"
            )
        loader: Callable[[Path], ZoneModel] = read_model_file if suffix == ".toml" else ZoneModel.load
        return loader(path)
    try:
        found = _builtin(text)
    except RczoneError:
        raise
    if found is None:
        raise ParameterError(
            f"unknown model {text!r}: not a built-in model ({did_you_mean(text, builtin_names())}) and not a"
            " file (give a model file .toml or a saved model .json; `rczone models` lists the built-ins)"
        )
    return found
