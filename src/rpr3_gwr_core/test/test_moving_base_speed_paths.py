"""The compiled paths of the slice builds against the numpy arithmetic they
replace, bit for bit: the difference and distance of poses and the separation of a
cell's solutions (:class:`~rpr3_gwr_core.mechanisms.base.Mechanism`), the
field's separation taken chunk by chunk, and the three-leg solver's per-root
work for base points per row
(:func:`~rpr3_gwr_core.mechanisms.three_leg_solver.solve_with_bases`)."""

import math

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, Axis, Grid, compute_field
from rpr3_gwr_core.mechanisms import DEFAULT_FIVE_BAR, DEFAULT_THREE_PRR, DEFAULT_THREE_RRR
from rpr3_gwr_core.mechanisms.three_leg_solver import (
    _FAKE_RESIDUAL, _BasePerRow, _linear_poses, _moving_base_fake, _moving_base_linear,
    residuals)
from rpr3_gwr_core.workspace.field import NSolutionField


def same_bits(a, b):
    a, b = np.atleast_1d(a), np.atleast_1d(b)
    return a.shape == b.shape and np.array_equal(a.view(np.uint8), b.view(np.uint8))


def numpy_difference(m, a, b):
    """The pose difference in numpy: angles wrapped by numpy's remainder."""
    difference = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    for k in np.flatnonzero(m.angular):
        difference[..., k] = (np.pi - np.remainder(np.pi - difference[..., k], 2 * np.pi)) \
            * m.scale
    return difference


def numpy_distance(m, a, b):
    return np.linalg.norm(numpy_difference(m, a, b), axis=-1)


@pytest.mark.parametrize("m", [PAPER_GEOMETRY, DEFAULT_FIVE_BAR])
def test_pose_difference_is_numpys_to_the_bit(m):
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(3000, m.pose_size)) * 20, rng.normal(size=(3000, m.pose_size)) * 20
    b[::4, -1] = a[::4, -1] + rng.choice([-3, -1, 0, 1, 3], 750) * math.pi
    a[::7, 0], b[::11, -1], a[::13, -1] = np.nan, np.inf, -0.0
    with np.errstate(invalid="ignore"):
        assert same_bits(m.pose_difference(a, b), numpy_difference(m, a, b))
        assert same_bits(m.pose_difference(a[:5, None], b[None, :4]),
                         numpy_difference(m, a[:5, None], b[None, :4]))
    assert m.pose_difference(a[0], b[0]).shape == (m.pose_size,)


@pytest.mark.parametrize("m", [PAPER_GEOMETRY, DEFAULT_FIVE_BAR])
def test_pose_distance_is_numpys_to_the_bit(m):
    rng = np.random.default_rng(3)
    size = m.pose_size
    for magnitude in (1e-9, 1.0, math.pi, 50.0, 1e6):
        a = rng.normal(size=(3000, size)) * magnitude
        b = rng.normal(size=(3000, size)) * magnitude
        # Differences of whole and half turns, where the wrap rounds.
        b[::4, -1] = a[::4, -1] + rng.choice([-3, -2, -1, 0, 1, 2, 3], 750) * math.pi
        a[::7, 0], b[::11, -1], a[::13, -1] = np.nan, np.inf, -0.0
        with np.errstate(invalid="ignore", over="ignore"):
            assert same_bits(m.pose_distance(a, b), numpy_distance(m, a, b))
    a, b = rng.normal(size=(40, 6, size)) * 20, rng.normal(size=(40, size)) * 20
    assert same_bits(m.pose_distance(a, b[:, None, :]), numpy_distance(m, a, b[:, None, :]))
    assert same_bits(m.pose_distance(a[:, ::2], b[:, None, :]),
                     numpy_distance(m, a[:, ::2], b[:, None, :]))
    one = m.pose_distance(list(a[0, 0]), tuple(b[0]))
    assert type(one) is np.float64 and same_bits(one, numpy_distance(m, a[0, 0], b[0]))


def numpy_separation(m, poses, count):
    out = np.where(np.arange(poses.shape[1]) < count[:, None], np.inf, np.nan)
    for slot in range(poses.shape[1]):
        for other in range(poses.shape[1]):
            if other != slot:
                both = np.flatnonzero(count > max(slot, other))
                distance = numpy_distance(m, poses[both, other], poses[both, slot])
                out[both, slot] = np.minimum(out[both, slot], distance)
    return out


def slice_field(m):
    if m is PAPER_GEOMETRY:
        grid = Grid(axes=(Axis(1, 5.0, 45.0, 0.5), Axis(2, 5.0, 45.0, 0.5)), fixed=((0, 17.0),))
    else:
        step = 2 * math.pi / 60
        grid = Grid(axes=(Axis(1, -math.pi, math.pi - step, step, periodic=True),
                          Axis(2, -math.pi, math.pi - step, step, periodic=True)),
                    fixed=((0, 0.0),))
    return compute_field(m, grid)


@pytest.mark.parametrize("m", [PAPER_GEOMETRY, DEFAULT_THREE_RRR])
def test_separation_is_numpys_and_the_field_takes_it_by_chunks(m):
    field = slice_field(m)
    assert np.count_nonzero(field.count > 1) > 100
    expected = numpy_separation(m, field.poses, field.count)
    assert same_bits(m.separation(field.poses, field.count), expected)
    # compute_field's, chunk by chunk, is the one a field without it computes.
    assert not field.separation.flags.writeable
    assert same_bits(field.separation, expected)
    bare = NSolutionField(mechanism=m, grid=field.grid, count=field.count, poses=field.poses,
                          margin=field.margin)
    assert same_bits(bare.separation, expected)
    poses = field.poses.copy()
    poses[::5, 0, 0] = np.nan
    assert same_bits(m.separation(poses, field.count), numpy_separation(m, poses, field.count))


@pytest.mark.parametrize("m", [DEFAULT_THREE_RRR, DEFAULT_THREE_PRR])
def test_per_root_kernels_are_the_numpy_formula(m):
    rng = np.random.default_rng(5)
    n = 3000
    joints = rng.uniform(-math.pi, math.pi, (n, 3)) if m is DEFAULT_THREE_RRR else \
        rng.uniform(0.0, 30.0, (n, 3))
    points = np.ascontiguousarray(m.base_points(joints))
    rho = np.full((n, 3), m.distal)
    platform = m.platform
    rows = np.repeat(np.arange(n), 2)
    alpha = rng.uniform(-math.pi, math.pi, rows.size)
    geometry = _BasePerRow(points, platform).take(rows)
    r = rho[rows]
    # The numpy formula, on every root's own copy of its base points.
    expected, expected_terms, regular, expected_rough = _linear_poses(alpha, r, geometry)
    candidate, terms, kernel_regular, rough = _moving_base_linear(
        points, rho, rows, alpha,
        (platform.d1, platform.d3, platform.beta, platform.d1**2, platform.d3**2))
    assert same_bits(candidate, expected)
    assert same_bits(terms, np.stack(expected_terms))
    assert np.array_equal(kernel_regular, regular)
    assert np.array_equal(rough, expected_rough)
    # Random orientations miss the legs mostly, and now and then fit them.
    limit = _FAKE_RESIDUAL * platform.scale**2
    poses = np.where(rng.random((rows.size, 1)) < 0.5, candidate, expected + 1e-3)
    poses[::17, 1] = np.nan
    fake = _moving_base_fake(points, rho, rows, poses, (platform.d1, platform.d3, platform.beta),
                             limit)
    with np.errstate(invalid="ignore"):
        misfit = np.max(np.abs(residuals(poses, r, geometry)), axis=-1)
    assert np.array_equal(fake, misfit > limit)
