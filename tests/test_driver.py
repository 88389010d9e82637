"""The simulated driver on control conventions: goals validated and rejected
when they arrive, one goal at a time, aborts that say why, diagnostics by
margin, hostile resets answered with codes, hostile goals accepted exactly
when the goal check (:mod:`rpr3_gwr_nodes.goal_checks`) passes them.  A
driver node over real DDS, spun by one executor thread, and a PlannerClient
spinning itself in the test's thread."""

import collections
import math
import time

import numpy as np
import pytest
import yaml
from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from hypothesis import HealthCheck, given, settings, strategies as st
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.serialization import deserialize_message, serialize_message
from rpr3_gwr_core.mechanisms.rpr3 import ThreeRPR
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import Configuration, PlatformPose
from rpr3_gwr_msgs.srv import ResetDriver
from rpr3_gwr_nodes.goal_checks import check_trajectory, trajectory_fields
from rpr3_gwr_nodes.profiles import SENSOR_QOS
from rpr3_gwr_nodes.roadmap_builder import RoadmapBuilder
from rpr3_gwr_nodes.rpr3_driver import Rpr3Driver
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import MarkerArray

from spun_nodes import SpunNodes

D = math.radians
Q1 = (17.0, 12.0, 18.0, D(122.82))
NAMES = ["rho1", "rho2", "rho3"]
TIMEOUT = 30.0
_Result = ExecuteTrajectory.Result
RESULT_CODES = {getattr(_Result, n): n for n in dir(_Result)
                if n.isupper() and isinstance(getattr(_Result, n), int)}
RESET_CODES = {getattr(ResetDriver.Response, n): n for n in dir(ResetDriver.Response)
               if n.startswith("ERROR_")}


def _stamp(seconds):
    nanoseconds = int(round(seconds * 1e9))
    return Duration(sec=nanoseconds // 10**9, nanosec=nanoseconds % 10**9)


def _trajectory(points, times, names=NAMES):
    return JointTrajectory(joint_names=list(names), points=[
        JointTrajectoryPoint(positions=[float(v) for v in p], time_from_start=t)
        for p, t in zip(points, times)])


def _line(start, end, seconds, n=21):
    """Straight legs from ``start`` to ``end`` in ``seconds``."""
    t = np.linspace(0.0, 1.0, n)
    points = np.asarray(start)[None, :] * (1 - t)[:, None] + np.asarray(end)[None, :] * t[:, None]
    return _trajectory(points, [_stamp(seconds * k) for k in t])


class DriverUnderTest(SpunNodes):
    def __init__(self, context):
        self.driver = Rpr3Driver(context=context, parameter_overrides=[
            Parameter("time_scale", value=20.0), Parameter("rate", value=100.0)])
        # Diagnostics arrive in the rig's executor, whatever the client does.
        self.listener = Node("driver_test_listener", context=context)
        self.diagnostics = []
        self.listener.create_subscription(DiagnosticArray, "/diagnostics",
                                          self.diagnostics.append, 10)
        super().__init__(context, (self.driver, self.listener), "driver_test_client")

    def reset(self, configuration, names=()):
        c = Configuration(joint_names=list(names), positions=list(configuration[:-1]),
                          mode=configuration[-1])
        return self.client.reset_driver(c, timeout_sec=TIMEOUT)

    def send(self, trajectory):
        return self.client.send_goal(trajectory, timeout_sec=TIMEOUT)

    def execute(self, trajectory):
        return self.client.execute(trajectory, timeout_sec=120.0).result

    def level_after(self, since, timeout=5.0):
        """The level of the first diagnostics published after index ``since``."""
        deadline = time.monotonic() + timeout
        while len(self.diagnostics) <= since and time.monotonic() < deadline:
            time.sleep(0.02)
        assert len(self.diagnostics) > since, "no diagnostics published"
        return self.diagnostics[since].status[0].level


@pytest.fixture(scope="module")
def rig(module_context):
    running = DriverUnderTest(module_context)
    try:
        yield running
    finally:
        running.close()


@pytest.mark.parametrize("configuration, code", [
    ((17.0, 1e100, 18.0, 0.0), ResetDriver.Response.ERROR_OUT_OF_RANGE),
    ((1e308, 1e308, 1e308, 0.0), ResetDriver.Response.ERROR_OUT_OF_RANGE),
    ((17.0, 60.0, 18.0, 0.0), ResetDriver.Response.ERROR_OUT_OF_RANGE),
    ((17.0, math.nan, 18.0, 0.0), ResetDriver.Response.ERROR_INVALID_INPUT),
    ((17.0, 12.0, 18.0, math.inf), ResetDriver.Response.ERROR_INVALID_INPUT),
    ((17.0, -1.0, 18.0, 0.0), ResetDriver.Response.ERROR_INVALID_INPUT),
    ((17.0, 2.0, 45.0, 0.0), ResetDriver.Response.ERROR_NO_SOLUTION),
    ((17.0, 12.0, 18.0, 0.0), ResetDriver.Response.ERROR_NO_ASSEMBLY_MODE),
])
def test_bad_resets_get_their_code_and_the_driver_still_serves(rig, configuration, code):
    response = rig.reset(configuration)
    assert not response.success and response.error_code == code, response.error_msg
    assert response.error_msg
    assert rig.reset(Q1).success


def _step(**last):
    """A step of rho2 in 1 s from q1, the second point with the fields ``last``."""
    start = np.array(Q1[:3])
    trajectory = _trajectory([start, start + [0.0, 0.5, 0.0]], [_stamp(0), _stamp(1)])
    for field, value in last.items():
        setattr(trajectory.points[1], field, value)
    return trajectory


def _good_goal():
    """A quarter step of rho2 with velocities and accelerations, as the planner's."""
    good = _line(Q1[:3], np.array(Q1[:3]) + [0.0, 0.25, 0.0], 1.0)
    for point in good.points:
        point.velocities, point.accelerations = [0.0, 0.25, 0.0], [0.0, 0.0, 0.0]
    return good


def _bad_goals():
    start = np.array(Q1[:3])
    later = start + [0.0, 0.5, 0.0]
    return {
        "empty": JointTrajectory(joint_names=NAMES),
        "wrong names": _trajectory([start], [_stamp(0)], names=["a", "b", "c"]),
        "not finite": _trajectory([start, [17.0, math.nan, 18.0]], [_stamp(0), _stamp(1)]),
        "out of range": _trajectory([start, [17.0, 12.0, 80.0]], [_stamp(0), _stamp(10)]),
        "negative stamp": _trajectory([start, later], [Duration(sec=-2), Duration(sec=-1)]),
        "equal stamps": _trajectory([start, later], [_stamp(0), _stamp(0)]),
        "0.5 in 1 ns": _trajectory([start, later], [_stamp(0), Duration(nanosec=1)]),
        "elsewhere": _trajectory([[17.0, 30.0, 30.0]], [_stamp(0)]),
        "nanosec of 2 s": _step(time_from_start=Duration(nanosec=2_000_000_000)),
        # Read as 0.5 s and 1 s, were nanosec not checked.
        "negative sec": _trajectory([start, later], [Duration(sec=-1, nanosec=1_500_000_000),
                                                     Duration(sec=-1, nanosec=2_000_000_000)]),
        "velocity nan": _step(velocities=[0.0, math.nan, 0.0]),
        "velocity inf": _step(velocities=[0.0, math.inf, 0.0]),
        "acceleration nan": _step(accelerations=[math.nan, 0.0, 0.0]),
        "acceleration -inf": _step(accelerations=[0.0, 0.0, -math.inf]),
        "2 velocities": _step(velocities=[0.0, 0.5]),
        "4 accelerations": _step(accelerations=[0.0, 0.0, 0.0, 0.0]),
        "effort": _step(effort=[0.0, 0.0, 0.0]),
    }


@pytest.mark.parametrize("name", list(_bad_goals()))
def test_bad_goals_are_rejected_when_they_arrive(rig, name):
    assert rig.reset(Q1).success
    assert not rig.send(_bad_goals()[name]).accepted
    assert rig.execute(_good_goal()).error_code == _Result.SUCCESS


def test_subscribers_with_the_default_qos_get_the_driver_state(rig):
    # Reliable, depth 10: what create_subscription(..., 10) asks for, as
    # robot_state_publisher and most tools do.
    listener = Node("default_qos_listener", context=rig.driver.context)
    executor = SingleThreadedExecutor(context=rig.driver.context)
    executor.add_node(listener)
    got = collections.defaultdict(list)
    for kind, topic in ((JointState, "joint_states"), (PlatformPose, "platform_pose"),
                        (MarkerArray, "mechanism_markers"), (DiagnosticArray, "/diagnostics")):
        listener.create_subscription(kind, topic, lambda msg, topic=topic: got[topic].append(msg),
                                     10)
    try:
        deadline = time.monotonic() + 10.0
        while len(got) < 4 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()
        listener.destroy_node()
    assert len(got) == 4, f"only {sorted(got)} arrived"
    state = got["joint_states"][-1]
    passive = ["base1", "base2", "base3", "platform1", "platform2", "platform3"]
    assert state.name == NAMES + passive
    # At rest, so the last pose is the state's.  B1 is the pose's point and
    # A1 the origin: leg 1's direction, and relative to the platform.
    message = got["platform_pose"][-1]
    pose = dict(zip(message.names, message.values))
    base1 = math.atan2(pose["y"], pose["x"])
    values = dict(zip(state.name, state.position))
    assert values["base1"] == pytest.approx(base1, abs=1e-9)
    assert math.cos(values["platform1"] - (base1 - pose["alpha"])) == pytest.approx(1.0, abs=1e-12)
    assert all(math.isnan(v) for v in state.velocity[len(NAMES):])


def test_a_second_goal_is_rejected_while_one_executes(rig):
    assert rig.reset(Q1).success
    # 30 s at time_scale 20: still executing however slow the machine is.
    slow = _line(Q1[:3], np.array(Q1[:3]) + [0.0, 0.5, 0.0], 600.0)
    first = rig.send(slow)
    assert first.accepted
    try:
        time.sleep(0.2)
        assert not rig.send(slow).accepted
        busy = rig.reset(Q1)
        assert busy.error_code == ResetDriver.Response.ERROR_BUSY
    finally:
        rig.client.cancel(first)
    assert rig.client.get_result(first, TIMEOUT).result.error_code == _Result.CANCELED


def test_an_abort_says_why_with_its_margin_and_diagnostics_go_to_error(rig):
    assert rig.reset(Q1).success
    seen = len(rig.diagnostics)
    assert rig.level_after(seen) == DiagnosticStatus.OK
    # Straight legs from q1 towards the far corner cross the singular locus.
    result = rig.execute(_line(Q1[:3], (17.0, 32.0, 6.0), 10.0, n=41))
    assert result.error_code in (_Result.SINGULARITY_ABORT, _Result.ASSEMBLY_MODE_LEFT)
    assert "margin" in result.error_msg and "t = " in result.error_msg, result.error_msg
    seen = len(rig.diagnostics)
    level = rig.level_after(seen)
    assert level == DiagnosticStatus.ERROR
    assert "abort" in rig.diagnostics[seen].status[0].message
    assert rig.reset(Q1).success
    seen = len(rig.diagnostics)
    assert rig.level_after(seen) == DiagnosticStatus.OK


def test_the_mechanism_markers_have_the_legs_of_the_joint_states(rig):
    # A listener of its own, spun only here: 100 Hz streams in the rig's
    # executor would slow every other test down.
    listener = Node("marker_listener", context=rig.driver.context)
    executor = SingleThreadedExecutor(context=rig.driver.context)
    executor.add_node(listener)
    markers, states = [], []
    listener.create_subscription(MarkerArray, "mechanism_markers", markers.append, SENSOR_QOS)
    listener.create_subscription(JointState, "joint_states", states.append, SENSOR_QOS)
    try:
        assert rig.reset(Q1).success
        moving = rig.send(_line(Q1[:3], np.array(Q1[:3]) + [0.0, 0.5, -0.5], 20.0))
        assert moving.accepted
        deadline = time.monotonic() + 10.0
        pairs = []
        while len(pairs) < 5 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
            stamps = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in states}
            pairs = [(stamps[key], array) for array in markers
                     if (key := (array.markers[0].header.stamp.sec,
                                 array.markers[0].header.stamp.nanosec)) in stamps]
        rig.client.get_result(moving, TIMEOUT)
    finally:
        executor.shutdown()
        listener.destroy_node()
    assert len(pairs) >= 5, "no marker array with the stamp of a joint state"
    base = rig.driver.mechanism.base
    for state, array in pairs:
        by_name = {m.ns: m for m in array.markers}
        assert {m.header.frame_id for m in array.markers} == {"base"}
        np.testing.assert_allclose([[p.x, p.y] for p in by_name["base"].points], base)
        ends = np.array([[p.x, p.y] for p in by_name["legs"].points]).reshape(3, 2, 2)
        np.testing.assert_allclose(ends[:, 0], base)
        np.testing.assert_allclose(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1),
                                   state.position[:3], atol=1e-9)
        corners = np.array([[p.x, p.y] for p in by_name["platform"].points])
        np.testing.assert_allclose(corners[:3], ends[:, 1], atol=1e-9)
        np.testing.assert_allclose(corners[3], corners[0])


def test_the_driver_takes_the_builders_mechanism_file(ros_context, tmp_path):
    geometry = ThreeRPR(d1=16.0)
    path = tmp_path / "d1_16.yaml"
    path.write_text(yaml.safe_dump({
        "mechanism": geometry.to_dict(),
        "joints": [{"name": n, "min": 0.0, "max": 50.0, "step": 0.5} for n in NAMES]}))
    pose = (5.0, 16.0, 2.0)
    start = [*geometry.inverse(pose), pose[2]]
    overrides = [Parameter("mechanism_file", value=str(path))]
    driver = Rpr3Driver(context=ros_context, parameter_overrides=overrides + [
        Parameter("initial_configuration", value=start)])
    builder = RoadmapBuilder(context=ros_context, parameter_overrides=overrides)
    try:
        assert driver.mechanism == builder.mechanism == geometry
        np.testing.assert_allclose(driver.state()[1], pose)
        assert driver.describe_parameter("mechanism_file").read_only
        assert builder.describe_parameter("mechanism_file").read_only
    finally:
        driver.destroy_node()
        builder.destroy_node()


# --- fuzzing --------------------------------------------------------------------------------

HOSTILE = [math.nan, math.inf, -math.inf, 1e308, -1e308, 1e100, 5e-324, -0.0, -1.0, 50.0,
           50.0001]
number = st.one_of(st.floats(0.0, 50.0), st.sampled_from(HOSTILE))
angle = st.one_of(st.floats(-math.pi, math.pi), st.sampled_from(HOSTILE))
FUZZ_RESETS = FUZZ_GOALS = 150
FUZZ_SETTINGS = settings(deadline=None, database=None,
                         suppress_health_check=[HealthCheck.too_slow])


def _serves_a_good_goal(rig):
    assert rig.reset(Q1).success
    good = _line(Q1[:3], np.array(Q1[:3]) + [0.0, 0.25, 0.0], 1.0)
    assert rig.execute(good).error_code == _Result.SUCCESS


@pytest.mark.slow
def test_fuzzed_resets_get_a_code_and_the_driver_serves_after(rig):
    outcomes = collections.Counter()

    @settings(FUZZ_SETTINGS, max_examples=FUZZ_RESETS)
    @given(configuration=st.one_of(st.tuples(st.just(17.0), number, number, angle),
                                   st.tuples(number, number, number, angle),
                                   st.tuples(number, angle), st.tuples(number, number, number,
                                                                       number, angle)),
           names=st.one_of(st.just([]), st.just([]), st.permutations(NAMES),
                           st.lists(st.sampled_from(NAMES + ["theta1", "th1", ""]),
                                    max_size=4)))
    def fuzz(configuration, names):
        response = rig.reset(configuration, names)
        assert response.error_code in RESET_CODES
        assert response.success == (response.error_code == ResetDriver.Response.ERROR_NONE)
        assert response.success or response.error_msg
        outcomes[RESET_CODES[response.error_code]] += 1

    fuzz()
    print(f"\ndriver reset fuzz outcomes: {dict(sorted(outcomes.items()))}")
    assert sum(outcomes.values()) >= FUZZ_RESETS
    _serves_a_good_goal(rig)


@st.composite
def goals(draw):
    n = draw(st.integers(0, 6))
    start = np.array(Q1[:3])
    points = [start] + [start + draw(st.tuples(*[st.floats(-0.3, 0.3)] * 3))
                        for _ in range(n - 1)]
    points = [[draw(st.one_of(st.just(v), st.sampled_from(HOSTILE))) if draw(st.booleans())
               and draw(st.integers(0, 4)) == 0 else v for v in p] for p in points[:n]]
    seconds = st.one_of(st.floats(0.0, 2.0), st.sampled_from([0.0, 1e-9, -1.0, 3e9]))
    stamps = sorted(draw(seconds) for _ in range(n)) if draw(st.booleans()) else [
        draw(seconds) for _ in range(n)]
    names = draw(st.sampled_from([NAMES, NAMES, ["rho1", "rho2"], ["a", "b", "c"]]))
    return JointTrajectory(joint_names=names, points=[
        JointTrajectoryPoint(positions=[float(v) for v in p],
                             time_from_start=Duration(sec=int(math.floor(t)),
                                                      nanosec=int((t % 1) * 1e9) % 10**9))
        for p, t in zip(points, stamps)])


def _verdict(driver, trajectory):
    """What the driver's goal check says of ``trajectory`` as the driver
    receives it, from the driver's joints and parameters now."""
    # The goal as it crosses the wire: a sec beyond int32 (3e9 s) wraps.
    received = deserialize_message(serialize_message(trajectory), JointTrajectory)
    return check_trajectory(
        **trajectory_fields(received), mechanism_joints=driver.mechanism.joint_names,
        ranges=driver.limits, max_velocity=driver.get_parameter("max_velocity").value,
        current_joints=driver.state()[0],
        start_tolerance=driver.get_parameter("start_tolerance").value)


@pytest.mark.slow
def test_fuzzed_goals_are_accepted_as_the_goal_check_says_and_end_with_a_code(rig):
    outcomes = collections.Counter()

    @settings(FUZZ_SETTINGS, max_examples=FUZZ_GOALS)
    @given(trajectory=goals())
    def fuzz(trajectory):
        if not rig.driver.state()[0].tolist() == list(Q1[:3]):
            assert rig.reset(Q1).success
        # No goal executes between two examples: each waits for its result.
        expected = _verdict(rig.driver, trajectory)
        handle = rig.send(trajectory)
        assert handle.accepted == expected.accepted, expected
        if not handle.accepted:
            outcomes["rejected: " + expected.code.value] += 1
            return
        result = rig.client.get_result(handle, 60.0).result
        assert result.error_code in RESULT_CODES
        assert result.error_code != _Result.INVALID_TRAJECTORY, result.error_msg
        outcomes[RESULT_CODES[result.error_code]] += 1

    fuzz()
    print(f"\ndriver goal fuzz outcomes: {dict(sorted(outcomes.items()))}")
    assert sum(outcomes.values()) >= FUZZ_GOALS
    _serves_a_good_goal(rig)
