"""Regions, patches, gates and aspects: the paper's numbers and the structural
properties on several rho1 values and geometries."""

import math

import networkx as nx
import numpy as np
import pytest

from gwr_cases import OTHER_GEOMETRY, nearest_slot
from rpr3_gwr_core.workspace.continuity import match_solutions, neighbour_pairs
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.workspace import compute_field
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY
from rpr3_gwr_core.workspace.roadmap import aspect_groups, build_roadmap, roadmap_graph
from rpr3_gwr_core.workspace.segmentation import segment

STRUCTURAL_CASES = ["paper", "paper_rho17_step0.25", "paper_rho13_step0.25",
                    "paper_rho30_step0.25", "other_rho10.1_step0.25"]
RDS_CASES = ["paper_rho17_step0.25", "paper_rho13_step0.25", "other_rho10.1_step0.25"]


@pytest.fixture(params=STRUCTURAL_CASES)
def case(request, cases):
    """(field, segmentation, graph) of one structural case."""
    if request.param == "paper":
        roadmap = request.getfixturevalue("paper_roadmap")
        return roadmap.field, roadmap.segmentation, roadmap.graph
    name = request.param
    return cases.field(name), cases.segmentation(name), cases.graph(name)


@pytest.fixture
def paper(paper_roadmap):
    return paper_roadmap.segmentation


def _patch_of(roadmap, rho2, rho3, alpha_deg):
    cell = roadmap.grid.cell_of((roadmap.grid.fixed_value(0), rho2, rho3))
    slot = nearest_slot(roadmap.field, cell, math.radians(alpha_deg))
    return int(roadmap.segmentation.patch[cell, slot])


def _slot_of(seg, cells, pid):
    """Slot of patch ``pid`` in each of ``cells`` (each must hold it once)."""
    hit = seg.patch[cells] == pid
    assert np.all(hit.sum(axis=1) == 1)
    return np.argmax(hit, axis=1)


# --- the paper's roadmap (401 x 401, rho1 = 17) ---------------------------------------

def test_paper_roadmap_has_7_regions(paper):
    assert paper.n_regions == 7


def test_paper_roadmap_has_24_patches(paper, paper_roadmap):
    assert len(paper.patches) == 24
    assert paper_roadmap.graph.number_of_nodes() == 24


def test_regions_are_numbered_by_decreasing_area(paper):
    sizes = [int(np.sum(paper.region == r)) for r in range(1, paper.n_regions + 1)]
    assert all(size > 0 for size in sizes)
    assert sizes == sorted(sizes, reverse=True)


@pytest.mark.parametrize("rho2, rho3, region", [(12.0, 18.0, 6), (10.0, 25.0, 1), (20.0, 25.0, 3)])
def test_paper_example_lies_in_the_papers_region(paper_roadmap, rho2, rho3, region):
    cell = paper_roadmap.grid.cell_of((17.0, rho2, rho3))
    assert paper_roadmap.segmentation.region[cell] == region


def test_mode_change_examples_are_two_patches_of_region_3(paper_roadmap):
    first = _patch_of(paper_roadmap, 20.0, 25.0, 29.47)
    second = _patch_of(paper_roadmap, 20.0, 25.0, 96.13)
    assert first // 10 == 3 and second // 10 == 3
    assert first != second


@pytest.mark.parametrize("region, n_solutions", [(1, 2), (4, 2), (5, 6)])
def test_region_has_the_papers_number_of_solutions(paper_roadmap, region, n_solutions):
    seg = paper_roadmap.segmentation
    cells = np.flatnonzero(seg.region == region)
    assert np.all(paper_roadmap.field.count[cells] == n_solutions)


def test_patch_ids_are_ten_times_region_plus_layer(paper):
    for r in range(1, paper.n_regions + 1):
        in_region = [p for p in paper.patches.values() if p.region == r]
        n = in_region[0].n_solutions
        assert sorted(p.layer for p in in_region) == list(range(1, n + 1))
        for p in in_region:
            assert p.id == 10 * r + p.layer and p.n_solutions == n


def test_paper_first_example_global_paths_go_through_the_papers_regions(paper_roadmap):
    # Paper section 5.2: 61 -> 41 -> 21 -> 12 and 61 -> 51 -> 21 -> 12.
    start = _patch_of(paper_roadmap, 12.0, 18.0, 122.82)
    goal = _patch_of(paper_roadmap, 10.0, 25.0, -24.24)
    paths = nx.all_shortest_paths(paper_roadmap.graph, start, goal)
    assert sorted([p // 10 for p in path] for path in paths) == [[6, 4, 2, 1], [6, 5, 2, 1]]


def test_paper_mode_change_path_goes_through_region_1(paper_roadmap):
    # Paper section 5.3: 31 -> 11 -> 32.
    start = _patch_of(paper_roadmap, 20.0, 25.0, 29.47)
    goal = _patch_of(paper_roadmap, 20.0, 25.0, 96.13)
    paths = list(nx.all_shortest_paths(paper_roadmap.graph, start, goal))
    assert [[p // 10 for p in path] for path in paths] == [[3, 1, 3]]


# --- aspects -------------------------------------------------------------------------

def test_paper_roadmap_has_exactly_two_aspect_groups(paper_roadmap):
    groups = aspect_groups(paper_roadmap.graph)
    assert len(groups) == 2
    aspects = {paper_roadmap.segmentation.patches[g[0]].aspect for g in groups}
    assert aspects == {-1, 1}


def test_rho1_13_coarse_roadmap_has_two_aspect_groups(cases):
    assert len(aspect_groups(cases.graph("paper_rho13_step0.25"))) == 2


def test_rho1_30_roadmap_has_two_aspect_groups():
    # Paper figure 10 (rho1 = 30); at step 0.25 a narrow region splits and
    # leaves isolated patches, so this one needs the paper's resolution.
    roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(rho1=30.0))
    assert len(aspect_groups(roadmap.graph)) == 2


def test_no_gate_joins_patches_of_different_aspects(case):
    _, seg, _ = case
    for a, b in seg.gates:
        assert seg.patches[a].aspect == seg.patches[b].aspect


def test_each_aspect_group_holds_one_aspect(case):
    _, seg, graph = case
    for group in aspect_groups(graph):
        assert len({seg.patches[p].aspect for p in group}) == 1


def test_aspect_groups_partition_the_patches(case):
    _, seg, graph = case
    groups = aspect_groups(graph)
    flat = [p for g in groups for p in g]
    assert sorted(flat) == sorted(seg.patches)
    assert [g[0] for g in groups] == sorted(g[0] for g in groups)


# --- structure -------------------------------------------------------------------------

def test_case_has_several_regions_and_gates(case):
    _, seg, _ = case
    assert seg.n_regions > 1
    assert len(seg.gates) > 0


def test_patches_cover_every_solution_of_region_cells_and_nothing_else(case):
    field, seg, _ = case
    assert np.all(seg.patch[field.valid & (seg.region[:, None] > 0)] > 0)
    assert not np.any(seg.patch[~field.valid])


def _continuation_partners(seg):
    """Per patched solution of a region-0 cell, the patch ids it is linked to."""
    partners = {}
    for lower, upper, match in seg.links:
        rows, slots = np.nonzero(match >= 0)
        for a, sa, b, sb in zip(lower[rows], slots, upper[rows], match[rows, slots]):
            for here, slot, there, other in ((a, sa, b, sb), (b, sb, a, sa)):
                if seg.region[here] == 0 and seg.patch[here, slot] > 0:
                    partners.setdefault((int(here), int(slot)), set()).add(
                        int(seg.patch[there, other]))
    return partners


def test_solutions_of_unresolved_cells_join_a_patch_they_continue_into(case):
    _, seg, _ = case
    for (cell, slot), linked in _continuation_partners(seg).items():
        assert seg.patch[cell, slot] in linked


def test_well_conditioned_solutions_of_unresolved_cells_keep_a_patch(case):
    # The fix for refusing good configurations in small sets of cells: only
    # solutions that continue into no patch (fold pairs) may be dropped.
    field, seg, _ = case
    unresolved = field.valid & (seg.region[:, None] == 0)
    assert unresolved.any()
    well = unresolved & (np.abs(np.nan_to_num(field.margin)) > 0.3)
    assert np.all(seg.patch[well] > 0)


def test_each_patch_covers_each_of_its_cells_once(case):
    _, seg, _ = case
    for pid, patch in seg.patches.items():
        assert np.unique(patch.cells).size == patch.cells.size
        assert np.all(np.sum(seg.patch[patch.cells] == pid, axis=1) == 1)


def test_patch_cells_and_slots_are_its_entries_of_the_patch_array(case):
    field, seg, _ = case
    for pid, patch in seg.patches.items():
        np.testing.assert_array_equal(seg.patch[patch.cells, patch.slots], pid)
        assert patch.cells.size == int(np.sum(seg.patch == pid))
        own = seg.region[patch.cells] == patch.region
        assert np.all(own | (seg.region[patch.cells] == 0))
        assert np.all(field.count[patch.cells[own]] == patch.n_solutions)


def test_a_region_has_one_patch_per_solution(case):
    field, seg, _ = case
    for r in range(1, seg.n_regions + 1):
        cells = np.flatnonzero(seg.region == r)
        n = field.count[cells[0]]
        assert np.all(field.count[cells] == n)
        assert sum(1 for p in seg.patches.values() if p.region == r) == n


def test_patch_aspect_is_the_sign_of_the_margin_on_all_its_cells(case):
    field, seg, _ = case
    for patch in seg.patches.values():
        assert patch.aspect in (-1, 1)
        assert np.all(np.sign(field.margin[patch.cells, patch.slots]) == patch.aspect)


def test_gate_faces_are_adjacent_cells_of_the_patches_regions(case):
    field, seg, _ = case
    n3 = field.grid.shape[1]
    for (a, b), gate in seg.gates.items():
        assert a < b and gate.patches == (a, b)
        ca, cb = gate.faces[:, 0], gate.faces[:, 1]
        delta = np.abs(ca - cb)
        assert np.all((delta == n3) | ((delta == 1) & (ca // n3 == cb // n3)))
        assert np.all(np.isin(seg.region[ca], [a // 10, 0]))
        assert np.all(np.isin(seg.region[cb], [b // 10, 0]))
        assert a != b
        assert gate.width == pytest.approx(len(gate.faces) * field.grid.step)


def test_gate_faces_continue_in_both_directions(case):
    field, seg, _ = case
    for (a, b), gate in seg.gates.items():
        ca, cb = gate.faces[:, 0], gate.faces[:, 1]
        i, j = _slot_of(seg, ca, a), _slot_of(seg, cb, b)
        rows = np.arange(len(ca))
        np.testing.assert_array_equal(match_solutions(field, ca, cb)[rows, i], j)
        np.testing.assert_array_equal(match_solutions(field, cb, ca)[rows, j], i)


def test_gate_cells_are_the_patch_cells_on_gate_faces(case):
    _, seg, _ = case
    on_gates = {}
    for (a, b), gate in seg.gates.items():
        on_gates.setdefault(a, set()).update(gate.faces[:, 0].tolist())
        on_gates.setdefault(b, set()).update(gate.faces[:, 1].tolist())
    for pid, patch in seg.patches.items():
        assert set(patch.gate_cells.tolist()) == on_gates.get(pid, set())
        assert set(patch.singular_cells.tolist()) <= set(patch.cells.tolist())


def test_continuation_links_are_symmetric_on_sampled_faces(case):
    field, seg, _ = case
    rng = np.random.default_rng(7)
    for axis, (lower, upper) in enumerate(neighbour_pairs(field.grid.shape)):
        pick = rng.choice(lower.size, size=min(lower.size, 3000), replace=False)
        lo, up = lower[pick], upper[pick]
        forward, backward = match_solutions(field, lo, up), match_solutions(field, up, lo)
        for m1, m2 in ((forward, backward), (backward, forward)):
            rows, slots = np.nonzero(m1 >= 0)
            np.testing.assert_array_equal(m2[rows, m1[rows, slots]], slots)
        np.testing.assert_array_equal(seg.links[axis][2][pick], forward)


def test_roadmap_graph_mirrors_patches_and_gates(case):
    field, seg, graph = case
    assert set(graph.nodes) == set(seg.patches)
    assert {tuple(sorted(e)) for e in graph.edges} == set(seg.gates)
    for pid, patch in seg.patches.items():
        node = graph.nodes[pid]
        assert node["aspect"] == patch.aspect and node["n_cells"] == patch.cells.size
        assert node["area"] == pytest.approx(patch.cells.size * field.grid.step ** 2)


# --- RDS and connected components agree ---------------------------------------------------

@pytest.mark.parametrize("name", RDS_CASES)
def test_rds_gives_the_same_regions_and_patch_array(cases, name):
    rds, components = cases.segmentation(name, "rds"), cases.segmentation(name)
    np.testing.assert_array_equal(rds.region, components.region)
    np.testing.assert_array_equal(rds.patch, components.patch)


@pytest.mark.parametrize("name", RDS_CASES)
def test_rds_gives_the_same_patches(cases, name):
    rds, components = cases.segmentation(name, "rds"), cases.segmentation(name)
    assert rds.patches.keys() == components.patches.keys()
    for pid, patch in components.patches.items():
        other = rds.patches[pid]
        assert (other.region, other.layer, other.aspect, other.n_solutions) == (
            patch.region, patch.layer, patch.aspect, patch.n_solutions)
        for attribute in ("cells", "slots", "gate_cells", "singular_cells"):
            np.testing.assert_array_equal(getattr(other, attribute), getattr(patch, attribute))


@pytest.mark.parametrize("name", RDS_CASES)
def test_rds_gives_the_same_gates(cases, name):
    rds, components = cases.segmentation(name, "rds"), cases.segmentation(name)
    assert list(rds.gates) == list(components.gates)
    for key, gate in components.gates.items():
        np.testing.assert_array_equal(rds.gates[key].faces, gate.faces)
        assert rds.gates[key].width == gate.width


# --- min_region_cells ------------------------------------------------------------------------

def test_small_connected_sets_become_singular_locus(cases):
    field = cases.field("paper_rho17_step0.25")
    strict = segment(field, min_region_cells=200)
    sizes = [int(np.sum(strict.region == r)) for r in range(1, strict.n_regions + 1)]
    assert min(sizes) >= 200
    assert strict.n_regions < cases.segmentation("paper_rho17_step0.25").n_regions
    assert np.all(strict.patch[field.valid & (strict.region[:, None] > 0)] > 0)


# --- known bugs: continuation across a singularity ----------------------------------------------

def _two_cell_field(rho1, rho2_range, rho3_range, step):
    grid = rho1_slice(rho1=rho1, rho2_range=rho2_range, rho3_range=rho3_range, step=step)
    assert grid.size == 2
    return compute_field(OTHER_GEOMETRY, grid)


@pytest.mark.parametrize("rho1, rho2_range, rho3_range, step", [
    (7.7, (9.25, 9.5), (1.25, 1.25), 0.25),   # jumps over a gap with no real solution
    (10.0, (8.0, 8.0), (15.0, 15.5), 0.5),    # passes through a singular pose
])
def test_continuation_never_links_opposite_aspects(rho1, rho2_range, rho3_range, step):
    field = _two_cell_field(rho1, rho2_range, rho3_range, step)
    match = match_solutions(field, np.array([0]), np.array([1]))[0]
    for i in np.flatnonzero(match >= 0):
        assert np.sign(field.margin[0, i]) == np.sign(field.margin[1, match[i]])


def test_other_geometry_rho1_7_7_gates_keep_aspects():
    grid = rho1_slice(rho1=7.7, rho2_range=(0.0, 30.0), rho3_range=(0.0, 30.0), step=0.25)
    seg = segment(compute_field(OTHER_GEOMETRY, grid))
    assert all(seg.patches[a].aspect == seg.patches[b].aspect for a, b in seg.gates)
    assert len(aspect_groups(roadmap_graph(seg))) == 2


def test_other_geometry_rho1_10_segments_without_error():
    grid = rho1_slice(rho1=10.0, rho2_range=(0.0, 30.0), rho3_range=(0.0, 30.0), step=0.5)
    seg = segment(compute_field(OTHER_GEOMETRY, grid))
    assert seg.n_regions > 1
