"""Grids refuse, before allocating anything, to have more cells than a build
can hold; and a grid that cannot give a roadmap is refused before its
build."""

import math

import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, Axis, Grid, rho1_slice
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.workspace import AdaptiveGrid, refine
from rpr3_gwr_core.workspace.grid import MAX_GRID_CELLS, check_roadmap_grid


def test_a_grid_over_the_cell_limit_is_refused_when_made():
    # 10001 x 10001 cells: building its roadmap ran out of memory.
    with pytest.raises(InvalidInputError, match=f"exceeds the limit of {MAX_GRID_CELLS}"):
        rho1_slice(0.3, step=0.005)


def test_the_limit_is_the_builders_four_million_cells():
    side = math.isqrt(MAX_GRID_CELLS)
    assert MAX_GRID_CELLS == side * side == 4_000_000
    assert Grid.regular({1: (0.0, side - 1.0), 2: (0.0, side - 1.0)}, 1.0,
                        fixed={0: 17.0}).size == MAX_GRID_CELLS
    with pytest.raises(InvalidInputError, match="grid of 4004001 cells exceeds the limit"):
        Grid.regular({1: (0.0, float(side)), 2: (0.0, float(side))}, 1.0, fixed={0: 17.0})


@pytest.mark.parametrize("low, high, step", [(0.0, 50.0, 1e-300), (0.0, 1e308, 1.0),
                                             (-1e308, 1e308, 1.0), (0.0, 50.0, 1e-5)])
def test_an_axis_whose_cells_cannot_be_counted_or_held_is_refused(low, high, step):
    with pytest.raises(InvalidInputError, match="more than 4000000 cells"):
        Axis(1, low, high, step)


def test_a_grid_whose_cell_volume_overflows_is_refused():
    # One cell per axis, but the volume of that cell, the product of the
    # steps, is infinite.
    with pytest.raises(InvalidInputError, match="overflow the volume of a cell"):
        rho1_slice(17.0, step=1e200)
    assert rho1_slice(17.0, step=1e100).shape == (1, 1)


def test_a_grid_read_from_a_document_is_held_to_the_limit():
    document = rho1_slice(step=1.0).to_dict()
    for axis in document["axes"]:
        axis["step"] = 1e-3
    with pytest.raises(InvalidInputError, match="exceeds the limit"):
        Grid.from_dict(document)


def test_an_adaptive_grid_refuses_a_fine_lattice_too_large_to_tabulate():
    base = rho1_slice(step=1.0)
    # (50 * 200 + 1)**2 = 100 million lattice points, however few are cells.
    with pytest.raises(InvalidInputError, match="fine lattice of 100020001 points"):
        AdaptiveGrid(base, 200, ())
    with pytest.raises(InvalidInputError, match="fine lattice"):
        refine(PAPER_GEOMETRY, base, 200)


def test_an_adaptive_grid_refuses_more_cells_than_the_limit():
    base = rho1_slice(step=1.0)
    every_block = range(math.prod(n - 1 for n in base.shape))
    # All 50 x 50 blocks refined 50 times: 2501 x 2501 cells.
    with pytest.raises(InvalidInputError, match="grid of 6255001 cells exceeds the limit"):
        AdaptiveGrid(base, 50, every_block)
    assert AdaptiveGrid(base, 39, every_block).size == 1951 ** 2


@pytest.mark.parametrize("grid, reason", [
    (rho1_slice(17.0, (12.0, 12.0)), "a grid of 1 x 401 cells has no faces along one axis"),
    (rho1_slice(17.0, step=100.0), "a grid of 1 x 1 cells has no faces"),
    (rho1_slice(1000.0), "about 0 cells of the grid have a direct-kinematic solution at "
                         "rho1 = 1000, fewer than one region needs (8)"),
    (rho1_slice(0.001, step=0.5), "fewer than one region needs"),
])
def test_grids_without_a_roadmap_are_refused_with_the_reason(grid, reason):
    with pytest.raises(InvalidInputError) as refused:
        check_roadmap_grid(PAPER_GEOMETRY, grid)
    assert reason in str(refused.value)


@pytest.mark.parametrize("grid", [rho1_slice(), rho1_slice(17.0, (4.0, 4.5), (6.0, 7.5), 0.5),
                                  refine(PAPER_GEOMETRY, rho1_slice(17.0, (10.0, 20.0),
                                                                    (10.0, 20.0), 1.0))])
def test_grids_that_can_give_a_roadmap_pass_the_check(grid):
    check_roadmap_grid(PAPER_GEOMETRY, grid)
