"""Connected components of an undirected graph given by its edges.

A compiled union-find over the edges, with no sparse matrix built: the
segmentation's graphs have a node per solution slot (a million on a 401 x
401 slice) and an edge per continuation link, and assembling them as
matrices cost more than finding their components.  Components are numbered
as :func:`scipy.sparse.csgraph.connected_components` numbers them (in the
order of their smallest node), so either gives the same labels.
"""

import numba
import numpy as np

__all__ = ["connected_labels", "find_root", "join"]


def connected_labels(n_nodes, edges):
    """Component label of every node of an undirected graph.

    Parameters
    ----------
    n_nodes : int
        Nodes ``0 .. n_nodes - 1``.
    edges : iterable of (ndarray, ndarray)
        Pairs ``(a, b)`` of integer arrays of one length: node ``a[k]`` is
        joined to node ``b[k]``.

    Returns
    -------
    ndarray of int32, shape (n_nodes,)
        Labels ``0 .. c - 1`` of the c components, numbered in the order of
        each component's smallest node (an isolated node is a component).
    """
    parent = np.arange(int(n_nodes), dtype=np.int64)
    for a, b in edges:
        _union(parent, np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64))
    return _labels(parent)


@numba.njit(cache=True, nogil=True)
def find_root(parent, node):
    """The root of ``node``'s tree in a union-find forest ``parent`` (int64
    array, a root its own parent), halving the path on the way; compiled,
    for other kernels' union-finds too."""
    while parent[node] != node:
        parent[node] = parent[parent[node]]
        node = parent[node]
    return node


@numba.njit(cache=True, nogil=True)
def join(parent, a, b):
    """Join the trees of nodes ``a`` and ``b``.  The smaller root becomes the
    parent, so a root is its component's smallest node."""
    root_a, root_b = find_root(parent, a), find_root(parent, b)
    if root_a < root_b:
        parent[root_b] = root_a
    elif root_b < root_a:
        parent[root_a] = root_b


@numba.njit(cache=True, nogil=True)
def _union(parent, a, b):
    """:func:`join` ``a[k]`` and ``b[k]`` for every k."""
    for k in range(a.size):
        join(parent, a[k], b[k])


@numba.njit(cache=True, nogil=True)
def _labels(parent):
    """Labels by smallest node: a node's root precedes it, so the root's
    label is known when the node is reached."""
    label = np.empty(parent.size, dtype=np.int32)
    count = 0
    for node in range(parent.size):
        root = find_root(parent, node)
        if root == node:
            label[node] = count
            count += 1
        else:
            label[node] = label[root]
    return label
