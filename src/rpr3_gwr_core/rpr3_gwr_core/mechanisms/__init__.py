"""Mechanisms: the interface the roadmap and the planner use, the 3-RPR,
the five-bar, the 3-RRR and the 3-PRR."""

from .base import Mechanism, mechanism_from_dict, register_mechanism
from .five_bar import DEFAULT_FIVE_BAR, FiveBar
from .prr3 import DEFAULT_THREE_PRR, ThreePRR
from .rpr3 import PAPER_GEOMETRY, ThreeRPR
from .rrr3 import DEFAULT_THREE_RRR, ThreeRRR

__all__ = ["Mechanism", "mechanism_from_dict", "register_mechanism", "ThreeRPR",
           "PAPER_GEOMETRY", "FiveBar", "DEFAULT_FIVE_BAR", "ThreeRRR",
           "DEFAULT_THREE_RRR", "ThreePRR", "DEFAULT_THREE_PRR"]
