"""The grid and the n-solution field."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from rpr3_gwr_core.paper import PAPER_GRID, rho1_slice
from rpr3_gwr_core.workspace import Grid, compute_field
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY
from rpr3_gwr_core.mechanisms.rpr3 import MAX_SOLUTIONS, direct_kinematics, singularity_margin


@pytest.fixture(scope="module")
def small_field():
    grid = rho1_slice(rho2_range=(10.0, 22.0), rho3_range=(15.0, 27.0), step=1.5)
    return compute_field(PAPER_GEOMETRY, grid)


def test_paper_grid_is_401_by_401():
    assert PAPER_GRID.shape == (401, 401)
    assert PAPER_GRID.size == 401 * 401
    assert PAPER_GRID.fixed == ((0, 17.0),) and PAPER_GRID.steps == (0.125, 0.125)


def test_grid_axes_include_both_ends():
    grid = rho1_slice(rho2_range=(1.0, 3.0), rho3_range=(0.0, 1.0), step=0.5)
    np.testing.assert_allclose(grid.axes[0].values, [1.0, 1.5, 2.0, 2.5, 3.0])
    np.testing.assert_allclose(grid.axes[1].values, [0.0, 0.5, 1.0])
    assert grid.shape == (5, 3)


def test_grid_rho_is_row_major():
    grid = rho1_slice(rho1=5.0, rho2_range=(1.0, 2.0), rho3_range=(3.0, 5.0), step=1.0)
    np.testing.assert_allclose(grid.joints(), [[5, 1, 3], [5, 1, 4], [5, 1, 5],
                                            [5, 2, 3], [5, 2, 4], [5, 2, 5]])


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 400), st.integers(0, 400))
def test_cell_of_inverts_the_flat_index(i, j):
    grid = PAPER_GRID
    rho2, rho3 = grid.axes[0].values[i], grid.axes[1].values[j]
    cell = grid.cell_of((grid.fixed_value(0), rho2, rho3))
    assert cell == i * grid.shape[1] + j
    np.testing.assert_allclose(grid.joints()[cell], [grid.fixed_value(0), rho2, rho3])


def test_cell_of_rounds_to_the_nearest_cell():
    grid = rho1_slice(step=0.5)
    assert grid.cell_of((17.0, 0.24, 0.26)) == 1
    assert grid.cell_of((17.0, 50.2, 0.0)) == (grid.shape[0] - 1) * grid.shape[1]


def test_grid_dict_round_trip():
    grid = rho1_slice(rho1=13.0, rho2_range=(1.0, 9.0), rho3_range=(2.0, 8.0), step=0.25)
    assert Grid.from_dict(grid.to_dict()) == grid


def test_field_counts_match_direct_kinematics(small_field):
    rho = small_field.grid.joints()
    for cell in range(small_field.grid.size):
        poses = direct_kinematics(rho[cell])
        assert small_field.count[cell] == len(poses)
        np.testing.assert_allclose(small_field.poses[cell, :len(poses)], poses)


def test_field_has_cells_of_several_counts(small_field):
    assert len(set(small_field.count.tolist())) >= 2


def test_field_valid_mask_follows_count(small_field):
    valid = small_field.valid
    assert valid.shape == (small_field.grid.size, MAX_SOLUTIONS)
    np.testing.assert_array_equal(valid.sum(axis=1), small_field.count)
    assert np.all(np.isfinite(small_field.poses[valid]))
    assert np.all(np.isnan(small_field.poses[~valid]))
    assert np.all(np.isnan(small_field.margin[~valid]))


def test_field_margin_is_the_singularity_margin(small_field):
    valid = small_field.valid
    np.testing.assert_allclose(small_field.margin[valid],
                               singularity_margin(small_field.poses[valid]))


def test_field_aspect_is_the_sign_of_margin_and_zero_where_none(small_field):
    valid = small_field.valid
    np.testing.assert_array_equal(small_field.aspect[valid], np.sign(small_field.margin[valid]))
    assert np.all(small_field.aspect[~valid] == 0)
