"""Which model is right: nesting of RC models, likelihood-ratio tests, information criteria, selection."""

from rczone.selection.compare import Selection, select_models
from rczone.selection.coupling import Basis, VuongTest, comparison_basis, conditional_logliks, vuong_test
from rczone.selection.nesting import Nesting, nesting, realize

__all__ = [
    "Basis",
    "Nesting",
    "Selection",
    "VuongTest",
    "comparison_basis",
    "conditional_logliks",
    "nesting",
    "realize",
    "select_models",
    "vuong_test",
]
