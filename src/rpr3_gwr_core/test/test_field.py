"""The grid and the n-solution field."""

from concurrent.futures import ThreadPoolExecutor
import threading

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from rpr3_gwr_core.paper import PAPER_GRID, rho1_slice
from rpr3_gwr_core.workspace import Grid, build_roadmap, compute_field
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY
from rpr3_gwr_core.mechanisms import three_leg_solver
from rpr3_gwr_core.mechanisms.three_leg_solver import MAX_SOLUTIONS
from rpr3_gwr_core.mechanisms.trig_roots import sampled_roots


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
        poses = PAPER_GEOMETRY.direct_kinematics(rho[cell])
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
                               PAPER_GEOMETRY.margin(small_field.poses[valid]))


def test_field_separation_is_the_distance_to_the_nearest_other_solution(small_field):
    separation = small_field.separation
    for cell in range(small_field.grid.size):
        poses = small_field.poses[cell, :small_field.count[cell]]
        distance = PAPER_GEOMETRY.pose_distance(poses[None, :, :], poses[:, None, :])
        np.fill_diagonal(distance, np.inf)
        np.testing.assert_array_equal(separation[cell, :len(poses)], distance.min(axis=1))
    assert np.all(np.isnan(separation[~small_field.valid]))
    assert not separation.flags.writeable and not small_field.valid.flags.writeable


def test_field_aspect_is_the_sign_of_margin_and_zero_where_none(small_field):
    valid = small_field.valid
    np.testing.assert_array_equal(small_field.aspect[valid], np.sign(small_field.margin[valid]))
    assert np.all(small_field.aspect[~valid] == 0)


# The fast path of the field: sampling proves most cells' roots simple and
# polishes them; only the rest go through the sextic's companion matrix.

def _full_sextic_field(monkeypatch, grid):
    """The field with every cell solved by the companion matrix."""
    with monkeypatch.context() as patch:
        patch.setattr(three_leg_solver, "sampled_roots", lambda coeffs, samples, slots: (
            np.zeros(len(coeffs), dtype=bool), np.full((len(coeffs), slots), np.nan)))
        return compute_field(PAPER_GEOMETRY, grid)


def _assert_same_field(fast, full):
    np.testing.assert_array_equal(fast.count, full.count)
    valid = full.valid
    np.testing.assert_array_equal(np.isnan(fast.poses), np.isnan(full.poses))
    np.testing.assert_array_equal(fast.aspect, full.aspect)
    np.testing.assert_allclose(fast.margin[valid], full.margin[valid], rtol=0, atol=1e-8)
    # Near a degenerate orientation the pose's position amplifies the last
    # digits of alpha, where the companion matrix is the less accurate of the
    # two: raw poses agree to 1e-7, and one Newton step takes both to the
    # same pose within 1e-9.
    np.testing.assert_allclose(fast.poses[valid], full.poses[valid], rtol=0, atol=1e-7)
    joints = full.grid.joints()[np.nonzero(valid)[0]]
    polished = [PAPER_GEOMETRY.correct(f.poses[valid], joints, 1) for f in (fast, full)]
    np.testing.assert_allclose(PAPER_GEOMETRY.pose_difference(*polished), 0.0, atol=1e-9)


def test_fast_field_equals_the_full_sextic_on_the_paper_slice(monkeypatch):
    fast = compute_field(PAPER_GEOMETRY, PAPER_GRID)
    _assert_same_field(fast, _full_sextic_field(monkeypatch, PAPER_GRID))
    assert np.bincount(fast.count, minlength=7)[[2, 4, 6]].min() > 1000


def test_fast_field_equals_the_full_sextic_on_a_3d_grid(monkeypatch):
    grid = Grid.regular({0: (1.0, 49.0), 1: (0.0, 50.0), 2: (0.0, 50.0)}, 1.5)
    _assert_same_field(compute_field(PAPER_GEOMETRY, grid), _full_sextic_field(monkeypatch, grid))


def test_sampling_settles_all_but_cells_near_the_singular_locus():
    rho = PAPER_GRID.joints()
    coeffs = three_leg_solver._equation7_coefficients(rho[:, 0], rho[:, 1], rho[:, 2],
                                                      PAPER_GEOMETRY)
    certified, _ = sampled_roots(coeffs, 64, MAX_SOLUTIONS)
    assert np.count_nonzero(~certified) < 0.01 * certified.size


def _trig_values(coeffs, phi):
    degree = (coeffs.shape[-1] - 1) // 2
    basis = [np.ones_like(phi)]
    for k in range(1, degree + 1):
        basis += [np.cos(k * phi), np.sin(k * phi)]
    return coeffs @ np.array(basis)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=7, max_size=7))
def test_sampled_roots_are_all_the_real_roots_when_certified(coefficients):
    coeffs = np.array([coefficients])
    certified, roots = sampled_roots(coeffs, 64, MAX_SOLUTIONS)
    if not certified[0]:
        return
    found = roots[0][np.isfinite(roots[0])]
    assert np.all(np.diff(found) > 0) and np.all(np.abs(found) <= np.pi)
    np.testing.assert_allclose(_trig_values(coeffs[0], found), 0.0, atol=1e-12)
    # Every sign change of a fine sampling is one of the roots found.
    phi = np.linspace(-np.pi, np.pi, 20001)
    values = _trig_values(coeffs[0], phi)
    changes = phi[:-1][np.sign(values[:-1]) != np.sign(values[1:])]
    assert changes.size == found.size
    np.testing.assert_allclose(changes, found, atol=2 * np.pi / 20000)


def test_roots_close_to_merging_are_left_to_the_full_sextic():
    # cos(phi) - 1 + c has a double root at phi = 0 for c = 0, two real roots
    # +-4.5e-5 for c = 1e-9 and two complex ones 4.5e-5 off the real axis for
    # c = -1e-9: all three are left to the companion matrix.  cos(2 phi) - 1/2
    # crosses zero four times.
    coeffs = np.array([[-1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                       [-1.0 + 1e-9, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                       [-1.0 - 1e-9, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                       [-0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])
    certified, roots = sampled_roots(coeffs, 64, MAX_SOLUTIONS)
    assert certified.tolist() == [False, False, False, True]
    assert np.all(np.isnan(roots[:3]))
    np.testing.assert_allclose(roots[3, :4], [-5 * np.pi / 6, -np.pi / 6, np.pi / 6,
                                              5 * np.pi / 6])
    assert np.all(np.isnan(roots[3, 4:]))


def test_the_core_starts_no_thread_and_a_callers_pool_builds_the_same_roadmap():
    grid = rho1_slice(step=0.5)
    before = threading.active_count()
    threads = []
    serial = build_roadmap(PAPER_GEOMETRY, grid,
                           progress=lambda *_: threads.append(threading.active_count()))
    assert threads and set(threads) == {before}
    with ThreadPoolExecutor(2) as pool:
        pooled = build_roadmap(PAPER_GEOMETRY, grid, workers=pool.map)
    for name in ("count", "poses", "margin"):
        np.testing.assert_array_equal(getattr(pooled.field, name), getattr(serial.field, name))
    np.testing.assert_array_equal(pooled.segmentation.patch, serial.segmentation.patch)
    assert sorted(pooled.segmentation.gates) == sorted(serial.segmentation.gates)
