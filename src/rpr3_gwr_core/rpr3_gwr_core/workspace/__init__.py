"""The workspace roadmap: grid, n-solution field, continuity, rotary disk
search, segmentation and the roadmap graph, on uniform or adaptive grids,
for any mechanism.

The builds that can take seconds (:func:`compute_field`, :func:`segment`,
:func:`refine`, :func:`build_roadmap`, and
:func:`~rpr3_gwr_core.workspace.cusps.cusp_curves`) take an optional
keyword ``progress``, called as ``progress(stage, fraction)`` with the name
of the running stage and the fraction of the call's work done
(non-decreasing, in [0, 1]); the core never prints, its caller shows the
progress (the command line on stderr, the builder node in its log).  The
first four also take ``workers``, a map-like callable such as
``ThreadPoolExecutor.map`` that runs their chunks in parallel: the core
starts no thread, its caller chooses (the command line and the nodes pass
a thread pool's).
Objects print a one-line summary, e.g. ``Roadmap(3-RPR: 7 regions, 24
patches, 36 gates; ...)``.
"""

from .adaptive import AdaptiveGrid, grid_from_dict, refine
from .field import NSolutionField, compute_field
from .grid import Axis, Grid
from .roadmap import Roadmap, aspect_groups, build_roadmap, roadmap_graph
from .segmentation import Gate, Patch, Segmentation, segment
from .thin_regions import ThinRefinement, refine_thin_regions, thin_patches

__all__ = ["Axis", "Grid", "AdaptiveGrid", "refine", "grid_from_dict", "NSolutionField",
           "compute_field", "Gate", "Patch", "Segmentation", "segment", "Roadmap",
           "aspect_groups", "build_roadmap", "roadmap_graph", "ThinRefinement",
           "refine_thin_regions", "thin_patches"]
