"""Corridors: where a cell search on a large roadmap looks first.

On a full 3-DOF roadmap (millions of nodes, a few large folded patches) the
least-cost search's estimates fall far below the costs wherever a way folds
back, and it settles a hundred thousand nodes for a path of two hundred
cells.  A coarse graph of the same roadmap answers the same question with a
hundredth of the nodes: a coarse node is a set of one patch's nodes in one
block of the grid that links join inside the block (where a patch folds,
its sheets in one block are apart), and two coarse nodes are joined where a
link joins their nodes.  Any node of a coarse path then reaches any other
through the path's nodes alone.  The cheapest coarse path, through the
same layers (the patches of a global path, in order) as the fine search,
widened by its coarse neighbours, is the corridor the fine search is kept in
(:func:`~.astar.layered_astar`'s ``corridor``); where the corridor holds no
fine path (blocked cells may cut it), the search runs on the whole graph.
A corridor's path is as short as the corridor allows, not always the
least-cost one of the whole graph.
"""

from typing import NamedTuple

import numba
import numpy as np

from .astar import NodeGraph, adjacency, edge_quanta

__all__ = ["CoarseGraph", "coarse_graph", "mark_corridor", "clear_corridor"]


class CoarseGraph(NamedTuple):
    """The coarse graph of a node graph (module doc), read-only once built.

    Attributes
    ----------
    graph : NodeGraph
        Coarse nodes: ``node_patch`` their patch index, ``position`` the
        middle of their block in half quanta, ``node_cell`` their own index.
    coarse_of : ndarray of int32, shape (n_nodes,)
        The coarse node of each node.
    member_start : ndarray of int64, shape (n_coarse + 1,)
        The nodes of coarse node ``c`` are ``members[member_start[c]:member_start[c + 1]]``.
    members : ndarray of int32, shape (n_nodes,)
    """

    graph: NodeGraph
    coarse_of: np.ndarray
    member_start: np.ndarray
    members: np.ndarray


def coarse_graph(graph, block):
    """The coarse graph of a node graph.

    Parameters
    ----------
    graph : NodeGraph
    block : int
        Side of a block in half quanta (of :func:`~.astar.node_positions`).

    Returns
    -------
    CoarseGraph
    """
    blocks = graph.position // block
    extent = blocks.max(axis=0).astype(np.int64) + 1 if blocks.size else \
        np.ones(blocks.shape[1], np.int64)
    key = graph.node_patch.astype(np.int64)
    for axis in range(blocks.shape[1]):
        key = key * extent[axis] + blocks[:, axis]
    roots, coarse_of = np.unique(_components_within(graph.indptr, graph.indices, key),
                                 return_inverse=True)
    coarse_of = coarse_of.astype(np.int32).ravel()
    n_coarse = roots.size
    patch = graph.node_patch[roots]
    position = np.ascontiguousarray(blocks[roots] * block + block // 2, dtype=np.int32)
    indptr, indices = adjacency(n_coarse, *_coarse_links(graph.indptr, graph.indices,
                                                          coarse_of, n_coarse))
    members = np.argsort(coarse_of, kind="stable").astype(np.int32)
    member_start = np.searchsorted(coarse_of[members], np.arange(n_coarse + 1)).astype(np.int64)
    coarse = NodeGraph(indptr, indices, edge_quanta(indptr, indices, position, graph.turn),
                       np.arange(n_coarse, dtype=np.int64), patch, position, graph.turn)
    return CoarseGraph(coarse, coarse_of, member_start, members)


@numba.njit(cache=True)
def _components_within(indptr, indices, key):
    """A root node of each node's set of nodes of its ``key`` that links
    join among themselves (union-find)."""
    parent = np.arange(indptr.size - 1)
    for u in range(indptr.size - 1):
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            if v > u and key[v] == key[u]:
                a, b = u, v
                while parent[a] != a:
                    parent[a] = parent[parent[a]]
                    a = parent[a]
                while parent[b] != b:
                    parent[b] = parent[parent[b]]
                    b = parent[b]
                if a != b:
                    parent[max(a, b)] = min(a, b)
    for u in range(parent.size):
        parent[u] = parent[parent[u]]
    return parent


@numba.njit(cache=True)
def _coarse_links(indptr, indices, coarse_of, n_coarse):
    """Each pair of coarse nodes joined by a link, once."""
    seen = set()
    a, b = [], []
    for u in range(indptr.size - 1):
        cu = coarse_of[u]
        for e in range(indptr[u], indptr[u + 1]):
            cv = coarse_of[indices[e]]
            if cu < cv:
                key = np.int64(cu) * n_coarse + cv
                if key not in seen:
                    seen.add(key)
                    a.append(cu)
                    b.append(cv)
    return np.array(a, dtype=np.int32), np.array(b, dtype=np.int32)


@numba.njit(cache=True, nogil=True)
def mark_corridor(coarse, path, corridor):
    """Mark the nodes of a coarse path and of its coarse neighbours.

    Parameters
    ----------
    coarse : CoarseGraph
    path : ndarray of int64
        Coarse nodes.
    corridor : ndarray of uint8, shape (n_nodes,)
        All zero; set to 1 on the corridor's nodes.

    Returns
    -------
    ndarray of int64
        The coarse nodes marked (for :func:`clear_corridor`).
    """
    indptr, indices = coarse.graph.indptr, coarse.graph.indices
    taken = set()
    for c in path:
        taken.add(c)
        for e in range(indptr[c], indptr[c + 1]):
            taken.add(np.int64(indices[e]))
    out = np.empty(len(taken), np.int64)
    k = 0
    for c in taken:
        out[k] = c
        k += 1
        for m in range(coarse.member_start[c], coarse.member_start[c + 1]):
            corridor[coarse.members[m]] = 1
    return out


@numba.njit(cache=True, nogil=True)
def clear_corridor(coarse, marked, corridor):
    """Set the corridor's marks of :func:`mark_corridor` back to zero."""
    for c in marked:
        for m in range(coarse.member_start[c], coarse.member_start[c + 1]):
            corridor[coarse.members[m]] = 0
