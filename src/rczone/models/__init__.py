"""Zone models: the paper's models from construction data, the standard family, and model files.

:func:`load_model` turns a built-in name, a model file (TOML) or a saved model (JSON) into a
:class:`ZoneModel`, the object every command works with.
"""

from rczone.models.aggregation import (
    first_order_values,
    outdoor_resistance,
    reduced_values,
    second_order_values,
    wall_capacity,
    wall_resistance,
)

from rczone.models.zone import DiscreteModel, ModelInputs, ZoneModel  # isort: skip  (first: others use it)
from rczone.models.elements import SurfaceElement, elements_from_values, full_scale_values, surface_elements
from rczone.models.library import FAMILY, family_model, family_network
from rczone.models.modelfile import model_to_toml, read_model_file
from rczone.models.multizone import multizone
from rczone.models.paper import (
    LOW_ORDER_INPUTS,
    SURROUNDINGS,
    first_order,
    full_scale,
    get_model,
    model_names,
    paper_inputs,
    paper_model,
    second_order,
    second_order_reduced,
    surroundings_to_tsd,
)
from rczone.models.plausibility import Plausibility, plausibility
from rczone.models.registry import builtin_models, builtin_names, load_model
from rczone.models.split import (
    WallSplit,
    exact_wall_response,
    lumped_wall_response,
    matched_split,
    split_construction,
    symmetric_split,
)

__all__ = [
    "FAMILY",
    "LOW_ORDER_INPUTS",
    "SURROUNDINGS",
    "DiscreteModel",
    "ModelInputs",
    "Plausibility",
    "SurfaceElement",
    "WallSplit",
    "ZoneModel",
    "builtin_models",
    "builtin_names",
    "elements_from_values",
    "exact_wall_response",
    "family_model",
    "family_network",
    "first_order",
    "first_order_values",
    "full_scale",
    "full_scale_values",
    "get_model",
    "load_model",
    "lumped_wall_response",
    "matched_split",
    "model_names",
    "model_to_toml",
    "multizone",
    "outdoor_resistance",
    "paper_inputs",
    "paper_model",
    "plausibility",
    "read_model_file",
    "reduced_values",
    "second_order",
    "second_order_reduced",
    "second_order_values",
    "split_construction",
    "surface_elements",
    "surroundings_to_tsd",
    "symmetric_split",
    "wall_capacity",
    "wall_resistance",
]
