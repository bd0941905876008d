"""Helpers shared by CLI commands: reading a zone's data and choosing a model."""

from __future__ import annotations

from rczone.models import get_model
from rczone.network import RCNetwork
from rczone.sources import read_frame

__all__ = ["model", "read_frame"]


def model(name: str) -> RCNetwork:
    """A model by registry name (``second-order-paper``, ``second-order``, ``first-order``, ``full-scale``)."""
    return get_model(name)
