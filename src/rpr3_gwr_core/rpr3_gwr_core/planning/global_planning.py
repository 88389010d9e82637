"""Global planning on the roadmap (paper section 3.1).

Feasibility comes from the roadmap alone: two patches are connectible exactly
when they lie in one connected component of the GWR.  At the grid's
resolution this is a guarantee both ways: every path the roadmap connects is
realised by the cell search, which crosses only gates.  Two components of
one aspect are apart only as far as the grid can tell: where that aspect
has thin regions left (:func:`~rpr3_gwr_core.workspace.thin_patches`), a
finer grid may join them, and the answer is "undecided", not "unreachable".

Global paths are the shortest sequences of patches (fewest gates, as in the
paper, whose A* search is unweighted); all of them are returned, ranked by
the weighted cost below.  The weighted mode ranks by that cost instead: for a
gate between patches a and b, the distance in the (rho2, rho3) plane from a's
centroid to the gate's midpoint and on to b's centroid, plus ``narrow_penalty`` over the
gate's number of faces, so that narrow gates cost more.
"""

from dataclasses import dataclass
from itertools import islice

import networkx as nx
import numpy as np

from ..exceptions import InvalidInputError
from ..workspace import thin_patches

__all__ = ["Feasibility", "GlobalPath", "PatchGraph", "feasibility", "global_paths",
           "longer_paths"]

NARROW_PENALTY = 1.0


@dataclass(frozen=True)
class Feasibility:
    """Whether a roadmap connects two patches.

    Attributes
    ----------
    feasible : bool
    reason : str
        ``"same_patch"``, ``"connected"``, ``"other_aspect"`` (the patches
        have different signs of det Jx, which no singularity-free motion
        changes), ``"unreachable"`` (same aspect, no chain of gates, and no
        thin region of that aspect left) or ``"undecided"`` (no chain of
        gates, but thin regions of that aspect left, which a finer grid may
        join to either patch).
    thin_patches : tuple of int
        With ``"undecided"``, the thin regions of the aspect, ascending;
        else empty.
    """

    feasible: bool
    reason: str
    thin_patches: tuple = ()


@dataclass(frozen=True)
class GlobalPath:
    """A sequence of patch ids from the start's patch to the goal's.

    Attributes
    ----------
    patches : tuple of int
    cost : float
        Sum of the weighted edge costs [length unit].
    """

    patches: tuple
    cost: float


class PatchGraph:
    """The roadmap's patches as a graph, with the lookups of repeated global
    queries: connected components, aspects, the thin regions of each aspect,
    and gate edges weighted by length.

    Parameters
    ----------
    roadmap : Roadmap
    index : CellSearchIndex
        The roadmap's: it holds the patches' centroids and the gates' middles.
    narrow_penalty : float
        Weight of ``step / width`` in the weighted edge cost.
    """

    def __init__(self, roadmap, index, narrow_penalty=NARROW_PENALTY):
        self.graph = roadmap.graph
        self.component = {}
        for label, nodes in enumerate(nx.connected_components(self.graph)):
            for node in nodes:
                self.component[node] = label
        self.aspect = nx.get_node_attributes(self.graph, "aspect")
        self.thin = {}
        for pid in thin_patches(roadmap):
            self.thin.setdefault(self.aspect[pid], []).append(pid)
        seg = roadmap.segmentation
        grid = seg.field.grid
        pids = index.pids.tolist()
        self.centroid = dict(zip(pids, index.centroids))
        position = {pid: k for k, pid in enumerate(pids)}
        self.weighted = nx.Graph()
        self.weighted.add_nodes_from(self.graph.nodes)
        for (a, b), gate in seg.gates.items():
            middle = index.gate_middles[index.pair(position[a], position[b])]
            cost = (np.linalg.norm(self.centroid[a] - middle)
                    + np.linalg.norm(middle - self.centroid[b])
                    + narrow_penalty * float(np.prod(grid.steps)) / gate.width)
            self.weighted.add_edge(a, b, cost=float(cost))

    def path_cost(self, patches):
        """Weighted cost of a sequence of patches [length unit]."""
        return float(sum(self.weighted.edges[a, b]["cost"] for a, b in zip(patches, patches[1:])))

    def heuristic(self, a, b):
        """Straight-line distance between patch centroids (admissible for A*)."""
        return float(np.linalg.norm(self.centroid[a] - self.centroid[b]))


def _check(index, *patches):
    for pid in patches:
        if pid not in index.component:
            raise InvalidInputError(f"patch {pid} is not in the roadmap")


def feasibility(index, start_patch, goal_patch):
    """Answer from the roadmap alone whether two patches are connectible.

    Parameters
    ----------
    index : PatchGraph
    start_patch, goal_patch : int

    Returns
    -------
    Feasibility
    """
    _check(index, start_patch, goal_patch)
    if start_patch == goal_patch:
        return Feasibility(True, "same_patch")
    if index.component[start_patch] == index.component[goal_patch]:
        return Feasibility(True, "connected")
    if index.aspect[start_patch] != index.aspect[goal_patch]:
        return Feasibility(False, "other_aspect")
    thin = index.thin.get(index.aspect[start_patch])
    if thin:
        return Feasibility(False, "undecided", tuple(thin))
    return Feasibility(False, "unreachable")


def global_paths(index, start_patch, goal_patch, weighted=False, max_paths=8):
    """Global paths between two patches, best first.

    Parameters
    ----------
    index : PatchGraph
    start_patch, goal_patch : int
    weighted : bool
        Rank by weighted cost (A* on edge costs, then the next simple paths
        by Yen's algorithm) instead of returning every path with fewest gates.
    max_paths : int
        Most paths returned.

    Returns
    -------
    list of GlobalPath
        Empty when the patches are not connectible.
    """
    _check(index, start_patch, goal_patch)
    if max_paths < 1:
        raise InvalidInputError("max_paths must be at least 1")
    if index.component[start_patch] != index.component[goal_patch]:
        return []
    if weighted:
        best = nx.astar_path(index.weighted, start_patch, goal_patch,
                             heuristic=index.heuristic, weight="cost")
        others = nx.shortest_simple_paths(index.weighted, start_patch, goal_patch, weight="cost")
        paths = [best] + [p for p in islice(others, max_paths) if p != best]
    else:
        paths = list(nx.all_shortest_paths(index.graph, start_patch, goal_patch))
    ranked = sorted((GlobalPath(tuple(p), index.path_cost(p)) for p in paths),
                    key=lambda g: (g.cost, g.patches))
    return ranked[:max_paths]


def longer_paths(index, start_patch, goal_patch):
    """Every simple global path between two patches, fewest gates first.

    For the planner's fallback when every path of :func:`global_paths`
    fails locally; lazy, so only the paths taken are computed.

    Parameters
    ----------
    index : PatchGraph
    start_patch, goal_patch : int

    Yields
    ------
    GlobalPath
    """
    _check(index, start_patch, goal_patch)
    if index.component[start_patch] != index.component[goal_patch]:
        return
    for path in nx.shortest_simple_paths(index.graph, start_patch, goal_patch):
        yield GlobalPath(tuple(path), index.path_cost(path))
