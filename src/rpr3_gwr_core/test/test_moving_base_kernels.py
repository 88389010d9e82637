"""The compiled kernels that the 3-RRR and the 3-PRR share
(:class:`~rpr3_gwr_core.mechanisms.moving_base.MovingBaseRPR`), against the
three-leg solver's row arithmetic on base points computed here, and the
tables of the sampled root finder (:mod:`.trig_roots`)."""

import math

import numpy as np
import pytest

from rpr3_gwr_core.mechanisms import DEFAULT_THREE_PRR, DEFAULT_THREE_RRR, ThreePRR, ThreeRRR
from rpr3_gwr_core.mechanisms.three_leg_solver import leg_residuals, row_terms, rows_margin
from rpr3_gwr_core.mechanisms.trig_roots import _MAX_DEPTH, _sampling, sampled_roots

MECHANISMS = [DEFAULT_THREE_RRR, DEFAULT_THREE_PRR,
              ThreeRRR(a2=(16.0, 1.0), l1=7.5, l2=11.0),
              ThreePRR(gamma1=0.3, gamma2=2.0, gamma3=-1.0, l=14.0)]


def moving_points(m, joints):
    """The C_i of joints (n, 3) from the mechanism's fields, shape (n, 3, 2)."""
    q = np.asarray(joints, dtype=float)[..., None]
    base = np.array([m.a1, m.a2, m.a3])
    if isinstance(m, ThreeRRR):
        return base + m.l1 * np.concatenate([np.cos(q), np.sin(q)], -1)
    gamma = np.array([m.gamma1, m.gamma2, m.gamma3])
    return base + q * np.stack([np.cos(gamma), np.sin(gamma)], -1)


def rows_of(m, poses, joints):
    """The rows of ``Jx / 2`` (the 3-RPR's) of poses at joints (n, 3)."""
    c = moving_points(m, joints).reshape(-1, 6).T
    return row_terms(poses[:, 0], poses[:, 1], poses[:, 2], (*c, m.d1, m.d3, m.beta))


def sample(m, n, seed):
    """``n`` random poses and joints (over the 3-PRR's strokes), shapes (n, 3)."""
    rng = np.random.default_rng(seed)
    low, high = (-math.pi, math.pi) if isinstance(m, ThreeRRR) else (0.0, 30.0)
    joints = rng.uniform(low, high, (n, 3))
    poses = rng.uniform([-10, -10, -math.pi], [25, 25, math.pi], (n, 3))
    return poses, joints


@pytest.mark.parametrize("m", MECHANISMS)
def test_parameters_say_how_the_joints_move_the_base_points(m):
    p = m.parameters
    assert len(p) == 19 and np.array_equal(m.step_kernel[1], p)
    assert p[:11] == (*m.a1, *m.a2, *m.a3, m.d1, m.d3, m.beta, m.distal, m.scale)
    if isinstance(m, ThreeRRR):
        assert p[11:13] == (1.0, m.l1)
    else:
        assert p[11:13] == (0.0, 1.0)
        assert p[13:] == tuple(f(g) for g in (m.gamma1, m.gamma2, m.gamma3)
                               for f in (math.cos, math.sin))


@pytest.mark.parametrize("m", MECHANISMS)
def test_kernels_are_the_rpr_rows_on_the_moving_base_points(m):
    poses, joints = sample(m, 400, 1)
    assert np.allclose(m.base_points(joints), moving_points(m, joints), rtol=0, atol=1e-12)
    rows = rows_of(m, poses, joints)
    legs = (m.distal, m.distal, m.distal)
    assert np.allclose(m.residual(poses, joints), np.stack(leg_residuals(rows, legs), -1),
                       rtol=0, atol=1e-9)
    expected = [rows_margin(tuple(float(v[k]) for v in rows), m.scale)
                for k in range(len(poses))]
    assert np.allclose(m.margin(poses, joints), expected, rtol=0, atol=1e-12)
    # Newton from a solution's neighbourhood lands on the solution.
    count, solutions = m.solve(joints)
    have = count > 0
    start = solutions[have, 0]
    corrected = m.correct(start + 1e-3, joints[have], 6)
    assert np.allclose(m.pose_difference(corrected, start), 0.0, atol=1e-8)


@pytest.mark.parametrize("m", MECHANISMS)
def test_rows_grouped_by_joints_answer_as_rows_alone(m):
    """A batch whose rows repeat their joints (a cell's solutions) reuses
    their base points: the answers are those of the rows one at a time."""
    poses, joints = sample(m, 300, 2)
    grouped = np.repeat(joints[:100], 3, axis=0)
    target = grouped + 0.01
    shuffled = np.random.default_rng(3).permutation(300)
    for method, args in (("margin", (poses, grouped)),
                         ("predict", (poses, grouped, target)),
                         ("correct", (poses, grouped, 3)),
                         ("residual", (poses, grouped))):
        batch = getattr(m, method)(*args)
        alone = getattr(m, method)(*(a[shuffled] if isinstance(a, np.ndarray) else a
                                     for a in args))
        assert np.array_equal(batch[shuffled], alone)
        one = [getattr(m, method)(*(a[k] if isinstance(a, np.ndarray) else a for a in args))
               for k in range(0, 300, 37)]
        assert np.array_equal(batch[::37], np.array(one))


@pytest.mark.parametrize("m", MECHANISMS)
def test_any_layout_and_broadcast_give_the_same_answers(m):
    poses, joints = sample(m, 60, 4)
    target = joints + 0.02
    expected = m.predict(poses, joints, target)
    strided = np.concatenate([poses, poses], -1)[:, :3]
    frozen = joints.copy()
    frozen.flags.writeable = False
    assert np.array_equal(m.predict(strided, frozen, target.tolist()), expected)
    assert np.array_equal(m.predict(np.asfortranarray(poses), joints, target), expected)
    one = m.predict(poses[:5], joints[0], target[0])
    assert np.array_equal(one, m.predict(poses[:5], np.tile(joints[0], (5, 1)),
                                         np.tile(target[0], (5, 1))))
    grid = m.margin(poses.reshape(3, 20, 3), joints.reshape(3, 20, 3))
    assert grid.shape == (3, 20)
    assert np.array_equal(grid.ravel(), m.margin(poses, joints))
    scalar = m.margin(poses[0], joints[0])
    assert np.ndim(scalar) == 0 and scalar == m.margin(poses, joints)[0]
    assert m.base_points(joints.reshape(3, 20, 3)).shape == (3, 20, 3, 2)


def test_revolute_joints_predict_the_short_way_round():
    m = DEFAULT_THREE_RRR
    poses, joints = sample(m, 50, 5)
    target = joints + 0.01
    turned = target + 2 * math.pi * np.array([1, -1, 2])
    assert np.allclose(m.predict(poses, joints, turned), m.predict(poses, joints, target),
                       rtol=0, atol=1e-9)


def test_sampling_tables_hold_the_halvings_middles():
    samples = 64
    basis, slope_basis, middles = _sampling(samples, 7)
    assert _sampling(samples, 7)[2] is middles and not middles.flags.writeable
    h = 2.0 * math.pi / samples
    for k in range(1, 4):
        assert np.array_equal(basis[2 * k - 1], np.cos(k * np.arange(samples) * h))
        assert np.array_equal(slope_basis[:, 2 * k], k * basis[2 * k - 1])
    # Each node's ends, halved as the root finder halves them.
    for i in (0, 17, 63):
        ends = {1: (i * h, (i + 1) * h)}
        for node in range(1, 2**_MAX_DEPTH):
            a, b = ends[node]
            middle = 0.5 * (a + b)
            assert tuple(middles[i, node]) == (math.cos(middle), math.sin(middle))
            ends[2 * node], ends[2 * node + 1] = (a, middle), (middle, b)


def test_sampled_roots_are_the_sign_changes_of_close_roots():
    """Rows with two roots close together, which the sampling separates by
    halving its intervals: the certified rows have exactly the roots
    ``c - g`` and ``c + g``."""
    rng = np.random.default_rng(6)
    centres = rng.uniform(-math.pi, math.pi, 300)
    gaps = rng.uniform(0.005, 0.05, 300)
    # (cos(phi - c) - cos(g)) (2 + sin(2 phi)), a trigonometric cubic,
    # written in its coefficients from 16 samples.
    phi = 2 * math.pi * np.arange(16) / 16
    values = (np.cos(phi - centres[:, None]) - np.cos(gaps)[:, None]) * (2 + np.sin(2 * phi))
    spectrum = np.fft.rfft(values, axis=-1) / 16
    coeffs = np.empty((300, 7))
    coeffs[:, 0] = spectrum[:, 0].real
    coeffs[:, 1::2], coeffs[:, 2::2] = 2 * spectrum[:, 1:4].real, -2 * spectrum[:, 1:4].imag
    certified, roots = sampled_roots(coeffs, 64, 6)
    assert np.count_nonzero(certified) > 250
    expected = np.sort(np.pi - np.remainder(
        np.pi - (centres[:, None] + np.array([-1, 1]) * gaps[:, None]), 2 * np.pi), axis=1)
    assert np.all(np.isnan(roots[certified, 2:]))
    assert np.allclose(roots[certified, :2], expected[certified], rtol=0, atol=1e-9)
