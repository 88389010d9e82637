"""Periodic grid axes (a revolute joint's full turn): faces, cell lookups,
distances and boxes wrap around the seam, and grids without them are as
before.  References are written here: the seam's neighbours by index
arithmetic, the distances by rolling the grid so nothing crosses the seam."""

import math

import numpy as np
import pytest
from scipy.ndimage import distance_transform_edt

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.workspace.adaptive import AdaptiveGrid
from rpr3_gwr_core.workspace.grid import Axis, Grid

N = 24
STEP = 2 * math.pi / N


def turn(joint):
    return Axis(joint, -math.pi, math.pi - STEP, STEP, periodic=True)


@pytest.fixture
def grid():
    """A periodic axis (joint 0) and a plain one (joint 1, 10 cells)."""
    return Grid(axes=(turn(0), Axis(1, 0.0, 9.0, 1.0)))


def test_a_periodic_axis_spans_one_turn():
    assert turn(0).count == N and turn(0).period == 2 * math.pi
    with pytest.raises(InvalidInputError, match="one turn"):
        Axis(0, -math.pi, math.pi, STEP, periodic=True)
    with pytest.raises(InvalidInputError, match="True or False"):
        Axis(0, -math.pi, math.pi - STEP, STEP, periodic=1)


def test_documents_name_periodic_axes_only():
    plain = Grid(axes=(Axis(0, 0.0, 9.0, 1.0),))
    assert plain.to_dict() == {"axes": [{"joint": 0, "min": 0.0, "max": 9.0, "step": 1.0}],
                               "fixed": []}
    periodic = Grid(axes=(turn(0),), fixed=((1, 0.5),))
    assert periodic.to_dict()["axes"][0]["periodic"] is True
    assert Grid.from_dict(periodic.to_dict()) == periodic


def test_faces_cross_the_seam(grid):
    lower, upper = grid.pairs()[0]
    assert lower.size == N * 10
    seam = set(zip(lower.tolist(), upper.tolist())) - {(c, c + 10) for c in range((N - 1) * 10)}
    assert seam == {((N - 1) * 10 + j, j) for j in range(10)}
    assert grid.pairs()[1][0].size == N * 9
    assert all(m.size == N * 10 for m in grid.face_measures()[:1])


@pytest.mark.parametrize("value, row", [(math.pi - STEP, N - 1), (math.pi - 0.4 * STEP, 0),
                                        (math.pi + 0.2 * STEP, 0), (-math.pi - 0.6 * STEP, N - 1),
                                        (3 * math.pi + STEP, 1), (-5 * math.pi, 0)])
def test_cells_are_found_across_the_seam(grid, value, row):
    assert grid.cell_of((value, 3.0)) == row * 10 + 3
    assert grid.cells_of(np.array([[value, 3.0]])).tolist() == [row * 10 + 3]


def test_distances_inside_a_set_wrap(grid):
    mask = np.zeros(grid.shape, dtype=bool)
    mask[[N - 3, N - 2, N - 1, 0, 1, 2], 2:8] = True
    depth = grid.depth(np.flatnonzero(mask))
    # Rolled so the set lies away from the seam, nothing wraps.
    rolled = np.roll(mask, 3, axis=0)
    reference = np.roll(distance_transform_edt(np.pad(rolled, 1))[1:-1, 1:-1], -3, axis=0)
    np.testing.assert_allclose(depth, reference[mask])
    assert depth.max() == 3.0


def test_cells_near_and_in_a_box_wrap(grid):
    near = grid.cells_near((math.pi - 0.5 * STEP, 4.0), 1.0)
    assert {(N - 1) * 10 + 4, 4} <= set(near)
    box = grid.cells_in_box(np.array([-math.pi, 4.0]), 1.5)
    rows = sorted({int(c) // 10 for c in box})
    assert rows == [0, 1, N - 1]


# --- adaptive grids over periodic axes ------------------------------------------------

R = 3
COARSE = Grid(axes=(Axis(0, -math.pi, math.pi - R * STEP, R * STEP, periodic=True),
                    Axis(1, 0.0, 9.0, 3.0)))


def _keys(grid, cells):
    """Lattice index pairs of cells, comparable between grids of one lattice."""
    index = np.rint((grid.coordinates_of(cells) - [-math.pi, 0.0]) / [STEP, 1.0])
    return [tuple(k) for k in index.astype(int).tolist()]


def test_an_adaptive_grid_refined_everywhere_is_the_uniform_periodic_grid(grid):
    """Every block refined: the cells, faces, volumes and depths of the
    uniform grid with the fine steps (``grid``), seam included."""
    full = AdaptiveGrid(COARSE, R, np.arange(N // R * 3))
    assert full.block_shape == (N // R, 3) and full.fine_shape == grid.shape
    assert [(a.count, a.periodic) for a in full.axes] == [(a.count, a.periodic)
                                                           for a in grid.axes]
    assert full.size == grid.size
    assert sorted(_keys(full, np.arange(full.size))) == _keys(grid, np.arange(grid.size))
    for (lower, upper), (lo, up) in zip(full.pairs(), grid.pairs()):
        assert set(zip(_keys(full, lower), _keys(full, upper))) == set(
            zip(_keys(grid, lo), _keys(grid, up)))
    # A cell on the plain axis' ends stands for half a step along it.
    volumes = grid.cell_volumes() * np.where(np.isin(grid.coordinates()[:, 1], [0.0, 9.0]),
                                             0.5, 1.0)
    order = np.argsort(full.cells_of(grid.coordinates()))
    np.testing.assert_allclose(full.cell_volumes(), volumes[order])
    mask = np.zeros(grid.shape, dtype=bool)
    mask[[N - 3, N - 2, N - 1, 0, 1, 2], 2:8] = True
    cells = np.flatnonzero(mask)
    np.testing.assert_allclose(full.depth(cells), grid.depth(cells))


def test_blocks_across_the_seam_are_refined_and_their_faces_wrap():
    # The block between the last base point of the turn and the first.
    seam_block = (N // R - 1) * 3 + 1
    adaptive = AdaptiveGrid(COARSE, R, [seam_block])
    # Base points (8 x 4) and the block's fine points (4 x 4, 4 of them base points).
    assert adaptive.size == 8 * 4 + 16 - 4
    assert adaptive.cell_volumes().sum() == pytest.approx(2 * math.pi * 9.0)
    lower, upper = adaptive.pairs()[0]
    keys = set(zip(_keys(adaptive, lower), _keys(adaptive, upper)))
    # Fine faces inside the block, across the seam: (N - 1, j) -> (0, j).
    assert {((N - 1, j), (0, j)) for j in (3, 4, 5, 6)} <= keys
    # Base faces away from it, the seam's included: (N - 3, 0) -> (0, 0).
    assert ((N - R, 0), (0, 0)) in keys
    assert np.unique(lower).size == lower.size and np.unique(upper).size == upper.size
    volumes = adaptive.cell_volumes()
    assert np.all(volumes > 0)


@pytest.mark.parametrize("value, row", [(math.pi - 0.4 * STEP, 0), (3 * math.pi - 0.4 * STEP, 0),
                                        (-math.pi - 1.1 * STEP, N - 1)])
def test_adaptive_cells_are_found_across_the_seam(value, row):
    adaptive = AdaptiveGrid(COARSE, R, [(N // R - 1) * 3 + 1])
    cell = adaptive.cell_of((value, 4.0))
    assert _keys(adaptive, [cell]) == [(row, 4)]
    near = adaptive.cells_near((math.pi - 0.5 * STEP, 4.0), 1.0)
    assert {(N - 1, 4), (0, 4)} <= set(_keys(adaptive, near))
    assert len(near) == len(set(near))
    box = adaptive.cells_in_box(np.array([-math.pi, 4.0]), 1.5)
    # Row 1 lies in a coarse block: no cell.
    assert sorted({k[0] for k in _keys(adaptive, box)}) == [0, N - 1]
