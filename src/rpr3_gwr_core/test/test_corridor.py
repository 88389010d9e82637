"""Corridors: the coarse graph joins what the node graph joins, and a cell
search kept to a corridor returns a walk of the node graph, never cheaper
than the least-cost one, and finds a path wherever the whole graph has one."""

import itertools

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY
from rpr3_gwr_core.exceptions import InfeasiblePathError
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.planning.astar import NodeGraph, adjacency, edge_quanta
from rpr3_gwr_core.planning.cell_search import CellSearch
from rpr3_gwr_core.planning.corridor import clear_corridor, coarse_graph, mark_corridor

GRID = rho1_slice(rho1=17, step=0.25)


def _graph(positions, patches, links):
    """A node graph of the given node positions [half quanta], patch indices and links."""
    position = np.array(positions, dtype=np.int32)
    a, b = (np.array(side, dtype=np.int32) for side in zip(*links))
    indptr, indices = adjacency(len(positions), a, b)
    turn = np.zeros(position.shape[1], np.int64)
    return NodeGraph(indptr, indices, edge_quanta(indptr, indices, position, turn),
                     np.arange(len(positions), dtype=np.int64),
                     np.array(patches, dtype=np.int32), position, turn)


# Two sheets of patch 0 in block (0, 0) (nodes 0-1 and 2-3, no link between
# them), node 4 of patch 0 in block (1, 0) linked to the first sheet, node 5
# of patch 1 in block (0, 0) linked to the second.
FOLDED = _graph([(0, 0), (2, 0), (0, 2), (2, 2), (4, 0), (2, 2)], [0, 0, 0, 0, 0, 1],
                [(0, 1), (2, 3), (1, 4), (3, 5)])


def _groups(coarse):
    return {frozenset(np.flatnonzero(coarse.coarse_of == c).tolist())
            for c in range(coarse.graph.node_patch.size)}


def test_a_coarse_node_is_a_patch_s_nodes_in_a_block_that_links_join_there():
    coarse = coarse_graph(FOLDED, 4)
    assert _groups(coarse) == {frozenset({0, 1}), frozenset({2, 3}), frozenset({4}),
                               frozenset({5})}
    for c in range(coarse.graph.node_patch.size):
        members = coarse.members[coarse.member_start[c]:coarse.member_start[c + 1]]
        assert set(members.tolist()) == set(np.flatnonzero(coarse.coarse_of == c).tolist())
        assert set(FOLDED.node_patch[members].tolist()) == {coarse.graph.node_patch[c]}


def test_coarse_nodes_are_joined_exactly_where_a_link_joins_their_nodes():
    coarse = coarse_graph(FOLDED, 4)
    of = coarse.coarse_of
    expected = {frozenset((int(of[u]), int(of[v])))
                for u in range(FOLDED.node_patch.size)
                for v in FOLDED.indices[FOLDED.indptr[u]:FOLDED.indptr[u + 1]].tolist()
                if of[u] != of[v]}
    g = coarse.graph
    got = {frozenset((c, int(d))) for c in range(g.node_patch.size)
           for d in g.indices[g.indptr[c]:g.indptr[c + 1]]}
    assert got == expected
    assert len(expected) == 2


def test_a_corridor_marks_its_path_s_nodes_and_their_neighbours_and_clears_them():
    coarse = coarse_graph(FOLDED, 4)
    corridor = np.zeros(FOLDED.node_patch.size, np.uint8)
    path = np.array([coarse.coarse_of[4]], dtype=np.int64)
    marked = mark_corridor(coarse, path, corridor)
    assert set(np.flatnonzero(corridor).tolist()) == {0, 1, 4}
    clear_corridor(coarse, marked, corridor)
    assert not corridor.any()


@pytest.fixture(scope="module")
def searches():
    """The slice's cell search on the whole graph and one kept to corridors."""
    roadmap, index, _ = cached_planning(PAPER_GEOMETRY, GRID)
    return roadmap, CellSearch(roadmap, index), CellSearch(roadmap, index,
                                                          corridor_min_nodes=0)


def _cell_pairs(roadmap, seed, count):
    """Random cell pairs of one patch, and of two patches joined by a gate."""
    rng = np.random.default_rng(seed)
    seg = roadmap.segmentation
    pairs = []
    gates = sorted(seg.gates)
    for _ in range(count):
        a, b = gates[rng.integers(len(gates))]
        pa, pb = seg.patches[a], seg.patches[b]
        pairs.append(((a,), int(rng.choice(pa.cells)), int(rng.choice(pa.cells))))
        pairs.append(((a, b), int(rng.choice(pa.cells)), int(rng.choice(pb.cells))))
    return pairs


def _is_walk(search, path):
    """Whether consecutive cells of a cell path are nodes joined by a link."""
    index, patches = search.index, search.segmentation.patches
    nodes = [int(index.offsets[np.searchsorted(index.pids, p)])
             + int(np.searchsorted(patches[int(p)].cells, c))
             for p, c in zip(path.patches, path.cells)]
    graph = index.graph
    return all(v in graph.indices[graph.indptr[u]:graph.indptr[u + 1]]
               for u, v in itertools.pairwise(nodes))


@pytest.mark.parametrize("any_gates", [False, True])
def test_a_corridor_s_path_is_a_walk_no_cheaper_than_the_least_cost_one(searches, any_gates):
    roadmap, whole, kept = searches
    for patches, start, goal in _cell_pairs(roadmap, 5, 15):
        least = whole.search(patches, start, goal, clearance=0.02, any_gates=any_gates)
        found = kept.search(patches, start, goal, clearance=0.02, any_gates=any_gates)
        assert (found.cells[0], found.cells[-1]) == (start, goal)
        assert _is_walk(kept, found)
        assert found.cost >= least.cost - 1e-9


def test_a_search_with_blocked_cells_that_cut_its_corridor_says_no_way(searches):
    """Blocking the least-cost path's middle stretch and the cells around it
    leaves the corridor of the coarse path, which avoids them, or raises."""
    roadmap, whole, kept = searches
    patches, start, goal = max(_cell_pairs(roadmap, 7, 10),
                               key=lambda p: whole.search(*p).cells.size)
    path = whole.search(patches, start, goal)
    middle = path.cells[path.cells.size // 4: 3 * path.cells.size // 4]
    blocked = set(middle.tolist())
    for _ in range(3):
        blocked |= {int(c) for cell in list(blocked)
                    for c in whole.cells_around(roadmap.grid.joints_of(cell)[:2], 1.0)}
    blocked -= {start, goal}
    try:
        found = kept.search(patches, start, goal, blocked=blocked)
    except InfeasiblePathError:
        return
    assert not blocked & set(found.cells.tolist())
    assert _is_walk(kept, found)
