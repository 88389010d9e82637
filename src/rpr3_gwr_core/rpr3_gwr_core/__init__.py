"""rpr3_gwr_core: global workspace roadmap planning for parallel mechanisms,
the planar 3-RPR first, without ROS.

The layers, bottom up: :mod:`.mechanisms` (the mechanism interface and the
3-RPR), :mod:`.workspace` (grid, n-solution field, continuity, rotary disk
search, segmentation, roadmap), :mod:`.planning` (locate, global and local
paths, smoothing, timing, validation, the planner), :mod:`.world` (bodies,
scenes, collisions), :mod:`.figures` and :mod:`.io` (JSON and GEXF, the
cache, mechanism and scene files, the ``rpr3-gwr`` tool); :mod:`.paper`
holds the paper's setting.

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

from .lazy import lazy_exports

# Names are loaded on first use (PEP 562), so that ``rpr3-gwr --help`` and
# light modules such as the exceptions do not load numpy and the compiled
# kernels with the package.
_SOURCES = {
    ".mechanisms": ("Mechanism", "ThreeRPR", "FiveBar", "DEFAULT_FIVE_BAR", "ThreeRRR",
                    "DEFAULT_THREE_RRR", "ThreePRR", "DEFAULT_THREE_PRR",
                    "mechanism_from_dict"),
    ".paper": ("PAPER_GEOMETRY", "PAPER_GRID", "rho1_slice"),
    ".workspace": ("Axis", "Grid", "compute_field", "build_roadmap", "Roadmap",
                   "aspect_groups"),
    ".planning": ("Planner", "PlanOptions", "Plan", "Termination", "assembly_modes",
                  "PoseEnd", "working_modes", "resolve_ends"),
    ".exceptions": ("GWRError", "InvalidInputError", "GridSizeError", "OutOfGridError",
                    "FixedJointMismatchError", "NoSolutionError", "AssemblyModeError",
                    "SingularityError", "InfeasiblePathError", "UndecidedError",
                    "CollisionError",
                    "ValidationError", "PlanningTimeoutError"),
}
_SOURCE_OF = {name: module for module, names in _SOURCES.items() for name in names}

__all__ = [name for names in _SOURCES.values() for name in names]


__getattr__, __dir__ = lazy_exports(__name__, globals(), _SOURCE_OF)
