"""Adaptive grids: cells, faces, volumes and nearby cells against the uniform
fine lattice, and the slice features a uniform 0.125 grid keeps."""

import math

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, Grid, OutOfGridError, build_roadmap, rho1_slice
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.export import roadmap_from_json, roadmap_to_json
from rpr3_gwr_core.planning import Planner
from rpr3_gwr_core.workspace import AdaptiveGrid, grid_from_dict, refine, segment
from rpr3_gwr_core.workspace.field import compute_field

SMALL_3D = Grid.regular({0: (12.0, 20.0), 1: (10.0, 18.0), 2: (16.0, 24.0)}, 1.0)


@pytest.fixture(scope="module")
def small_grid():
    return refine(PAPER_GEOMETRY, SMALL_3D, 4)


def test_cells_are_base_points_and_fine_points_of_refined_blocks(small_grid):
    grid = small_grid
    assert 0 < grid.blocks.size < 8 ** 3
    points = {tuple(p) for p in np.rint(grid.coordinates() / 0.25).astype(int).tolist()}
    base = {tuple(p) for p in np.rint(SMALL_3D.coordinates() / 0.25).astype(int).tolist()}
    assert base <= points
    corner = np.array(np.unravel_index(grid.blocks, grid.block_shape)).T
    low = np.array([a.low for a in SMALL_3D.axes])
    expected = set(base)
    for c in corner:
        for offset in np.ndindex(5, 5, 5):
            expected.add(tuple(np.rint((low + c) / 0.25).astype(int) + np.array(offset)))
    assert points == expected


def test_faces_join_consecutive_cells_of_a_line_within_a_base_step(small_grid):
    coordinates = small_grid.coordinates()
    for axis, ((lower, upper), length) in enumerate(zip(small_grid.pairs(),
                                                        small_grid.pair_lengths())):
        step = coordinates[upper] - coordinates[lower]
        others = [k for k in range(3) if k != axis]
        assert np.all(step[:, others] == 0)
        assert np.allclose(step[:, axis], length)
        assert set(np.round(length, 9)) <= {0.25, 0.5, 0.75, 1.0}
        # No cell lies between the two ends of a face.
        for a, b in zip(lower[::97], upper[::97]):
            between = np.all(coordinates[:, others] == coordinates[a, others], axis=1) & (
                coordinates[:, axis] > coordinates[a, axis]) & (
                coordinates[:, axis] < coordinates[b, axis])
            assert not between.any()


def test_cell_volumes_fill_the_box(small_grid):
    assert small_grid.cell_volumes().sum() == pytest.approx(8.0 ** 3)
    assert np.all(small_grid.cell_volumes() > 0)


def test_cells_of_and_nearby_cells(small_grid):
    grid = small_grid
    coordinates = grid.coordinates()
    rng = np.random.default_rng(0)
    points = rng.uniform([12, 10, 16], [20, 18, 24], (200, 3))
    cells = grid.cells_of(points)
    assert np.all(cells >= 0)
    # A point's cell is within half a base diagonal of it.
    assert np.all(np.linalg.norm(coordinates[cells] - points, axis=1) <= math.sqrt(3) / 2 + 1e-9)
    for point in points[:20]:
        near = grid.cells_near(point, 4.0)
        distance = np.linalg.norm(coordinates[near] - point, axis=1)
        assert near and np.all(np.diff(distance) >= -1e-12)
    with pytest.raises(OutOfGridError):
        grid.cell_of(np.array([12.0, 9.0, 20.0]))
    with pytest.raises(InvalidInputError):
        grid.cell_of(np.array([math.nan, 12.0, 20.0]))


def test_cells_near_are_the_cells_a_full_scan_finds_in_their_order(small_grid):
    """The fine points around the point's nearest lattice point and the base
    points of the blocks around it, within reach, nearest first, ties in
    cell order."""
    grid = small_grid
    r, d = grid.refinement, grid.ndim
    low, steps = np.array([a.low for a in grid.axes]), np.array(grid.steps)
    index = np.rint((grid.coordinates() - low) / steps).astype(int)
    cells = np.arange(grid.size)
    rng = np.random.default_rng(2)
    for _ in range(300):
        point = rng.uniform([11.5, 9.5, 15.5], [20.5, 18.5, 24.5])
        if rng.random() < 0.3:  # on lattice points and halfway between them
            point = low + np.round((point - low) / steps * 2) / 2 * steps
        radius = float(rng.choice([0.5, 1.0, 2.5, 4.0]))
        here = (point - low) / steps
        in_box = np.max(np.abs(index - np.rint(here)), axis=1) <= math.ceil(radius)
        blocks = index // r - np.floor(here / r)
        base = np.all(index % r == 0, axis=1) & np.all((blocks >= -1) & (blocks <= 2), axis=1)
        distance = np.linalg.norm(index - here, axis=1)
        found = (in_box | base) & (distance <= max(radius, r * math.sqrt(d)))
        order = np.lexsort((cells[found], distance[found]))
        assert grid.cells_near(point, radius) == cells[found][order].tolist()


@pytest.mark.parametrize("which", ["adaptive", "uniform"])
def test_cells_in_box_are_the_cells_a_full_scan_finds(small_grid, which):
    grid = small_grid if which == "adaptive" else small_grid.base
    coords, steps = grid.coordinates(), np.array(grid.steps)
    rng = np.random.default_rng(1)
    for _ in range(200):
        point = coords[rng.integers(len(coords))] + steps * rng.integers(-6, 7, 3) * 0.5
        radius = float(rng.choice([0.0, 0.5, 1.0, 2.5, 4.5]))
        scan = np.flatnonzero(np.max(np.abs(coords - point) / steps, axis=1) <= radius)
        np.testing.assert_array_equal(grid.cells_in_box(point, radius), scan)


def test_depth_counts_fine_steps_to_the_nearest_cell_outside(small_grid):
    grid = small_grid
    cells = np.arange(grid.size)
    depth = grid.depth(cells)
    fine = np.rint((grid.coordinates() - [12, 10, 16]) / 0.25)
    to_border = np.min(np.minimum(fine, 32 - fine), axis=1) + 1
    assert np.array_equal(depth, to_border)


def test_adaptive_grids_round_trip_as_documents(small_grid):
    again = grid_from_dict(small_grid.to_dict())
    assert isinstance(again, AdaptiveGrid)
    assert np.array_equal(again.coordinates(), small_grid.coordinates())
    assert grid_from_dict(SMALL_3D.to_dict()) == SMALL_3D
    with pytest.raises(InvalidInputError):
        AdaptiveGrid(SMALL_3D, 1, [])
    with pytest.raises(InvalidInputError):
        AdaptiveGrid(SMALL_3D, 4, [10 ** 6])


def test_refinement_rule_refines_every_block_the_field_is_not_uniform_in():
    base = rho1_slice(17.0, step=1.0)
    grid = refine(PAPER_GEOMETRY, base, 4)
    field = compute_field(PAPER_GEOMETRY, base)
    count = field.count.reshape(base.shape)
    changes = ((count[:-1, :-1] != count[1:, :-1]) | (count[:-1, :-1] != count[:-1, 1:])
               | (count[:-1, :-1] != count[1:, 1:]))
    refined = np.zeros(changes.size, dtype=bool)
    refined[grid.blocks] = True
    assert np.all(refined[changes.ravel()])
    # Far from the singular curve blocks stay coarse: most of the slice.
    assert refined.mean() < 0.25


@pytest.mark.parametrize("refinement", [4, 8])
def test_a_refined_slice_keeps_the_features_of_the_uniform_0125_grid(paper_roadmap, refinement):
    roadmap = build_roadmap(PAPER_GEOMETRY, refine(PAPER_GEOMETRY, rho1_slice(17.0, step=1.0),
                                                   refinement))
    seg, paper = roadmap.segmentation, paper_roadmap.segmentation
    assert (seg.n_regions, len(seg.patches), len(seg.gates)) == (7, 24, 36)
    assert set(seg.patches) == set(paper.patches)
    if refinement == 8:  # the paper's own step: the same gates
        assert set(seg.gates) == set(paper.gates)
    for r in range(1, 8):
        area = roadmap.grid.volume_of(np.flatnonzero(seg.region == r))
        paper_area = 0.125 ** 2 * np.count_nonzero(paper.region == r)
        assert area == pytest.approx(paper_area, abs=0.6 if refinement == 4 else 0.1)
    assert roadmap.grid.size < paper_roadmap.grid.size / 4


def test_the_rotary_disk_search_finds_the_components_on_an_adaptive_grid(small_grid):
    field = compute_field(PAPER_GEOMETRY, small_grid)
    by_components = segment(field, method="components")
    by_rds = segment(field, method="rds")
    assert np.array_equal(by_components.patch, by_rds.patch)
    assert set(by_components.gates) == set(by_rds.gates)


def test_an_adaptive_roadmap_round_trips_through_json_and_plans_alike(small_grid):
    roadmap = build_roadmap(PAPER_GEOMETRY, small_grid)
    again = roadmap_from_json(roadmap_to_json(roadmap))
    assert np.array_equal(again.segmentation.patch, roadmap.segmentation.patch)
    largest = max(roadmap.segmentation.patches.values(), key=lambda p: p.cells.size)
    joints = roadmap.grid.joints()[largest.cells]
    poses = roadmap.field.poses[largest.cells, largest.slots]
    start = (*joints[0], poses[0, 2])
    goal = (*joints[-1], poses[-1, 2])
    plans = [Planner(r).plan(start, goal) for r in (roadmap, again)]
    assert plans[0].validation.ok
    assert np.array_equal(plans[0].joints, plans[1].joints)
    assert np.ptp(plans[0].joints, axis=0).min() > 1.0  # all three legs move
