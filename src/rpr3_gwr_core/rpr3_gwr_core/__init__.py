"""rpr3_gwr_core: global workspace roadmap planning for parallel mechanisms,
the planar 3-RPR first, without ROS.

The layers, bottom up: :mod:`.mechanisms` (the mechanism interface and the
3-RPR), :mod:`.workspace` (grid, n-solution field, continuity, rotary disk
search, segmentation, roadmap), :mod:`.planning` (locate, global and local
paths, smoothing, timing, validation, the planner) and :mod:`.io` (JSON and
GEXF, the cache, figures, the ``rpr3-gwr`` tool); :mod:`.paper` holds the
paper's setting.

Examples
--------
The paper's first example (section 5.2) on a grid twice as coarse as its
own: its two global paths go through regions 6, 4, 2, 1 and 6, 5, 2, 1.

>>> import math
>>> from rpr3_gwr_core import PAPER_GEOMETRY, Planner, build_roadmap, rho1_slice
>>> roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(17.0, step=0.25))
>>> plan = Planner(roadmap).plan((17, 12, 18, math.radians(122.82)),
...                              (17, 10, 25, math.radians(-24.24)))
>>> patches = roadmap.segmentation.patches
>>> sorted([patches[p].region for p in path.patches] for path in plan.global_paths)
[[6, 4, 2, 1], [6, 5, 2, 1]]
>>> plan.validation.ok
True
"""

from .exceptions import (AssemblyModeError, FixedJointMismatchError, GWRError,
                         InfeasiblePathError, InvalidInputError, NoSolutionError, OutOfGridError,
                         PlanningTimeoutError, SingularityError, ValidationError)
from .mechanisms import Geometry, Mechanism, mechanism_from_dict
from .paper import PAPER_GEOMETRY, PAPER_GRID, rho1_slice
from .planning import Plan, PlanOptions, Planner, Termination
from .workspace import Axis, Grid, Roadmap, aspect_groups, build_roadmap, compute_field

__all__ = [
    "Mechanism", "Geometry", "mechanism_from_dict", "PAPER_GEOMETRY",
    "Axis", "Grid", "PAPER_GRID", "rho1_slice", "compute_field", "build_roadmap", "Roadmap",
    "aspect_groups", "Planner", "PlanOptions", "Plan", "Termination",
    "GWRError", "InvalidInputError", "OutOfGridError", "FixedJointMismatchError",
    "NoSolutionError", "AssemblyModeError", "SingularityError", "InfeasiblePathError",
    "ValidationError", "PlanningTimeoutError",
]
