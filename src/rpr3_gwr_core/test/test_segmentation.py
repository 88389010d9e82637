"""Regions, patches, gates and aspects: the paper's numbers and the structural
properties on several rho1 values and geometries."""

import math

import networkx as nx
import numpy as np
import pytest

from gwr_cases import OTHER_GEOMETRY, nearest_slot
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.workspace import continuity, segmentation
from rpr3_gwr_core.workspace.components import connected_labels
from rpr3_gwr_core.workspace.continuity import match_solutions, neighbour_pairs
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.workspace import compute_field
from rpr3_gwr_core.workspace.adaptive import refine
from rpr3_gwr_core.workspace.grid import Grid
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY
from rpr3_gwr_core.workspace.roadmap import aspect_groups, build_roadmap, roadmap_graph
from rpr3_gwr_core.workspace.segmentation import Segmentation, segment

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


# --- compiled stages against their plain numpy forms --------------------------------------------

@pytest.fixture(scope="module")
def adaptive_case():
    """(field, segmentation) on a small refined 3-D grid."""
    base = Grid.regular({0: (12.0, 20.0), 1: (10.0, 18.0), 2: (16.0, 24.0)}, 1.0)
    field = compute_field(PAPER_GEOMETRY, refine(PAPER_GEOMETRY, base, 4))
    return field, segment(field)


def _reference_decode(field, region, patch, links):
    """Patches and gates of :meth:`Segmentation.from_arrays` in plain numpy,
    as ``{id: (region, layer, aspect, n_solutions, cells, slots, gate_cells,
    singular_cells)}`` and ``{(a, b): (faces, width)}``."""
    n, width = patch.shape
    linked = []
    for lo, up, match in links:
        rows, slots = np.nonzero(match >= 0)
        lower, upper, target = lo[rows], up[rows], match[rows, slots].astype(np.int64)
        into = (patch[lower, slots] > 0) & (patch[upper, target] > 0)
        linked.append((rows[into], lower[into], slots[into], upper[into], target[into]))
    faces = np.zeros(n, dtype=np.int64)
    continued = np.zeros(n * width, dtype=np.int64)
    on_gate = np.zeros(n * width, dtype=bool)
    for (lo, up, _), (_, lower, lower_slot, upper, upper_slot) in zip(links, linked):
        faces += np.bincount(lo, minlength=n) + np.bincount(up, minlength=n)
        keys = np.concatenate([lower * width + lower_slot, upper * width + upper_slot])
        continued += np.bincount(keys, minlength=n * width)
        crossing = patch[lower, lower_slot] != patch[upper, upper_slot]
        on_gate[lower[crossing] * width + lower_slot[crossing]] = True
        on_gate[upper[crossing] * width + upper_slot[crossing]] = True
    on_singular = field.valid & (patch > 0) & (continued.reshape(n, width) < faces[:, None])
    on_gate = on_gate.reshape(n, width)
    patches, layers = {}, {}
    for pid in np.unique(patch[patch > 0]).tolist():
        cells, slots = np.nonzero(patch == pid)
        own = int(region[cells].max())
        layers.setdefault(own, []).append(pid)
        (aspect,) = np.unique(np.sign(field.margin[cells, slots]).astype(int))
        patches[pid] = (own, len(layers[own]), aspect,
                        int(field.count[cells[region[cells] == own][0]]), cells, slots,
                        cells[on_gate[cells, slots]], cells[on_singular[cells, slots]])
    gates = {}
    for measures, (rows, ca, sa, cb, sb) in zip(field.grid.face_measures(), linked):
        for k in np.flatnonzero(patch[ca, sa] != patch[cb, sb]):
            a, b, fa, fb = patch[ca[k], sa[k]], patch[cb[k], sb[k]], ca[k], cb[k]
            if a > b:
                a, b, fa, fb = b, a, fb, fa
            faces_so_far, width_so_far = gates.get((int(a), int(b)), ([], 0.0))
            gates[(int(a), int(b))] = (faces_so_far + [(fa, fb)], width_so_far + measures[rows[k]])
    return patches, {key: (np.array(sorted(f), dtype=np.int64).reshape(-1, 2), w)
                     for key, (f, w) in sorted(gates.items())}


def _check_decode(field, seg):
    patches, gates = _reference_decode(field, seg.region, seg.patch, seg.links)
    assert list(seg.patches) == list(patches)
    for pid, (region, layer, aspect, n_solutions, *arrays) in patches.items():
        patch = seg.patches[pid]
        assert (patch.region, patch.layer, patch.aspect, patch.n_solutions) == (
            region, layer, aspect, n_solutions)
        for name, expected in zip(("cells", "slots", "gate_cells", "singular_cells"), arrays):
            np.testing.assert_array_equal(getattr(patch, name), expected)
    assert list(seg.gates) == list(gates)
    for key, (faces, width) in gates.items():
        np.testing.assert_array_equal(seg.gates[key].faces, faces)
        assert seg.gates[key].width == pytest.approx(width, rel=1e-12)


def test_decoded_patches_and_gates_match_the_numpy_reference(case):
    field, seg, _ = case
    _check_decode(field, seg)


def test_decoded_patches_and_gates_match_the_numpy_reference_on_an_adaptive_grid(adaptive_case):
    _check_decode(*adaptive_case)


def test_adaptive_pairs_match_the_numpy_reference(adaptive_case):
    grid = adaptive_case[0].grid
    rank = np.full(math.prod(grid.fine_shape), -1, dtype=np.int64)
    rank[grid._index] = np.arange(grid.size)
    multi = np.stack(np.unravel_index(grid._index, grid.fine_shape), axis=1)
    for axis, (lower, upper) in enumerate(grid.pairs()):
        stride = math.prod(grid.fine_shape[axis + 1:])
        expected = np.full(grid.size, -1, dtype=np.int64)
        for step in range(grid.refinement, 0, -1):
            ahead = multi[:, axis] + step < grid.fine_shape[axis]
            found = np.full(grid.size, -1, dtype=np.int64)
            found[ahead] = rank[grid._index[ahead] + step * stride]
            expected = np.where(found >= 0, found, expected)
        np.testing.assert_array_equal(lower, np.flatnonzero(expected >= 0))
        np.testing.assert_array_equal(upper, expected[expected >= 0])


def test_patch_numbering_matches_the_whole_array_assignment(cases):
    field = cases.field("paper_rho17_step0.25")
    seg = cases.segmentation("paper_rho17_step0.25")
    linked = [segmentation.linked_solutions(lo, up, m) for lo, up, m in seg.links]
    disk_links = segmentation._within_region_links(field, seg.region, linked)
    valid = (field.valid & (seg.region[:, None] > 0)).ravel()
    component = np.where(valid, connected_labels(valid.size, disk_links), -1)
    full_faces = [segmentation._full_faces(lo, up, m, field.count) for lo, up, m in seg.links]
    got = segmentation._number_patches(field, seg.region, component, disk_links, full_faces)
    component = component.reshape(got.shape)
    expected = np.zeros(got.shape, dtype=np.int32)
    for r in range(1, seg.n_regions + 1):
        cells = np.flatnonzero(seg.region == r)
        labels = np.unique(component[cells][component[cells] >= 0])
        first = [np.flatnonzero(component[cells[0]] == label)[0] for label in labels]
        order = sorted(range(labels.size), key=lambda k: (field.aspect[cells[0], first[k]],
                                                           first[k]))
        for layer, k in enumerate(order, start=1):
            expected[component == labels[k]] = 10 * r + layer
    np.testing.assert_array_equal(got, expected)


def test_the_compiled_link_filters_keep_what_numpy_masks_keep(case):
    field, seg, _ = case
    n = field.max_solutions
    count = field.count.astype(int)
    rng = np.random.default_rng(3)
    marked = rng.random(field.grid.size * n) < 0.01
    for lo, up, match in seg.links:
        # A forest of some of the axis's faces, as breadth_first_order marks one.
        parent = np.full(field.grid.size, -9999)
        some = rng.random(lo.size) < 0.3
        parent[up[some]] = lo[some]
        full = (count[lo] == count[up]) & (count[lo] > 0) & ((match >= 0).sum(axis=1) == count[lo])
        for got, expected in zip(segmentation._full_faces(lo, up, match, field.count),
                                 (lo[full], up[full])):
            np.testing.assert_array_equal(got, expected)
        a, b = segmentation.linked_solutions(lo, up, match)
        cells_a, cells_b = a // n, b // n
        masks = [
            (segmentation._inside_regions(a, b, seg.region, n),
             (seg.region[cells_a] == seg.region[cells_b]) & (seg.region[cells_a] > 0)),
            (segmentation._tree_links(a, b, parent, n),
             (parent[cells_a] == cells_b) | (parent[cells_b] == cells_a)),
            (segmentation._touching(a, b, marked), marked[a] | marked[b]),
        ]
        # The forest and the marks leave links out.
        assert not (masks[1][1].all() or masks[2][1].all())
        for (got_a, got_b), mask in masks:
            assert mask.any()
            np.testing.assert_array_equal(got_a, a[mask])
            np.testing.assert_array_equal(got_b, b[mask])


def test_linked_solutions_are_the_nonzero_links(case):
    field, seg, _ = case
    n = field.max_solutions
    for lo, up, match in seg.links:
        rows, slots = np.nonzero(match >= 0)
        a, b = segmentation.linked_solutions(lo, up, match)
        np.testing.assert_array_equal(a, lo[rows] * n + slots)
        np.testing.assert_array_equal(b, up[rows] * n + match[rows, slots])


def test_matching_tracks_the_same_links_as_chunk_by_chunk(cases, monkeypatch):
    field = cases.field("other_rho10.1_step0.25")
    joints = field.grid.joints()
    monkeypatch.setattr(continuity, "_CHUNK", 997)
    for lower, upper in field.grid.pairs():
        expected = np.full((lower.size, field.max_solutions), -1, dtype=np.int8)
        for start in range(0, lower.size, 997):
            lo, up = lower[start:start + 997], upper[start:start + 997]
            settled = continuity._screened(field, joints, lo, up)
            part = expected[start:start + 997]
            part[settled] = np.where(field.valid[lo[settled]], np.arange(field.max_solutions), -1)
            todo = np.flatnonzero(~settled)
            part[todo] = continuity._track_both_ways(field, joints, lo[todo], up[todo])
        np.testing.assert_array_equal(match_solutions(field, lower, upper), expected)


@pytest.mark.parametrize("change", [-1, 10 ** 6])
def test_decoding_refuses_patch_ids_outside_the_regions(cases, change):
    seg = cases.segmentation("paper_rho17_step0.25")
    patch = seg.patch.copy()
    patch[np.flatnonzero(seg.region)[0], 0] = change
    with pytest.raises(InvalidInputError):
        Segmentation.from_arrays(seg.field, seg.region, patch, [m for _, _, m in seg.links])


def test_decoding_refuses_links_to_no_slot(cases):
    seg = cases.segmentation("paper_rho17_step0.25")
    links = [m.copy() for _, _, m in seg.links]
    links[0][0, 0] = seg.field.max_solutions
    with pytest.raises(InvalidInputError):
        Segmentation.from_arrays(seg.field, seg.region, seg.patch, links)
