"""The inverse kinematics of every mechanism, against the legs written here
from their definitions: the platform points of a pose, each leg's moving
point from its joint, and each leg's length; the working modes' branch signs
from the elbow's or slider's side, written here too.  Also against the
references the other tests use (``pose_reference``, the 3-RRR's and 3-PRR's
torus references, the five-bar's circle intersection) and the mechanism's
own direct kinematics.
"""

import math
import warnings

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.mechanisms import (DEFAULT_FIVE_BAR, DEFAULT_THREE_PRR, DEFAULT_THREE_RRR,
                                      PAPER_GEOMETRY)
from rpr3_gwr_core.mechanisms.base import working_mode_label

import pose_reference
import test_five_bar
import test_prr3
import test_rrr3

# The shipped geometries, written again rather than read from the mechanisms.
A = np.array([[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]])
D1, D2, D3 = 17.04, 16.54, 20.84
BETA = math.acos((D1**2 + D3**2 - D2**2) / (2 * D1 * D3))
RRR_L1, RRR_L2 = 8.0, 12.0
PRR_GAMMA, PRR_L = np.array([0.0, math.pi / 2, math.pi / 4]), 15.0
FIVE_BAR_D, FIVE_BAR_L1, FIVE_BAR_L2 = 0.118, 0.09, 0.118
FIVE_BAR_BASES = np.array([[0.0, 0.0], [FIVE_BAR_D, 0.0]])

# Poses every leg of which reaches on both branches (8, 8 and 4 working modes).
POSES = {
    "3-RPR": (12.0, 18.0, 2.14),
    "3-RRR": (8.0, 6.0, 0.8),
    "3-PRR": (5.0, 8.0, 0.5),
    "5R": (0.05, 0.12),
}
MECHANISMS = {"3-RPR": PAPER_GEOMETRY, "3-RRR": DEFAULT_THREE_RRR, "3-PRR": DEFAULT_THREE_PRR,
              "5R": DEFAULT_FIVE_BAR}
MODE_COUNTS = {"3-RPR": 1, "3-RRR": 8, "3-PRR": 8, "5R": 4}
# Poses no leg of the mechanism reaches on any branch except the 3-RPR's,
# whose legs reach every pose.
FAR = {"3-RRR": (60.0, 60.0, 0.3), "3-PRR": (80.0, -70.0, 0.3), "5R": (0.5, 0.5)}


def platform_points(pose):
    """B1, B2, B3 of a pose (x, y, alpha), or P of the five-bar, shape (k, 2)."""
    if len(pose) == 2:
        return np.array([pose, pose], dtype=float)
    x, y, alpha = pose
    b1 = np.array([x, y])
    return np.array([b1, b1 + D1 * np.array([math.cos(alpha), math.sin(alpha)]),
                     b1 + D3 * np.array([math.cos(alpha + BETA), math.sin(alpha + BETA)])])


def leg_lengths(kind, pose, joints):
    """|B_i - C_i| of each leg (its moving point C_i placed by its joint), and
    the length the leg must have."""
    points = platform_points(pose)
    joints = np.asarray(joints, dtype=float)
    if kind == "3-RPR":
        return np.linalg.norm(points - A, axis=-1), joints
    if kind == "3-PRR":
        moving = A + joints[:, None] * np.stack([np.cos(PRR_GAMMA), np.sin(PRR_GAMMA)], -1)
        return np.linalg.norm(points - moving, axis=-1), np.full(3, PRR_L)
    base, proximal, distal = ((A, RRR_L1, RRR_L2) if kind == "3-RRR"
                              else (FIVE_BAR_BASES, FIVE_BAR_L1, FIVE_BAR_L2))
    moving = base + proximal * np.stack([np.cos(joints), np.sin(joints)], -1)
    return np.linalg.norm(points - moving, axis=-1), np.full(len(joints), distal)


def branch_signs(kind, pose, joints):
    """The side of each leg's moving point, as the working modes name it: for
    a revolute leg the sign of cross(C - A, B - C) (the elbow angle in
    [0, pi] is +1), for a slider the sign of -(B - C) . e (beyond the foot of
    B's perpendicular is +1)."""
    points, joints = platform_points(pose), np.asarray(joints, dtype=float)
    if kind == "3-PRR":
        rails = np.stack([np.cos(PRR_GAMMA), np.sin(PRR_GAMMA)], -1)
        moving = A + joints[:, None] * rails
        return np.sign(-np.sum((points - moving) * rails, -1))
    base, proximal = (A, RRR_L1) if kind == "3-RRR" else (FIVE_BAR_BASES, FIVE_BAR_L1)
    link = proximal * np.stack([np.cos(joints), np.sin(joints)], -1)
    distal = points - base - link
    return np.sign(link[:, 0] * distal[:, 1] - link[:, 1] * distal[:, 0])


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
def test_a_generic_reachable_pose_has_every_working_mode(kind):
    mechanism = MECHANISMS[kind]
    joints = mechanism.inverse_kinematics(POSES[kind])
    assert joints.shape == (MODE_COUNTS[kind], mechanism.n_joints)
    assert np.all(np.isfinite(joints))
    assert len(mechanism.working_modes) == MODE_COUNTS[kind]
    assert len({working_mode_label(m) for m in mechanism.working_modes}) == MODE_COUNTS[kind]


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
def test_each_working_mode_reproduces_the_pose_through_its_legs(kind):
    mechanism = MECHANISMS[kind]
    scale = np.max(np.abs(platform_points(POSES[kind])))
    for joints in mechanism.inverse_kinematics(POSES[kind]):
        lengths, wanted = leg_lengths(kind, POSES[kind], joints)
        assert np.allclose(lengths, wanted, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
def test_each_working_mode_has_the_branch_signs_it_names(kind):
    mechanism = MECHANISMS[kind]
    for signs, joints in zip(mechanism.working_modes,
                             mechanism.inverse_kinematics(POSES[kind])):
        if kind == "3-RPR":
            assert tuple(signs) == (1, 1, 1)
        else:
            assert np.array_equal(branch_signs(kind, POSES[kind], joints), signs)


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
def test_direct_kinematics_of_each_working_mode_contains_the_pose(kind):
    mechanism = MECHANISMS[kind]
    pose = np.array(POSES[kind])
    for joints in mechanism.inverse_kinematics(pose):
        count, poses = mechanism.solve(joints[None])
        gap = mechanism.pose_distance(poses[0, :count[0]], pose)
        assert np.min(gap) <= 1e-9 * mechanism.scale


@pytest.mark.parametrize("kind", ["3-RRR", "5R"])
def test_revolute_joints_are_angles_within_one_turn(kind):
    joints = MECHANISMS[kind].inverse_kinematics(POSES[kind])
    assert np.all((joints > -math.pi) & (joints <= math.pi))


def test_the_3rpr_legs_are_pose_reference_legs():
    rng = np.random.default_rng(3)
    poses = np.column_stack([rng.uniform(-40, 40, (20, 2)), rng.uniform(-math.pi, math.pi, 20)])
    joints = PAPER_GEOMETRY.inverse_kinematics(poses)
    for pose, legs in zip(poses, joints[:, 0]):
        assert np.allclose(legs, pose_reference.legs_of(pose), rtol=1e-12)


def test_the_3rrr_branches_are_the_torus_reference_leg_angles():
    pose = POSES["3-RRR"]
    points = platform_points(pose)
    legs = DEFAULT_THREE_RRR.leg_joints(np.array(pose))
    for i in range(3):
        expected = sorted(float(test_rrr3.leg_angle(points[i], i, side)) for side in (1, -1))
        assert np.allclose(sorted(legs[i]), expected, rtol=0, atol=1e-12)


def test_the_3prr_branches_are_the_torus_reference_slider_values():
    pose = POSES["3-PRR"]
    points = platform_points(pose)
    legs = DEFAULT_THREE_PRR.leg_joints(np.array(pose))
    for i in range(3):
        expected = sorted(float(test_prr3.slider_value(points[i], i, side)) for side in (1, -1))
        assert np.allclose(sorted(legs[i]), expected, rtol=0, atol=1e-12)


def test_the_five_bar_working_modes_are_the_reference_circle_intersections():
    pose = np.array(POSES["5R"])
    for joints in DEFAULT_FIVE_BAR.inverse_kinematics(pose):
        exists, plus, minus = test_five_bar.reference_solutions(*joints)
        assert exists
        assert min(np.linalg.norm(plus - pose), np.linalg.norm(minus - pose)) < 1e-12


@pytest.mark.parametrize("kind", sorted(FAR))
def test_an_unreachable_pose_has_no_working_mode(kind):
    mechanism = MECHANISMS[kind]
    assert np.all(np.isnan(mechanism.leg_joints(np.array(FAR[kind]))))
    assert np.all(np.isnan(mechanism.inverse_kinematics(FAR[kind])))


def test_a_leg_out_of_reach_removes_only_the_modes_that_need_it():
    # B1 of the 3-RRR beyond l1 + l2 = 20 of A1, the other legs within reach.
    pose = (-21.0, 0.0, 0.0)
    points = platform_points(pose)
    reaches = np.linalg.norm(points - A, axis=-1)
    assert reaches[0] > RRR_L1 + RRR_L2
    assert np.all(np.abs(reaches[1:] - RRR_L2) < RRR_L1)
    legs = DEFAULT_THREE_RRR.leg_joints(np.array(pose))
    assert np.all(np.isnan(legs[0])) and np.all(np.isfinite(legs[1:]))
    assert np.all(np.isnan(DEFAULT_THREE_RRR.inverse_kinematics(pose)))


@pytest.mark.parametrize("kind", ["3-RRR", "5R"])
@pytest.mark.parametrize("offset", [0.0, 5e-324, 1e-310])
def test_a_point_on_a_revolute_joint_is_out_of_reach_without_a_warning(kind, offset):
    # |AB| = 0, or a distance whose cosine overflows: no angle reaches B
    # (the links differ in length), and nothing is raised or warned.
    pose = np.zeros(len(POSES[kind]))
    pose[1] = offset
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        legs = MECHANISMS[kind].leg_joints(pose)
    assert np.all(np.isnan(legs[0]))


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
def test_a_batch_of_poses_gives_each_pose_its_own_modes(kind):
    mechanism = MECHANISMS[kind]
    pose = np.array(POSES[kind])
    batch = np.stack([pose, pose * 1.01, pose])
    joints = mechanism.inverse_kinematics(batch)
    assert joints.shape == (3, MODE_COUNTS[kind], mechanism.n_joints)
    assert np.array_equal(joints[0], mechanism.inverse_kinematics(pose))
    assert np.array_equal(joints[1], mechanism.inverse_kinematics(pose * 1.01))


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
@pytest.mark.parametrize("bad", ["nan", "shape", "text"])
def test_malformed_poses_are_invalid_input(kind, bad):
    mechanism = MECHANISMS[kind]
    pose = list(POSES[kind])
    poses = {"nan": pose[:-1] + [math.nan], "shape": pose + [1.0], "text": ["x"] * len(pose)}
    with pytest.raises(InvalidInputError):
        mechanism.inverse_kinematics(poses[bad])


def test_a_leg_at_full_stretch_is_reached_on_one_elbow():
    # P of the five-bar straight above A1 at l1 + l2: leg 1 stretched.
    pose = np.array([0.0, FIVE_BAR_L1 + FIVE_BAR_L2])
    legs = DEFAULT_FIVE_BAR.leg_joints(pose)
    assert np.allclose(legs[0], math.pi / 2, rtol=0, atol=1e-6)
