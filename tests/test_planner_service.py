"""The planner node under hostile requests: every request gets an answer with
a code from the list, every success is a sound trajectory (or, from the
assembly modes service, the joints' modes as the reference finds them), the
node keeps serving.  Real rclpy and Fast DDS: a planner node and a publisher of the
paper's roadmap messages, spun by one executor thread, and a PlannerClient
spinning itself in the test's thread."""

import collections
import math
import os
import signal
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.paper import PAPER_GEOMETRY, PAPER_GRID
from rpr3_gwr_core.planning import Planner, PlanOptions, PlanStatus
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_msgs.msg import (AssemblyMode, Configuration, JointLimits, NSolutionField,
                               WorkspaceRoadmap)
from rpr3_gwr_msgs.srv import AssemblyModes, InverseKinematics, PlanPath
from rpr3_gwr_nodes.client import platform_pose
from rpr3_gwr_nodes.conversions import roadmap_to_msgs
from rpr3_gwr_nodes.planner import PLAN_STATUS, PlannerNode
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from std_msgs.msg import Header
from visualization_msgs.msg import MarkerArray

from pose_reference import follow, legs_of, margin_of
from process_tree import children, wait_for_children

from spun_nodes import SpunNodes

D = math.radians
Q1, Q2 = (17.0, 12.0, 18.0, D(122.82)), (17.0, 10.0, 25.0, D(-24.24))
MODE_A, MODE_B = (17.0, 20.0, 25.0, D(29.47)), (17.0, 20.0, 25.0, D(96.13))
TIMEOUT = 30.0
CODES = {getattr(PlanPath.Response, name): name for name in dir(PlanPath.Response)
         if name.startswith("ERROR_")}
FUZZ_REQUESTS = 500


NAMES = ["rho1", "rho2", "rho3"]


def _configuration(values, names=()):
    """Joints (in the order of ``names``, else the 3-RPR's) then alpha."""
    return Configuration(joint_names=list(names), positions=list(values[:-1]), mode=values[-1])


def _joints(configuration):
    """The legs of a valid configuration message, in the 3-RPR's order."""
    if not configuration.joint_names:
        return list(configuration.positions)
    by_name = dict(zip(configuration.joint_names, configuration.positions))
    return [by_name[name] for name in NAMES]


class PlannerUnderTest(SpunNodes):
    """A planner node fed the paper's roadmap messages by a feeder node that
    also listens to its path markers, and a client."""

    def __init__(self, context, namespace="", **planner_options):
        self.stamp = Header(frame_id="rpr3_base")
        self.stamp.stamp.sec, self.stamp.stamp.nanosec = 1_700_000_000, 123
        self.roadmap = build_roadmap(PAPER_GEOMETRY, PAPER_GRID)
        field_msg, roadmap_msg = roadmap_to_msgs(self.roadmap, self.stamp)
        self.planner = PlannerNode(context=context, namespace=namespace, **planner_options)
        self.feeder = Node("roadmap_feeder", context=context, namespace=namespace)
        self.feeder.create_publisher(NSolutionField, "field", LATCHED_QOS).publish(field_msg)
        self.feeder.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS).publish(roadmap_msg)
        self.path_markers = []
        self.feeder.create_subscription(MarkerArray, "planned_path_markers",
                                        self.path_markers.append, 10)
        super().__init__(context, (self.planner, self.feeder), "planner_test_client",
                         namespace=namespace)
        assert self.planner.ready.wait(60.0), "the planner got no roadmap"
        assert self.planner.indexed.wait(120.0), "the planner's workers did not start"
        self.client.wait_until_ready(timeout_sec=TIMEOUT)

    def call(self, request, timeout=TIMEOUT):
        """The planner's answer to ``request``, every field of it passed on."""
        start, goal = (getattr(request, f"{end}_pose") if getattr(request, f"{end}_is_pose")
                       else getattr(request, end) for end in ("start", "goal"))
        options = {name: getattr(request, name) for name in request.get_fields_and_field_types()
                   if not name.startswith(("start", "goal")) or name.endswith("working_mode")}
        return self.client.plan(start, goal, timeout_sec=timeout, **options)

    def plan(self, start, goal, **options):
        """Plan between configurations (None: the end is a pose of ``options``)."""
        ends = {name: _configuration(end) for name, end in (("start", start), ("goal", goal))
                if end is not None}
        return self.call(PlanPath.Request(**ends, **options))

    def default_limits(self):
        """The limits of each joint that time requests without their own:
        the planner's ``joint_limits.<joint>.*`` parameters where nonzero,
        else its defaults; arrays of velocities and accelerations in the
        3-RPR's joint order."""
        return tuple(np.array([self.planner.get_parameter(f"joint_limits.{joint}.{kind}").value
                               or self.planner.get_parameter(f"default_{kind}").value
                               for joint in NAMES])
                     for kind in ("max_velocity", "max_acceleration"))


@pytest.fixture(scope="module")
def service(module_context):
    running = PlannerUnderTest(module_context)
    try:
        yield running
    finally:
        running.close()


def _seconds(point):
    return point.time_from_start.sec + point.time_from_start.nanosec * 1e-9


def check_sound(request, response, stamp, default_limits):
    """The contract of every answer (the fuzz test's assertions); requests
    without limits for all joints are timed with ``default_limits`` (per
    joint, :meth:`PlannerUnderTest.default_limits`), and the limits of single
    joints replace those where nonzero."""
    assert response.error_code in CODES, response.error_code
    if response.error_code != PlanPath.Response.ERROR_NO_ROADMAP:
        assert response.roadmap_stamp == stamp.stamp
        assert list(response.roadmap_fixed_joints) == ["rho1"]
        assert list(response.roadmap_fixed_values) == [17.0]
    if not response.success:
        assert response.error_code != PlanPath.Response.ERROR_NONE and response.error_msg
        assert not response.trajectory.points
        assert response.plan_status == PlanPath.Response.PLAN_STATUS_NONE
        return
    assert response.error_code == PlanPath.Response.ERROR_NONE and not response.error_msg
    points = response.trajectory.points
    if request.feasibility_only:
        assert not points and response.global_paths
        assert response.plan_status == PlanPath.Response.PLAN_STATUS_NONE
        return
    # Approximate exactly when the time limit skipped a step.
    assert response.plan_status == (
        PlanPath.Response.PLAN_STATUS_APPROXIMATE_SOLUTION if response.skipped_steps
        else PlanPath.Response.PLAN_STATUS_EXACT_SOLUTION)
    assert set(response.skipped_steps) <= {"pulling taut", "rounding"}
    assert len(points) >= 1 and len(response.poses) == len(points)
    numbers = np.array([list(p.positions) + list(p.velocities) + list(p.accelerations)
                        for p in points])
    assert numbers.shape[1] == 9 and np.all(np.isfinite(numbers))
    assert all(list(p.names) == ["x", "y", "alpha"] for p in response.poses)
    assert all(math.isfinite(v) for p in response.poses for v in p.values)
    assert list(response.trajectory.joint_names) == NAMES
    nanoseconds = [p.time_from_start.sec * 10**9 + p.time_from_start.nanosec for p in points]
    assert nanoseconds[0] == 0 and all(b > a for a, b in zip(nanoseconds, nanoseconds[1:]))
    for end, point in (("start", points[0]), ("goal", points[-1])):
        if getattr(request, f"{end}_is_pose"):
            pose = getattr(request, f"{end}_pose").pose
            # The legs that place the pose, to the validator's continuation.
            joints = legs_of((pose.position.x, pose.position.y,
                              2 * math.atan2(pose.orientation.z, pose.orientation.w)))
            np.testing.assert_allclose(point.positions, joints, rtol=0, atol=1e-6)
            assert getattr(response, f"{end}_working_mode") == "+++"
        else:
            np.testing.assert_allclose(point.positions, _joints(getattr(request, end)), rtol=0,
                                       atol=1e-9)
    # A second, independent continuation, in pose space, follows the
    # trajectory from the pose it starts at to the one it ends at, keeping
    # one sign of det Jx and the planner's margin threshold.
    poses = np.array([list(p.values) for p in response.poses])
    np.testing.assert_allclose(legs_of(poses[0]), numbers[0, :3], rtol=0, atol=1e-7)
    followed = follow(numbers[:, :3], poses[0], 1e-3 * (1 - 1e-3))
    assert followed["ok"], followed["why"]
    np.testing.assert_allclose(followed["pose"][:2], poses[-1, :2], rtol=0, atol=1e-6)
    assert abs(math.remainder(followed["pose"][2] - poses[-1, 2], 2 * math.pi)) < 1e-6
    np.testing.assert_allclose(legs_of(poses[-1]), numbers[-1, :3], rtol=0, atol=1e-7)
    # The limits hold between the points, for a driver moving each joint
    # linearly from point to point: the joint change over each interval, and
    # the change of the point velocities over it.
    max_velocity, max_acceleration = (np.array(v, dtype=float) for v in default_limits)
    if request.max_velocity > 0:
        max_velocity[:], max_acceleration[:] = request.max_velocity, request.max_acceleration
    for entry in request.joint_limits:
        joint = NAMES.index(entry.joint_name)
        max_velocity[joint] = entry.max_velocity or max_velocity[joint]
        max_acceleration[joint] = entry.max_acceleration or max_acceleration[joint]
    interval = np.diff(nanoseconds)[:, None] * 1e-9
    rounding = 1 + 1e-9
    assert np.all(np.abs(np.diff(numbers[:, :3], axis=0)) / interval
                  <= max_velocity * rounding)
    assert np.all(np.abs(np.diff(numbers[:, 3:6], axis=0)) / interval
                  <= max_acceleration * rounding)


# --- regression tests, one per defect -----------------------------------------------------------

@pytest.mark.parametrize("limit", [5e-324, 1e-300])
def test_tiny_limits_are_an_invalid_input_and_the_node_still_serves(service, limit):
    response = service.plan(Q1, Q2, max_velocity=limit, max_acceleration=limit)
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg
    assert service.plan(Q1, Q2).success


def test_a_plan_given_time_is_an_exact_solution_and_every_status_has_a_constant(service):
    response = service.plan(Q1, Q2)
    assert response.success, response.error_msg
    assert response.plan_status == PlanPath.Response.PLAN_STATUS_EXACT_SOLUTION
    assert list(response.skipped_steps) == []
    assert set(PLAN_STATUS) == set(PlanStatus)
    assert len(set(PLAN_STATUS.values())) == len(PlanStatus)


def test_a_passed_time_limit_is_a_timeout_and_the_node_serves_on(service):
    response = service.plan(Q1, Q2, time_limit=1e-9)
    assert response.error_code == PlanPath.Response.ERROR_TIMEOUT, response.error_msg
    assert "time limit" in response.error_msg and not response.trajectory.points
    assert service.plan(Q1, Q2).success


def test_a_one_millisecond_limit_is_answered_with_a_plan_or_a_timeout(service):
    """Each answer comes within the limit plus the service's own overhead:
    a plan of what was found by then, or ERROR_TIMEOUT."""
    for _ in range(10):
        request = PlanPath.Request(start=_configuration(Q1), goal=_configuration(Q2),
                                   time_limit=1e-3)
        response = service.call(request)
        assert response.error_code in (PlanPath.Response.ERROR_NONE,
                                       PlanPath.Response.ERROR_TIMEOUT), response.error_msg
        check_sound(request, response, service.stamp, service.default_limits())


@pytest.mark.parametrize("limit", [-1.0, math.nan, math.inf, -math.inf])
def test_a_time_limit_that_is_no_duration_is_an_invalid_input(service, limit):
    response = service.plan(Q1, Q2, time_limit=limit)
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg
    assert "time_limit" in response.error_msg


@pytest.mark.parametrize("limit", [1e-9, 1e-12, 1e100, 1e308])
def test_limits_beyond_what_a_duration_holds_are_refused(service, limit):
    response = service.plan(Q1, Q2, max_velocity=limit, max_acceleration=limit)
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg
    assert "Duration" in response.error_msg or "ns" in response.error_msg \
        or "floating point" in response.error_msg


def test_a_huge_leg_is_out_of_the_grid(service):
    response = service.plan((17.0, 1e308, 18.0, 0.0), Q2)
    assert response.error_code == PlanPath.Response.ERROR_OUT_OF_GRID, response.error_msg


def test_one_limit_alone_asks_for_both(service):
    response = service.plan(Q1, Q2, max_velocity=1.0)
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT
    assert "give both" in response.error_msg


def test_a_huge_alpha_is_not_reported_as_infinity(service):
    response = service.plan((17.0, 12.0, 18.0, 1e308), Q2)
    assert response.error_code == PlanPath.Response.ERROR_NO_ASSEMBLY_MODE
    assert "inf" not in response.error_msg


def test_no_limits_take_the_default_limits_as_the_interface_says(service):
    response = service.plan(Q1, Q2)
    assert response.success, response.error_msg
    points = response.trajectory.points
    assert _seconds(points[-1]) > 0
    speed = max(abs(v) for p in points for v in p.velocities)
    assert 0 < speed <= service.planner.get_parameter("default_max_velocity").value + 1e-9


def test_limits_of_single_joints_hold_each_for_its_joint(service):
    request = PlanPath.Request(start=_configuration(Q1), goal=_configuration(Q2),
                               max_velocity=2.0, max_acceleration=4.0, joint_limits=[
                                   JointLimits(joint_name="rho3", max_velocity=0.25),
                                   JointLimits(joint_name="rho2", max_acceleration=0.5)])
    response = service.call(request)
    assert response.success, response.error_msg
    check_sound(request, response, service.stamp, service.default_limits())
    fast = service.plan(Q1, Q2, max_velocity=2.0, max_acceleration=4.0)
    assert _seconds(response.trajectory.points[-1]) > _seconds(fast.trajectory.points[-1])


def test_the_joint_limit_parameters_time_requests_without_limits(service):
    node = service.planner
    try:
        assert not node.set_parameters([Parameter("joint_limits.rho2.max_velocity",
                                                  value=-1.0)])[0].successful
        assert node.set_parameters([Parameter("joint_limits.rho2.max_velocity",
                                              value=0.125)])[0].successful
        request = PlanPath.Request(start=_configuration(Q1), goal=_configuration(Q2))
        response = service.call(request)
        assert response.success, response.error_msg
        check_sound(request, response, service.stamp, service.default_limits())
        # rho2 moves 2 at most 0.125 a second.
        assert _seconds(response.trajectory.points[-1]) >= 2 / 0.125
    finally:
        node.set_parameters([Parameter("joint_limits.rho2.max_velocity", value=0.0)])


@pytest.mark.parametrize("entries", [[JointLimits(joint_name="th1", max_velocity=1.0)],
                                     [JointLimits(joint_name="rho2", max_velocity=1.0)] * 2,
                                     [JointLimits(joint_name="rho2", max_velocity=math.nan)],
                                     [JointLimits(joint_name="rho2", max_acceleration=-1.0)]])
def test_limits_of_unknown_repeated_or_bad_joints_are_an_invalid_input(service, entries):
    response = service.plan(Q1, Q2, joint_limits=entries)
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg
    assert "joint_limits" in response.error_msg


# The paper's first example as poses: B1 [length unit] and alpha [rad] of the
# legs (17, 12, 18) and (17, 10, 25).
START_POSE = (14.2844098014, -9.21713820156, D(122.818069928))
GOAL_POSE = (0.329281929849, 16.9968106835, D(-24.2435688728))


def test_ends_given_as_poses_plan_between_the_legs_that_place_them(service):
    request = PlanPath.Request(start_is_pose=True, start_pose=platform_pose(*START_POSE),
                               goal_is_pose=True, goal_pose=platform_pose(*GOAL_POSE))
    response = service.call(request)
    assert response.success, response.error_msg
    # The independent continuation follows it, within the default limits.
    check_sound(request, response, service.stamp, service.default_limits())
    # The 3-RPR has one working mode.
    assert (response.start_working_mode, response.goal_working_mode) == ("+++", "+++")
    points = response.trajectory.points
    np.testing.assert_allclose(points[0].positions, legs_of(START_POSE), atol=1e-6)
    np.testing.assert_allclose(points[-1].positions, legs_of(GOAL_POSE), atol=1e-6)
    np.testing.assert_allclose(response.poses[-1].values[:2], GOAL_POSE[:2], atol=1e-6)
    joints = service.plan(Q1, Q2)
    assert joints.success and not joints.start_working_mode


def test_inverse_kinematics_gives_the_legs_of_a_pose_and_its_patch(service):
    response = service.client.inverse_kinematics(platform_pose(*START_POSE))
    assert response.success, response.error_msg
    (mode,) = response.modes
    assert mode.working_mode == "+++" and mode.in_box and mode.on_slice and mode.located
    np.testing.assert_allclose(mode.configuration.positions, legs_of(START_POSE), atol=1e-9)
    assert abs(math.remainder(mode.configuration.mode - START_POSE[2], 2 * math.pi)) < 1e-12
    assert mode.aspect == np.sign(margin_of(START_POSE)) == np.sign(mode.signed_margin)
    off_slice = service.client.inverse_kinematics(platform_pose(5.0, 5.0, 0.0))
    assert off_slice.success and not off_slice.modes[0].on_slice
    assert not off_slice.modes[0].located


def _tilted(pose, **fields):
    msg = platform_pose(*pose)
    for name, value in fields.items():
        target, attribute = name.split("_")
        setattr(getattr(msg.pose, target), attribute, value)
    return msg


@pytest.mark.parametrize("pose", [
    _tilted(START_POSE, position_z=1.0), _tilted(START_POSE, orientation_x=0.5),
    _tilted(START_POSE, position_x=math.nan), _tilted(START_POSE, orientation_w=2.0)])
def test_a_pose_off_the_base_plane_is_an_invalid_input(service, pose):
    response = service.client.inverse_kinematics(pose)
    assert response.error_code == InverseKinematics.Response.ERROR_INVALID_INPUT
    planned = service.plan(None, Q2, start_is_pose=True, start_pose=pose)
    assert planned.error_code == PlanPath.Response.ERROR_INVALID_INPUT, planned.error_msg


def test_a_pose_in_another_frame_is_refused_and_the_base_frame_may_be_empty(service):
    pose = platform_pose(*START_POSE)
    pose.header.frame_id = "map"
    response = service.plan(None, Q2, start_is_pose=True, start_pose=pose)
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT
    assert "frame" in response.error_msg
    pose.header.frame_id = ""
    assert service.plan(None, Q2, start_is_pose=True, start_pose=pose).success


def test_a_pose_off_the_slice_is_infeasible_and_says_why(service):
    response = service.plan(Q1, None, goal_is_pose=True,
                            goal_pose=platform_pose(5.0, 5.0, 0.0))
    assert response.error_code == PlanPath.Response.ERROR_INFEASIBLE, response.error_msg
    assert response.feasibility == PlanPath.Response.FEASIBILITY_UNREACHABLE
    assert "off the slice" in response.error_msg


def test_a_working_mode_without_a_pose_or_not_one_sign_per_leg_is_an_invalid_input(service):
    assert service.plan(Q1, Q2, start_working_mode="+++").error_code == \
        PlanPath.Response.ERROR_INVALID_INPUT
    response = service.plan(None, Q2, start_is_pose=True,
                            start_pose=platform_pose(*START_POSE), start_working_mode="+x")
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg


def test_the_response_names_the_roadmap_that_answered(service):
    response = service.plan(MODE_A, MODE_B)
    assert response.success, response.error_msg
    assert response.roadmap_stamp == service.stamp.stamp
    assert list(response.roadmap_fixed_joints) == ["rho1"]
    assert list(response.roadmap_fixed_values) == [17.0]
    failed = service.plan((13.0, 12.0, 18.0, 0.0), Q2)
    assert failed.error_code == PlanPath.Response.ERROR_FIXED_JOINT_MISMATCH
    assert list(failed.roadmap_fixed_values) == [17.0]


def test_joints_may_come_by_name_in_any_order(service):
    reordered = [2, 0, 1]
    start = PlanPath.Request(start=_configuration(
        [Q1[k] for k in reordered] + [Q1[3]], [NAMES[k] for k in reordered]),
        goal=_configuration(Q2))
    response = service.call(start)
    assert response.success, response.error_msg
    np.testing.assert_allclose(response.trajectory.points[0].positions, Q1[:3], rtol=0,
                               atol=1e-9)


@pytest.mark.parametrize("configuration, reason", [
    (Configuration(positions=[17.0, 12.0], mode=Q1[3]), "3 positions"),
    (Configuration(positions=[17.0, 12.0, 18.0, 1.0], mode=Q1[3]), "3 positions"),
    (Configuration(joint_names=["th1", "th2", "th3"], positions=Q1[:3], mode=Q1[3]),
     "are not the 3-RPR's"),
    (Configuration(joint_names=["rho1", "rho1", "rho3"], positions=Q1[:3], mode=Q1[3]),
     "are not the 3-RPR's"),
    (Configuration(joint_names=["rho1", "rho2"], positions=Q1[:3], mode=Q1[3]),
     "are not the 3-RPR's"),
])
def test_a_configuration_of_other_joints_is_an_invalid_input(service, configuration, reason):
    response = service.call(PlanPath.Request(start=configuration, goal=_configuration(Q2)))
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg
    assert reason in response.error_msg


def test_each_plan_is_drawn_for_rviz(service):
    response = service.plan(Q1, Q2)
    assert response.success, response.error_msg
    stamp = response.trajectory.header.stamp
    deadline = time.monotonic() + TIMEOUT
    drawn = []
    while not drawn and time.monotonic() < deadline:
        drawn = [a for a in service.path_markers if a.markers[0].header.stamp == stamp]
        time.sleep(0.02)
    assert drawn, "no markers for the plan"
    by_name = {m.ns: m for m in drawn[0].markers}
    np.testing.assert_allclose([[p.x, p.y] for p in by_name["joint_path"].points],
                               [p.positions[1:] for p in response.trajectory.points])
    np.testing.assert_allclose([[p.x, p.y] for p in by_name["platform_path"].points],
                               [p.values[:2] for p in response.poses])
    assert by_name["platform_path"].header.frame_id == "base"
    assert by_name["joint_path"].header.frame_id == "joint_space"


# --- the fuzz test ------------------------------------------------------------------------------

HOSTILE = [math.nan, math.inf, -math.inf, 1e308, -1e308, 1e300, 5e-324, -5e-324, 0.0, -0.0,
           -1.0, 1e-12, 50.0, 50.0625, 50.07, 1e6]
hostile = st.sampled_from(HOSTILE)
leg = st.one_of(st.floats(0.0, 50.0), hostile)
angle = st.one_of(st.floats(-math.pi, math.pi), hostile)
PAPER_ENDS = [Q1, Q2, MODE_A, MODE_B]


@st.composite
def configurations(draw):
    """Three in five a real assembly mode in the grid (or the paper's), else
    a configuration at rho1 = 17 with hostile values among its numbers, or
    anything at all."""
    kind = draw(st.sampled_from(["valid", "valid", "valid", "rho1_17", "anything"]))
    if kind == "valid":
        rho = (17.0, draw(st.floats(0.0, 50.0)), draw(st.floats(0.0, 50.0)))
        alphas = PAPER_GEOMETRY.direct_kinematics(rho)[:, 2]
        if alphas.size == 0:
            return draw(st.sampled_from(PAPER_ENDS))
        return (*rho, float(draw(st.sampled_from(alphas.tolist()))))
    rho1 = 17.0 if kind == "rho1_17" else draw(leg)
    return (rho1, draw(leg), draw(leg), draw(angle))


@st.composite
def configuration_messages(draw):
    """Mostly a configuration in the 3-RPR's order; else its joints by name
    in any order, too few or too many positions, or names of other joints."""
    values = draw(configurations())
    kind = draw(st.sampled_from(["ordered", "ordered", "ordered", "named", "count", "names"]))
    if kind == "ordered":
        return _configuration(values)
    if kind == "named":
        order = draw(st.permutations(range(3)))
        return _configuration([values[k] for k in order] + [values[3]],
                              [NAMES[k] for k in order])
    if kind == "count":
        count = draw(st.sampled_from([0, 1, 2, 4, 7]))
        return Configuration(positions=(list(values[:3]) * 3)[:count], mode=values[3])
    names = draw(st.lists(st.sampled_from(NAMES + ["th1", "", "rho4", "x"]), min_size=0,
                          max_size=4))
    return _configuration(values, names)


@st.composite
def limits(draw):
    """Both 0 (the defaults), both sound, or anything."""
    kind = draw(st.sampled_from(["defaults", "sound", "sound", "anything"]))
    if kind == "defaults":
        return 0.0, 0.0
    value = st.floats(1e-2, 1e2) if kind == "sound" else st.one_of(st.floats(1e-3, 1e3), hostile)
    return draw(value), draw(value)


@st.composite
def joint_limits(draw):
    """None mostly; else up to four entries of the joints or others, with
    sound, zero or hostile values."""
    if draw(st.integers(0, 3)):
        return []
    value = st.one_of(st.just(0.0), st.floats(1e-2, 1e2), st.floats(1e-2, 1e2), hostile)
    return draw(st.lists(st.builds(JointLimits,
                                   joint_name=st.sampled_from(NAMES + NAMES + ["th1", ""]),
                                   max_velocity=value, max_acceleration=value), max_size=2,
                         unique_by=lambda entry: entry.joint_name))


@st.composite
def pose_messages(draw):
    """The paper's example poses, poses of drawn or hostile numbers, in
    the base frame or not, turned about z or not."""
    pose = draw(st.one_of(st.sampled_from([START_POSE, GOAL_POSE]),
                          st.tuples(leg, leg, st.floats(-4.0, 4.0))))
    msg = platform_pose(*pose)
    if not draw(st.integers(0, 4)):
        msg.pose.orientation.w = draw(hostile)
    if not draw(st.integers(0, 4)):
        msg.header.frame_id = draw(st.sampled_from(["", "map", "base_link"]))
    if not draw(st.integers(0, 4)):
        msg.pose.position.z = draw(hostile)
        msg.pose.orientation.x = draw(hostile)
    return msg


@st.composite
def requests(draw):
    max_velocity, max_acceleration = draw(limits())
    ends = {}
    for end in ("start", "goal"):
        if draw(st.integers(0, 3)):
            ends[end] = draw(configuration_messages())
        else:
            ends.update({f"{end}_is_pose": True, f"{end}_pose": draw(pose_messages())})
        if not draw(st.integers(0, 9)):
            ends[f"{end}_working_mode"] = draw(st.sampled_from(["+++", "+++", "-++", "x"]))
    return PlanPath.Request(
        **ends,
        mode_tolerance=draw(st.one_of(st.just(0.0), st.just(0.0), st.floats(1e-4, 0.2),
                                       hostile)),
        skip_smoothing=draw(st.booleans()), weighted=draw(st.booleans()),
        feasibility_only=draw(st.booleans()),
        max_velocity=max_velocity, max_acceleration=max_acceleration,
        joint_limits=draw(joint_limits()),
        time_limit=draw(st.one_of(st.just(0.0), st.just(0.0), st.floats(1e-4, 1.0), hostile)))


@pytest.mark.slow
def test_fuzzed_requests_get_sound_answers_and_the_node_answers_a_good_one_after(service):
    outcomes = collections.Counter()

    @settings(max_examples=FUZZ_REQUESTS, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(request=requests())
    def fuzz(request):
        response = service.call(request)
        outcomes[CODES[response.error_code]] += 1
        check_sound(request, response, service.stamp, service.default_limits())

    fuzz()
    print(f"\nplan_path fuzz outcomes over {sum(outcomes.values())} requests: "
          f"{dict(sorted(outcomes.items()))}")
    assert sum(outcomes.values()) >= FUZZ_REQUESTS
    response = service.plan(Q1, Q2)
    assert response.success, response.error_msg
    check_sound(PlanPath.Request(start=_configuration(Q1), goal=_configuration(Q2)), response,
                service.stamp, service.default_limits())


def test_the_clearance_parameter_sets_the_margin_paths_keep(service):
    node = service.planner
    default = node.get_parameter("clearance").value
    try:
        assert not node.set_parameters([Parameter("clearance", value=-0.1)])[0].successful
        assert node.set_parameters([Parameter("clearance", value=0.02)])[0].successful
        response = service.plan(MODE_A, MODE_B)
        assert response.success, response.error_msg
        assert response.min_singularity_margin >= 0.005
    finally:
        node.set_parameters([Parameter("clearance", value=default)])


# --- plans from worker processes ----------------------------------------------------------------

def _positions(response):
    return np.array([p.positions for p in response.trajectory.points])


@pytest.mark.parametrize("count", [0, pytest.param(2, marks=pytest.mark.slow)])
def test_plans_from_workers_and_from_the_node_are_the_same(ros_context, count):
    earlier = children()
    # A namespace of its own: the module's planner would also take this
    # roadmap, and fork workers of its own.
    service = PlannerUnderTest(ros_context, f"workers_{count}", parameter_overrides=[
        Parameter("plan_workers", value=count)])
    try:
        assert len(wait_for_children(count, earlier, timeout=TIMEOUT if count else 1.0)) == count
        for start, goal in ((Q1, Q2), (MODE_A, MODE_B)):
            response = service.plan(start, goal)
            assert response.success, response.error_msg
            expected = Planner(service.roadmap).plan(start, goal, PlanOptions(smooth=True))
            np.testing.assert_allclose(_positions(response), expected.joints, rtol=0, atol=1e-12)
        refused = service.plan((17.0, 20.0, 25.0, D(60.0)), MODE_B)
        assert refused.error_code == PlanPath.Response.ERROR_NO_ASSEMBLY_MODE, refused.error_msg
        # An error's attributes cross from a worker too.
        infeasible = service.plan(Q1, MODE_B)
        assert infeasible.error_code == PlanPath.Response.ERROR_INFEASIBLE
        assert infeasible.feasibility == PlanPath.Response.FEASIBILITY_OTHER_ASPECT
    finally:
        service.close()


@pytest.mark.slow
def test_killed_plan_workers_leave_the_node_planning_in_its_own_process(ros_context):
    earlier = children()
    service = PlannerUnderTest(ros_context, "killed_workers", parameter_overrides=[
        Parameter("plan_workers", value=2)])
    try:
        workers = wait_for_children(2, earlier)
        assert len(workers) == 2
        before = service.plan(Q1, Q2)
        assert before.success, before.error_msg
        for pid in workers:
            os.kill(pid, signal.SIGKILL)
        for _ in range(3):
            after = service.plan(Q1, Q2)
            assert after.success, after.error_msg
            np.testing.assert_array_equal(_positions(after), _positions(before))
        infeasible = service.plan(Q1, MODE_B)
        assert infeasible.error_code == PlanPath.Response.ERROR_INFEASIBLE
        assert infeasible.feasibility == PlanPath.Response.FEASIBILITY_OTHER_ASPECT
    finally:
        service.close()


# --- the assembly modes service -----------------------------------------------------------------

MODE_CODES = {getattr(AssemblyModes.Response, name): name
              for name in dir(AssemblyModes.Response) if name.startswith("ERROR_")}
MODE_FEASIBILITY = {getattr(AssemblyMode, name): name for name in dir(AssemblyMode)
                    if name.startswith("FEASIBILITY_")}
MODES_FUZZ_REQUESTS = 150


def check_modes(joints, start_mode, response):
    """An answer is an error of the list (never a bug) or the modes of the
    joints: each closes the legs, its aspect the sign of det Jx, by the
    independent reference; with a start mode, exactly one is the start."""
    assert response.error_code in MODE_CODES, response.error_code
    assert response.error_code != AssemblyModes.Response.ERROR_INTERNAL, response.error_msg
    assert response.success == (response.error_code == AssemblyModes.Response.ERROR_NONE)
    if not response.success:
        assert response.error_msg and not response.modes
        return
    assert response.modes
    for mode in response.modes:
        pose = list(mode.pose.values)
        np.testing.assert_allclose(legs_of(pose), _joints(mode.configuration), atol=1e-7)
        np.testing.assert_allclose(_joints(mode.configuration), joints, rtol=1e-4)
        assert mode.aspect == np.sign(margin_of(pose))
        assert mode.feasibility in MODE_FEASIBILITY
        assert mode.located == (not mode.unlocated)
    starts = [m for m in response.modes if m.feasibility == AssemblyMode.FEASIBILITY_START]
    assert len(starts) == (1 if start_mode is not None else 0)


def test_the_modes_a_path_reaches_from_a_start_are_planned_to(service):
    joints, start = MODE_A[:3], MODE_A[3]
    response = service.client.assembly_modes(joints, start, timeout_sec=TIMEOUT)
    check_modes(joints, start, response)
    reachable = [m for m in response.modes if m.feasibility in (
        AssemblyMode.FEASIBILITY_SAME_PATCH, AssemblyMode.FEASIBILITY_CONNECTED)]
    assert any(abs(m.configuration.mode - MODE_B[3]) < D(1) for m in reachable)
    for mode in reachable:
        plan = service.client.plan(_configuration(MODE_A), mode.configuration,
                                   timeout_sec=TIMEOUT)
        assert plan.success, plan.error_msg
        assert follow(np.array([p.positions for p in plan.trajectory.points]),
                      list(plan.poses[0].values), 1e-3 * (1 - 1e-3))["ok"]


@pytest.mark.parametrize("joints, start, code", [
    ((17.0, math.nan, 25.0), None, "ERROR_INVALID_INPUT"),
    ((17.0, 20.0), None, "ERROR_INVALID_INPUT"),
    ((13.0, 20.0, 25.0), None, "ERROR_FIXED_JOINT_MISMATCH"),
    ((17.0, 60.0, 25.0), None, "ERROR_OUT_OF_GRID"),
    ((17.0, 2.0, 45.0), None, "ERROR_NO_SOLUTION"),
    ((17.0, 20.0, 25.0), 0.0, "ERROR_NO_ASSEMBLY_MODE"),
    ({"rho1": 17.0, "rho2": 20.0, "rho4": 25.0}, None, "ERROR_INVALID_INPUT"),
])
def test_joints_the_roadmap_cannot_take_get_their_code(service, joints, start, code):
    response = service.client.assembly_modes(joints, start, timeout_sec=TIMEOUT)
    assert MODE_CODES[response.error_code] == code, response.error_msg
    check_modes(joints, start, response)


@st.composite
def mode_requests(draw):
    """Joints mostly of the roadmap's slice, in order or by name, else of
    any count and value; a start mode or none; a tolerance or the default."""
    values = draw(configurations())
    kind = draw(st.sampled_from(["ordered", "ordered", "named", "count"]))
    if kind == "ordered":
        joints = list(values[:3])
    elif kind == "named":
        order = draw(st.permutations(range(3)))
        joints = {NAMES[k]: values[k] for k in order}
    else:
        joints = (list(values[:3]) * 3)[:draw(st.sampled_from([0, 1, 2, 4]))]
    start = draw(st.one_of(st.none(), st.just(values[3]), angle))
    tolerance = draw(st.one_of(st.just(0.0), st.floats(1e-4, 0.2), hostile))
    return joints, start, tolerance


@pytest.mark.slow
@settings(max_examples=MODES_FUZZ_REQUESTS, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(request=mode_requests())
def test_fuzzed_assembly_mode_requests_get_sound_answers(service, request):
    joints, start, tolerance = request
    response = service.client.assembly_modes(joints, start, mode_tolerance=tolerance,
                                             timeout_sec=TIMEOUT)
    ordered = [joints[n] for n in NAMES] if isinstance(joints, dict) else joints
    check_modes(ordered, start, response)
    # The node still plans.
    if not response.success:
        assert service.plan(Q1, Q2).success
