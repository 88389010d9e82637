"""Planning on a roadmap: locating configurations, global paths and cell
searches, the repair loop, the motion checker (the independent validator
and the collision check), path simplification, timing, and ends given as
platform poses."""

from .cell_search import CellPath, CellSearch
from .global_planning import Feasibility, GlobalPath, PatchGraph, feasibility, global_paths
from .index import CellSearchIndex
from .locate import Location, locate
from .modes import AssemblyMode, assembly_modes
from .motion import MotionChecker
from .pose_goals import PlanEnds, PoseEnd, WorkingMode, resolve_ends, working_modes
from .planner import Planner, build_cell_search_index
from .problem import PlanningProblem
from .request import DEFAULT_CLEARANCE, Plan, PlanOptions, PlanStatus, Retries
from .simplifier import PathSimplifier
from .termination import NEVER, Termination
from .trajectory import time_parameterize
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN, Validation, validate_path

__all__ = ["Feasibility", "GlobalPath", "PatchGraph", "feasibility", "global_paths",
           "CellPath", "CellSearch", "CellSearchIndex", "build_cell_search_index",
           "Location", "locate", "AssemblyMode", "assembly_modes",
           "WorkingMode", "PoseEnd", "PlanEnds", "working_modes", "resolve_ends",
           "DEFAULT_CLEARANCE", "Plan", "PlanOptions", "Planner", "PlanStatus", "Retries",
           "PlanningProblem", "MotionChecker", "PathSimplifier",
           "Termination", "NEVER",
           "time_parameterize",
           "DEFAULT_MAX_STEP", "DEFAULT_MIN_MARGIN", "Validation", "validate_path"]
