"""Compiled graph kernels of the local planner: the node graph's adjacency and
an A* search restricted to the layers of a global path.

Each node is one solution of one cell of a patch.  The search may stay in a
layer (a patch of the global path) or step to the next layer (across a face
of the gate to the next patch), never elsewhere, so its path crosses exactly
the planned gates in order.  Edge weights are not stored: an edge between
face-adjacent cells costs its length (the cells' coordinate difference, one
axis) times the mean cost of its two nodes, which keeps a 3-D roadmap's
adjacency to one index array.

The heuristic is the smallest node cost of the path's patches times a
length that no path to the goal can undercut: the L1 distance to the goal
cell (every face-to-face move runs along one axis); in the layers before the
last, the larger of that and the node's shortest distance to the gate to the
next layer within its patch (:func:`gate_distances`, which depend on the
roadmap alone, computed once per patch and gate and kept by the caller) plus
the least such estimate at that gate's far side; in the last layer, where
the path stays in the goal's patch, the larger of the L1 distance and the
landmark bounds: by the triangle inequality a node is at least as far from
the goal as the difference of its and the goal's distances to one of the
patch's gates.  Each of these lengths drops by at most an edge's length
along an edge, so the heuristic is consistent; A* therefore returns a
least-cost path, like Dijkstra, after settling only the nodes whose estimate
is below its cost.  Ties are broken towards the deeper node, which on a
lattice with many equal-cost staircases keeps the search near one of them.
"""

import numba
import numpy as np

__all__ = ["adjacency", "edge_quanta", "layered_astar", "gate_distances", "gate_nodes"]


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


@numba.njit(cache=True)
def _before(key, tie, i, j):
    return key[i] < key[j] or (key[i] == key[j] and tie[i] < tie[j])


@numba.njit(cache=True)
def _swap(key, tie, item, i, j):
    key[i], key[j] = key[j], key[i]
    tie[i], tie[j] = tie[j], tie[i]
    item[i], item[j] = item[j], item[i]


@numba.njit(cache=True)
def _sift_up(key, tie, item, i):
    while i > 0:
        parent = (i - 1) >> 1
        if not _before(key, tie, i, parent):
            break
        _swap(key, tie, item, i, parent)
        i = parent


@numba.njit(cache=True)
def _sift_down(key, tie, item, size):
    i = 0
    while True:
        best = 2 * i + 1
        if best >= size:
            break
        if best + 1 < size and _before(key, tie, best + 1, best):
            best += 1
        if not _before(key, tie, best, i):
            break
        _swap(key, tie, item, i, best)
        i = best


@numba.njit(cache=True)
def _l1(coords, c, d):
    total = 0.0
    for k in range(coords.shape[1]):
        total += abs(coords[c, k] - coords[d, k])
    return total


@numba.njit(cache=True)
def _is_blocked(blocked, cell):
    k = np.searchsorted(blocked, cell)
    return k < blocked.size and blocked[k] == cell


@numba.njit(cache=True)
def _cost(node_cost, node_margin, clearance, penalty, u):
    return node_cost[u] * penalty if node_margin[u] < clearance else node_cost[u]


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


@numba.njit(cache=True)
def edge_quanta(indptr, indices, node_cell, coords, quantum):
    """Length of each edge of :func:`adjacency` in whole ``quantum``, rounded
    down, shape (indices.size,), uint16."""
    out = np.empty(indices.size, np.uint16)
    for u in range(indptr.size - 1):
        for e in range(indptr[u], indptr[u + 1]):
            out[e] = min(65535, int(_l1(coords, node_cell[u], node_cell[indices[e]]) / quantum
                                    + 1e-9))
    return out


@numba.njit(cache=True, nogil=True)
def gate_distances(indptr, indices, quanta, quantum, first, stop, sources):
    """Shortest distance [joint unit] from each node of one patch to any of
    ``sources`` within the patch, along the node graph, with the edge
    lengths of :func:`edge_quanta`.

    Rounded down, every distance stays a lower bound of the true one and
    drops by at most an edge's length along an edge; in whole quanta the
    search is Dial's (a ring of buckets instead of a heap).  A grid's face
    lengths are whole multiples of its smallest step, the quantum the
    planner takes, so nothing is lost.

    Parameters
    ----------
    quanta : ndarray of uint16, shape (indices.size,)
    quantum : float
        Length unit of ``quanta`` [joint unit].
    first, stop : int
        The patch's nodes are ``first .. stop - 1``.
    sources : ndarray of int
        Nodes of the patch at distance 0.

    Returns
    -------
    ndarray of float64, shape (stop - first,)
        Infinite where no source can be reached.
    """
    n = stop - first
    unreached = np.iinfo(np.int64).max
    distance = np.full(n, unreached, np.int64)
    longest = 1
    for e in range(indptr[first], indptr[stop]):
        longest = max(longest, int(quanta[e]))
    # Entries of the ring's buckets, as linked lists; a node enters once per
    # improvement, so the edges bound the entries.
    ring = longest + 1
    head = np.full(ring, -1, np.int64)
    capacity = sources.size + indptr[stop] - indptr[first]
    entry_node = np.empty(capacity, np.int64)
    entry_next = np.empty(capacity, np.int64)
    entries = 0
    for s in sources:
        distance[s - first] = 0
        entry_node[entries], entry_next[entries] = s, head[0]
        head[0] = entries
        entries += 1
    pending = sources.size
    level = 0
    while pending > 0:
        bucket = level % ring
        while head[bucket] >= 0:
            k = head[bucket]
            head[bucket] = entry_next[k]
            pending -= 1
            u = entry_node[k]
            if distance[u - first] != level:
                continue  # a stale entry: u was reached closer since
            for e in range(indptr[u], indptr[u + 1]):
                v = indices[e]
                if v < first or v >= stop:
                    continue
                reach = level + quanta[e]
                if reach < distance[v - first]:
                    distance[v - first] = reach
                    slot = reach % ring
                    entry_node[entries], entry_next[entries] = v, head[slot]
                    head[slot] = entries
                    entries += 1
                    pending += 1
        level += 1
    out = np.empty(n)
    for k in range(n):
        out[k] = np.inf if distance[k] == unreached else distance[k] * quantum
    return out


@numba.njit(cache=True)
def _estimate(coords, node_cell, node_patch, layer, to_gate, to_gate_start, rest, landmarks,
              last, cost_floor, goal, v):
    """The heuristic of node ``v`` (module doc)."""
    length = _l1(coords, node_cell[v], goal)
    here = layer[node_patch[v]]
    if here < last:
        length = max(length, to_gate[to_gate_start[here] + v] + rest[here])
    else:
        at = v + to_gate_start[last]
        for j in range(landmarks.shape[0]):
            length = max(length, abs(landmarks[j, at] - landmarks[j, -1]))
    return cost_floor * length


@numba.njit(cache=True, nogil=True)
def layered_astar(indptr, indices, node_cell, node_patch, node_cost, node_margin, clearance,
                  penalty, coords, layer, source, target, blocked, cost_floor, to_gate,
                  to_gate_start, rest, landmarks, g, pred, closed, touched):
    """Least-cost node path from ``source`` to ``target`` through the layers.

    Parameters
    ----------
    indptr, indices : ndarray
        The node graph (:func:`adjacency`).
    node_cell : ndarray of int, shape (n_nodes,)
        Cell of each node.
    node_patch : ndarray of int32, shape (n_nodes,)
        Index of each node's patch.
    node_cost : ndarray of float64, shape (n_nodes,)
        Cost per unit length of each node (needed on the path's patches).
    node_margin : ndarray of float64, shape (n_nodes,)
        Margin magnitude of each node's solution.
    clearance, penalty : float
        Nodes with a margin below ``clearance`` cost ``penalty`` times more.
    coords : ndarray of float64, shape (n_cells, d)
        Coordinates of the cells [joint unit].
    layer : ndarray of int32, shape (n_patches,)
        Position of each patch on the global path, -1 off it.
    source, target : int
        Nodes of the start cell (layer 0) and of the goal cell (last layer).
    blocked : ndarray of int64, shape (k,)
        Cells not to enter, ascending.
    cost_floor : float
        Smallest ``node_cost`` on the path's patches (scales the heuristic).
    to_gate, to_gate_start, rest : ndarray of float64, int64, float64
        Lengths [joint unit] for the layers before the last: a node ``v`` in
        layer ``i`` is at least ``to_gate[to_gate_start[i] + v] + rest[i]``
        from the target (:func:`gate_distances` of its patch to the next
        gate, and the least such bound beyond that gate);
        ``-to_gate_start[last]`` is the first node of the last layer.
    landmarks : ndarray of float64, shape (k, n + 1)
        :func:`gate_distances` of the last layer's patch (its ``n`` nodes) to
        each of its gates, then of the target: by the triangle inequality,
        within the patch a node is at least ``|landmarks[j, node] -
        landmarks[j, -1]|`` from the target.
    g, pred, closed, touched : ndarray, shape (n_nodes,)
        Work arrays: ``g`` all infinite and ``closed`` all zero on entry,
        and so again on return.

    Returns
    -------
    nodes : ndarray of int64
        The path, empty when the target cannot be reached.
    cost : float
    """
    capacity = 1024
    key = np.empty(capacity)
    tie = np.empty(capacity)
    item = np.empty(capacity, np.int64)
    goal = node_cell[target]
    last = layer[node_patch[target]]
    g[source] = 0.0
    pred[source] = -1
    touched[0] = source
    n_touched = 1
    key[0] = _estimate(coords, node_cell, node_patch, layer, to_gate, to_gate_start, rest,
                       landmarks, last, cost_floor, goal, source)
    tie[0] = 0.0
    item[0] = source
    size = 1
    found = False
    while size > 0:
        u = item[0]
        size -= 1
        if size > 0:
            key[0], tie[0], item[0] = key[size], tie[size], item[size]
            _sift_down(key, tie, item, size)
        if closed[u]:
            continue
        closed[u] = 1
        if u == target:
            found = True
            break
        here = layer[node_patch[u]]
        cell = node_cell[u]
        cost_u = _cost(node_cost, node_margin, clearance, penalty, u)
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            if closed[v]:
                continue
            there = layer[node_patch[v]]
            if there != here and there != here + 1:
                continue
            other = node_cell[v]
            if blocked.size and _is_blocked(blocked, other):
                continue
            reach = g[u] + 0.5 * _l1(coords, cell, other) * (
                cost_u + _cost(node_cost, node_margin, clearance, penalty, v))
            if reach < g[v]:
                if g[v] == np.inf:
                    touched[n_touched] = v
                    n_touched += 1
                g[v] = reach
                pred[v] = u
                if size == capacity:
                    capacity *= 2
                    key = np.concatenate((key, np.empty(size)))
                    tie = np.concatenate((tie, np.empty(size)))
                    item = np.concatenate((item, np.empty(size, np.int64)))
                key[size] = reach + _estimate(coords, node_cell, node_patch, layer, to_gate,
                                              to_gate_start, rest, landmarks, last, cost_floor,
                                              goal, v)
                tie[size] = -reach
                item[size] = v
                _sift_up(key, tie, item, size)
                size += 1
    cost = g[target]
    count = 0
    if found:
        node = target
        while node >= 0:
            count += 1
            node = pred[node]
    nodes = np.empty(count, np.int64)
    node = target
    for k in range(count - 1, -1, -1):
        nodes[k] = node
        node = pred[node]
    for k in range(n_touched):
        g[touched[k]] = np.inf
        closed[touched[k]] = 0
    return nodes, cost
