"""Planning on a roadmap: locating configurations, global and local paths,
shortcutting, smoothing, timing and the independent validator."""

from .global_planning import Feasibility, GlobalPath, RoadmapIndex, feasibility, global_paths
from .index import PlanningIndex
from .locate import Location, locate
from .modes import AssemblyMode, assembly_modes
from .planner import DEFAULT_CLEARANCE, Plan, PlanOptions, Planner, Retries, planning_index
from .termination import NEVER, Termination
from .trajectory import time_parameterize
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN, Validation, validate_path

__all__ = ["Feasibility", "GlobalPath", "RoadmapIndex", "feasibility", "global_paths",
           "PlanningIndex", "planning_index",
           "Location", "locate", "AssemblyMode", "assembly_modes",
           "DEFAULT_CLEARANCE", "Plan", "PlanOptions", "Planner", "Retries",
           "Termination", "NEVER",
           "time_parameterize",
           "DEFAULT_MAX_STEP", "DEFAULT_MIN_MARGIN", "Validation", "validate_path"]
