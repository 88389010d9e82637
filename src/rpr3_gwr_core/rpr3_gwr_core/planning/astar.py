"""Compiled graph kernels of the cell search: the node graph, and one
least-cost search that serves both an A* through the layers of a global path
and the distances inside a patch that guide it.

Each node is one solution of one cell of a patch.  The search may stay in a
layer (a patch of the global path) or step to the next layer (across a face
of the gate to the next patch), never elsewhere, so its path crosses exactly
the planned gates in order.  Edge weights are not stored: an edge between
face-adjacent cells costs its length times the mean cost of its two nodes,
which keeps a 3-D roadmap's adjacency to one index array.

Costs are integers: lengths in whole quanta (the longest length of which
every grid step is a whole multiple: the smallest step on the grids built
here; :func:`edge_quanta`), node costs in
whole units (1, or ``penalty`` below the clearance, times the caller's
clearance weight cost in whole units), so an edge of ``q`` quanta between
nodes of costs ``a`` and ``b`` costs ``q (a + b)``.  The open set is then a
ring of buckets, one per cost, with no heap: Dial's algorithm, and A* on it.

The heuristic is the smallest node cost of the path's patches times a length,
in half quanta, that no path to the goal can undercut: the L1 distance to the
goal cell (every face-to-face move runs along one axis); in the layers
before the last, the larger of that and the node's least cost to the gate to
the next layer within its patch (:func:`gate_distances`, which depend on the
roadmap and the clearance only, computed once per patch and gate and kept by
the caller) plus the least such estimate at that gate's far side; in the last
layer, where the path stays in the goal's patch, the larger of the L1
distance and the landmark bounds: by the triangle inequality a node costs at
least the difference of its and the goal's costs to one of the patch's
gates.  Each of these drops by at most an edge's cost along an edge, so the
heuristic is consistent and A* returns a least-cost path, like Dijkstra,
after settling only the nodes whose estimate is below its cost.  A bucket is
a stack, so of nodes with equal estimates the one pushed last, the deeper
one, is settled first, which on a lattice with many equal-cost staircases
keeps the search near one of them.
"""

from typing import NamedTuple

import numba
import numpy as np

from .termination import monotonic

__all__ = ["NodeGraph", "NodeCosts", "Guide", "Stop", "WorkArrays", "adjacency", "node_positions",
           "edge_quanta", "gate_nodes", "work_arrays", "gate_distances", "layered_astar",
           "UNREACHED", "TIMED_OUT"]

# Cost of a node the search did not reach; far above any path's, with room
# to add estimates without overflow.
UNREACHED = 2**50
# The cost layered_astar returns when it stopped (deadline or node budget) before the target.
TIMED_OUT = -1
# Buckets of the open set's ring; estimates farther ahead wait in an overflow list.
_RING = 4096
# Nodes settled between two looks at the clock (a look costs about 30 ns).
_CLOCK_PERIOD = 1024


class NodeGraph(NamedTuple):
    """The node graph of a roadmap, read-only once built.

    Attributes
    ----------
    indptr, indices : ndarray
        Adjacency (CSR, :func:`adjacency`).
    quanta : ndarray of uint16, shape (indices.size,)
        Edge lengths in quanta (:func:`edge_quanta`).
    node_cell : ndarray of int, shape (n_nodes,)
        Cell of each node.
    node_patch : ndarray of int32, shape (n_nodes,)
        Index of each node's patch, ascending.
    position : ndarray of int32, shape (n_nodes, d)
        Coordinates of the nodes' cells in half quanta (:func:`node_positions`).
    turn : ndarray of int64, shape (d,)
        The period of each axis in half quanta, 0 where it has none: along a
        periodic axis a length is the shorter way round.
    """

    indptr: np.ndarray
    indices: np.ndarray
    quanta: np.ndarray
    node_cell: np.ndarray
    node_patch: np.ndarray
    position: np.ndarray
    turn: np.ndarray


class NodeCosts(NamedTuple):
    """What a node costs in one search.

    Attributes
    ----------
    node_cost : ndarray of int64, shape (n_nodes,)
        Cost of each node in whole units (needed on the searched patches).
    node_margin : ndarray of float64, shape (n_nodes,)
        Margin magnitude of each node's solution; negative for a node no
        search may enter (a scene blocks it).
    clearance : float
    penalty : int
        Nodes with a margin below ``clearance`` cost ``penalty`` times more.
    """

    node_cost: np.ndarray
    node_margin: np.ndarray
    clearance: float
    penalty: int


class Guide(NamedTuple):
    """The heuristic of :func:`layered_astar` (module doc).

    Attributes
    ----------
    cost_floor : int
        Smallest ``node_cost`` on the path's patches (scales the heuristic);
        0 searches without heuristic; ``k`` times it inflates the estimate
        (weighted A*): the path found costs at most ``k`` times the least.
    fields : ndarray of int64
        :func:`gate_distances` of patches, each at an offset of its own.
    to_gate_start, rest : ndarray of int64, shape (layers,)
        Costs for the layers before the last: a node ``v`` in layer ``i``
        costs at least ``fields[to_gate_start[i] + v] + rest[i]`` to the
        target (the distances of its patch to the next gate, and the least
        such bound beyond that gate).
    landmark_start, landmark_goal : ndarray of int64, shape (k,)
        The last layer's patch's distances to each of its gates, at
        ``fields[landmark_start[j] + v]``, and the target's: within the
        patch a node costs at least their difference.
    """

    cost_floor: int
    fields: np.ndarray
    to_gate_start: np.ndarray
    rest: np.ndarray
    landmark_start: np.ndarray
    landmark_goal: np.ndarray


class Stop(NamedTuple):
    """Where a search stops before its target.

    Attributes
    ----------
    deadline : float
        [s] on the monotonic clock (:func:`~.termination.monotonic`).
    most_settled : int
        Nodes settled at most: a budget of work, the same on any machine
        and under any load, where a deadline is not.
    """

    deadline: float
    most_settled: int


class WorkArrays(NamedTuple):
    """The arrays one search at a time works in (:func:`work_arrays`):
    ``g`` all :data:`UNREACHED` and ``closed`` all zero between searches."""

    g: np.ndarray
    pred: np.ndarray
    closed: np.ndarray
    touched: np.ndarray
    entry_node: np.ndarray
    entry_next: np.ndarray
    waiting_node: np.ndarray
    waiting_key: np.ndarray


@numba.njit(cache=True)
def adjacency(n_nodes, a, b):
    """Symmetric adjacency (CSR) of undirected edges.

    Parameters
    ----------
    n_nodes : int
    a, b : ndarray of int32, shape (n_edges,)
        The two nodes of each edge.

    Returns
    -------
    indptr : ndarray of int64, shape (n_nodes + 1,)
    indices : ndarray of int32, shape (2 * n_edges,)
    """
    indptr = np.zeros(n_nodes + 1, np.int64)
    for k in range(a.size):
        indptr[a[k] + 1] += 1
        indptr[b[k] + 1] += 1
    for i in range(n_nodes):
        indptr[i + 1] += indptr[i]
    fill = indptr[:-1].copy()
    indices = np.empty(2 * a.size, np.int32)
    for k in range(a.size):
        indices[fill[a[k]]] = b[k]
        fill[a[k]] += 1
        indices[fill[b[k]]] = a[k]
        fill[b[k]] += 1
    return indptr, indices


def node_positions(coords, quantum):
    """Coordinates of nodes (or cells) in whole half quanta from the lowest,
    shape (n, d), int32: the search's lengths are their L1 distances, read
    next to each node's other data rather than through its cell.

    Parameters
    ----------
    coords : ndarray, shape (n, d)
        Coordinates on the grid's axes [joint unit], on the quantum's lattice.
    quantum : float
        The length of one quantum [joint unit].
    """
    coords = np.asarray(coords, dtype=float)
    low = coords.min(axis=0) if coords.size else 0.0
    return np.ascontiguousarray(np.rint(2.0 * (coords - low) / quantum), dtype=np.int32)


@numba.njit(cache=True, inline="always")
def _half_quanta(position, turn, u, v):
    """L1 distance of two nodes in half quanta, the shorter way round along
    the axes with a ``turn``."""
    total = 0
    for k in range(position.shape[1]):
        length = abs(np.int64(position[u, k]) - np.int64(position[v, k]))
        if turn[k] > 0:
            length = min(length, turn[k] - length)
        total += length
    return total


@numba.njit(cache=True)
def edge_quanta(indptr, indices, position, turn):
    """Length of each edge of :func:`adjacency` in whole quanta (of
    :func:`node_positions`; ``turn`` as :class:`NodeGraph`'s), shape
    (indices.size,), uint16."""
    out = np.empty(indices.size, np.uint16)
    for u in range(indptr.size - 1):
        for e in range(indptr[u], indptr[u + 1]):
            out[e] = min(65535, _half_quanta(position, turn, u, indices[e]) // 2)
    return out


@numba.njit(cache=True, nogil=True)
def gate_nodes(indptr, indices, node_patch, first, stop, other):
    """Nodes in ``[first, stop)`` (one patch) with an edge to a node of patch
    index ``other``, ascending."""
    out = np.empty(stop - first, np.int64)
    count = 0
    for u in range(first, stop):
        for e in range(indptr[u], indptr[u + 1]):
            if node_patch[indices[e]] == other:
                out[count] = u
                count += 1
                break
    return out[:count]


@numba.njit(cache=True, inline="always")
def _is_blocked(blocked, cell):
    k = np.searchsorted(blocked, cell)
    return k < blocked.size and blocked[k] == cell


@numba.njit(cache=True, inline="always")
def _node_cost(node_cost, node_margin, clearance, penalty, u):
    return node_cost[u] * penalty if node_margin[u] < clearance else node_cost[u]


def work_arrays(n_nodes, n_links):
    """The work arrays of one search at a time (:func:`layered_astar`,
    :func:`gate_distances`), reusable from one search to the next.

    A search pushes a node at most once per link that reaches it and once
    as a source, so its open set fits in ``n_links + n_nodes`` entries: it
    never grows them, and numba then keeps no reference counts in its loop
    (growing arrays there cost a third of the search in atomic counts).
    Pages are only taken as a search fills them.

    Parameters
    ----------
    n_nodes, n_links : int
        Nodes, and directed links (``indices.size`` of :func:`adjacency`).

    Returns
    -------
    WorkArrays
        ``g`` (int64, all :data:`UNREACHED`), ``pred`` (int64), ``closed``
        (uint8, all zero), ``touched`` (int64), each of ``n_nodes``; then
        the open set's entries (node and next entry, int32), and the nodes
        (int32) and keys (int64) waiting beyond the ring, each of
        ``n_links + n_nodes``.
    """
    capacity = n_links + n_nodes
    return WorkArrays(np.full(n_nodes, UNREACHED, np.int64), np.empty(n_nodes, np.int64),
                      np.zeros(n_nodes, np.uint8), np.empty(n_nodes, np.int64),
                      np.empty(capacity, np.int32), np.empty(capacity, np.int32),
                      np.empty(capacity, np.int32), np.empty(capacity, np.int64))


@numba.njit(cache=True, nogil=True)
def _search(graph, costs, layer, sources, target, blocked, corridor, guide, stop, work):
    """Least costs from ``sources`` through the layers, up to ``target`` (all
    reachable nodes when it is -1), in the ``corridor`` when it is not
    empty, stopping where ``stop`` says; returns
    how many nodes it touched, which are the first entries of ``touched``,
    and whether it stopped before the target."""
    # Unpacked once: the loop then reads plain local arrays, without the
    # reference counting of taking them out of a bundle at each use.
    indptr, indices, quanta, node_cell, node_patch, position, turn = graph
    node_cost, node_margin, clearance, penalty = costs
    cost_floor, fields, to_gate_start, rest, landmark_start, landmark_goal = guide
    g, pred, closed, touched, entry_node, entry_next, waiting_node, waiting_key = work
    goal = max(target, 0)
    last = layer[node_patch[target]] if target >= 0 else 0
    # The ring's buckets are stacks linked through the entries.
    head = np.full(_RING, -1, np.int64)
    entries = 0
    waiting = 0
    n_touched = 0
    # Sources cost 0 and are settled first, whatever their estimates: the
    # keys of the nodes they reach are estimated as usual.
    for s in sources:
        g[s] = 0
        pred[s] = -1
        touched[n_touched] = s
        n_touched += 1
        waiting_node[waiting], waiting_key[waiting] = s, 0
        waiting += 1
    pending = 0
    current = 0
    taken_at = -1
    settled = 0
    while True:
        if pending == 0:
            if waiting == 0:
                break
            current = max(current, waiting_key[:waiting].min())
        if current != taken_at and (pending == 0 or current % _RING == 0):
            taken_at = current
            # The ring holds the keys current .. current + _RING - 1: take
            # the waiting ones that now fall in it.
            kept = 0
            for w in range(waiting):
                if waiting_key[w] < current + _RING:
                    bucket = waiting_key[w] % _RING
                    entry_node[entries], entry_next[entries] = waiting_node[w], head[bucket]
                    head[bucket] = entries
                    entries += 1
                    pending += 1
                else:
                    waiting_node[kept], waiting_key[kept] = waiting_node[w], waiting_key[w]
                    kept += 1
            waiting = kept
        bucket = current % _RING
        if head[bucket] < 0:
            current += 1
            continue
        k = head[bucket]
        head[bucket] = entry_next[k]
        pending -= 1
        u = entry_node[k]
        if closed[u]:
            continue
        closed[u] = 1
        if u == target:
            break
        settled += 1
        if settled >= stop.most_settled or (settled % _CLOCK_PERIOD == 0
                                            and monotonic() >= stop.deadline):
            return n_touched, True
        here = layer[node_patch[u]]
        cost_u = _node_cost(node_cost, node_margin, clearance, penalty, u)
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            # The corridor's marks first: of the node's own arrays, a search
            # kept to a corridor then reads only those of the nodes in it.
            if closed[v] or (corridor.size and corridor[v] == 0):
                continue
            there = layer[node_patch[v]]
            if there < 0 or (there != here and there != here + 1) or node_margin[v] < 0:
                continue
            if blocked.size and _is_blocked(blocked, node_cell[v]):
                continue
            reach = g[u] + quanta[e] * (cost_u + _node_cost(node_cost, node_margin, clearance,
                                                            penalty, v))
            if reach < g[v]:
                if g[v] == UNREACHED:
                    touched[n_touched] = v
                    n_touched += 1
                g[v] = reach
                pred[v] = u
                # The estimate (module doc), written out here, its only use:
                # a call passing these arrays would count references.
                length = 0
                if cost_floor:
                    length = _half_quanta(position, turn, v, goal)
                    if there < last:
                        length = max(length, fields[to_gate_start[there] + v] + rest[there])
                    else:
                        for j in range(landmark_start.size):
                            at = fields[landmark_start[j] + v]
                            if at < UNREACHED and landmark_goal[j] < UNREACHED:
                                length = max(length, abs(at - landmark_goal[j]))
                # A consistent estimate never puts a key behind the current one;
                # an inflated one may, and such a node is settled next.
                key = max(current, reach + cost_floor * length)
                if key < current + _RING:
                    bucket = key % _RING
                    entry_node[entries], entry_next[entries] = v, head[bucket]
                    head[bucket] = entries
                    entries += 1
                    pending += 1
                else:
                    waiting_node[waiting], waiting_key[waiting] = v, key
                    waiting += 1
    return n_touched, False


@numba.njit(cache=True)
def _reset(g, closed, touched, n_touched):
    for k in range(n_touched):
        g[touched[k]] = UNREACHED
        closed[touched[k]] = 0


@numba.njit(cache=True, nogil=True)
def gate_distances(graph, costs, n_patches, k, sources, work):
    """Least cost from each node of one patch to any of ``sources`` within the
    patch, in the units of :func:`layered_astar`.

    Taken with node costs of 1 (or ``penalty`` below ``clearance``), these
    are lower bounds of the search's costs, after scaling by its smallest
    node cost, and drop by at most an edge's cost along an edge.

    Parameters
    ----------
    graph : NodeGraph
    costs : NodeCosts
        ``node_cost`` 1 on the patch's nodes.
    n_patches, k : int
        Number of patches, index of this one; its nodes are those with
        ``node_patch == k``, contiguous.
    sources : ndarray of int
        Nodes of the patch at cost 0.
    work : WorkArrays

    Returns
    -------
    ndarray of int64, shape (patch nodes,)
        :data:`UNREACHED` where no source can be reached.
    """
    first = np.searchsorted(graph.node_patch, k)
    end = np.searchsorted(graph.node_patch, k, side="right")
    layer = np.full(n_patches, -1, np.int32)
    layer[k] = 0
    empty = np.zeros(0, np.int64)
    n_touched, _ = _search(graph, costs, layer, sources, -1, empty, np.zeros(0, np.uint8),
                           (0, empty, empty, empty, empty, empty), Stop(np.inf, 2**62), work)
    out = work.g[first:end].copy()
    _reset(work.g, work.closed, work.touched, n_touched)
    return out


@numba.njit(cache=True, nogil=True)
def layered_astar(graph, costs, layer, source, target, blocked, corridor, guide, stop, work):
    """Least-cost node path from ``source`` to ``target`` through the layers.

    Parameters
    ----------
    graph : NodeGraph
    costs : NodeCosts
    layer : ndarray of int32, shape (n_patches,)
        Position of each patch on the global path, -1 off it.
    source, target : int
        Nodes of the start cell (layer 0) and of the goal cell (last layer).
    blocked : ndarray of int64, shape (k,)
        Cells not to enter, ascending.
    corridor : ndarray of uint8, shape (n_nodes,) or (0,)
        Nodes that may be entered (1) and not (0) (:mod:`~.corridor`);
        empty: all.
    guide : Guide
        The heuristic; its ``cost_floor`` at least 1.
    stop : Stop
        Where the search stops before the target.
    work : WorkArrays
        Left as it was found.

    Returns
    -------
    nodes : ndarray of int64
        The path, empty when the target cannot be reached or the search
        stopped first.
    cost : int
        Its cost: lengths in half quanta times node costs in units;
        :data:`TIMED_OUT` when the search stopped first.
    """
    sources = np.full(1, source, np.int64)
    n_touched, timed_out = _search(graph, costs, layer, sources, target, blocked, corridor,
                                   guide, stop, work)
    g, pred, closed = work.g, work.pred, work.closed
    cost = TIMED_OUT if timed_out else g[target]
    count = 0
    if closed[target] and not timed_out:
        node = target
        while node >= 0:
            count += 1
            node = pred[node]
    nodes = np.empty(count, np.int64)
    node = target
    for k in range(count - 1, -1, -1):
        nodes[k] = node
        node = pred[node]
    _reset(g, closed, work.touched, n_touched)
    return nodes, cost
