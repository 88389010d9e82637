"""The cell search: local planning inside patches and stitching along a
global path (paper section 3.3).

A move between face-adjacent cells costs its length times the mean cost of
the two cells.  A cell costs 1, so paths are as short as the cells allow,
unless its solution is closer to singular than the requested ``clearance``
(its normalised ``|det Jx|``): then it costs a hundred times more, so a path
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
order, and never a singular boundary or another gate.  The node graph, and
the gate distances that guide the search for the clearances in use, are the
roadmap's :class:`~.index.CellSearchIndex`, built once; a clearance or weight
the index lacks is computed on first use and kept by the planner.  Searches
run outside the interpreter's lock, each on work arrays of its thread, so
requests in several threads plan at once.

On a full 3-DOF roadmap, whose few large patches fold, the estimates fall
far below the costs where a way folds back, and a least-cost search settles
a hundred thousand nodes for a path of two hundred cells; there a coarse
graph's path marks a corridor that the search keeps to first
(:mod:`~.corridor`).
"""

from dataclasses import dataclass
import heapq
import math
import numbers
import threading

import numpy as np

from .astar import TIMED_OUT, UNREACHED, Guide, NodeCosts, Stop, layered_astar, work_arrays
from .corridor import clear_corridor, coarse_graph, mark_corridor
from .index import COST_UNITS, LOW_MARGIN_FACTOR, patch_costs, patch_depth, patch_gate_distances
from .termination import NEVER
from ..exceptions import InfeasiblePathError, InvalidInputError, PlanningTimeoutError

__all__ = ["CellSearch", "CellPath", "DEFAULT_CLEARANCE_WEIGHT", "CORRIDOR_MIN_NODES"]

DEFAULT_CLEARANCE_WEIGHT = 0.0
# Clearances outside the index whose gate distances a planner keeps (a full
# 3-DOF roadmap's take up to 180 MB each).
_KEPT_CLEARANCES = 4
# Scenes whose node margins a planner keeps (a full 3-DOF roadmap's take 24 MB each).
_KEPT_SCENES = 2
CORRIDOR_MIN_NODES = 1_000_000
"""Node graphs from this size on are searched in a corridor first
(:mod:`~.corridor`): a full 3-DOF roadmap's millions of nodes, not a slice's
hundreds of thousands, whose least-cost searches take a millisecond or two."""
# Side of a corridor's blocks [finest grid steps]: about a hundred nodes a
# block on the full 3-DOF roadmap.
_CORRIDOR_BLOCK = 8


@dataclass(frozen=True)
class CellPath:
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


class CellSearch:
    """Cost-weighted searches on the node graph of a roadmap's patches (cells
    of any dimension).

    Parameters
    ----------
    roadmap : Roadmap
    index : CellSearchIndex
        The roadmap's (:meth:`~.index.CellSearchIndex.build`).
    corridor_min_nodes : int
        Node graphs of at least this many nodes are searched in a corridor
        first (:meth:`search`); building their coarse graph takes about half
        a second on the full 3-DOF roadmap.
    """

    def __init__(self, roadmap, index, corridor_min_nodes=CORRIDOR_MIN_NODES):
        self.segmentation = roadmap.segmentation
        self.index = index
        # Gate distances and node costs the index lacks, filled patch by
        # patch on first use.  Threads may fill one part at once: they write
        # the same values, and a part is marked filled only once written.
        self._extra_fields = {}
        self._extra_costs = {}
        self._crossings = {}
        self._scenes = {}
        self._work = threading.local()
        self._coarse = None
        graph = index.graph
        if index.n_nodes >= corridor_min_nodes:
            finest = 2 * int(graph.quanta[graph.quanta > 0].min())
            self._coarse = coarse_graph(graph, _CORRIDOR_BLOCK * finest)
            n_coarse = self._coarse.graph.node_patch.size
            self._coarse_costs = NodeCosts(np.ones(n_coarse, np.int64), np.ones(n_coarse),
                                           0.0, 1)
            # Gate distances of nought: the coarse search's estimate is the
            # straight length alone, in every layer.
            self._coarse_fields = np.zeros(n_coarse, np.int64)

    def _costs(self, weight, k):
        """The node costs for a clearance weight, with those of the patch at
        index ``k`` filled; and that patch's smallest."""
        held = self.index.costs(weight)
        if held is not None:
            return held[0], int(held[1][k])
        costs, floors = self._extra_costs.setdefault(
            weight, (np.ones(self.index.n_nodes, dtype=np.int64), {}))
        if k not in floors:
            cost = patch_costs(self.segmentation, self.index, weight, k)
            costs[self.index.offsets[k]:self.index.offsets[k + 1]] = cost
            floors[k] = int(cost.min())
        return costs, floors[k]

    def _scene_margins(self, world):
        """The node margins of a scene: -1 where it blocks the solution (no
        search enters), 0 where it crowds an obstacle (costs as below any
        clearance).  The last few scenes' are kept."""
        kept = self._scenes.get(id(world))
        if kept is not None and kept[0] is world:
            return kept[1]
        graph = self.index.graph
        margins = np.where(world.free[graph.node_cell, self.index.node_slot],
                           self.index.node_margin, -1.0)
        margins[world.crowded[graph.node_cell, self.index.node_slot]] = 0.0
        self._scenes[id(world)] = (world, margins)
        for oldest in list(self._scenes)[:-_KEPT_SCENES]:
            self._scenes.pop(oldest, None)
        return margins

    def _work_arrays(self):
        """Work arrays of this thread's searches (:func:`~.astar.layered_astar`),
        kept for its next."""
        work = getattr(self._work, "arrays", None)
        if work is None:
            work = self._work.arrays = work_arrays(self.index.n_nodes,
                                                   self.index.graph.indices.size)
        return work

    def _corridor_arrays(self):
        """This thread's corridor marks (all zero between searches) and the
        work arrays of its coarse searches."""
        arrays = getattr(self._work, "corridor", None)
        if arrays is None:
            coarse = self._coarse.graph
            arrays = self._work.corridor = (
                np.zeros(self.index.n_nodes, np.uint8),
                work_arrays(coarse.node_patch.size, coarse.indices.size))
        return arrays

    def _astar(self, costs, layer, source, target, blocked, guide, stop, world):
        """:func:`~.astar.layered_astar` on the node graph, in a corridor first
        where the graph has a coarse one and no scene blocks nodes (which
        the coarse graph does not know).

        The corridor's coarse path avoids the coarse nodes that hold blocked
        cells.  A search with blocked cells (a repair, around a step the
        motion checker refused) that finds no way in its corridor ends
        there, as if the blocked cells cut the patches: on the whole graph
        it could settle every node of a patch to prove it.
        """
        graph, work = self.index.graph, self._work_arrays()
        everywhere = np.zeros(0, np.uint8)
        if self._coarse is None or world is not None:
            return layered_astar(graph, costs, layer, source, target, blocked, everywhere,
                                 guide, stop, work)
        corridor, coarse_work = self._corridor_arrays()
        coarse_of = self._coarse.coarse_of
        ends = (int(coarse_of[source]), int(coarse_of[target]))
        empty = np.zeros(0, np.int64)
        layers = np.zeros(int(layer.max()) + 1, np.int64)
        path, _ = layered_astar(
            self._coarse.graph, self._coarse_costs, layer, *ends,
            np.setdiff1d(coarse_of[self._nodes_of(blocked, layer)], ends), everywhere,
            Guide(1, self._coarse_fields, layers, layers, empty, empty),
            Stop(stop.deadline, 2**62), coarse_work)
        if path.size:
            marked = mark_corridor(self._coarse, path, corridor)
            try:
                nodes, cost = layered_astar(graph, costs, layer, source, target, blocked,
                                            corridor, guide, stop, work)
            finally:
                clear_corridor(self._coarse, marked, corridor)
            if nodes.size or cost == TIMED_OUT:
                return nodes, cost
        if blocked.size:
            return np.zeros(0, np.int64), UNREACHED
        return layered_astar(graph, costs, layer, source, target, blocked, everywhere, guide,
                             stop, work)

    def _nodes_of(self, cells, layer):
        """The nodes of the cells (ascending) in the patches with a layer."""
        if not cells.size:
            return np.zeros(0, np.int64)
        offsets, node_cell = self.index.offsets, self.index.graph.node_cell
        found = []
        for k in np.flatnonzero(layer >= 0).tolist():
            ours = node_cell[offsets[k]:offsets[k + 1]]
            at = np.minimum(np.searchsorted(ours, cells), max(ours.size - 1, 0))
            hit = ours[at] == cells if ours.size else np.zeros(cells.size, bool)
            found.append(offsets[k] + at[hit])
        return np.concatenate(found).astype(np.int64)

    def _fields(self, clearance):
        """The gate distances of a clearance (module doc of :mod:`~.astar`) and
        the set of gate pairs filled (None: all)."""
        held = self.index.distances(clearance)
        if held is not None:
            return held, None
        fields = self._extra_fields.get(clearance)
        if fields is None:
            # Pages of an empty array are only taken when filled.
            fields = self._extra_fields.setdefault(
                clearance, (np.empty(self.index.field_size, np.int64), set()))
            for oldest in list(self._extra_fields)[:-_KEPT_CLEARANCES]:
                self._extra_fields.pop(oldest, None)
        return fields

    def _distances_to_gate(self, fields, filled, k, other, clearance):
        """Offset in ``fields`` of the distances of the patch at index ``k`` to
        its gate to ``other``, computed if not yet filled."""
        pair = self.index.pair(k, other)
        offset = self.index.field_offset(pair)
        if filled is not None and pair not in filled:
            values = patch_gate_distances(self.index, pair, clearance, self._work_arrays())
            fields[offset:offset + values.size] = values
            filled.add(pair)
        return offset

    def _heuristic(self, index, target, clearance):
        """``fields``, ``to_gate_start``, ``rest``, ``landmark_start`` and
        ``landmark_goal`` of :func:`~.astar.layered_astar` for the patches at
        ``index``, the layers in order, and the target node."""
        fields, filled = self._fields(clearance)
        offsets = self.index.offsets
        starts = np.array([self._distances_to_gate(fields, filled, k, m, clearance)
                           for k, m in zip(index, index[1:])] + [0], dtype=np.int64)
        starts -= offsets[index]
        last = index[-1]
        neighbours = self.index.neighbours(last).tolist()
        landmark_start = np.array(
            [self._distances_to_gate(fields, filled, last, other, clearance)
             for other in neighbours], dtype=np.int64) - offsets[last]
        landmark_goal = fields[landmark_start + target]
        rest = np.zeros(len(index), dtype=np.int64)
        position, turn = self.index.graph.position, self.index.graph.turn
        if len(index) > 1:
            entry = self.index.gate_nodes(self.index.pair(index[-1], index[-2]))
            length = np.abs(position[entry].astype(np.int64) - position[target])
            length = np.where(turn > 0, np.minimum(length, turn - length), length)
            rest[-2] = np.min(length.sum(axis=1))
            # The goal's own cost to that gate, within its patch, bounds
            # every path entering there; usually far tighter.
            through = landmark_goal[neighbours.index(index[-2])]
            if through < UNREACHED:
                rest[-2] = max(rest[-2], through)
        for i in range(len(index) - 3, -1, -1):
            entry = self.index.gate_nodes(self.index.pair(index[i + 1], index[i]))
            rest[i] = rest[i + 1] + int(np.min(fields[starts[i + 1] + entry]))
        return fields, starts, rest, landmark_start, landmark_goal

    def _crossing_costs(self, clearance):
        """Least search cost, for each patch, from each of its gates to each
        other: ``{(k, entry, exit): cost}`` over patch indices (the gate
        distances of ``entry`` at the nodes next to ``exit``)."""
        crossings = self._crossings.get(clearance)
        if crossings is None:
            fields, filled = self._fields(clearance)
            crossings = {}
            for k in range(self.index.pids.size):
                neighbours = self.index.neighbours(k).tolist()
                for entry in neighbours:
                    start = self._distances_to_gate(fields, filled, k, entry, clearance) \
                        - int(self.index.offsets[k])
                    for leave in neighbours:
                        if leave != entry:
                            nodes = self.index.gate_nodes(self.index.pair(k, leave))
                            crossings[k, entry, leave] = int(fields[start + nodes].min())
            self._crossings[clearance] = crossings
        return crossings

    def cheapest_patches(self, start_patch, start_cell, goal_patch, goal_cell, clearance=0.0):
        """The sequence of patches whose local search promises to cost least.

        Each patch's share is the least cost between the gates it is
        entered and left by (from the start cell, to the goal cell), as if
        the crossing points could be chosen patch by patch, so the sum
        bounds the search's cost from below; a Dijkstra search over the gates
        minimises it.  Unlike the fewest gates, this weighs how far a path
        goes inside each patch.

        Parameters
        ----------
        start_patch, goal_patch : int
            Patch ids.
        start_cell, goal_cell : int
            Flat cells of those patches.
        clearance : float
            As for :meth:`plan`.

        Returns
        -------
        tuple of int or None
            Distinct patch ids from the start's to the goal's (where the
            cheapest bound comes back to a patch, the loop is cut out), or
            None when the gates join none.
        """
        if start_patch == goal_patch:
            return (int(start_patch),)
        pids = self.index.pids
        first, last = (int(k) for k in np.searchsorted(pids, [start_patch, goal_patch]))
        source = self._node(first, start_cell, "start")
        target = self._node(last, goal_cell, "goal")
        fields, filled = self._fields(clearance)
        crossings = self._crossing_costs(clearance)
        offsets = self.index.offsets

        def to_gate(k, other, node):
            start = self._distances_to_gate(fields, filled, k, other, clearance)
            return int(fields[start + node - offsets[k]])

        # States are (patch, the patch it was entered from); the goal is (-1, -1).
        queue = [(to_gate(first, other, source), other, first, ((first, -1),))
                 for other in self.index.neighbours(first).tolist()]
        heapq.heapify(queue)
        done = set()
        while queue:
            cost, k, entry, trail = heapq.heappop(queue)
            if k == -1:
                return _without_loops([int(pids[p]) for p, _ in trail]) \
                    if cost < UNREACHED else None
            if (k, entry) in done or cost >= UNREACHED:
                continue
            done.add((k, entry))
            trail = trail + ((k, entry),)
            if k == last:
                heapq.heappush(queue, (cost + to_gate(last, entry, target), -1, -1, trail))
            for leave in self.index.neighbours(k).tolist():
                if leave != entry and (leave, k) not in done:
                    heapq.heappush(queue, (cost + crossings[k, entry, leave], leave, k, trail))
        return None

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
        cells = self.segmentation.patches[int(self.index.pids[k])].cells
        local = int(np.searchsorted(cells, cell))
        if local >= cells.size or cells[local] != cell:
            raise InvalidInputError(f"{which} cell {cell} is not in its patch")
        return int(self.index.offsets[k]) + local

    def clearance(self, pid):
        """:func:`~.index.patch_depth` of a patch [cells]."""
        return patch_depth(self.segmentation, pid)

    def _layered_search(self, patches, start_cell, goal_cell, weight, clearance):
        """Source, target, layers, guide and node costs of a search through
        the patches of a global path."""
        seg = self.segmentation
        pids = self.index.pids
        patches = [int(pid) for pid in patches]
        index = np.searchsorted(pids, patches)
        if (not patches or np.any(index >= pids.size)
                or np.any(pids[np.minimum(index, pids.size - 1)] != patches)
                or len(set(patches)) != len(patches)):
            raise InvalidInputError(f"patches {patches} are not distinct patches of the roadmap")
        for a, b in zip(patches, patches[1:]):
            if (min(a, b), max(a, b)) not in seg.gates:
                raise InvalidInputError(f"patches {a} and {b} share no gate")
        source = self._node(index[0], start_cell, "start")
        target = self._node(index[-1], goal_cell, "goal")
        layer = np.full(pids.size, -1, dtype=np.int32)
        layer[index] = np.arange(len(patches), dtype=np.int32)
        index = index.tolist()
        costed = [self._costs(weight, k) for k in index]
        floor = min(f for _, f in costed)
        guide = Guide(floor, *self._heuristic(index, target, clearance))
        return source, target, layer, guide, costed[0][0]

    def _free_search(self, patches, start_cell, goal_cell, weight):
        """Source, target, layers, guide and node costs of a search from the
        start cell of the first patch to the goal cell of the last one,
        through every patch and gate."""
        pids = self.index.pids
        first, last = np.searchsorted(pids, [patches[0], patches[-1]]).tolist()
        if max(first, last) >= pids.size or pids[first] != patches[0] \
                or pids[last] != patches[-1]:
            raise InvalidInputError(f"patches {list(patches)} are not patches of the roadmap")
        source = self._node(first, start_cell, "start")
        target = self._node(last, goal_cell, "goal")
        costed = [self._costs(weight, k) for k in range(pids.size)]
        floor = min(f for _, f in costed)
        empty = np.zeros(0, dtype=np.int64)
        # One layer: the estimate is the straight length to the goal.
        guide = Guide(floor, empty, np.zeros(1, np.int64), np.zeros(1, np.int64), empty, empty)
        return source, target, np.zeros(pids.size, dtype=np.int32), guide, costed[0][0]

    def search(self, patches, start_cell, goal_cell, blocked=(), clearance=0.0,
               clearance_weight=DEFAULT_CLEARANCE_WEIGHT, termination=NEVER, any_gates=False,
               most_settled=None, world=None, inflation=1):
        """Best cell path from a start cell to a goal cell through given patches,
        or through any.

        On a node graph of at least ``corridor_min_nodes`` nodes, outside a
        scene, the search keeps to a corridor first (:mod:`~.corridor`): its
        path is the least-cost one of the corridor, and where the corridor
        holds none, of the whole graph; but a search with blocked cells that
        finds no way in its corridor raises ``InfeasiblePathError`` as if
        the blocked cells cut the patches.

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
            ``LOW_MARGIN_FACTOR`` times more.
        clearance_weight : float
            ``w`` of the paper's cell cost ``1 + w / d``; 0 gives shortest
            paths.
        termination : Termination
            The search stops at its deadline.
        any_gates : bool
            Search every patch, crossing any gate any number of times, from
            the start cell of the first of ``patches`` to the goal cell of
            the last: the shortest path on the node graph, which may leave
            a patch and come back, but with a weaker estimate to guide it.
        most_settled : int, optional
            The search stops after settling this many nodes, as at its
            deadline: a budget of work that, unlike time, gives the same
            answer on any machine and under any load.
        world : SceneRoadmap, optional
            A scene (:meth:`~rpr3_gwr_core.world.WorldIndex.apply`): the
            solutions it blocks are not entered, and those crowding its
            obstacles cost as those below the clearance.
        inflation : int
            Factor on the search's estimate (weighted A*): the path costs at
            most this many times the least, found after settling fewer
            nodes where the estimate falls far below the costs (a positive
            ``clearance_weight``); 1 gives a least-cost path.

        Returns
        -------
        CellPath

        Raises
        ------
        InvalidInputError
            If a patch is not in the roadmap or repeats, the cells are not in
            the end patches, two consecutive patches share no gate, the
            weight is negative or the inflation not a whole number of at
            least 1.
        InfeasiblePathError
            If no path exists (a patch's solutions are cut between its gates).
        PlanningTimeoutError
            If the deadline passed, or the budget was spent, first.
        """
        pids = self.index.pids
        if not (math.isfinite(clearance_weight) and clearance_weight >= 0):
            raise InvalidInputError("clearance_weight must be finite and non-negative")
        if isinstance(inflation, bool) or not isinstance(inflation, numbers.Integral) \
                or inflation < 1:
            raise InvalidInputError(f"inflation must be a whole number of at least 1, got "
                                    f"{inflation!r}")
        weight, clearance = float(clearance_weight), float(clearance)
        blocked = np.array(sorted(blocked), dtype=np.int64)
        if any_gates:
            source, target, layer, guide, costs = self._free_search(
                [int(pid) for pid in patches], start_cell, goal_cell, weight)
        else:
            source, target, layer, guide, costs = self._layered_search(
                patches, start_cell, goal_cell, weight, clearance)
        graph = self.index.graph
        margins = self.index.node_margin if world is None else self._scene_margins(world)
        nodes, cost = self._astar(
            NodeCosts(costs, margins, clearance, LOW_MARGIN_FACTOR), layer, source, target,
            blocked, guide._replace(cost_floor=guide.cost_floor * int(inflation)),
            Stop(termination.deadline, 2**62 if most_settled is None else int(most_settled)),
            world)
        if cost == TIMED_OUT:
            where = f"the local search through patches {'any' if any_gates else patches}"
            if termination():
                raise PlanningTimeoutError(f"the time limit passed in {where}")
            raise PlanningTimeoutError(f"{where} settled its budget of {most_settled} nodes")
        # Lengths in half quanta, node costs in units: back to length times cost.
        cost = float(cost) * self.index.quantum / 2 / (COST_UNITS if weight > 0 else 1)
        if nodes.size == 0:
            raise InfeasiblePathError(f"no local path through patches "
                                      f"{'any' if any_gates else patches}")
        return CellPath(cells=graph.node_cell[nodes], patches=pids[graph.node_patch[nodes]],
                         slots=self.index.node_slot[nodes], cost=cost)


def _without_loops(sequence):
    """A sequence of patches with every stretch between two visits of one
    patch cut out: consecutive patches stay joined by a gate."""
    out = []
    for patch in sequence:
        if patch in out:
            del out[out.index(patch) + 1:]
        else:
            out.append(patch)
    return tuple(out)
