"""The cell search index of a roadmap: everything a cell search reads,
built once and only read afterwards.

It holds the node graph (one node per solution of a patch's cell, joined by
the continuation links within patches and across gates), the nodes of each
patch next to each of its gates, the node costs of given clearance weights
and, for given clearances, each patch's distances to each of its gates,
which guide the searches (:mod:`~.astar`); and the centroids of the patches
and the middles of their gates, which weigh the global search's edges
(:class:`~.global_planning.PatchGraph`).  The gate distances and the
nodes' margins along their links (:mod:`~.link_margins`) are most of the
work of building one: 10.5 s on the full 3-DOF roadmap (3.5 of them the links'),
half a second on the paper's slice.

An index is plain named arrays (:meth:`CellSearchIndex.arrays`,
:meth:`CellSearchIndex.from_arrays`), so the roadmap cache
(:mod:`~rpr3_gwr_core.io.cache`) stores it beside its roadmap and a process
maps the files instead of computing it; several processes mapping them share
one copy of their pages.
"""

import math

import numpy as np

from .astar import (NodeCosts, NodeGraph, adjacency, edge_quanta, gate_distances, gate_nodes,
                    node_positions, work_arrays)
from .link_margins import LinkEnds, link_margins
from ..exceptions import InvalidInputError
from ..workspace.segmentation import linked_solutions

__all__ = ["CellSearchIndex", "INDEX_TYPES", "LOW_MARGIN_FACTOR", "COST_UNITS",
           "patch_depth", "patch_costs"]

LOW_MARGIN_FACTOR = 100
"""A node whose margin is below the clearance costs this many times more."""

COST_UNITS = 8
"""The searches count in integers: the paper's cell cost ``1 + w / d`` is
rounded up to whole ``1 / COST_UNITS``."""

# Depth [cells] of a patch's cells taken from unresolved sets (region 0).
_UNRESOLVED_DEPTH = 0.5

INDEX_TYPES = {
    "pids": "<i8", "offsets": "<i8", "node_cell": "<i8", "node_slot": "<i8",
    "node_patch": "<i4", "node_margin": "<f8", "indptr": "<i8", "indices": "<i4",
    "quanta": "<u2", "position": "<i4", "turn": "<i8", "gate_pairs": "<i8",
    "gate_node_offsets": "<i8",
    "gate_node_list": "<i8", "quantum": "<f8", "clearances": "<f8", "distances": "<i8",
    "weights": "<f8", "node_costs": "<i8", "cost_floors": "<i8", "centroids": "<f8",
    "gate_middles": "<f8",
}
"""The arrays of an index (:meth:`CellSearchIndex.arrays`) and their dtypes."""


class CellSearchIndex:
    """The read-only lookups of one roadmap's local searches (module doc).

    Build one with :meth:`build`, or restore one with :meth:`from_arrays`.

    Attributes
    ----------
    pids : ndarray of int64, shape (P,)
        Patch ids, ascending; a patch's index is its position here.
    offsets : ndarray of int64, shape (P + 1,)
        The nodes of the patch at index ``k`` are ``offsets[k]:offsets[k + 1]``.
    graph : NodeGraph
    node_slot : ndarray of int64, shape (N,)
        Solution slot of each node in its cell.
    node_margin : ndarray of float64, shape (N,)
        Margin magnitude (normalised ``|det Jx|``) of each node's solution,
        or less where one of its links dips between the cell centres
        (:func:`~.link_margins.link_margins`).
    quantum : float
        The searches' length unit [joint unit] (:func:`~.astar.edge_quanta`).
    gate_pairs : ndarray of int64, shape (E, 2)
        Every ordered pair ``(k, other)`` of patch indices joined by a gate, sorted.
    centroids : ndarray of float64, shape (P, d)
        Mean axis values of each patch's cells [joint units].
    gate_middles : ndarray of float64, shape (E, d)
        Mean axis values of the cells on the faces of each pair's gate [joint units].
    clearances, weights : tuple of float
        Those the index holds gate distances and node costs for.
    """

    def __init__(self, arrays):
        self._arrays = arrays
        self.pids = arrays["pids"]
        self.offsets = arrays["offsets"]
        self.node_slot = arrays["node_slot"]
        self.node_margin = arrays["node_margin"]
        self.graph = NodeGraph(arrays["indptr"], arrays["indices"], arrays["quanta"],
                               arrays["node_cell"], arrays["node_patch"], arrays["position"],
                               arrays["turn"])
        self.quantum = float(arrays["quantum"][0])
        self.gate_pairs = arrays["gate_pairs"]
        self.centroids = arrays["centroids"]
        self.gate_middles = arrays["gate_middles"]
        self.clearances = tuple(arrays["clearances"].tolist())
        self.weights = tuple(arrays["weights"].tolist())
        sizes = np.diff(self.offsets)
        self._field_offsets = np.concatenate(
            [[0], np.cumsum(sizes[self.gate_pairs[:, 0]])]).astype(np.int64)
        self._pair_start = np.searchsorted(self.gate_pairs[:, 0], np.arange(self.pids.size + 1))
        self._ones = np.ones(self.n_nodes, dtype=np.int64)

    @property
    def n_nodes(self):
        """Number of nodes N."""
        return int(self.offsets[-1])

    @property
    def field_size(self):
        """Length of one clearance's gate distances (all patches and gates)."""
        return int(self._field_offsets[-1])

    def neighbours(self, k):
        """Indices of the patches joined to the patch at index ``k`` by a gate, ascending."""
        return self.gate_pairs[self._pair_start[k]:self._pair_start[k + 1], 1]

    def pair(self, k, other):
        """Position of ``(k, other)`` in :attr:`gate_pairs`."""
        others = self.neighbours(k)
        j = int(np.searchsorted(others, other))
        if j >= others.size or others[j] != other:
            raise InvalidInputError(f"patches {int(self.pids[k])} and {int(self.pids[other])} "
                                    "share no gate")
        return int(self._pair_start[k]) + j

    def field_offset(self, pair):
        """Offset of a pair's distances in one clearance's gate distances."""
        return int(self._field_offsets[pair])

    def gate_nodes(self, pair):
        """Nodes of patch ``k`` joined to patch ``other`` for ``pair = (k, other)``."""
        starts = self._arrays["gate_node_offsets"]
        return self._arrays["gate_node_list"][starts[pair]:starts[pair + 1]]

    def distances(self, clearance):
        """The gate distances of a clearance the index holds, else None."""
        if clearance in self.clearances:
            return self._arrays["distances"][self.clearances.index(clearance)]
        return None

    def costs(self, weight):
        """Node costs of a clearance weight the index holds and each patch's
        smallest, else None; weight 0 costs 1 everywhere."""
        if weight == 0:
            return self._ones, np.ones(self.pids.size, dtype=np.int64)
        if weight in self.weights:
            j = self.weights.index(weight)
            return self._arrays["node_costs"][j], self._arrays["cost_floors"][j]
        return None

    def arrays(self):
        """The index as named arrays (:data:`INDEX_TYPES`); :meth:`from_arrays` inverts it."""
        return dict(self._arrays)

    @classmethod
    def build(cls, roadmap, clearances=(), weights=(), graph_from=None):
        """Index a roadmap.

        Parameters
        ----------
        roadmap : Roadmap
        clearances : sequence of float
            Clearances (normalised ``|det Jx|``, in [0, 1)) to compute the gate
            distances of.
        weights : sequence of float
            Clearance weights (the paper's ``w``, finite, non-negative) to
            compute the node costs of; 0 needs none.
        graph_from : CellSearchIndex, optional
            An index of the same roadmap whose node graph is taken rather
            than built again; returned as it is when it holds the gate
            distances and node costs asked for already.

        Returns
        -------
        CellSearchIndex

        Raises
        ------
        InvalidInputError
            If a clearance or weight is out of range.
        """
        clearances = _distinct(clearances, "clearance", lambda c: 0 <= c < 1)
        weights = [w for w in _distinct(weights, "clearance weight", lambda w: w >= 0) if w > 0]
        if graph_from is None:
            bare = cls(_graph_arrays(roadmap))
        else:
            _check_index(roadmap, graph_from.arrays())
            if set(clearances) <= set(graph_from.clearances) \
                    and all(graph_from.costs(w) is not None for w in weights):
                return graph_from
            bare = cls(dict(graph_from.arrays(), **_no_tables(graph_from.n_nodes,
                                                               graph_from.pids.size)))
        arrays = bare.arrays()
        work = work_arrays(bare.n_nodes, bare.graph.indices.size)
        arrays["clearances"] = np.array(clearances, dtype=np.float64)
        arrays["distances"] = np.empty((len(clearances), bare.field_size), dtype=np.int64)
        for row, clearance in zip(arrays["distances"], clearances):
            for pair in range(bare.gate_pairs.shape[0]):
                start = bare.field_offset(pair)
                values = patch_gate_distances(bare, pair, clearance, work)
                row[start:start + values.size] = values
        arrays["weights"] = np.array(weights, dtype=np.float64)
        arrays["node_costs"] = np.empty((len(weights), bare.n_nodes), dtype=np.int64)
        arrays["cost_floors"] = np.empty((len(weights), bare.pids.size), dtype=np.int64)
        for j, weight in enumerate(weights):
            for k in range(bare.pids.size):
                cost = patch_costs(roadmap.segmentation, bare, weight, k)
                arrays["node_costs"][j, bare.offsets[k]:bare.offsets[k + 1]] = cost
                arrays["cost_floors"][j, k] = cost.min()
        return cls(arrays)

    @classmethod
    def from_arrays(cls, roadmap, arrays):
        """The index of a roadmap from :meth:`arrays` (loaded or mapped).

        The dtypes, shapes and the ranges of every array used as an index
        into another are checked, so that damaged arrays never reach the
        compiled searches.

        Raises
        ------
        InvalidInputError
            If the arrays do not index this roadmap.
        """
        if set(arrays) != set(INDEX_TYPES):
            raise InvalidInputError("the arrays are not a cell search index's")
        for name, dtype in INDEX_TYPES.items():
            if arrays[name].dtype != np.dtype(dtype):
                raise InvalidInputError(f"index array {name} is {arrays[name].dtype}, "
                                        f"not {np.dtype(dtype)}")
        _check_index(roadmap, arrays)
        return cls(dict(arrays))


def _distinct(values, what, in_range):
    out = []
    for value in values:
        value = float(value)
        if not (math.isfinite(value) and in_range(value)):
            raise InvalidInputError(f"{what} {value} is out of range")
        if value not in out:
            out.append(value)
    return out


def _graph_arrays(roadmap):
    """The arrays of an index without gate distances or node costs."""
    seg = roadmap.segmentation
    pids = np.array(sorted(seg.patches), dtype=np.int64)
    patches = [seg.patches[pid] for pid in pids.tolist()]
    sizes = [p.cells.size for p in patches]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    n_nodes = int(offsets[-1])
    empty = [np.zeros(0, np.int64)]
    node_cell = np.concatenate([p.cells for p in patches] + empty).astype(np.int64)
    node_slot = np.concatenate([p.slots for p in patches] + empty).astype(np.int64)
    node_patch = np.repeat(np.arange(len(patches), dtype=np.int32), sizes)
    indptr, indices = adjacency(n_nodes, *_edges(seg, patches, offsets))
    grid = seg.field.grid
    quantum = _lattice_quantum(grid.steps)
    coordinates = grid.coordinates_of(node_cell)
    position = node_positions(coordinates, quantum)
    turn = np.rint(2.0 * grid.periods / quantum).astype(np.int64)
    mechanism = roadmap.mechanism
    node_margin = link_margins(mechanism, LinkEnds(
        indptr, indices, np.ascontiguousarray(roadmap.grid.joints_at(node_cell), dtype=float),
        _joint_periods(roadmap.grid),
        np.ascontiguousarray(seg.field.poses[node_cell, node_slot], dtype=float),
        np.ascontiguousarray(seg.field.margin[node_cell, node_slot], dtype=float),
        np.array(mechanism.angular, dtype=np.bool_)))
    index_of = {pid: k for k, pid in enumerate(pids.tolist())}
    pairs = sorted({(index_of[a], index_of[b]) for a, b in seg.gates}
                   | {(index_of[b], index_of[a]) for a, b in seg.gates})
    gate_pairs = np.array(pairs, dtype=np.int64).reshape(-1, 2)
    pid_of = pids.tolist()
    middles = {key: grid.coordinates_of(gate.faces.ravel()).mean(axis=0)
               for key, gate in seg.gates.items()}
    lists = [gate_nodes(indptr, indices, node_patch, offsets[k], offsets[k + 1], other)
             for k, other in pairs]
    return {
        "pids": pids, "offsets": offsets, "node_cell": node_cell, "node_slot": node_slot,
        "node_patch": node_patch,
        "node_margin": node_margin,
        "indptr": indptr, "indices": indices,
        "quanta": edge_quanta(indptr, indices, position, turn), "position": position,
        "turn": turn,
        "gate_pairs": gate_pairs,
        "gate_node_offsets": np.concatenate(
            [[0], np.cumsum([a.size for a in lists])]).astype(np.int64),
        "gate_node_list": np.concatenate(lists + empty).astype(np.int64),
        "quantum": np.array([quantum]), **_no_tables(n_nodes, pids.size),
        "centroids": np.array([coordinates[offsets[k]:offsets[k + 1]].mean(axis=0)
                               for k in range(pids.size)]).reshape(-1, grid.ndim),
        "gate_middles": np.array([middles[min(pid_of[k], pid_of[other]),
                                          max(pid_of[k], pid_of[other])]
                                  for k, other in pairs]).reshape(-1, grid.ndim),
    }


def _joint_periods(grid):
    """The period of each joint along the grid [joint unit], 0 where it has none."""
    periods = np.zeros(grid.n_joints)
    periods[list(grid.axis_joints)] = grid.periods
    return periods


def _no_tables(n_nodes, n_patches):
    """The gate distance and node cost arrays of an index that holds none."""
    return {"clearances": np.zeros(0), "distances": np.zeros((0, 0), dtype=np.int64),
            "weights": np.zeros(0), "node_costs": np.zeros((0, n_nodes), dtype=np.int64),
            "cost_floors": np.zeros((0, n_patches), dtype=np.int64)}


def _edges(seg, patches, offsets):
    """The node pairs of every continuation link between two patch
    solutions, within a patch or across a gate."""
    node_of = np.full(seg.patch.size, -1, dtype=np.int32)
    for p, offset in zip(patches, offsets.tolist()):
        node_of[p.cells * seg.patch.shape[1] + p.slots] = np.arange(
            offset, offset + p.cells.size, dtype=np.int32)
    a_all, b_all = [np.zeros(0, np.int32)], [np.zeros(0, np.int32)]
    for lower, upper, match in seg.links:
        a, b = (node_of[disks] for disks in linked_solutions(lower, upper, match))
        keep = (a >= 0) & (b >= 0)
        a_all.append(a[keep])
        b_all.append(b[keep])
    return np.concatenate(a_all), np.concatenate(b_all)


def _lattice_quantum(steps, most=16):
    """The longest length of which every step is a whole multiple: the
    smallest step divided by 1, 2, ... up to ``most`` (then lengths round
    down to that last one)."""
    smallest = min(steps)
    for divisor in range(1, most + 1):
        quantum = smallest / divisor
        if all(abs(s / quantum - round(s / quantum)) < 1e-9 * s / quantum for s in steps):
            return quantum
    return smallest / most


def patch_gate_distances(index, pair, clearance, work):
    """:func:`~.astar.gate_distances` of patch ``k`` to its gate to ``other``
    for ``index.gate_pairs[pair] = (k, other)``, with node costs of 1.

    Parameters
    ----------
    index : CellSearchIndex
    pair : int
    clearance : float
    work : WorkArrays

    Returns
    -------
    ndarray of int64, shape (nodes of patch k,)
    """
    k = int(index.gate_pairs[pair, 0])
    costs = NodeCosts(index.costs(0.0)[0], index.node_margin, clearance, LOW_MARGIN_FACTOR)
    return gate_distances(index.graph, costs, index.pids.size, k, index.gate_nodes(pair), work)


def patch_depth(segmentation, pid):
    """Distance of each cell of a patch to its nearest outside cell [cells].

    Cells the patch took from unresolved sets (region 0, see
    :mod:`~rpr3_gwr_core.workspace.segmentation`) lie on the singular locus:
    they count as outside for the others, and as half a cell deep themselves.

    Returns
    -------
    ndarray of float, shape (patch cells,)
    """
    patch = segmentation.patches[pid]
    own = segmentation.region[patch.cells] == patch.region
    depth = np.full(patch.cells.size, _UNRESOLVED_DEPTH)
    depth[own] = segmentation.field.grid.depth(patch.cells[own])
    return depth


def patch_costs(segmentation, index, weight, k):
    """Node costs ``ceil(COST_UNITS (1 + weight / depth))`` of the patch at
    index ``k`` (:func:`patch_depth`), shape (its nodes,), int64."""
    depth = patch_depth(segmentation, int(index.pids[k]))
    return np.ceil(COST_UNITS * (1.0 + weight / depth)).astype(np.int64)


def _check_index(roadmap, arrays):
    """The shapes and index ranges of :meth:`CellSearchIndex.from_arrays`."""
    seg = roadmap.segmentation
    pids, offsets = arrays["pids"], arrays["offsets"]
    if not np.array_equal(pids, sorted(seg.patches)):
        raise InvalidInputError("the index lists other patches than the roadmap's")
    sizes = [seg.patches[pid].cells.size for pid in pids.tolist()]
    if not np.array_equal(offsets, np.concatenate([[0], np.cumsum(sizes)])):
        raise InvalidInputError("the index's patch sizes differ from the roadmap's")
    n, p = int(offsets[-1]), pids.size
    indptr, indices = arrays["indptr"], arrays["indices"]
    pairs = arrays["gate_pairs"]
    n_gates = 2 * len(seg.gates)
    d = seg.field.grid.ndim
    n_weights, n_clearances = arrays["weights"].size, arrays["clearances"].size
    shapes = {"node_cell": (n,), "node_slot": (n,), "node_patch": (n,), "node_margin": (n,),
              "indptr": (n + 1,), "quanta": indices.shape, "position": (n, d), "turn": (d,),
              "gate_pairs": (n_gates, 2), "gate_node_offsets": (n_gates + 1,),
              "quantum": (1,), "node_costs": (n_weights, n), "cost_floors": (n_weights, p),
              "centroids": (p, d), "gate_middles": (n_gates, d)}
    wrong = [name for name, shape in shapes.items() if arrays[name].shape != shape]
    if wrong or indices.ndim != 1 or arrays["clearances"].ndim != 1 \
            or arrays["weights"].ndim != 1:
        raise InvalidInputError(f"index arrays {wrong or ['indices/clearances/weights']} "
                                "have the wrong shape")
    starts = arrays["gate_node_offsets"]
    if (indptr[0] != 0 or indptr[-1] != indices.size or np.any(np.diff(indptr) < 0)
            or np.any(np.diff(starts) < 0) or starts[0] != 0
            or starts[-1] != arrays["gate_node_list"].size):
        raise InvalidInputError("the index's offsets are not ascending over its arrays")
    ranges = {"indices": n, "node_cell": seg.field.grid.size, "node_patch": p,
              "node_slot": seg.field.max_solutions, "gate_pairs": p, "gate_node_list": n}
    for name, stop in ranges.items():
        values = arrays[name]
        if values.size and (values.min() < 0 or values.max() >= stop):
            raise InvalidInputError(f"index array {name} points outside its range")
    if n_gates and (np.any(np.diff(pairs[:, 0]) < 0) or np.any(pairs[:, 0] == pairs[:, 1])):
        raise InvalidInputError("the index's gate pairs are not sorted pairs of two patches")
    field_size = int(np.diff(offsets)[pairs[:, 0]].sum()) if n_gates else 0
    if arrays["distances"].shape != (n_clearances, field_size):
        raise InvalidInputError("the index's gate distances have the wrong shape")
    if not (np.all(np.isfinite(arrays["node_margin"])) and arrays["quantum"][0] > 0
            and np.all(np.isfinite(arrays["centroids"]))
            and np.all(np.isfinite(arrays["gate_middles"]))):
        raise InvalidInputError("the index's margins, quantum, centroids or gate middles "
                                "are not finite")
