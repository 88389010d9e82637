"""Connected components by union-find, against scipy's graph search."""

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.csgraph import connected_components

from rpr3_gwr_core.workspace.components import connected_labels


def _scipy_labels(n_nodes, a, b):
    graph = sparse.coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(n_nodes, n_nodes))
    return connected_components(graph, directed=False)[1]


@pytest.mark.parametrize("seed", range(6))
def test_labels_are_scipys_on_random_graphs(seed):
    rng = np.random.default_rng(seed)
    n_nodes = int(rng.integers(1, 3000))
    # From almost no edges (mostly isolated nodes) to one giant component,
    # with repeated edges and self-loops among them.
    n_edges = int(rng.integers(0, 2 * n_nodes))
    a = rng.integers(n_nodes, size=n_edges)
    b = rng.integers(n_nodes, size=n_edges)
    split = int(rng.integers(0, n_edges + 1))
    got = connected_labels(n_nodes, [(a[:split], b[:split]), (a[split:], b[split:])])
    assert got.dtype == np.int32
    np.testing.assert_array_equal(got, _scipy_labels(n_nodes, a, b))


def test_a_path_given_backwards_is_one_component():
    # Each edge joins the next node to a tree rooted far away: the worst case
    # for a union-find without path compression.
    n_nodes = 100_000
    nodes = np.arange(n_nodes - 1, 0, -1)
    labels = connected_labels(n_nodes, [(nodes, nodes - 1)])
    np.testing.assert_array_equal(labels, np.zeros(n_nodes, dtype=np.int32))


def test_no_edges_makes_every_node_its_own_component():
    np.testing.assert_array_equal(connected_labels(5, []), np.arange(5))
    assert connected_labels(0, []).size == 0
