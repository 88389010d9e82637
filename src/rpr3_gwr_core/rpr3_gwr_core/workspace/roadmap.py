"""The global workspace roadmap (GWR): patches as nodes, gates as edges.

:func:`build_roadmap` runs the whole pipeline (field, regions, patches,
gates, graph); :func:`roadmap_graph` turns a segmentation into a networkx
graph whose connected components are the aspects' groups of patches.
"""

from dataclasses import dataclass
from time import perf_counter

import networkx as nx

from .progress import part
from .field import compute_field
from .segmentation import segment

__all__ = ["Roadmap", "build_roadmap", "roadmap_graph", "aspect_groups"]


@dataclass(frozen=True, eq=False, repr=False)
class Roadmap:
    """A built roadmap: its field, segmentation and graph.

    Attributes
    ----------
    segmentation : Segmentation
    graph : networkx.Graph
        Nodes are patch ids with attributes ``region``, ``layer``, ``aspect``,
        ``n_solutions``, ``n_cells`` and ``area`` [length unit**2]; edges are
        gates with ``width`` [length unit] and ``n_faces``.
    timings : dict of str to float
        Seconds spent per stage.
    """

    segmentation: object
    graph: nx.Graph
    timings: dict

    def __repr__(self):
        seg, mechanism = self.segmentation, self.mechanism
        return (f"Roadmap({mechanism.kind}: {seg.n_regions} regions, {len(seg.patches)} "
                f"patches, {len(seg.gates)} gates; {self.grid.describe(mechanism.joint_names)})")

    @property
    def field(self):
        """The n-solution field the roadmap was built from."""
        return self.segmentation.field

    @property
    def mechanism(self):
        """The mechanism the roadmap was built for."""
        return self.segmentation.field.mechanism

    @property
    def grid(self):
        return self.segmentation.field.grid


def roadmap_graph(segmentation, areas=None):
    """The GWR of a segmentation as an undirected networkx graph.

    Parameters
    ----------
    segmentation : Segmentation
    areas : mapping of int to float, optional
        Each patch's area (:meth:`~.grid.Grid.volume_of` its cells), when
        known: on an adaptive grid the cells' volumes take a large share of
        the time a stored roadmap takes to load.

    Returns
    -------
    networkx.Graph
    """
    grid = segmentation.field.grid
    graph = nx.Graph()
    for pid, patch in segmentation.patches.items():
        area = grid.volume_of(patch.cells) if areas is None else float(areas[pid])
        graph.add_node(pid, region=patch.region, layer=patch.layer, aspect=patch.aspect,
                       n_solutions=patch.n_solutions, n_cells=int(patch.cells.size), area=area)
    for (a, b), gate in segmentation.gates.items():
        graph.add_edge(a, b, width=float(gate.width), n_faces=int(len(gate.faces)))
    return graph


def aspect_groups(graph):
    """Connected components of a roadmap, each a sorted list of patch ids,
    ordered by their smallest id."""
    return sorted((sorted(c) for c in nx.connected_components(graph)), key=lambda c: c[0])


def build_roadmap(mechanism, grid, method="components", min_region_cells=8, progress=None, *,
                  workers=map):
    """Build the global workspace roadmap of a mechanism on a grid.

    Parameters
    ----------
    mechanism : Mechanism
    grid : Grid
        Over the mechanism's joints, of any dimension.
    method : {"components", "rds"}
        Patch search (see :func:`~rpr3_gwr_core.workspace.segmentation.segment`).
    min_region_cells : int
        Smallest set of cells that counts as a region.
    progress : callable, optional
        Called as ``progress(stage, fraction)``, the stage's name and the
        fraction of the build done (non-decreasing, ``("done", 1.0)``
        last), as the field's cells are solved and between the stages of
        the segmentation.

    workers : callable, optional
        A map-like callable, ``workers(function, iterable)`` yielding the
        results in order, such as ``ThreadPoolExecutor.map``: the field and the segmentation
        work with it (:func:`~.field.compute_field`, :func:`~.segmentation.segment`).  The
        default, the builtin ``map``, works in the calling thread.

    Returns
    -------
    Roadmap

    Examples
    --------
    The paper's roadmap at rho1 = 17 (section 5.1), on a grid twice as
    coarse as its 401 x 401: 7 regions, 24 patches, one group per aspect.

    >>> from rpr3_gwr_core import PAPER_GEOMETRY, build_roadmap, rho1_slice
    >>> roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(17.0, step=0.25))
    >>> roadmap.segmentation.n_regions, len(roadmap.segmentation.patches)
    (7, 24)
    >>> [len(group) for group in aspect_groups(roadmap.graph)]
    [12, 12]
    """
    report = part(progress)
    timings = {}
    start = perf_counter()
    report("n-solution field", 0.0)
    field = compute_field(mechanism, grid, progress=part(progress, 0.0, 0.4), workers=workers)
    timings["field"] = perf_counter() - start
    start = perf_counter()
    segmentation = segment(field, method=method, min_region_cells=min_region_cells,
                           progress=part(progress, 0.4, 0.99), workers=workers)
    timings["segmentation"] = perf_counter() - start
    report("graph", 0.99)
    start = perf_counter()
    graph = roadmap_graph(segmentation)
    timings["graph"] = perf_counter() - start
    report("done", 1.0)
    return Roadmap(segmentation=segmentation, graph=graph, timings=timings)
