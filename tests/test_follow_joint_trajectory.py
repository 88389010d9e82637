"""control_msgs/FollowJointTrajectory both ways, and TF.

The driver serves FollowJointTrajectory as joint_trajectory_controller does:
a plain rclpy ActionClient here drives it (joints in any order, feedback,
success, cancel, an abort as a path tolerance violated) and every goal
joint_trajectory_controller rejects is rejected (its INVALID_JOINTS,
INVALID_GOAL and OLD_HEADER_TIMESTAMP cases), fuzzed, the driver serving on;
its /tf reaches a default subscriber with each link's frame and the
platform's.  The client's forwarder drives a FollowJointTrajectory server
written here (the goal passed on, its feedback and result relayed, its
rejection raised) and publishes to a controller's ~/joint_trajectory.
Real rclpy and Fast DDS, the nodes in this process."""

import collections
import math
import threading
import time

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTolerance
from hypothesis import HealthCheck, given, settings, strategies as st
from rclpy.action import ActionClient, ActionServer, GoalResponse
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_msgs.msg import Configuration
from rpr3_gwr_nodes.client import GoalRejectedError
from rpr3_gwr_nodes.rpr3_driver import Rpr3Driver
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import (JointTrajectory, JointTrajectoryPoint, MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from pose_reference import legs_of
from spun_nodes import SpunNodes

D = math.radians
Q1 = (17.0, 12.0, 18.0, D(122.82))
NAMES = ["rho1", "rho2", "rho3"]
TIMEOUT = 30.0
_Result = FollowJointTrajectory.Result
CODES = {getattr(_Result, n): n for n in dir(_Result)
         if n.isupper() and isinstance(getattr(_Result, n), int)}


def _stamp(seconds):
    nanoseconds = int(round(seconds * 1e9))
    return Duration(sec=nanoseconds // 10**9, nanosec=nanoseconds % 10**9)


def _trajectory(points, seconds, names=NAMES):
    """Points (in the 3-RPR's joint order) at ``seconds``, the joints in the
    order of ``names``."""
    order = [NAMES.index(name) if name in NAMES else 0 for name in names]
    return JointTrajectory(joint_names=list(names), points=[
        JointTrajectoryPoint(positions=[float(p[k]) for k in order], time_from_start=_stamp(t))
        for p, t in zip(points, seconds)])


def _line(end, seconds, n=11, names=NAMES):
    """Straight legs from Q1's to ``end`` in ``seconds``."""
    t = np.linspace(0.0, 1.0, n)
    points = np.outer(1 - t, Q1[:3]) + np.outer(t, end)
    return _trajectory(points, seconds * t, names)


def _wait(future, timeout=TIMEOUT):
    """The result of a future the rig's executor completes."""
    deadline = time.monotonic() + timeout
    while not future.done():
        assert time.monotonic() < deadline, "no answer"
        time.sleep(0.01)
    return future.result()


class Rig(SpunNodes):
    """A driver, a FollowJointTrajectory action client and a default /tf
    subscriber, spun by the rig's executor."""

    def __init__(self, context):
        self.driver = Rpr3Driver(context=context, parameter_overrides=[
            Parameter("time_scale", value=20.0), Parameter("rate", value=100.0)])
        self.user = Node("follow_test_user", context=context)
        self.action = ActionClient(self.user, FollowJointTrajectory,
                                   "/rpr3_driver/follow_joint_trajectory")
        self.transforms = collections.deque(maxlen=10)
        # A default subscription, as a TransformListener's or RViz's.
        self.user.create_subscription(TFMessage, "/tf", lambda msg: self.transforms.append(msg),
                                      10)
        super().__init__(context, (self.driver, self.user), "follow_test_client")
        assert self.action.wait_for_server(timeout_sec=TIMEOUT)

    def reset(self, configuration=Q1):
        response = self.client.reset_driver(
            Configuration(positions=list(configuration[:3]), mode=configuration[3]),
            timeout_sec=TIMEOUT)
        assert response.success, response.error_msg

    def send(self, goal, feedback=None):
        return _wait(self.action.send_goal_async(goal, feedback_callback=feedback))


@pytest.fixture(scope="module")
def rig(module_context):
    running = Rig(module_context)
    try:
        yield running
    finally:
        running.close()


def test_a_goal_with_its_joints_in_any_order_succeeds_with_feedback(rig):
    rig.reset()
    end = np.array(Q1[:3]) + [0.0, 0.25, 0.1]
    feedback = []
    handle = rig.send(FollowJointTrajectory.Goal(
        trajectory=_line(end, 1.0, names=["rho3", "rho1", "rho2"])), feedback.append)
    assert handle.accepted
    response = _wait(handle.get_result_async())
    assert response.status == GoalStatus.STATUS_SUCCEEDED
    assert response.result.error_code == _Result.SUCCESSFUL, response.result.error_string
    np.testing.assert_allclose(rig.driver.state()[0], end, atol=1e-12)
    assert feedback and all(list(f.feedback.joint_names) == NAMES for f in feedback)
    last = feedback[-1].feedback
    np.testing.assert_allclose(last.actual.positions, end, atol=1e-12)
    assert list(last.desired.positions) == list(last.actual.positions)
    assert list(last.error.positions) == [0.0, 0.0, 0.0]


def _goal(**changes):
    """A goal of a short move from Q1 with one thing changed."""
    goal = FollowJointTrajectory.Goal(trajectory=_line(np.array(Q1[:3]) + [0, 0.1, 0], 1.0))
    for name, value in changes.items():
        setattr(goal, name, value) if hasattr(goal, name) else setattr(goal.trajectory, name,
                                                                       value)
    return goal


def _with_last_velocity(goal):
    goal.trajectory.points[-1].velocities = [0.0, 0.1, 0.0]
    return goal


def _stamped(seconds_ago):
    goal = _goal()
    stamp = time.time() - seconds_ago
    goal.trajectory.header.stamp.sec = int(stamp)
    goal.trajectory.header.stamp.nanosec = int((stamp % 1) * 1e9)
    return goal


# joint_trajectory_controller's checks, by the code its users would see.
REJECTED = {
    "INVALID_JOINTS: a joint of another robot":
        _goal(trajectory=_line(np.array(Q1[:3]), 1.0, names=["rho1", "rho2", "th3"])),
    "INVALID_JOINTS: a joint missing": _goal(joint_names=["rho1", "rho2"]),
    "INVALID_JOINTS: a joint twice": _goal(joint_names=["rho1", "rho2", "rho2"]),
    "INVALID_GOAL: no points": _goal(points=[]),
    "INVALID_GOAL: times not increasing": _goal(trajectory=_trajectory(
        [Q1[:3], np.array(Q1[:3]) + [0, 0.1, 0]], [1.0, 1.0])),
    "INVALID_GOAL: not at rest at the end": _with_last_velocity(_goal()),
    "INVALID_GOAL: multi-DOF points": _goal(multi_dof_trajectory=MultiDOFJointTrajectory(
        joint_names=["platform"], points=[MultiDOFJointTrajectoryPoint()])),
    "INVALID_GOAL: a start away from the joints": _goal(trajectory=_line(
        np.array(Q1[:3]) + [0, 0.1, 0], 1.0, n=2)),
    "OLD_HEADER_TIMESTAMP: ended in the past": _stamped(100.0),
}
# The start away from the joints: a line from elsewhere.
REJECTED["INVALID_GOAL: a start away from the joints"].trajectory.points[0].positions = [
    17.0, 13.0, 18.0]


@pytest.mark.parametrize("case", sorted(REJECTED))
def test_goals_joint_trajectory_controller_rejects_are_rejected(rig, case):
    rig.reset()
    assert not rig.send(REJECTED[case]).accepted
    # And the driver takes the next good goal.
    handle = rig.send(_goal())
    assert handle.accepted
    assert _wait(handle.get_result_async()).result.error_code == _Result.SUCCESSFUL


def test_a_goal_stamped_in_the_future_starts_then(rig):
    rig.reset()
    goal = _stamped(-1.0)
    begin = time.monotonic()
    handle = rig.send(goal)
    assert handle.accepted
    assert _wait(handle.get_result_async()).result.error_code == _Result.SUCCESSFUL
    # 1 s of waiting, then 1 s of trajectory at time_scale 20.
    assert time.monotonic() - begin >= 0.9


def test_a_canceled_goal_ends_canceled_and_the_driver_holds(rig):
    rig.reset()
    # 30 s at time_scale 20: still executing however slow the machine is.
    handle = rig.send(FollowJointTrajectory.Goal(
        trajectory=_line(np.array(Q1[:3]) + [0.0, 0.5, 0.0], 600.0)))
    assert handle.accepted
    time.sleep(0.3)
    _wait(handle.cancel_goal_async())
    response = _wait(handle.get_result_async())
    assert response.status == GoalStatus.STATUS_CANCELED
    held = rig.driver.state()[0]
    time.sleep(0.2)
    np.testing.assert_array_equal(rig.driver.state()[0], held)


def test_an_abort_on_the_way_is_a_path_tolerance_violated_saying_why(rig):
    rig.reset()
    # Straight legs from q1 towards the far corner cross the singular locus.
    handle = rig.send(FollowJointTrajectory.Goal(
        trajectory=_line((17.0, 32.0, 6.0), 10.0, n=41),
        path_tolerance=[JointTolerance(name="rho2", position=0.01)]))
    assert handle.accepted
    result = _wait(handle.get_result_async()).result
    assert result.error_code == _Result.PATH_TOLERANCE_VIOLATED
    assert "margin" in result.error_string and "t = " in result.error_string


def _platform_at(message, point):
    """Whether a /tf message puts the platform frame at ``point``."""
    return any(t.child_frame_id == "platform"
               and np.allclose([t.transform.translation.x, t.transform.translation.y], point,
                               rtol=0.0, atol=1e-12) for t in message.transforms)


def test_tf_reaches_a_default_subscriber_with_the_frames_of_the_legs_and_platform(rig):
    rig.reset()
    joints, pose, _ = rig.driver.state()
    # Messages of the state before the reset may still be on their way on a
    # loaded machine: the state's own must come.
    deadline = time.monotonic() + TIMEOUT
    while not any(_platform_at(m, pose[:2]) for m in list(rig.transforms)):
        assert time.monotonic() < deadline, "no /tf of the state after the reset"
        time.sleep(0.02)
    message = next(m for m in reversed(list(rig.transforms)) if _platform_at(m, pose[:2]))
    frames = {t.child_frame_id: t for t in message.transforms}
    assert sorted(frames) == ["leg1", "leg2", "leg3", "platform"]
    assert {t.header.frame_id for t in message.transforms} == {"base"}
    # The platform frame is at B1, turned by alpha; the leg frames are at
    # the base points, their lengths the joints.
    platform = frames["platform"].transform
    yaw = 2 * math.atan2(platform.rotation.z, platform.rotation.w)
    assert abs(math.remainder(yaw - pose[2], 2 * math.pi)) < 1e-9
    np.testing.assert_allclose(legs_of(pose), joints, atol=1e-9)


HOSTILE = [math.nan, math.inf, -math.inf, 1e308, -1.0, 0.0, 1e-12, 60.0]
# A goal that executes lasts up to a second: 40 keep the fuzzing under a minute.
FUZZ_GOALS = 40


@st.composite
def fuzzed_goals(draw):
    n = draw(st.integers(0, 5))
    start = np.array(Q1[:3])
    points = [start] + [start + draw(st.tuples(*[st.floats(-0.3, 0.3)] * 3))
                        for _ in range(n - 1)]
    points = [[draw(st.sampled_from(HOSTILE)) if not draw(st.integers(0, 9)) else v for v in p]
              for p in points[:n]]
    seconds = sorted(draw(st.floats(0.0, 1.0)) for _ in range(n))
    names = draw(st.sampled_from([NAMES, NAMES[::-1], ["rho2", "rho3", "rho1"], NAMES[:2],
                                  ["a", "b", "c"], NAMES + ["rho1"]]))
    goal = FollowJointTrajectory.Goal(trajectory=_trajectory(points, seconds, names))
    if not draw(st.integers(0, 4)):
        goal.trajectory.points[-1:] = [JointTrajectoryPoint(
            positions=p.positions, velocities=[draw(st.sampled_from(HOSTILE))] * 3,
            time_from_start=p.time_from_start) for p in goal.trajectory.points[-1:]]
    if not draw(st.integers(0, 4)):
        goal.path_tolerance = [JointTolerance(
            name=draw(st.sampled_from(NAMES + ["x"])), position=draw(st.sampled_from(HOSTILE)))]
    if not draw(st.integers(0, 6)):
        goal.trajectory.header.stamp.sec = draw(st.sampled_from([1, 2**31 - 1]))
    return goal


@pytest.mark.slow
def test_fuzzed_goals_are_rejected_or_end_with_a_code_and_the_driver_serves_on(rig):
    outcomes = collections.Counter()

    @settings(max_examples=FUZZ_GOALS, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(goal=fuzzed_goals())
    def fuzz(goal):
        if rig.driver.state()[0].tolist() != list(Q1[:3]):
            rig.reset()
        handle = rig.send(goal)
        if not handle.accepted:
            outcomes["rejected"] += 1
            return
        response = _wait(handle.get_result_async(), 60.0)
        assert response.result.error_code in CODES
        outcomes[CODES[response.result.error_code]] += 1

    fuzz()
    print(f"\nfollow_joint_trajectory fuzz outcomes: {dict(sorted(outcomes.items()))}")
    assert sum(outcomes.values()) >= FUZZ_GOALS
    rig.reset()
    handle = rig.send(_goal())
    assert handle.accepted
    assert _wait(handle.get_result_async()).result.error_code == _Result.SUCCESSFUL


# --- the forwarder ------------------------------------------------------------------------------

class _Controller(Node):
    """A FollowJointTrajectory server and a ~/joint_trajectory subscriber,
    as a controller named ``test_controller`` has: it rejects a goal without
    points, and answers the others with two feedback messages and a path
    tolerance violated."""

    def __init__(self, context):
        super().__init__("test_controller", context=context)
        self.goals, self.topic = [], []
        self.received = threading.Event()
        ActionServer(self, FollowJointTrajectory, "~/follow_joint_trajectory", self._execute,
                     goal_callback=lambda goal: (GoalResponse.ACCEPT if goal.trajectory.points
                                                 else GoalResponse.REJECT))
        self.create_subscription(JointTrajectory, "~/joint_trajectory", self._take, 10)

    def _take(self, msg):
        self.topic.append(msg)
        self.received.set()

    def _execute(self, goal_handle):
        self.goals.append(goal_handle.request)
        for k in range(2):
            goal_handle.publish_feedback(FollowJointTrajectory.Feedback(
                joint_names=NAMES, actual=JointTrajectoryPoint(positions=[float(k)] * 3)))
        goal_handle.abort()
        return FollowJointTrajectory.Result(error_code=_Result.PATH_TOLERANCE_VIOLATED,
                                            error_string="the test's controller says so")


def test_the_forwarder_passes_a_goal_on_and_relays_feedback_and_result(ros_context):
    controller = _Controller(ros_context)
    rig = SpunNodes(ros_context, [controller], "forwarder_test_client")
    try:
        trajectory = _line(np.array(Q1[:3]) + [0, 0.1, 0], 1.0)
        feedback = []
        response = rig.client.follow_joint_trajectory(
            trajectory, "/test_controller/follow_joint_trajectory",
            path_tolerance=[JointTolerance(name="rho2", position=0.01)],
            goal_time_tolerance=0.5, feedback_callback=feedback.append, timeout_sec=TIMEOUT)
        assert response.status == GoalStatus.STATUS_ABORTED
        assert response.result.error_code == _Result.PATH_TOLERANCE_VIOLATED
        assert response.result.error_string == "the test's controller says so"
        (goal,) = controller.goals
        assert goal.trajectory == trajectory
        assert [t.name for t in goal.path_tolerance] == ["rho2"]
        assert goal.goal_time_tolerance == Duration(sec=0, nanosec=500_000_000)
        assert [list(f.feedback.actual.positions) for f in feedback] == [[0.0] * 3, [1.0] * 3]
        with pytest.raises(GoalRejectedError):
            rig.client.follow_joint_trajectory(JointTrajectory(joint_names=NAMES),
                                               "/test_controller/follow_joint_trajectory",
                                               timeout_sec=TIMEOUT)
        assert rig.client.publish_trajectory(trajectory, "/test_controller/joint_trajectory",
                                             timeout_sec=TIMEOUT) == 1
        assert controller.received.wait(TIMEOUT)
        assert controller.topic == [trajectory]
    finally:
        rig.close()
