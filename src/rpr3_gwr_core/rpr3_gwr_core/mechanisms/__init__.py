"""Mechanisms: the interface the roadmap and the planner use, and the 3-RPR."""

from .base import Mechanism, mechanism_from_dict, register_mechanism
from .rpr3 import PAPER_GEOMETRY, Geometry

__all__ = ["Mechanism", "mechanism_from_dict", "register_mechanism", "Geometry",
           "PAPER_GEOMETRY"]
