"""The rotary disk search (paper section 2.4) on small hand-made grids."""

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from rpr3_gwr_core.workspace.continuity import neighbour_pairs
from rpr3_gwr_core.workspace.rotary_disk import (passage_from_links, rotary_disk_search,
                                                 rotary_order)


def build(shape, open_cells, walls=()):
    """Passage table of a grid: faces between two open cells pass unless walled.

    Returns the passage table and the undirected graph of passable faces."""
    open_cells = np.asarray(open_cells, dtype=bool).ravel()
    walls = {frozenset(w) for w in walls}
    links, graph = [], nx.Graph()
    graph.add_nodes_from(np.flatnonzero(open_cells).tolist())
    for lower, upper in neighbour_pairs(shape):
        keep = [k for k in range(lower.size)
                if open_cells[lower[k]] and open_cells[upper[k]]
                and frozenset((int(lower[k]), int(upper[k]))) not in walls]
        links.append((lower[keep], upper[keep]))
        graph.add_edges_from(zip(lower[keep].tolist(), upper[keep].tolist()))
    return passage_from_links(int(np.prod(shape)), links), graph


def expected_boundary(passage, cells):
    return sorted(c for c in cells if any(passage[f][c] < 0 for f in passage))


def test_rotary_order_in_two_dimensions():
    assert rotary_order(2) == (-2, -1, 1, 2)


def test_rotary_order_in_one_and_three_dimensions():
    assert rotary_order(1) == (-1, 1)
    assert rotary_order(3) == (-3, -2, -1, 1, 2, 3)


def test_passage_from_links_is_symmetric():
    passage = passage_from_links(4, [(np.array([0, 2]), np.array([1, 3]))])
    assert passage[1].tolist() == [1, -1, 3, -1]
    assert passage[-1].tolist() == [-1, 0, -1, 2]


def test_one_dimensional_line_stops_at_a_wall():
    passage, _ = build((6,), np.ones(6), walls=[(2, 3)])
    visited, boundary = rotary_disk_search(0, passage, 1)
    assert visited == [0, 1, 2]
    assert boundary == [0, 2]


def test_one_dimensional_search_from_the_middle_visits_both_sides():
    passage, _ = build((5,), np.ones(5))
    visited, boundary = rotary_disk_search(2, passage, 1)
    assert sorted(visited) == [0, 1, 2, 3, 4]
    assert boundary == [0, 4]


def test_single_isolated_disk_is_its_own_boundary():
    passage, _ = build((3, 3), np.eye(3))
    assert rotary_disk_search(4, passage, 2) == ([4], [4])


def test_two_dimensional_first_move_follows_rotary_order():
    # From the centre of an open 3 x 3 grid the first face is -2 (lower along axis 1).
    passage, _ = build((3, 3), np.ones((3, 3)))
    visited, _ = rotary_disk_search(4, passage, 2)
    assert visited[:2] == [4, 3]
    assert sorted(visited) == list(range(9))


def test_two_dimensional_ring_around_a_hole():
    mask = np.ones((4, 4), dtype=bool)
    mask[1:3, 1:3] = False
    passage, graph = build((4, 4), mask)
    visited, boundary = rotary_disk_search(0, passage, 2)
    assert sorted(visited) == sorted(graph.nodes)
    assert len(set(visited)) == len(visited) == 12
    assert boundary == expected_boundary(passage, visited)


def test_two_dimensional_wall_splits_the_grid():
    # A full wall between columns 1 and 2 of a 3 x 4 grid.
    shape = (3, 4)
    walls = [(i * 4 + 1, i * 4 + 2) for i in range(3)]
    passage, _ = build(shape, np.ones(shape), walls)
    visited, boundary = rotary_disk_search(0, passage, 2)
    assert sorted(visited) == [0, 1, 4, 5, 8, 9]
    assert boundary == [0, 1, 4, 5, 8, 9]


def test_three_dimensional_cube_with_a_sealed_corner():
    shape = (3, 3, 3)
    corner = 26  # (2, 2, 2): wall off its three faces
    walls = [(corner, corner - 1), (corner, corner - 3), (corner, corner - 9)]
    passage, graph = build(shape, np.ones(shape), walls)
    visited, boundary = rotary_disk_search(0, passage, 3)
    assert sorted(visited) == list(range(26))
    assert boundary == expected_boundary(passage, visited)
    assert 13 not in boundary  # the centre has all six faces open
    assert rotary_disk_search(corner, passage, 3) == ([corner], [corner])


def _check_search(shape, mask, walls, start_index):
    passage, graph = build(shape, mask, walls)
    cells = sorted(graph.nodes)
    if not cells:
        return
    start = cells[start_index % len(cells)]
    visited, boundary = rotary_disk_search(start, passage, len(shape))
    component = nx.node_connected_component(graph, start)
    # Every disk of the connected set, each exactly once ...
    assert len(visited) == len(set(visited))
    assert set(visited) == component
    assert visited[0] == start
    # ... each new disk entered through a passable face of an earlier one ...
    assert not set(visited) - component
    for k in range(1, len(visited)):
        assert any(graph.has_edge(visited[k], earlier) for earlier in visited[:k])
    # ... and the boundary is exactly the disks with an impassable face.
    assert boundary == expected_boundary(passage, visited)


def _grid_case(dimension, max_side):
    @st.composite
    def case(draw):
        shape = tuple(draw(st.integers(1, max_side)) for _ in range(dimension))
        size = int(np.prod(shape))
        mask = np.array(draw(st.lists(st.booleans(), min_size=size, max_size=size)))
        pairs = [(int(a), int(b)) for lo, up in neighbour_pairs(shape) for a, b in zip(lo, up)]
        walls = [p for p, cut in zip(pairs, draw(st.lists(st.booleans(), min_size=len(pairs),
                                                          max_size=len(pairs)))) if cut]
        return shape, mask, walls, draw(st.integers(0, 10**6))
    return case()


@settings(max_examples=150, deadline=None)
@given(_grid_case(2, 7))
def test_search_visits_exactly_the_connected_component_in_2d(case):
    _check_search(*case)


@settings(max_examples=80, deadline=None)
@given(_grid_case(3, 4))
def test_search_visits_exactly_the_connected_component_in_3d(case):
    _check_search(*case)


@settings(max_examples=50, deadline=None)
@given(_grid_case(1, 12))
def test_search_visits_exactly_the_connected_component_in_1d(case):
    _check_search(*case)


def test_search_handles_a_long_snake_without_recursion():
    # A 1-D chain of 20000 disks: a recursive search would exceed Python's stack.
    passage, _ = build((20000,), np.ones(20000))
    visited, boundary = rotary_disk_search(0, passage, 1)
    assert visited == list(range(20000))
    assert boundary == [0, 19999]


@pytest.mark.parametrize("start", [0, 5, 11])
def test_search_result_does_not_depend_on_the_start_as_a_set(start):
    mask = np.array([[1, 1, 0, 1], [0, 1, 1, 1], [1, 1, 0, 1]], dtype=bool)
    passage, graph = build((3, 4), mask)
    visited, _ = rotary_disk_search(start, passage, 2)
    assert set(visited) == nx.node_connected_component(graph, start)
