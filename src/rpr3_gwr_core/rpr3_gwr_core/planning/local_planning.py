"""Local planning inside patches and stitching along a global path
(paper section 3.3).

A move between face-adjacent cells costs its length times the mean cost of
the two cells.  A cell costs 1, so paths are as short as the cells allow,
unless its solution is closer to singular than the requested ``clearance``
(its normalised |det Jx|): then it costs a hundred times more, so a path
passes there only where nothing else leads on, as next to a cusp or through
a narrow gate.  The paper's cost, ``1 + clearance_weight / d`` with ``d`` the
distance in cells to the nearest cell outside the patch (singular edge,
gate, other region or grid edge alike; Euclidean on uniform grids, along
faces on adaptive ones), is there too, rounded up to eighths (the search
counts in integers): a positive ``clearance_weight`` keeps paths clear of
every boundary until they must cross the planned gate, at the price of
longer paths.

Rather than planning patch by patch to a chosen gate cell, the patches of a
global path are the layers of one search: the nodes are the patches'
solutions, joined by their continuation links, and the search
(:func:`~rpr3_gwr_core.planning.astar.layered_astar`) stays in a layer or
steps to the next one across a face of the planned gate.  One least-cost
search from the start cell to the goal cell of the last layer then gives the
best stitched path: it crosses exactly the gates of the global path, in
order, and never a singular boundary or another gate.  The node graph of the
whole roadmap is built once, when the planner is made; each patch's
distances to each of its gates, which guide the search, are computed on
first use (or by :meth:`LocalPlanner.prepare`) and kept.  Searches run
outside the interpreter's lock, each on work arrays of its own, so requests
in several threads plan at once.
"""

import collections
from dataclasses import dataclass
import math
import os
import queue
import threading
import weakref

import numpy as np

from .astar import (TIMED_OUT, UNREACHED, Guide, NodeCosts, NodeGraph, adjacency, edge_quanta,
                    gate_distances, gate_nodes, layered_astar, node_positions, work_arrays)
from .termination import NEVER
from ..exceptions import InfeasiblePathError, InvalidInputError, PlanningTimeoutError
from ..workspace.segmentation import linked_solutions

__all__ = ["LocalPlanner", "LocalPath", "DEFAULT_CLEARANCE_WEIGHT"]

DEFAULT_CLEARANCE_WEIGHT = 0.0
_LOW_MARGIN_FACTOR = 100
_UNRESOLVED_DEPTH = 0.5
# The search's costs are integers (:mod:`~.astar`): the paper's cell cost
# 1 + w / d is rounded up to whole eighths.
_COST_UNITS = 8
# Clearances whose gate distances are kept (a full 3-DOF roadmap's take up to
# 180 MB each).
_KEPT_CLEARANCES = 4
# Every local planner, so that a process forked while another thread held one's
# lock gets a free one (the logging module does the same for its handlers).
_PLANNERS = weakref.WeakSet()


def _renew_locks():
    for planner in _PLANNERS:
        planner._lock = threading.Lock()


os.register_at_fork(after_in_child=_renew_locks)


@dataclass(frozen=True)
class LocalPath:
    """A stitched cell path.

    Attributes
    ----------
    cells : ndarray of int, shape (n,)
        Flat cell indices from the start cell to the goal cell.
    patches : ndarray of int, shape (n,)
        The patch of each cell.
    slots : ndarray of int, shape (n,)
        The solution slot of each cell in its patch.
    cost : float
        Weighted length [length unit].
    """

    cells: np.ndarray
    patches: np.ndarray
    slots: np.ndarray
    cost: float


class LocalPlanner:
    """Cost-weighted planning on the node graph of a roadmap's patches (cells
    of any dimension).

    Parameters
    ----------
    roadmap : Roadmap
    """

    def __init__(self, roadmap):
        seg = self.segmentation = roadmap.segmentation
        self._pids = np.array(sorted(seg.patches), dtype=np.int64)
        patches = [seg.patches[pid] for pid in self._pids.tolist()]
        sizes = [p.cells.size for p in patches]
        self._offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        n_nodes = int(self._offsets[-1])
        self._node_cell = np.concatenate([p.cells for p in patches] + [np.zeros(0, np.int64)])
        self._node_slot = np.concatenate([p.slots for p in patches] + [np.zeros(0, np.int64)])
        self._node_patch = np.repeat(np.arange(len(patches), dtype=np.int32), sizes)
        self._indptr, self._indices = adjacency(n_nodes, *self._edges(patches))
        index_of = {pid: k for k, pid in enumerate(self._pids.tolist())}
        self._neighbours = [[] for _ in patches]
        for a, b in seg.gates:
            self._neighbours[index_of[a]].append(index_of[b])
            self._neighbours[index_of[b]].append(index_of[a])
        self._coords = np.ascontiguousarray(seg.field.grid.coordinates(), dtype=np.float64)
        self._quantum = _lattice_quantum(seg.field.grid.steps)
        self._position = node_positions(self._coords[self._node_cell], self._quantum)
        self._quanta = edge_quanta(self._indptr, self._indices, self._position)
        self._graph = NodeGraph(self._indptr, self._indices, self._quanta, self._node_cell,
                                self._node_patch, self._position)
        self._node_margin = np.abs(seg.field.margin[self._node_cell, self._node_slot])
        # Per clearance weight, costs are filled patch by patch on first use
        # (the clearance of a large 3-D patch takes a while).
        self._node_cost = {}
        self._cost_floor = {}
        # Per clearance (most recently used last), the distances of every
        # patch to each of its gates in one array, each at an offset of its
        # own, filled on first use: a search then reads them in place.
        self._field_offset = {}
        total = 0
        for k, others in enumerate(self._neighbours):
            for other in others:
                self._field_offset[k, other] = total
                total += int(self._offsets[k + 1] - self._offsets[k])
        self._field_total = total
        self._to_gate = collections.OrderedDict()
        self._gate_nodes = {}
        self._lock = threading.Lock()
        _PLANNERS.add(self)
        self._work = queue.SimpleQueue()

    def _edges(self, patches):
        """The node pairs of every continuation link between two patch
        solutions, within a patch or across a gate."""
        seg = self.segmentation
        node_of = np.full(seg.patch.size, -1, dtype=np.int32)
        for p, offset in zip(patches, self._offsets.tolist()):
            node_of[p.cells * seg.patch.shape[1] + p.slots] = np.arange(
                offset, offset + p.cells.size, dtype=np.int32)
        a_all, b_all = [np.zeros(0, np.int32)], [np.zeros(0, np.int32)]
        for lower, upper, match in seg.links:
            a, b = (node_of[disks] for disks in linked_solutions(lower, upper, match))
            keep = (a >= 0) & (b >= 0)
            a_all.append(a[keep])
            b_all.append(b[keep])
        return np.concatenate(a_all), np.concatenate(b_all)

    def _costed(self, weight, k):
        """The node costs for a clearance weight, in whole units, with those of
        the patch at index ``k`` filled; and that patch's smallest."""
        if weight not in self._node_cost:
            self._node_cost[weight] = np.ones(self._node_cell.size, dtype=np.int64)
        costs = self._node_cost[weight]
        pid = int(self._pids[k])
        if (weight, pid) not in self._cost_floor:
            cost = np.ones(1, dtype=np.int64)
            if weight > 0:
                cost = np.ceil(_COST_UNITS * (1.0 + weight / self.clearance(pid)))
                costs[self._offsets[k]:self._offsets[k + 1]] = cost
            self._cost_floor[weight, pid] = int(np.min(cost))
        return costs, self._cost_floor[weight, pid]

    def _borrow(self):
        """Work arrays of a search (:func:`~.astar.layered_astar`): one set per
        search at a time, kept for the next."""
        try:
            return self._work.get_nowait()
        except queue.Empty:
            return work_arrays(self._node_cell.size, self._indices.size)

    def _patch_nodes(self, k, other):
        """Nodes of the patch at index ``k`` joined to the patch at index ``other``."""
        nodes = self._gate_nodes.get((k, other))
        if nodes is None:
            nodes = self._gate_nodes.setdefault((k, other), gate_nodes(
                self._indptr, self._indices, self._node_patch, self._offsets[k],
                self._offsets[k + 1], other))
        return nodes

    def _fields(self, clearance):
        """The gate distances of a clearance (module doc of
        :mod:`~.astar`) and the set of ``(k, other)`` already filled."""
        with self._lock:
            if clearance not in self._to_gate:
                # Pages of an empty array are only taken when filled.
                self._to_gate[clearance] = (np.empty(self._field_total, np.int64), set())
            self._to_gate.move_to_end(clearance)
            while len(self._to_gate) > _KEPT_CLEARANCES:
                self._to_gate.popitem(last=False)
            return self._to_gate[clearance]

    def _distances_to_gate(self, fields, filled, k, other, clearance):
        """Offset in ``fields`` of :func:`~.astar.gate_distances` of the patch at
        index ``k`` to its gate to ``other``, computed if not yet filled."""
        offset = self._field_offset[k, other]
        if (k, other) not in filled:
            # Computed without the lock: two threads may both compute one the
            # first time, and write the same values.
            work = self._borrow()
            try:
                costs = NodeCosts(self._costed(0.0, k)[0], self._node_margin, clearance,
                                  _LOW_MARGIN_FACTOR)
                fields[offset:offset + self._offsets[k + 1] - self._offsets[k]] = gate_distances(
                    self._graph, costs, self._pids.size, k, self._patch_nodes(k, other), work)
            finally:
                self._work.put(work)
            filled.add((k, other))
        return offset

    def _heuristic(self, index, target, clearance):
        """``fields``, ``to_gate_start``, ``rest``, ``landmark_start`` and
        ``landmark_goal`` of :func:`~.astar.layered_astar` for the patches at
        ``index``, the layers in order, and the target node."""
        fields, filled = self._fields(clearance)
        starts = np.array([self._distances_to_gate(fields, filled, k, m, clearance)
                           for k, m in zip(index, index[1:])] + [0], dtype=np.int64)
        starts -= self._offsets[index]
        last = index[-1]
        landmark_start = np.array(
            [self._distances_to_gate(fields, filled, last, other, clearance)
             for other in self._neighbours[last]], dtype=np.int64) - self._offsets[last]
        landmark_goal = fields[landmark_start + target]
        rest = np.zeros(len(index), dtype=np.int64)
        if len(index) > 1:
            entry = self._patch_nodes(index[-1], index[-2])
            rest[-2] = np.min(np.abs(self._position[entry].astype(np.int64)
                                     - self._position[target]).sum(axis=1))
            # The goal's own cost to that gate, within its patch, bounds
            # every path entering there; usually far tighter.
            through = landmark_goal[self._neighbours[last].index(index[-2])]
            if through < UNREACHED:
                rest[-2] = max(rest[-2], through)
        for i in range(len(index) - 3, -1, -1):
            entry = self._patch_nodes(index[i + 1], index[i])
            rest[i] = rest[i + 1] + int(np.min(fields[starts[i + 1] + entry]))
        return fields, starts, rest, landmark_start, landmark_goal

    def prepare(self, clearance, weights=()):
        """Compute every patch's costs to each of its gates for a clearance,
        and its node costs for clearance weights, now rather than on first
        use (a few tenths of a second for the paper's roadmap, seconds for
        the full 3-DOF one)."""
        fields, filled = self._fields(float(clearance))
        for k, others in enumerate(self._neighbours):
            for other in others:
                self._distances_to_gate(fields, filled, k, other, float(clearance))
        with self._lock:
            for weight in weights:
                for k in range(self._pids.size):
                    self._costed(float(weight), k)

    def cells_around(self, point, radius):
        """Cells within ``radius`` grid steps of a point along every axis.

        Parameters
        ----------
        point : ndarray, shape (d,)
            Coordinates on the grid's axes [joint unit].
        radius : float

        Returns
        -------
        ndarray of int
        """
        return self.segmentation.field.grid.cells_in_box(point, radius)

    def _node(self, k, cell, which):
        cells = self.segmentation.patches[int(self._pids[k])].cells
        local = int(np.searchsorted(cells, cell))
        if local >= cells.size or cells[local] != cell:
            raise InvalidInputError(f"{which} cell {cell} is not in its patch")
        return int(self._offsets[k]) + local

    def clearance(self, pid):
        """Distance of each cell of a patch to its nearest outside cell [cells].

        Cells the patch took from unresolved sets (region 0, see
        :mod:`~rpr3_gwr_core.segmentation`) lie on the singular locus: they
        count as outside for the others, and as half a cell deep themselves.
        """
        seg = self.segmentation
        patch = seg.patches[pid]
        own = seg.region[patch.cells] == patch.region
        depth = np.full(patch.cells.size, _UNRESOLVED_DEPTH)
        depth[own] = seg.field.grid.depth(patch.cells[own])
        return depth

    def plan(self, patches, start_cell, goal_cell, blocked=(), clearance=0.0,
             clearance_weight=DEFAULT_CLEARANCE_WEIGHT, termination=NEVER):
        """Best cell path from a start cell to a goal cell through given patches.

        Parameters
        ----------
        patches : sequence of int
            A global path: distinct patch ids, consecutive ones joined by a
            gate.
        start_cell, goal_cell : int
            Flat cells of the first and the last patch.
        blocked : collection of int
            Cells not to enter, such as those around a step the validator
            refused (the start cell is left anyway).
        clearance : float
            Cells whose solution's margin is below this cost
            ``_LOW_MARGIN_FACTOR`` times more.
        clearance_weight : float
            ``w`` of the paper's cell cost ``1 + w / d``; 0 gives shortest
            paths.
        termination : Termination
            The search stops at its deadline.

        Returns
        -------
        LocalPath

        Raises
        ------
        InvalidInputError
            If a patch is not in the roadmap or repeats, the cells are not in
            the end patches, two consecutive patches share no gate, or the
            weight is negative.
        InfeasiblePathError
            If no path exists (a patch's solutions are cut between its gates).
        PlanningTimeoutError
            If the deadline passed first.
        """
        seg = self.segmentation
        if not (math.isfinite(clearance_weight) and clearance_weight >= 0):
            raise InvalidInputError("clearance_weight must be finite and non-negative")
        patches = [int(pid) for pid in patches]
        index = np.searchsorted(self._pids, patches)
        if (not patches or np.any(index >= self._pids.size)
                or np.any(self._pids[np.minimum(index, self._pids.size - 1)] != patches)
                or len(set(patches)) != len(patches)):
            raise InvalidInputError(f"patches {patches} are not distinct patches of the roadmap")
        for a, b in zip(patches, patches[1:]):
            if (min(a, b), max(a, b)) not in seg.gates:
                raise InvalidInputError(f"patches {a} and {b} share no gate")
        source = self._node(index[0], start_cell, "start")
        target = self._node(index[-1], goal_cell, "goal")
        layer = np.full(self._pids.size, -1, dtype=np.int32)
        layer[index] = np.arange(len(patches), dtype=np.int32)
        blocked = np.array(sorted(blocked), dtype=np.int64)
        key = (float(clearance_weight), float(clearance))
        index = index.tolist()
        with self._lock:
            costed = [self._costed(key[0], k) for k in index]
        costs = costed[0][0]
        floor = min(f for _, f in costed)
        heuristic = self._heuristic(index, target, key[1])
        work = self._borrow()
        try:
            nodes, cost = layered_astar(
                self._graph, NodeCosts(costs, self._node_margin, key[1], _LOW_MARGIN_FACTOR),
                layer, source, target, blocked, Guide(floor, *heuristic), termination.deadline,
                work)
        finally:
            # layered_astar leaves its work arrays as it found them.
            self._work.put(work)
        if cost == TIMED_OUT:
            raise PlanningTimeoutError(f"the time limit passed in the local search through "
                                       f"patches {patches}")
        # Lengths in half quanta, node costs in units: back to length times cost.
        cost = float(cost) * self._quantum / 2 / (_COST_UNITS if key[0] > 0 else 1)
        if nodes.size == 0:
            raise InfeasiblePathError(f"no local path through patches {patches}")
        return LocalPath(cells=self._node_cell[nodes],
                         patches=self._pids[self._node_patch[nodes]],
                         slots=self._node_slot[nodes], cost=cost)


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
