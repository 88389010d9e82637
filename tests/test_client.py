"""PlannerClient against the real nodes: a builder, a planner and a driver of
the paper's 3-RPR in this process, spun by one executor thread, and the
client spinning itself in the test's thread.  Real rclpy and Fast DDS."""

import math
import time

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from rclpy.parameter import Parameter
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import Configuration, JointRange, Scene
from rpr3_gwr_msgs.srv import PlanPath, ResetDriver
from rpr3_gwr_nodes.client import GoalRejectedError, PlannerClient, configuration
from rpr3_gwr_nodes.planner import PlannerNode
from rpr3_gwr_nodes.roadmap_builder import RoadmapBuilder
from rpr3_gwr_nodes.rpr3_driver import Rpr3Driver
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from spun_nodes import SpunNodes

D = math.radians
Q1 = ({"rho1": 17.0, "rho2": 12.0, "rho3": 18.0}, D(122.82))
Q2 = ({"rho3": 25.0, "rho2": 10.0, "rho1": 17.0}, D(-24.24))
TIMEOUT = 60.0


@pytest.fixture(scope="module")
def suite(module_context):
    """The nodes, spun in a thread, and a client of theirs."""
    nodes = [RoadmapBuilder(context=module_context),
             PlannerNode(context=module_context,
                         parameter_overrides=[Parameter("plan_workers", value=0)]),
             Rpr3Driver(context=module_context,
                        parameter_overrides=[Parameter("time_scale", value=20.0)])]
    rig = SpunNodes(module_context, nodes)
    try:
        yield rig.client, nodes
    finally:
        rig.close()


def test_ready_means_the_planner_answers_from_the_latest_roadmap(suite):
    client, (builder, planner, _) = suite
    roadmap = client.wait_until_ready(timeout_sec=TIMEOUT)
    assert roadmap is client.roadmap
    assert planner.ready.is_set()
    response = client.plan(Q1, Q2, feasibility_only=True)
    assert response.success, response.error_msg
    assert response.roadmap_stamp == roadmap.header.stamp
    assert list(response.roadmap_fixed_joints) == ["rho1"]
    assert list(response.roadmap_fixed_values) == [builder.get_parameter("fixed_value").value]


def test_limits_of_single_joints_go_by_name(suite):
    client, _ = suite
    client.wait_until_ready(timeout_sec=TIMEOUT)
    response = client.plan(Q1, Q2, max_velocity=2.0, max_acceleration=4.0,
                           joint_limits={"rho3": (0.25, 0.0)})
    assert response.success, response.error_msg
    velocities = np.array([p.velocities for p in response.trajectory.points])
    assert np.max(np.abs(velocities[:, 2])) <= 0.25 + 1e-9
    assert np.max(np.abs(velocities[:, 1])) > 0.25


def test_a_plan_by_joint_names_reaches_the_goal(suite):
    client, _ = suite
    client.wait_until_ready(timeout_sec=TIMEOUT)
    response = client.plan(Q1, Q2, max_velocity=2.0, max_acceleration=4.0, time_limit=20.0)
    assert response.success, response.error_msg
    assert response.error_code == PlanPath.Response.ERROR_NONE
    assert response.feasibility in (PlanPath.Response.FEASIBILITY_SAME_PATCH,
                                    PlanPath.Response.FEASIBILITY_CONNECTED)
    points = response.trajectory.points
    assert list(response.trajectory.joint_names) == ["rho1", "rho2", "rho3"]
    assert list(points[0].positions) == pytest.approx([17.0, 12.0, 18.0], abs=1e-9)
    assert list(points[-1].positions) == pytest.approx([17.0, 10.0, 25.0], abs=1e-9)
    assert abs(math.remainder(response.poses[-1].values[2] - D(-24.24), 2 * math.pi)) < 1e-3
    assert response.min_singularity_margin > 0.0


def test_a_nan_start_is_an_invalid_input_answered_not_raised(suite):
    client, _ = suite
    client.wait_until_ready(timeout_sec=TIMEOUT)
    response = client.plan(([17.0, math.nan, 18.0], 0.0), Q2)
    assert not response.success
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg
    assert response.feasibility == PlanPath.Response.FEASIBILITY_UNKNOWN
    assert response.error_msg
    # One limit alone: the options are the request's own.
    response = client.plan(Q1, Q2, max_velocity=1.0)
    assert response.error_code == PlanPath.Response.ERROR_INVALID_INPUT, response.error_msg


@pytest.mark.parametrize("timeout", [math.nan, -1.0, "10", None, True])
def test_a_timeout_that_is_not_a_number_of_seconds_is_refused_before_sending(suite, timeout):
    client, _ = suite
    client.wait_until_ready(timeout_sec=TIMEOUT)
    started = time.monotonic()
    for call in (lambda: client.plan(Q1, Q2, timeout_sec=timeout),
                 lambda: client.reset_driver(Q1, timeout_sec=timeout),
                 lambda: client.wait_until_ready(timeout_sec=timeout)):
        with pytest.raises(ValueError, match="timeout_sec is a non-negative number"):
            call()
    assert time.monotonic() - started < 1.0


def test_an_execution_reports_feedback_and_ends_at_the_goal(suite):
    client, _ = suite
    client.wait_until_ready(timeout_sec=TIMEOUT)
    response = client.plan(Q1, Q2, max_velocity=2.0, max_acceleration=4.0)
    assert response.success, response.error_msg
    reset = client.reset_driver(Q1)
    assert reset.success and reset.error_code == ResetDriver.Response.ERROR_NONE, \
        reset.error_msg
    feedback = []
    outcome = client.execute(response.trajectory, lambda msg: feedback.append(msg.feedback),
                             timeout_sec=TIMEOUT)
    assert outcome.status == GoalStatus.STATUS_SUCCEEDED
    assert outcome.result.error_code == ExecuteTrajectory.Result.SUCCESS, \
        outcome.result.error_msg
    assert abs(math.remainder(outcome.result.final_pose.values[2] - D(-24.24),
                              2 * math.pi)) < 1e-3
    assert feedback, "no feedback while executing"
    progress = [f.progress for f in feedback]
    assert progress == sorted(progress) and 0.0 <= progress[0] and progress[-1] <= 1.0
    assert all(f.singularity_margin >= outcome.result.min_singularity_margin - 1e-12
               for f in feedback)


def test_a_bad_reset_and_a_rejected_goal_are_reported(suite):
    client, _ = suite
    reset = client.reset_driver(Configuration(positions=[17.0, 12.0, 18.0], mode=math.inf))
    assert reset.error_code == ResetDriver.Response.ERROR_INVALID_INPUT, reset.error_msg
    assert client.reset_driver(Q1).success
    response = client.plan(Q1, Q2)
    assert response.success, response.error_msg
    # The driver is at Q1; a trajectory starting at the goal is off its legs.
    assert client.reset_driver(Q2).success
    with pytest.raises(GoalRejectedError):
        client.execute(response.trajectory, timeout_sec=TIMEOUT)
    handle = client.send_goal(response.trajectory)
    assert not handle.accepted


def test_an_execution_past_its_timeout_is_canceled(suite):
    client, _ = suite
    assert client.reset_driver(Q1).success
    # 30 s at time_scale 20: still executing when the timeout passes.
    slow = JointTrajectory(joint_names=["rho1", "rho2", "rho3"], points=[
        JointTrajectoryPoint(positions=[17.0, 12.0, 18.0], time_from_start=Duration(sec=0)),
        JointTrajectoryPoint(positions=[17.0, 12.5, 18.0], time_from_start=Duration(sec=600))])
    begin = time.monotonic()
    with pytest.raises(TimeoutError, match="result"):
        client.execute(slow, timeout_sec=1.0)
    assert time.monotonic() - begin < 10.0
    # Canceled: the driver takes a reset again once its control loop saw it.
    deadline = time.monotonic() + 10.0
    while (reset := client.reset_driver(Q1)).error_code == ResetDriver.Response.ERROR_BUSY:
        assert time.monotonic() < deadline, "the goal was not canceled"
        time.sleep(0.05)
    assert reset.success, reset.error_msg


def test_a_scene_is_published_and_echoed_by_the_planner(suite):
    client, (_, planner, _) = suite
    client.wait_until_ready(timeout_sec=TIMEOUT)
    refused = planner.refused_scenes
    published = client.set_scene(Scene(), timeout_sec=TIMEOUT)
    assert published.header.stamp.sec > 0
    assert planner.refused_scenes == refused
    assert client.plan(Q1, Q2, feasibility_only=True).success
    # A stroke of a joint the 3-RPR lacks: refused, never echoed.
    other = Scene(strokes=[JointRange(name="rho9", min=0.0, max=10.0)])
    with pytest.raises(TimeoutError, match="refused"):
        client.set_scene(other, timeout_sec=2.0)
    assert planner.refused_scenes == refused + 1
    client.set_scene(Scene(), timeout_sec=TIMEOUT)


def test_a_rebuilt_roadmap_is_waited_for_by_its_stamp(suite):
    client, (builder, _, _) = suite
    before = client.wait_until_ready(timeout_sec=TIMEOUT).header.stamp
    builder.set_parameters([Parameter("fixed_value", value=16.0)])
    try:
        roadmap = client.wait_until_ready(timeout_sec=2 * TIMEOUT, newer_than=before)
        assert (roadmap.header.stamp.sec, roadmap.header.stamp.nanosec) > \
            (before.sec, before.nanosec)
        response = client.plan(([16.0, 12.0, 18.0], D(122.82)),
                               ([16.0, 12.0, 18.0], D(122.82)), feasibility_only=True)
        assert response.roadmap_stamp == roadmap.header.stamp
        assert list(response.roadmap_fixed_values) == [16.0]
    finally:
        builder.set_parameters([Parameter("fixed_value", value=17.0)])
        client.wait_until_ready(timeout_sec=2 * TIMEOUT, newer_than=client.roadmap.header.stamp)


def test_every_wait_is_bounded_when_no_node_runs(ros_context):
    client = PlannerClient(context=ros_context, namespace="nobody_here")
    try:
        begin = time.monotonic()
        with pytest.raises(TimeoutError, match="/nobody_here/roadmap"):
            client.wait_until_ready(timeout_sec=0.5)
        with pytest.raises(TimeoutError, match="/nobody_here/plan_path"):
            client.plan(Q1, Q2, timeout_sec=0.5)
        with pytest.raises(TimeoutError, match="/nobody_here/reset"):
            client.reset_driver(Q1, timeout_sec=0.5)
        with pytest.raises(TimeoutError, match="/nobody_here/execute_trajectory"):
            client.execute(JointTrajectory(), timeout_sec=0.5)
        with pytest.raises(TimeoutError, match="/nobody_here/planner/current_scene"):
            client.set_scene(Scene(), timeout_sec=0.5)
        assert time.monotonic() - begin < 10.0
    finally:
        client.destroy_node()


def test_the_convenient_forms_make_configurations():
    by_name = configuration({"rho2": 12, "rho1": 17, "rho3": 18}, 1)
    assert list(by_name.joint_names) == ["rho2", "rho1", "rho3"]
    assert list(by_name.positions) == [12.0, 17.0, 18.0] and by_name.mode == 1.0
    in_order = configuration((17, 12, 18), -1)
    assert not in_order.joint_names and list(in_order.positions) == [17.0, 12.0, 18.0]
