"""The paper's zone models (full-scale, 2nd-order, 1st-order, reduced) from construction data."""

from rczone.models.aggregation import (
    first_order_values,
    outdoor_resistance,
    reduced_values,
    second_order_values,
    wall_capacity,
    wall_resistance,
)
from rczone.models.elements import SurfaceElement, elements_from_values, full_scale_values, surface_elements
from rczone.models.paper import (
    LOW_ORDER_INPUTS,
    SURROUNDINGS,
    first_order,
    full_scale,
    get_model,
    model_names,
    second_order,
    second_order_reduced,
    surroundings_to_tsd,
)
from rczone.models.split import (
    WallSplit,
    exact_wall_response,
    lumped_wall_response,
    matched_split,
    split_construction,
    symmetric_split,
)

__all__ = [
    "LOW_ORDER_INPUTS",
    "SURROUNDINGS",
    "SurfaceElement",
    "WallSplit",
    "elements_from_values",
    "exact_wall_response",
    "first_order",
    "first_order_values",
    "full_scale",
    "full_scale_values",
    "get_model",
    "lumped_wall_response",
    "matched_split",
    "model_names",
    "outdoor_resistance",
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
