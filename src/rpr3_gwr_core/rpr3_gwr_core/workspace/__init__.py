"""The workspace roadmap: grid, n-solution field, continuity, rotary disk
search, segmentation and the roadmap graph, on uniform or adaptive grids,
for any mechanism."""

from .adaptive import AdaptiveGrid, grid_from_dict, refine
from .field import NSolutionField, compute_field
from .grid import Axis, Grid
from .roadmap import Roadmap, aspect_groups, build_roadmap, roadmap_graph
from .segmentation import Gate, Patch, Segmentation, segment

__all__ = ["Axis", "Grid", "AdaptiveGrid", "refine", "grid_from_dict", "NSolutionField",
           "compute_field", "Gate", "Patch", "Segmentation", "segment", "Roadmap",
           "aspect_groups", "build_roadmap", "roadmap_graph"]
