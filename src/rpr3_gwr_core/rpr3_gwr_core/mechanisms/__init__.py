"""Mechanisms: the interface the roadmap and the planner use, the 3-RPR,
the five-bar and the 3-RRR."""

from .base import Mechanism, mechanism_from_dict, register_mechanism
from .five_bar import DEFAULT_FIVE_BAR, FiveBar
from .rpr3 import PAPER_GEOMETRY, ThreeRPR
from .rrr3 import DEFAULT_THREE_RRR, ThreeRRR

__all__ = ["Mechanism", "mechanism_from_dict", "register_mechanism", "ThreeRPR",
           "PAPER_GEOMETRY", "FiveBar", "DEFAULT_FIVE_BAR", "ThreeRRR",
           "DEFAULT_THREE_RRR"]
