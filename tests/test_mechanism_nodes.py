"""The nodes on mechanisms other than the paper's 3-RPR, each given by its
mechanism file: the builder builds the 3-RRR's slice th1 = 0, the planner
plans its non-singular assembly-mode change (checked by a continuation of
the test's own) and the driver executes it; on the five-bar the planner
refuses an assembly-mode change as FEASIBILITY_OTHER_ASPECT; on a user's
3-RRR whose box middle cannot be assembled the nodes start from its file
alone, and the docs' script finds, plans and executes an assembly-mode
change on it from a process of its own.  Real rclpy and
Fast DDS, the nodes in this process, spun by one executor thread, and a
PlannerClient spinning itself in the test's thread."""

import math
import os
import pathlib
import re
import subprocess
import sys
import time

import numpy as np
import pytest
import yaml
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import AssemblyMode, Configuration
from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.planner import PlannerNode
from rpr3_gwr_nodes.profiles import SENSOR_QOS
from rpr3_gwr_nodes.roadmap_builder import RoadmapBuilder
from rpr3_gwr_nodes.rpr3_driver import Rpr3Driver
from sensor_msgs.msg import JointState
from visualization_msgs.msg import MarkerArray

from moving_base_reference import MovingBaseReference, wrap

from spun_nodes import SpunNodes

CONFIG = pathlib.Path(__file__).resolve().parents[1] / "config"
THREE_RRR, FIVE_BAR = CONFIG / "three_rrr.yaml", CONFIG / "five_bar.yaml"
TIMEOUT = 60.0
# Two assembly modes of the same joints, one aspect, joined through the
# slice's two-solution region.
TH = (0.0, 1.2043, 2.2515)
MODE_A, MODE_B = 0.6526, 2.1165
TH_NAMES = ["th1", "th2", "th3"]
# Both assembly modes of the five-bar's th = (3.1, 2.5), by the circle
# intersection (their y is the mode coordinate): opposite aspects.
FIVE_BAR_TH, PLUS_Y, MINUS_Y = (3.1, 2.5), 0.11622901, -0.05862426

# The 3-RRR written again from its file, not from the package: elbows
# C_i = A_i + l1 (cos th_i, sin th_i), distal links l2.
_RRR = yaml.safe_load(THREE_RRR.read_text())["mechanism"]
_A = np.array([_RRR["a1"], _RRR["a2"], _RRR["a3"]], dtype=float)


def _elbows(th):
    th = np.asarray(th, dtype=float)
    return _A + _RRR["l1"] * np.stack([np.cos(th), np.sin(th)], -1)


# The torus direct kinematics is not used here: no closed form is needed.
REFERENCE = MovingBaseReference(_elbows, None, _RRR["l2"], _RRR["d1"], _RRR["d3"],
                                _RRR["beta"], angular=True)


def _densified(joints, largest):
    """The joint path with points inserted so that no joint changes more than
    ``largest`` between two, and the indices of the original points."""
    dense, waypoints = [joints[0]], [0]
    for a, b in zip(joints[:-1], joints[1:]):
        pieces = max(1, math.ceil(np.max(np.abs(b - a)) / largest))
        dense += [a + (b - a) * k / pieces for k in range(1, pieces + 1)]
        waypoints.append(len(dense) - 1)
    return np.array(dense), waypoints


class Suite(SpunNodes):
    """Builder, planner and (optionally) driver on one mechanism file, in a
    namespace of their own, a listener of the driver's streams and a client."""

    def __init__(self, context, path, namespace, builder_parameters=(), driver=False):
        mechanism = [Parameter("mechanism_file", value=str(path))]
        self.builder = RoadmapBuilder(context=context, namespace=namespace,
                                      parameter_overrides=mechanism + list(builder_parameters))
        self.planner = PlannerNode(context=context, namespace=namespace, parameter_overrides=[
            *mechanism, Parameter("plan_workers", value=0)])
        self.nodes = [self.builder, self.planner]
        if driver:
            self.driver = Rpr3Driver(context=context, namespace=namespace, parameter_overrides=[
                *mechanism, Parameter("time_scale", value=50.0)])
            self.nodes.append(self.driver)
        listener = Node("mechanism_test_listener", context=context, namespace=namespace)
        self.nodes.append(listener)
        self.joint_states, self.markers = [], []
        listener.create_subscription(JointState, "joint_states", self.joint_states.append,
                                     SENSOR_QOS)
        listener.create_subscription(MarkerArray, "mechanism_markers", self.markers.append,
                                     SENSOR_QOS)
        super().__init__(context, self.nodes, "mechanism_test_client", namespace=namespace)
        assert self.planner.ready.wait(TIMEOUT), "the planner got no roadmap"
        self.client.wait_until_ready(timeout_sec=TIMEOUT)

    def plan(self, start, goal, smooth=False, **options):
        return self.client.plan(start, goal, skip_smoothing=not smooth, timeout_sec=TIMEOUT,
                                **options)


@pytest.fixture
def three_rrr(ros_context):
    suite = Suite(ros_context, THREE_RRR, "three_rrr", driver=True)
    try:
        yield suite
    finally:
        suite.close()


def _rrr(mode):
    return Configuration(joint_names=TH_NAMES, positions=list(TH), mode=mode)


@pytest.mark.slow
def test_the_three_rrr_changes_assembly_mode_through_the_nodes(three_rrr):
    roadmap = three_rrr.builder.roadmap
    assert roadmap.mechanism.kind == "3-RRR" and roadmap.grid.fixed == ((0, 0.0),)
    response = three_rrr.plan(_rrr(MODE_A), _rrr(MODE_B), smooth=True, max_velocity=1.0,
                              max_acceleration=2.0)
    assert response.success, response.error_msg
    assert response.feasibility == PlanPath.Response.FEASIBILITY_CONNECTED
    assert list(response.roadmap_fixed_joints) == ["th1"]
    assert list(response.roadmap_fixed_values) == [0.0]
    trajectory = response.trajectory
    assert list(trajectory.joint_names) == TH_NAMES
    assert all(list(p.names) == ["x", "y", "alpha"] for p in response.poses)
    joints = np.array([p.positions for p in trajectory.points])
    poses = np.array([p.values for p in response.poses])
    np.testing.assert_allclose(joints[0], TH, rtol=0, atol=1e-9)
    np.testing.assert_allclose(wrap(joints[-1] - TH), 0.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(joints[:, 0], 0.0, rtol=0, atol=1e-12)  # the slice's th1
    # The endpoints are the two assembly modes asked for, of one aspect.
    assert abs(wrap(poses[0, 2] - MODE_A)) < 1e-3 and abs(wrap(poses[-1, 2] - MODE_B)) < 1e-3
    start_residual = REFERENCE.residual(poses[0], joints[0])
    assert np.max(np.abs(start_residual)) < 1e-8 * REFERENCE.scale**2
    sign = np.sign(REFERENCE.margin(poses[0], joints[0]))
    assert sign == np.sign(REFERENCE.margin(poses[-1], joints[-1]))
    # The test's own continuation follows the joints: on the constraints,
    # one sign of det Jx above the planner's margin threshold, no jump to
    # another solution, through the planned poses to the goal's mode.
    dense, waypoints = _densified(joints, 0.05)
    followed, vertices = REFERENCE.follow(poses[0], dense, steps=10)
    before = (joints[0], poses[0])
    for at, pose, move in followed:
        assert np.max(np.abs(REFERENCE.residual(pose, at))) < 1e-9 * REFERENCE.scale**2
        assert np.sign(REFERENCE.margin(pose, at)) == sign
        assert abs(REFERENCE.margin(pose, at)) > 1e-3
        if move > 0.1:
            # Near a fold the pose moves fast: fifty times finer steps must
            # arrive at the same pose, else Newton jumped to another solution.
            _, finer = REFERENCE.follow(before[1], np.array([before[0], at]), steps=50)
            assert np.max(np.abs(finer[-1] - pose)) < 1e-6
        before = (at, pose)
    for vertex, planned in zip([vertices[k] for k in waypoints], poses):
        assert np.max(np.abs(np.r_[vertex[:2] - planned[:2], wrap(vertex[2] - planned[2])])) \
            < 1e-6
    # The driver executes it: from the first mode to the second.
    reset = three_rrr.client.reset_driver(_rrr(MODE_A), timeout_sec=TIMEOUT)
    assert reset.success, reset.error_msg
    result = three_rrr.client.execute(trajectory, timeout_sec=TIMEOUT).result
    assert result.error_code == ExecuteTrajectory.Result.SUCCESS, result.error_msg
    assert abs(wrap(result.final_pose.values[2] - MODE_B)) < 1e-3
    assert result.min_singularity_margin > 1e-3
    # Its joint states carry the 3-RRR's joints; its markers draw each leg
    # from its base joint through its elbow to the platform.
    # Two of each after the result: both drawn at rest.
    streams = three_rrr.joint_states, three_rrr.markers
    wanted = [len(stream) + 2 for stream in streams]
    deadline = time.monotonic() + 10.0
    while any(len(s) < n for s, n in zip(streams, wanted)) and time.monotonic() < deadline:
        time.sleep(0.05)
    state = three_rrr.joint_states[-1]
    assert list(state.name) == TH_NAMES + [f"{joint}{i}" for joint in ("elbow", "platform")
                                           for i in (1, 2, 3)]
    legs = {m.ns: m for m in three_rrr.markers[-1].markers}["legs"]
    segments = np.array([[p.x, p.y] for p in legs.points]).reshape(3, 2, 2, 2)
    # At rest, the elbows the joint states give are the angles between the
    # drawn proximal and distal links.
    direction = segments[:, :, 1] - segments[:, :, 0]
    angle = np.arctan2(direction[..., 1], direction[..., 0])
    np.testing.assert_allclose(wrap(np.array(state.position[3:6]) - (angle[:, 1] - angle[:, 0])),
                               0.0, atol=1e-9)
    np.testing.assert_allclose(segments[:, 0, 0], _A)
    np.testing.assert_allclose(segments[:, 0, 1], segments[:, 1, 0])
    np.testing.assert_allclose(np.linalg.norm(segments[:, 0, 1] - _A, axis=1), _RRR["l1"])
    np.testing.assert_allclose(np.linalg.norm(segments[:, 1, 1] - segments[:, 1, 0], axis=1),
                               _RRR["l2"])


def test_the_three_rrr_planner_refuses_the_joints_of_another_mechanism(three_rrr):
    legs = Configuration(joint_names=["rho1", "rho2", "rho3"], positions=list(TH), mode=MODE_A)
    response = three_rrr.plan(legs, _rrr(MODE_B))
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg
    assert "th1" in response.error_msg
    off_slice = Configuration(positions=[0.5, *TH[1:]], mode=MODE_A)
    response = three_rrr.plan(off_slice, _rrr(MODE_B))
    assert response.error_code == PlanPath.Response.ERROR_FIXED_JOINT_MISMATCH, response.error_msg
    assert response.error_msg.startswith("th1 = 0.5 but the roadmap is built for th1 = 0")


def test_the_five_bar_refuses_an_assembly_mode_change_as_other_aspect(ros_context):
    # Its 2-D roadmap is the whole torus of its two joints: full.
    suite = Suite(ros_context, FIVE_BAR, "five_bar", [Parameter("full", value=True)])
    try:
        assert suite.planner.planner.roadmap.grid.shape == (120, 120)
        plus = Configuration(positions=list(FIVE_BAR_TH), mode=PLUS_Y)
        minus = Configuration(positions=list(FIVE_BAR_TH), mode=MINUS_Y)
        for feasibility_only in (True, False):
            response = suite.plan(plus, minus, feasibility_only=feasibility_only)
            assert response.error_code == PlanPath.Response.ERROR_INFEASIBLE, response.error_msg
            assert response.feasibility == PlanPath.Response.FEASIBILITY_OTHER_ASPECT
            assert not response.trajectory.points
        # The same mode across the seam of th1 is planned.
        across = Configuration(positions=[-3.1, 2.5], mode=0.10985067)
        response = suite.plan(plus, across)
        assert response.success, response.error_msg
        assert list(response.trajectory.joint_names) == ["th1", "th2"]
        assert not response.roadmap_fixed_joints
        assert math.isclose(response.trajectory.points[0].positions[0], 3.1, abs_tol=1e-9)
    finally:
        suite.close()


# A user's 3-RRR (base side 30, platform side 8, links 10 and 10) whose box
# middle th = (0, 0, 0) cannot be assembled, in a file without a home.
USER_RRR = {"mechanism": {"kind": "3-RRR", "a1": [0.0, 0.0], "a2": [30.0, 0.0],
                          "a3": [15.0, 15.0 * math.sqrt(3)], "d1": 8.0, "d3": 8.0,
                          "beta": math.pi / 3, "l1": 10.0, "l2": 10.0},
            "joints": [{"name": name, "periodic": True, "cells": 120} for name in TH_NAMES]}


def test_the_nodes_start_from_a_file_alone_where_the_box_middle_cannot_be_assembled(
        ros_context, tmp_path):
    path = tmp_path / "user_rrr.yaml"
    path.write_text(yaml.safe_dump(USER_RRR))
    home = load_mechanism_file(str(path)).default_home()
    suite = Suite(ros_context, path, "user_rrr", driver=True)
    try:
        assert suite.planner.planner.roadmap.grid.fixed == ((0, home[0]),)
        deadline = time.monotonic() + 10.0
        while not suite.joint_states and time.monotonic() < deadline:
            time.sleep(0.05)
        np.testing.assert_allclose(suite.joint_states[-1].position[:3], home[:3], atol=1e-12)
        at_home = Configuration(joint_names=TH_NAMES, positions=list(home[:3]), mode=home[3])
        response = suite.plan(at_home, at_home, feasibility_only=True)
        assert response.success, response.error_msg
    finally:
        suite.close()


OWN_ROBOT = pathlib.Path(__file__).resolve().parents[1] / "docs" / "howto" / "own_robot"
OWN_JOINTS = (0.2617993877991494, -2.670353755551324, -1.6755160819145565)


@pytest.mark.slow
def test_the_docs_own_robot_script_changes_the_assembly_mode_it_finds(ros_context):
    # The how-to's recipe as a user runs it: the script in a process of its
    # own, the nodes on the user's 3-RRR file alone.
    path = OWN_ROBOT / "user_3rrr.yaml"
    suite = Suite(ros_context, path, "own_robot", driver=True)
    try:
        done = subprocess.run(
            [sys.executable, str(OWN_ROBOT / "mode_change.py"), str(path),
             "--joints", *map(repr, OWN_JOINTS), "--ros-args", "-r", "__ns:=/own_robot"],
            capture_output=True, text=True, timeout=2 * TIMEOUT, env=os.environ.copy())
        assert done.returncode == 0, done.stdout + done.stderr
        assert "executed: error_code 0 (success)" in done.stdout
        planned = re.search(r"planned \d+ points from mode (\S+) to (\S+)", done.stdout)
        start, goal = float(planned[1]), float(planned[2])
        assert abs(wrap(goal - start)) > 0.1
        # The driver ends at the joints asked for, on the other assembly
        # mode: the loop closes there by the file's own dimensions, on the
        # side of the singularity the start is on.
        robot = yaml.safe_load(path.read_text())["mechanism"]
        bases = np.array([robot["a1"], robot["a2"], robot["a3"]], dtype=float)
        reference = MovingBaseReference(
            lambda th: bases + robot["l1"] * np.stack([np.cos(th), np.sin(th)], -1), None,
            robot["l2"], robot["d1"], robot["d3"], math.radians(robot["beta_deg"]),
            angular=True)
        joints, pose = suite.driver.rho.copy(), suite.driver.pose.copy()
        np.testing.assert_allclose(wrap(joints - OWN_JOINTS), 0.0, atol=1e-6)
        assert abs(wrap(pose[2] - goal)) < 1e-3
        assert np.max(np.abs(reference.residual(pose, joints))) < 1e-6 * reference.scale**2
        start_pose = suite.plan(_own(start), _own(goal)).poses[0].values
        assert np.sign(reference.margin(start_pose, np.array(OWN_JOINTS))) == np.sign(
            reference.margin(pose, joints))
    finally:
        suite.close()


def _own(mode):
    return Configuration(joint_names=TH_NAMES, positions=list(OWN_JOINTS), mode=mode)


# Two solutions of th = (1.5, 165 deg, -87 deg) in one aspect, joined along
# a strip that narrows below the default grid's cell.
THIN_TH = (1.5, math.radians(165.0), math.radians(-87.0))
THIN_MODES = (math.radians(-122.510593), math.radians(-33.654195))


@pytest.mark.slow
@pytest.mark.parametrize("thin_refinement, connected", [(4, True), (0, False)])
def test_the_builder_refines_a_slice_s_thin_regions_unless_told_not_to(ros_context,
                                                                     thin_refinement,
                                                                     connected):
    parameters = [Parameter("fixed_value", value=THIN_TH[0]),
                  Parameter("thin_refinement", value=thin_refinement)]
    suite = Suite(ros_context, THREE_RRR, "thin_rrr", builder_parameters=parameters)
    try:
        assert (suite.builder.roadmap.grid.size > 120 * 120) == connected
        ends = [Configuration(joint_names=TH_NAMES, positions=list(THIN_TH), mode=mode)
                for mode in THIN_MODES]
        response = suite.plan(*ends)
        if connected:
            assert response.success, response.error_msg
            assert response.feasibility == PlanPath.Response.FEASIBILITY_CONNECTED
            # The reference's det Jx keeps its sign along the planned joints.
            joints = np.array([p.positions for p in response.trajectory.points])
            poses = np.array([p.values for p in response.poses])
            followed, _ = REFERENCE.follow(poses[0], joints, steps=8)
            sign = np.sign(REFERENCE.margin(poses[0], joints[0]))
            assert all(np.sign(REFERENCE.margin(pose, at)) == sign for at, pose, _ in followed)
        else:
            # The grid alone cannot tell: the answer is not "no path".
            assert response.error_code == PlanPath.Response.ERROR_UNDECIDED, response.error_msg
            assert response.feasibility == PlanPath.Response.FEASIBILITY_UNDECIDED
            assert list(response.undecided_patches) and "thin_refinement" in response.error_msg
            assert list(response.undecided_steps) == pytest.approx([math.radians(3.0)] * 2)
            assert set(response.undecided_patches) <= set(
                suite.builder.roadmap.segmentation.patches)
            modes = suite.client.assembly_modes(list(THIN_TH), THIN_MODES[0],
                                                timeout_sec=TIMEOUT).modes
            goal = min(modes, key=lambda m: abs(wrap(m.configuration.mode - THIN_MODES[1])))
            assert goal.feasibility == AssemblyMode.FEASIBILITY_UNDECIDED
        refused = suite.builder.set_parameters([Parameter("thin_refinement", value=1)])[0]
        assert not refused.successful and "thin_refinement" in refused.reason
    finally:
        suite.close()
