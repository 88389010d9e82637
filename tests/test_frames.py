"""The TF frames of a mechanism sit where its geometry puts them: checked
against the platform points and elbows written here from the mechanism's
parameters (the 3-RPR's legs from A_i to B_i, the 3-RRR's proximal links
turned by the actuated angles), not through the project's kinematics.  Pure
message logic, no ROS graph."""

import math
import pathlib

import numpy as np
from builtin_interfaces.msg import Time
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_nodes.frames import PLATFORM_FRAME, frame_names, frame_transforms

CONFIG = pathlib.Path(__file__).resolve().parents[1] / "config"
STAMP = Time(sec=12, nanosec=34)


def _configuration(name):
    described = load_mechanism_file(CONFIG / name)
    mechanism = described.mechanism
    *joints, mode = described.default_home()
    count, poses = mechanism.solve(np.array([joints]))
    k = mechanism.mode_coordinate
    pose = min(poses[0, :count[0]], key=lambda p: abs(math.remainder(p[k] - mode, 2 * math.pi)))
    return mechanism, pose, np.array(joints)


def _platform_points(parameters, pose):
    """B1..B3 of the three-leg mechanisms' platform (their shared convention)."""
    x, y, alpha = pose
    d1, d3, beta = parameters["d1"], parameters["d3"], parameters["beta"]
    return np.array([[x, y], [x + d1 * math.cos(alpha), y + d1 * math.sin(alpha)],
                     [x + d3 * math.cos(alpha + beta), y + d3 * math.sin(alpha + beta)]])


def _by_child(transforms):
    out = {}
    for t in transforms:
        q = t.transform.rotation
        assert (q.x, q.y) == (0.0, 0.0) and t.transform.translation.z == 0.0
        assert math.isclose(q.z ** 2 + q.w ** 2, 1.0)
        out[t.child_frame_id] = (np.array([t.transform.translation.x, t.transform.translation.y]),
                                 2 * math.atan2(q.z, q.w))
    return out


def _same_angle(a, b):
    return abs(math.remainder(a - b, 2 * math.pi)) < 1e-9


def test_the_3rpr_legs_run_from_a_to_b_and_the_platform_is_at_b1():
    mechanism, pose, joints = _configuration("paper_3rpr.yaml")
    transforms = frame_transforms(mechanism, pose, joints, STAMP, "robot/")
    assert all(t.header.frame_id == "base" and t.header.stamp == STAMP for t in transforms)
    frames = _by_child(transforms)
    assert list(frames) == ["robot/leg1", "robot/leg2", "robot/leg3", "robot/platform"]
    parameters = mechanism.to_dict()
    points = _platform_points(parameters, pose)
    for i in range(3):
        base = np.array(parameters[f"a{i + 1}"])
        origin, yaw = frames[f"robot/leg{i + 1}"]
        np.testing.assert_allclose(origin, base, atol=1e-12)
        leg = points[i] - base
        # The leg's length is the actuated joint.
        assert math.isclose(np.hypot(*leg), joints[i], rel_tol=1e-9)
        assert _same_angle(yaw, math.atan2(leg[1], leg[0]))
    origin, yaw = frames["robot/platform"]
    np.testing.assert_allclose(origin, points[0], atol=1e-12)
    assert _same_angle(yaw, pose[2])


def test_the_3rrr_proximal_links_turn_by_the_actuated_angles():
    mechanism, pose, joints = _configuration("three_rrr.yaml")
    frames = _by_child(frame_transforms(mechanism, pose, joints, STAMP))
    assert list(frames) == frame_names(mechanism, pose, joints)
    parameters = mechanism.to_dict()
    points = _platform_points(parameters, pose)
    for i, theta in enumerate(joints):
        base = np.array(parameters[f"a{i + 1}"])
        elbow = base + parameters["l1"] * np.array([math.cos(theta), math.sin(theta)])
        origin, yaw = frames[f"proximal{i + 1}"]
        np.testing.assert_allclose(origin, base, atol=1e-12)
        assert _same_angle(yaw, theta)
        origin, yaw = frames[f"distal{i + 1}"]
        np.testing.assert_allclose(origin, elbow, atol=1e-9)
        distal = points[i] - elbow
        assert math.isclose(np.hypot(*distal), parameters["l2"], rel_tol=1e-9)
        assert _same_angle(yaw, math.atan2(distal[1], distal[0]))
    origin, yaw = frames[PLATFORM_FRAME]
    np.testing.assert_allclose(origin, points[0], atol=1e-12)
    assert _same_angle(yaw, pose[2])


def test_the_3prr_sliders_move_along_their_directions():
    mechanism, pose, joints = _configuration("three_prr.yaml")
    frames = _by_child(frame_transforms(mechanism, pose, joints, STAMP))
    parameters = mechanism.to_dict()
    points = _platform_points(parameters, pose)
    for i, stroke in enumerate(joints):
        gamma = parameters[f"gamma{i + 1}"]
        base = np.array(parameters[f"a{i + 1}"])
        slider = base + stroke * np.array([math.cos(gamma), math.sin(gamma)])
        np.testing.assert_allclose(frames[f"proximal{i + 1}"][0], base, atol=1e-12)
        origin, yaw = frames[f"distal{i + 1}"]
        np.testing.assert_allclose(origin, slider, atol=1e-9)
        distal = points[i] - slider
        assert math.isclose(np.hypot(*distal), parameters["l"], rel_tol=1e-9)
        assert _same_angle(yaw, math.atan2(distal[1], distal[0]))
    np.testing.assert_allclose(frames[PLATFORM_FRAME][0], points[0], atol=1e-12)


def test_the_five_bar_links_meet_at_its_end_point():
    mechanism, pose, joints = _configuration("five_bar.yaml")
    frames = _by_child(frame_transforms(mechanism, pose, joints, STAMP))
    parameters = mechanism.to_dict()
    for i, theta in enumerate(joints):
        origin, yaw = frames[f"proximal{i + 1}"]
        assert _same_angle(yaw, theta)
        elbow = origin + parameters["l1"] * np.array([math.cos(theta), math.sin(theta)])
        origin, yaw = frames[f"distal{i + 1}"]
        np.testing.assert_allclose(origin, elbow, atol=1e-9)
        distal = pose[:2] - elbow
        assert math.isclose(np.hypot(*distal), parameters["l2"], rel_tol=1e-9)
        assert _same_angle(yaw, math.atan2(distal[1], distal[0]))
    # The base joints are d apart.
    np.testing.assert_allclose(np.hypot(*(frames["proximal2"][0] - frames["proximal1"][0])),
                               parameters["d"], rtol=1e-12)
    origin, yaw = frames[PLATFORM_FRAME]
    np.testing.assert_allclose(origin, pose[:2], atol=1e-12)
    assert yaw == 0.0
