"""Which model is right: nesting of RC models, likelihood-ratio tests, information criteria, selection."""

from rczone.selection.nesting import Nesting, nesting, realize

__all__ = ["Nesting", "nesting", "realize"]
