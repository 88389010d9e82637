"""Kinematics: the paper's examples, degeneracy, round trips and Jacobians."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from gwr_cases import PAPER_EXAMPLES
from rpr3_gwr_core.mechanisms.rpr3 import (PAPER_GEOMETRY, ThreeRPR, beta_from_sides,
                                           serial_jacobian)
from rpr3_gwr_core.mechanisms.three_leg_solver import MAX_SOLUTIONS

TOL_DEG = 0.05


def _alpha_error_deg(rho2, rho3, alpha_deg, geometry):
    poses = geometry.direct_kinematics(np.array([17.0, rho2, rho3]))
    if len(poses) == 0:
        return math.inf
    gap = np.angle(np.exp(1j * (poses[:, 2] - math.radians(alpha_deg))))
    return float(np.degrees(np.min(np.abs(gap))))


# --- the paper's geometry --------------------------------------------------------

@pytest.mark.parametrize("rho2, rho3, alpha_deg", PAPER_EXAMPLES)
def test_paper_example_is_a_direct_kinematic_solution(rho2, rho3, alpha_deg):
    assert _alpha_error_deg(rho2, rho3, alpha_deg, PAPER_GEOMETRY) < TOL_DEG


def test_printed_beta_37_deg_misses_some_paper_example():
    printed = ThreeRPR(beta=math.radians(37.0))
    errors = [_alpha_error_deg(r2, r3, a, printed) for r2, r3, a in PAPER_EXAMPLES]
    assert max(errors) > TOL_DEG


def test_default_beta_comes_from_the_triangle_sides():
    assert PAPER_GEOMETRY.beta == pytest.approx(beta_from_sides(17.04, 16.54, 20.84))
    assert PAPER_GEOMETRY.d2 == pytest.approx(16.54)
    assert math.degrees(PAPER_GEOMETRY.beta) == pytest.approx(50.56, abs=0.01)


def test_beta_from_sides_of_a_right_triangle():
    assert beta_from_sides(3.0, 5.0, 4.0) == pytest.approx(math.pi / 2)


# --- degeneracy --------------------------------------------------------------------

@pytest.mark.parametrize("expected", [0.03, 0.885])
def test_degenerate_orientations_match_the_paper(expected):
    values = PAPER_GEOMETRY.degenerate_orientations()
    assert np.min(np.abs(values - expected)) < 0.01


def _second_pose_with_same_alpha(pose):
    """Solutions of the legs of ``pose``: (has the pose itself, has another
    solution with the same alpha but a different position)."""
    poses = PAPER_GEOMETRY.direct_kinematics(PAPER_GEOMETRY.inverse(pose))
    same_alpha = poses[np.abs(np.angle(np.exp(1j * (poses[:, 2] - pose[2])))) < 1e-6]
    distance = np.linalg.norm(same_alpha[:, :2] - pose[:2], axis=1)
    return bool(np.any(distance < 1e-6)), bool(np.any(distance > 1e-3))


@pytest.mark.parametrize("which, xy", [(0, (-3.0, 12.0)), (0, (0.0, 17.0)),
                                       (1, (5.0, 10.0)), (1, (8.0, -4.0))])
def test_degenerate_orientation_gives_two_positions_with_one_alpha(which, xy):
    alpha = PAPER_GEOMETRY.degenerate_orientations()[which]
    has_pose, has_other = _second_pose_with_same_alpha(np.array([*xy, alpha]))
    assert has_pose and has_other


@pytest.mark.parametrize("xy", [(5.0, 10.0), (1.0141728990290346, -7.5903249776417745)])
def test_degenerate_orientation_pose_is_recovered(xy):
    alpha = PAPER_GEOMETRY.degenerate_orientations()[0]
    has_pose, has_other = _second_pose_with_same_alpha(np.array([*xy, alpha]))
    assert has_pose and has_other


def test_degenerate_orientation_solutions_satisfy_the_constraints():
    alpha = PAPER_GEOMETRY.degenerate_orientations()[0]
    rho = PAPER_GEOMETRY.inverse(np.array([1.0141728990290346, -7.5903249776417745, alpha]))
    poses = PAPER_GEOMETRY.direct_kinematics(rho)
    residual = PAPER_GEOMETRY.residual(poses, np.broadcast_to(rho, poses.shape))
    assert np.max(np.abs(residual)) < 1e-6


# --- round trips -------------------------------------------------------------------

coordinate = st.floats(-25.0, 25.0, allow_nan=False)
orientation = st.floats(-math.pi, math.pi, allow_nan=False)


def _distance_to_degenerate(alpha):
    degenerate = PAPER_GEOMETRY.degenerate_orientations()
    gap = np.angle(np.exp(1j * (np.asarray(alpha)[..., None] - degenerate)))
    return np.min(np.abs(gap), axis=-1)


def _well_conditioned(pose):
    rho = PAPER_GEOMETRY.inverse(pose)
    return (rho.min() > 0.5 and abs(PAPER_GEOMETRY.margin(pose)) > 1e-2
            and _distance_to_degenerate(pose[2]) > 1e-2)


@settings(max_examples=150, deadline=None)
@given(coordinate, coordinate, orientation)
def test_every_direct_solution_has_the_given_legs(x, y, alpha):
    pose = np.array([x, y, alpha])
    assume(_well_conditioned(pose))
    rho = PAPER_GEOMETRY.inverse(pose)
    poses = PAPER_GEOMETRY.direct_kinematics(rho)
    assert 1 <= len(poses) <= MAX_SOLUTIONS
    # Solutions within 0.01 rad of a degenerate orientation are less accurate
    # (test_solution_near_a_degenerate_orientation_is_accurate); the others must be exact.
    poses = poses[_distance_to_degenerate(poses[:, 2]) > 1e-2]
    np.testing.assert_allclose(PAPER_GEOMETRY.inverse(poses), np.broadcast_to(rho, poses.shape),
                               rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("rho", [(48.0, 46.0, 19.0), (16.25, 48.0, 43.0)])
def test_a_degenerate_double_root_without_a_real_pose_is_no_solution(rho):
    """The sextic has a double root at a degenerate orientation whose line of
    B1 misses leg 1's circle: no pose has these legs and that orientation."""
    poses = PAPER_GEOMETRY.direct_kinematics(np.array(rho))
    assert len(poses) == 2
    np.testing.assert_allclose(PAPER_GEOMETRY.inverse(poses), np.broadcast_to(rho, poses.shape),
                               rtol=0, atol=1e-9)


legs = st.floats(0.5, 50.0)


@settings(max_examples=300, deadline=None)
@given(legs, legs, legs)
def test_every_solution_of_any_legs_has_those_legs(r1, r2, r3):
    rho = np.array([r1, r2, r3])
    poses = PAPER_GEOMETRY.direct_kinematics(rho)
    residual = PAPER_GEOMETRY.residual(poses, np.broadcast_to(rho, poses.shape))
    assert np.all(np.abs(residual) <= 1e-6 * PAPER_GEOMETRY.scale**2)


def test_solution_near_a_degenerate_orientation_is_accurate():
    rho = PAPER_GEOMETRY.inverse(np.array([0.0, -1.0, 0.0]))
    poses = PAPER_GEOMETRY.direct_kinematics(rho)
    assert len(poses) == 4
    np.testing.assert_allclose(PAPER_GEOMETRY.inverse(poses), np.broadcast_to(rho, poses.shape),
                               rtol=0, atol=1e-6)


@settings(max_examples=150, deadline=None)
@given(coordinate, coordinate, orientation)
def test_direct_kinematics_recovers_the_pose(x, y, alpha):
    pose = np.array([x, y, alpha])
    assume(_well_conditioned(pose))
    poses = PAPER_GEOMETRY.direct_kinematics(PAPER_GEOMETRY.inverse(pose))
    gap = poses - pose
    gap[:, 2] = np.angle(np.exp(1j * gap[:, 2]))
    assert np.min(np.linalg.norm(gap, axis=1)) < 1e-6


def test_direct_solutions_are_sorted_by_alpha_in_range():
    poses = PAPER_GEOMETRY.direct_kinematics(np.array([17.0, 20.0, 25.0]))
    assert len(poses) == 4
    assert np.all(np.diff(poses[:, 2]) > 0)
    assert np.all((poses[:, 2] > -math.pi) & (poses[:, 2] <= math.pi))


def test_batch_agrees_with_single_configurations():
    rho = np.array([[17.0, 12.0, 18.0], [17.0, 20.0, 25.0], [17.0, 0.5, 49.0]])
    count, poses = PAPER_GEOMETRY.solve(rho)
    assert poses.shape == (3, MAX_SOLUTIONS, 3)
    for k in range(3):
        single = PAPER_GEOMETRY.direct_kinematics(rho[k])
        assert count[k] == len(single)
        np.testing.assert_allclose(poses[k, :count[k]], single)
        assert np.all(np.isnan(poses[k, count[k]:]))


def test_unreachable_legs_have_no_solution():
    assert PAPER_GEOMETRY.direct_kinematics(np.array([17.0, 0.0, 50.0])).shape == (0, 3)


def test_passive_angle_of_leg_one_is_the_direction_of_b1():
    pose = np.array([3.0, 4.0, 0.7])
    assert PAPER_GEOMETRY.passive_angles(pose)[0] == pytest.approx(math.atan2(4.0, 3.0))


# --- Jacobians ---------------------------------------------------------------------

@settings(max_examples=60, deadline=None)
@given(coordinate, coordinate, orientation, st.floats(1.0, 40.0), st.floats(1.0, 40.0),
       st.floats(1.0, 40.0))
def test_parallel_jacobian_is_the_derivative_of_the_constraints(x, y, alpha, r1, r2, r3):
    pose, rho, h = np.array([x, y, alpha]), np.array([r1, r2, r3]), 1e-6
    numeric = np.empty((3, 3))
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        numeric[:, k] = (PAPER_GEOMETRY.residual(pose + step, rho)
                         - PAPER_GEOMETRY.residual(pose - step, rho)) / (2 * h)
    np.testing.assert_allclose(PAPER_GEOMETRY.parallel_jacobian(pose), numeric, rtol=1e-5,
                               atol=1e-4)


def test_serial_jacobian_is_twice_the_legs_on_the_diagonal():
    rho = np.array([17.0, 12.5, 3.0])
    np.testing.assert_array_equal(serial_jacobian(rho), np.diag(2 * rho))


def test_serial_jacobian_broadcasts_over_configurations():
    rho = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    out = serial_jacobian(rho)
    assert out.shape == (2, 3, 3)
    np.testing.assert_array_equal(out[1], np.diag([8.0, 10.0, 12.0]))


def test_velocity_equation_links_the_two_jacobians():
    pose, h = np.array([2.0, 16.0, 1.2]), 1e-6
    rho = PAPER_GEOMETRY.inverse(pose)
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        drho = (PAPER_GEOMETRY.inverse(pose + step)
                - PAPER_GEOMETRY.inverse(pose - step)) / (2 * h)
        np.testing.assert_allclose(serial_jacobian(rho) @ drho,
                                   PAPER_GEOMETRY.parallel_jacobian(pose)[:, k],
                                   rtol=1e-6, atol=1e-6)


@settings(max_examples=150, deadline=None)
@given(coordinate, coordinate, orientation)
def test_singularity_margin_is_bounded_and_signed_like_det_jx(x, y, alpha):
    pose = np.array([x, y, alpha])
    margin = float(PAPER_GEOMETRY.margin(pose))
    assert -1.0 <= margin <= 1.0
    det = np.linalg.det(PAPER_GEOMETRY.parallel_jacobian(pose))
    # The margin normalises each row, so it stays finite as a leg shrinks to
    # zero (a serial singularity) while det(Jx) itself underflows.
    assume(abs(margin) > 1e-9 and PAPER_GEOMETRY.inverse(pose).min() > 1e-6)
    assert np.sign(margin) == np.sign(det) == PAPER_GEOMETRY.aspect(pose)


@settings(max_examples=100, deadline=None)
@given(coordinate, coordinate, orientation, st.floats(1.0, 30.0), st.floats(1.0, 30.0),
       st.floats(1.0, 30.0))
def test_mechanism_margin_and_residual_of_one_pose_agree_with_the_batch(x, y, alpha, r1, r2,
                                                                        r3):
    # One pose takes a compiled path of its own (the validator's), a batch numpy's.
    pose, rho = np.array([x, y, alpha]), np.array([r1, r2, r3])
    batch = PAPER_GEOMETRY.margin(np.stack([pose, pose]))
    assert PAPER_GEOMETRY.margin(pose) == pytest.approx(batch[0], rel=1e-12, abs=1e-15)
    np.testing.assert_allclose(PAPER_GEOMETRY.residual(pose, rho),
                               PAPER_GEOMETRY.residual(np.stack([pose]), np.stack([rho]))[0],
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(PAPER_GEOMETRY.residual(pose, rho),
                               PAPER_GEOMETRY.inverse(pose) ** 2 - rho**2, rtol=1e-12,
                               atol=1e-9)


def test_aspect_is_int8_and_vectorised():
    poses = PAPER_GEOMETRY.direct_kinematics(np.array([17.0, 20.0, 25.0]))
    signs = PAPER_GEOMETRY.aspect(poses)
    assert signs.dtype == np.int8 and signs.shape == (4,)
    assert set(signs.tolist()) == {-1, 1}


def test_singularity_margin_vanishes_on_a_flat_singularity():
    # B1 on the line A1A2 with the platform side B1B2 along it: rows 1, 2 parallel.
    assert PAPER_GEOMETRY.margin(np.array([5.0, 0.0, 0.0])) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("pose", [[2.0, 16.0, 1.2], [-5.0, 10.0, -0.4], [12.0, -3.0, 2.5]])
def test_correct_converges_to_the_pose(pose):
    pose = np.array(pose)
    rho = PAPER_GEOMETRY.inverse(pose)
    start = pose + np.array([0.05, -0.04, 0.01])
    corrected = PAPER_GEOMETRY.correct(start, rho, 8)
    np.testing.assert_allclose(corrected, pose, atol=1e-9)
    assert np.max(np.abs(PAPER_GEOMETRY.residual(corrected, rho))) < 1e-9


def test_correct_does_not_modify_its_input():
    start = np.array([2.05, 15.96, 1.21])
    copy = start.copy()
    PAPER_GEOMETRY.correct(start, PAPER_GEOMETRY.inverse(np.array([2.0, 16.0, 1.2])), 3)
    np.testing.assert_array_equal(start, copy)
