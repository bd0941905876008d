"""Which model is right: nesting of RC models, likelihood-ratio tests, information criteria, selection."""

from rczone.selection.compare import Selection, select_models
from rczone.selection.nesting import Nesting, nesting, realize

__all__ = ["Nesting", "Selection", "nesting", "realize", "select_models"]
