"""The planner and the driver in a scene: scenes that block the paper's first
example, collide with its start or narrow its way, trajectories followed by
the core-independent reference of the core's tests, a planner that answers
while it switches scenes, a driver that stops before a collision, and
malformed scenes refused while the nodes keep serving.  Real rclpy and Fast
DDS, each rig's nodes in a namespace of their own."""

import collections
import itertools
import math
import pathlib
import threading
import time

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Point, Point32, Polygon
from hypothesis import HealthCheck, given, settings, strategies as st
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY
from rpr3_gwr_core.io.scene_file import load_scene
from rpr3_gwr_core.world import configuration_collision, scene_from_dict
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import JointRange, Obstacle, Scene
from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.conversions import scene_from_msg, scene_to_msg
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from rpr3_gwr_nodes.rpr3_driver import Rpr3Driver
from rpr3_gwr_nodes.scene_publisher import ScenePublisher
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from test_planner_service import PlannerUnderTest, check_sound, TIMEOUT
from test_world_reference import reference_blocked, reference_track, torus_platform

from spun_nodes import SpunNodes

D = math.radians
Q1, Q2 = (17.0, 12.0, 18.0, D(122.82)), (17.0, 10.0, 25.0, D(-24.24))
SCENES = pathlib.Path(__file__).resolve().parents[1] / "config" / "scenes"
BASE = np.array([PAPER_GEOMETRY.a1, PAPER_GEOMETRY.a2, PAPER_GEOMETRY.a3])
_Result = ExecuteTrajectory.Result
_stamps = itertools.count(1)


def _document(name):
    return yaml.safe_load((SCENES / f"{name}.yaml").read_text())


def _scene_msg(document):
    """A scene document as a message with a stamp of its own."""
    header = Header(frame_id="base")
    header.stamp.sec = next(_stamps)
    return scene_to_msg(scene_from_dict(document), header)


def _start_pose():
    """Q1's pose (x, y, alpha): the direct-kinematic solution nearest its alpha."""
    solutions = PAPER_GEOMETRY.direct_kinematics(list(Q1[:3]))
    return solutions[np.argmin(np.abs(np.angle(np.exp(1j * (solutions[:, 2] - Q1[3])))))]


def _wait_until(condition, timeout=TIMEOUT, what="a condition"):
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


class SceneFeed:
    """A publisher of scenes on a rig's ``scene`` topic and a reader of a
    node's ``~/current_scene`` echo, on a node the rig's executor spins: the
    echoes of the planner and of the driver, and the refusals (no echo),
    are observed as they come."""

    def __init__(self, node, echo_topic):
        self.publisher = node.create_publisher(Scene, "scene", LATCHED_QOS)
        self.echoes = []
        node.create_subscription(Scene, echo_topic, self.echoes.append, LATCHED_QOS)

    def apply(self, msg, timeout=60.0):
        """Publish a scene and wait until the node echoes it (it plans or
        checks with it then)."""
        self.publisher.publish(msg)
        _wait_until(lambda: any(e.header.stamp == msg.header.stamp for e in self.echoes),
                    timeout, "the scene's echo")
        return self.echoes[-1]

    def refuse(self, node, msg):
        """Publish a scene the node must refuse, and wait until it did."""
        refused = node.refused_scenes
        self.publisher.publish(msg)
        _wait_until(lambda: node.refused_scenes > refused, TIMEOUT, "the scene's refusal")
        assert all(e.header.stamp != msg.header.stamp for e in self.echoes)


@pytest.fixture(scope="module")
def rig(module_context):
    # One plan worker: with a scene, requests must plan in the node's process.
    running = PlannerUnderTest(module_context, "scene_rig", parameter_overrides=[
        Parameter("plan_workers", value=1)])
    running.scenes = SceneFeed(running.feeder, "planner/current_scene")
    try:
        yield running
    finally:
        running.close()


def test_a_scene_that_cuts_the_first_example_answers_blocked(rig):
    echo = rig.scenes.apply(_scene_msg(_document("paper_example1_blocked")))
    assert [o.id for o in echo.obstacles] == ["post"] and echo.header.frame_id == "base"
    response = rig.plan(Q1, Q2)
    assert response.error_code == PlanPath.Response.ERROR_INFEASIBLE, response.error_msg
    assert response.feasibility == PlanPath.Response.FEASIBILITY_BLOCKED
    assert "blocked" in response.error_msg
    only = rig.plan(Q1, Q2, feasibility_only=True)
    assert only.feasibility == PlanPath.Response.FEASIBILITY_BLOCKED


def test_an_obstacle_on_the_starts_leg_is_a_collision_naming_it(rig):
    on_leg_2 = 0.5 * (BASE[1] + torus_platform(_start_pose())[1])
    rig.scenes.apply(_scene_msg({"obstacles": [
        {"id": "on_leg_2", "disc": {"center": on_leg_2.tolist(), "radius": 0.2}}]}))
    response = rig.plan(Q1, Q2)
    assert response.error_code == PlanPath.Response.ERROR_IN_COLLISION, response.error_msg
    assert "start" in response.error_msg and "leg2" in response.error_msg \
        and "on_leg_2" in response.error_msg
    check_sound(PlanPath.Request(), response, rig.stamp, rig.default_limits())


def _followed_bodies(response):
    """The platform triangles along a trajectory, followed in small steps by
    the reference (not the core's continuation)."""
    joints = np.array([p.positions for p in response.trajectory.points])
    poses = np.array([p.values for p in response.poses])
    track = reference_track(joints, poses[0])
    assert np.allclose(track[-1][:2], poses[-1][:2], atol=1e-6)
    return np.array([torus_platform(p) for p in track])


def _request(**options):
    request = PlanPath.Request(**options)
    request.start.positions, request.start.mode = list(Q1[:3]), Q1[3]
    request.goal.positions, request.goal.mode = list(Q2[:3]), Q2[3]
    return request


def _on_the_way(response):
    """A post where a trajectory's platform passes half way (by the reference)."""
    bodies = _followed_bodies(response)
    middle = bodies[len(bodies) // 2].mean(axis=0)
    document = {"obstacles": [{"id": "on_the_way",
                               "disc": {"center": middle.tolist(), "radius": 0.5}}]}
    assert reference_blocked(bodies, document).any()
    return document


@pytest.mark.parametrize("smooth", [False, True])
@pytest.mark.parametrize("name", ["paper_narrowed", "on_the_way"])
def test_a_plan_in_a_scene_keeps_every_body_off_its_obstacles(rig, name, smooth):
    """Each trajectory, followed in small steps by the reference, keeps off
    the obstacles: those of the narrowing scene, and a post put where the
    unsmoothed plan without a scene passes."""
    request = _request(skip_smoothing=not smooth)
    if name == "on_the_way":
        rig.scenes.apply(_scene_msg({}))
        free = rig.call(_request(skip_smoothing=True))
        assert free.success, free.error_msg
        document = _on_the_way(free)
    else:
        document = _document(name)
    rig.scenes.apply(_scene_msg(document))
    response = rig.call(request)
    assert response.success, response.error_msg
    check_sound(request, response, rig.stamp, rig.default_limits())
    assert not reference_blocked(_followed_bodies(response), document).any()
    feasibility = rig.call(_request(feasibility_only=True))
    assert feasibility.feasibility in (PlanPath.Response.FEASIBILITY_CONNECTED,
                                       PlanPath.Response.FEASIBILITY_SAME_PATCH)


def test_a_scene_for_another_mechanism_is_refused_and_the_previous_one_stays(rig):
    rig.scenes.apply(_scene_msg(_document("paper_example1_blocked")))
    for limits in ({"strokes": {"rho9": [0.0, 10.0]}}, {"passive": {"elbow1": [0.0, 1.0]}}):
        rig.scenes.refuse(rig.planner, _scene_msg({"limits": limits}))
        response = rig.plan(Q1, Q2)
        assert response.feasibility == PlanPath.Response.FEASIBILITY_BLOCKED, response.error_msg
    # The paper's limits are its mechanism's: taken.
    echo = rig.scenes.apply(_scene_msg(_document("paper_limits")))
    assert {r.name for r in echo.passive_ranges} == {"base1", "platform2"}
    assert {r.name for r in echo.strokes} == {"rho1", "rho2", "rho3"}
    # A stroke that the goal leaves.
    rig.scenes.apply(_scene_msg({"limits": {"strokes": {"rho3": [3.0, 20.0]}}}))
    response = rig.plan(Q1, Q2)
    assert response.error_code == PlanPath.Response.ERROR_IN_COLLISION, response.error_msg
    assert "goal" in response.error_msg and "rho3" in response.error_msg


def test_the_planner_answers_in_the_previous_scene_while_it_switches(ros_context):
    """A fresh planner (its first scene indexes the roadmap, a second or
    more): feasibility requests sent meanwhile are answered without the
    scene, then with it, never the other way round."""
    rig = PlannerUnderTest(ros_context, "switching", parameter_overrides=[
        Parameter("plan_workers", value=0)])
    try:
        feed = SceneFeed(rig.feeder, "planner/current_scene")
        msg = _scene_msg(_document("paper_example1_blocked"))
        feed.publisher.publish(msg)
        answers = []
        while not any(e.header.stamp == msg.header.stamp for e in feed.echoes):
            answers.append(rig.plan(Q1, Q2, feasibility_only=True).feasibility)
            assert len(answers) < 100000
        after = rig.plan(Q1, Q2, feasibility_only=True).feasibility
    finally:
        rig.close()
    connected, blocked = (PlanPath.Response.FEASIBILITY_CONNECTED,
                          PlanPath.Response.FEASIBILITY_BLOCKED)
    assert set(answers) <= {connected, blocked}
    assert answers and answers[0] == connected, answers
    switched = answers.index(blocked) if blocked in answers else len(answers)
    assert all(a == blocked for a in answers[switched:]) and after == blocked
    print(f"\n{switched} answer(s) in the previous scene during the switch")


def test_a_scene_published_before_the_roadmap_is_planned_in(ros_context):
    """A scene latched before the planner starts waits for its first roadmap."""
    early = Node("early_scene", context=ros_context, namespace="early")
    publisher = early.create_publisher(Scene, "scene", LATCHED_QOS)
    msg = _scene_msg(_document("paper_example1_blocked"))
    publisher.publish(msg)
    try:
        rig = PlannerUnderTest(ros_context, "early", parameter_overrides=[
            Parameter("plan_workers", value=0)])
        try:
            feed = SceneFeed(rig.feeder, "planner/current_scene")
            _wait_until(lambda: any(e.header.stamp == msg.header.stamp for e in feed.echoes),
                        what="the scene's echo")
            response = rig.plan(Q1, Q2)
            assert response.feasibility == PlanPath.Response.FEASIBILITY_BLOCKED, \
                response.error_msg
        finally:
            rig.close()
    finally:
        early.destroy_node()


# --- the driver ------------------------------------------------------------------------------

class DriverRig(SpunNodes):
    """A driver (from Q1, the paper's start) in a namespace of its own, its
    scene feed, and listeners of its state and markers."""

    def __init__(self, context):
        self.driver = Rpr3Driver(context=context, namespace="scene_driver", parameter_overrides=[
            Parameter("time_scale", value=20.0)])
        self.listener = Node("scene_driver_listener", context=context,
                             namespace="scene_driver")
        self.scenes = SceneFeed(self.listener, "rpr3_driver/current_scene")
        self.states, self.diagnostics, self.markers, self.obstacles = [], [], [], []
        for kind, topic, store, qos in (
                (JointState, "joint_states", self.states, 10),
                (DiagnosticArray, "/diagnostics", self.diagnostics, 10),
                (MarkerArray, "mechanism_markers", self.markers, 10),
                (MarkerArray, "scene_markers", self.obstacles, LATCHED_QOS)):
            self.listener.create_subscription(kind, topic, store.append, qos)
        super().__init__(context, (self.driver, self.listener), "scene_driver_client",
                         namespace="scene_driver")

    def execute(self, trajectory):
        return self.client.execute(trajectory, timeout_sec=120.0).result


@pytest.fixture(scope="module")
def driver_rig(module_context):
    running = DriverRig(module_context)
    try:
        yield running
    finally:
        running.close()


@pytest.mark.slow
def test_the_driver_stops_before_an_obstacle_put_on_the_planned_way(rig, driver_rig):
    rig.scenes.apply(_scene_msg({}))
    response = rig.plan(Q1, Q2)
    assert response.success, response.error_msg
    # A post where the platform passes half way, after the plan was made.
    document = _on_the_way(response)
    driver_rig.scenes.apply(_scene_msg(document))
    _wait_until(lambda: any(m.ns == "obstacles" and m.type == Marker.CYLINDER
                            for a in driver_rig.obstacles for m in a.markers),
                what="the obstacle's marker")
    result = driver_rig.execute(response.trajectory)
    assert result.error_code == _Result.COLLISION_ABORT, result.error_msg
    assert "on_the_way" in result.error_msg and "holding" in result.error_msg
    # Where it holds, the joints it reports are free of collision, by the
    # reference and by the core.
    seen = len(driver_rig.states)
    _wait_until(lambda: len(driver_rig.states) > seen + 2, what="joint states")
    legs = np.array(driver_rig.states[-1].position[:3])
    pose = np.array(result.final_pose.values)
    held = torus_platform(pose)
    np.testing.assert_allclose(np.linalg.norm(held - BASE, axis=1), legs, atol=1e-7)
    assert not reference_blocked(held[None], document)[0]
    assert configuration_collision(PAPER_GEOMETRY, scene_from_dict(document), legs, pose) is None
    assert np.linalg.norm(legs - np.array(Q2[:3])) > 0.5, "it did not stop on the way"
    # The body that would have collided is drawn, named in the reason.
    seen = len(driver_rig.markers)
    _wait_until(lambda: len(driver_rig.markers) > seen + 2, what="markers")
    highlight = {m.ns: m for m in driver_rig.markers[-1].markers}["collision"]
    assert highlight.action == Marker.ADD and len(highlight.points) >= 2
    assert any(name in result.error_msg for name in ("leg1", "leg2", "leg3", "platform"))
    # Diagnostics say ERROR while it holds, with the reason.
    seen = len(driver_rig.diagnostics)
    _wait_until(lambda: len(driver_rig.diagnostics) > seen, what="diagnostics")
    status = driver_rig.diagnostics[-1].status[0]
    assert status.level == DiagnosticStatus.ERROR and "on_the_way" in status.message


# --- the scene publisher ---------------------------------------------------------------------

def test_the_scene_publisher_publishes_its_file_and_refuses_bad_ones(ros_context, tmp_path):
    path = str(SCENES / "paper_narrowed.yaml")
    publisher = ScenePublisher(context=ros_context, namespace="published",
                               parameter_overrides=[Parameter("scene_file", value=path)])
    listener = Node("scene_listener", context=ros_context, namespace="published")
    got = []
    listener.create_subscription(Scene, "scene", got.append, LATCHED_QOS)
    executor = MultiThreadedExecutor(num_threads=2, context=ros_context)
    for node in (publisher, listener):
        executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    try:
        _wait_until(lambda: got, what="the published scene")
        assert got[-1].header.frame_id == "base"
        assert scene_from_msg(got[-1]).to_dict() == load_scene(path).to_dict()
        bad = tmp_path / "bad.yaml"
        bad.write_text("obstacles: [{id: post, disc: {center: [0, 0], radius: -1}}]\n")
        for refused in (str(bad), str(tmp_path / "missing.yaml")):
            result = publisher.set_parameters([Parameter("scene_file", value=refused)])[0]
            assert not result.successful and result.reason
        assert publisher.get_parameter("scene_file").value == path
        assert publisher.set_parameters([Parameter("scene_file", value="")])[0].successful
        _wait_until(lambda: not got[-1].obstacles, what="no scene")
    finally:
        executor.shutdown(timeout_sec=10.0)
        thread.join(timeout=10.0)
        listener.destroy_node()
        publisher.destroy_node()


# --- malformed scenes ------------------------------------------------------------------------

def _disc(oid="disc", x=40.0, y=40.0, radius=1.0):
    return Obstacle(id=oid, type=Obstacle.DISC, center=Point(x=x, y=y), radius=radius)


def _polygon(points, oid="polygon"):
    return Obstacle(id=oid, type=Obstacle.POLYGON,
                    polygon=Polygon(points=[Point32(x=float(x), y=float(y)) for x, y in points]))


SQUARE = [(30.0, 30.0), (34.0, 30.0), (34.0, 34.0), (30.0, 34.0)]
MALFORMED = {
    "nan centre": lambda: Scene(obstacles=[_disc(x=math.nan)]),
    "inf radius": lambda: Scene(obstacles=[_disc(radius=math.inf)]),
    "negative radius": lambda: Scene(obstacles=[_disc(radius=-1.0)]),
    "zero radius": lambda: Scene(obstacles=[_disc(radius=0.0)]),
    "nan vertex": lambda: Scene(obstacles=[_polygon([(math.nan, 0.0)] + SQUARE[1:])]),
    "two vertices": lambda: Scene(obstacles=[_polygon(SQUARE[:2])]),
    "collinear polygon": lambda: Scene(obstacles=[_polygon([(0, 40), (1, 41), (2, 42)])]),
    "crossing edges": lambda: Scene(obstacles=[_polygon([SQUARE[0], SQUARE[2], SQUARE[1],
                                                        SQUARE[3]])]),
    "no shape": lambda: Scene(obstacles=[Obstacle(id="none")]),
    "unknown shape": lambda: Scene(obstacles=[Obstacle(id="box", type=7)]),
    "no id": lambda: Scene(obstacles=[_disc(oid="")]),
    "one id twice": lambda: Scene(obstacles=[_disc(), _disc(x=-40.0)]),
    "other frame": lambda: Scene(header=Header(frame_id="map"), obstacles=[_disc()]),
    "unknown stroke": lambda: Scene(strokes=[JointRange(name="rho4", min=1.0, max=2.0)]),
    "unknown passive": lambda: Scene(passive_ranges=[JointRange(name="theta1", min=0.0,
                                                                max=1.0)]),
    "stroke twice": lambda: Scene(strokes=[JointRange(name="rho2", min=1.0, max=40.0)] * 2),
    "min above max": lambda: Scene(strokes=[JointRange(name="rho2", min=40.0, max=1.0)]),
    "nan stroke": lambda: Scene(strokes=[JointRange(name="rho2", min=math.nan, max=1.0)]),
    "passive over a turn": lambda: Scene(passive_ranges=[JointRange(name="base1", min=0.0,
                                                                    max=7.0)]),
    "negative clearance": lambda: Scene(obstacles=[_disc()], obstacle_clearance=-0.1),
    "nan clearance": lambda: Scene(obstacles=[_disc()], obstacle_clearance=math.nan),
}
FUZZ_PLANNER_SCENES, FUZZ_DRIVER_SCENES = 60, 40


@st.composite
def malformed_scenes(draw):
    """A malformed scene, its defect among sound obstacles and limits."""
    kind = draw(st.sampled_from(sorted(MALFORMED)))
    msg = MALFORMED[kind]()
    sound = [_disc("far", draw(st.floats(40.0, 45.0)), draw(st.floats(40.0, 45.0)),
                   draw(st.floats(0.1, 2.0))),
             _polygon([(x - 40.0, y) for x, y in SQUARE], "plate")]
    msg.obstacles = draw(st.permutations(list(msg.obstacles) + draw(
        st.lists(st.sampled_from(sound), max_size=2, unique_by=lambda o: o.id))))
    if draw(st.booleans()) and kind not in ("stroke twice", "unknown stroke", "min above max",
                                            "nan stroke"):
        msg.strokes = list(msg.strokes) + [JointRange(name="rho3", min=2.0, max=48.0)]
    msg.header.stamp.sec = next(_stamps)
    return kind, msg


@pytest.mark.parametrize("kind", sorted(MALFORMED))
def test_each_kind_of_malformed_scene_is_refused_by_both_nodes(rig, driver_rig, kind):
    for node, feed in ((rig.planner, rig.scenes), (driver_rig.driver, driver_rig.scenes)):
        msg = MALFORMED[kind]()
        msg.header.stamp.sec = next(_stamps)
        feed.refuse(node, msg)


@pytest.mark.slow
def test_malformed_scenes_are_refused_and_the_planner_plans_on(rig):
    outcomes = collections.Counter()

    @settings(max_examples=FUZZ_PLANNER_SCENES, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(case=malformed_scenes())
    def fuzz(case):
        kind, msg = case
        rig.scenes.refuse(rig.planner, msg)
        outcomes[kind] += 1
        request = _request(feasibility_only=True)
        check_sound(request, rig.call(request), rig.stamp, rig.default_limits())

    fuzz()
    print(f"\nmalformed scenes the planner refused: {dict(sorted(outcomes.items()))}")
    assert sum(outcomes.values()) >= FUZZ_PLANNER_SCENES
    rig.scenes.apply(_scene_msg(_document("paper_narrowed")))
    assert rig.plan(Q1, Q2).success


@pytest.mark.slow
def test_malformed_scenes_are_refused_by_the_driver_and_it_takes_a_good_one_after(driver_rig):
    outcomes = collections.Counter()

    @settings(max_examples=FUZZ_DRIVER_SCENES, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(case=malformed_scenes())
    def fuzz(case):
        kind, msg = case
        driver_rig.scenes.refuse(driver_rig.driver, msg)
        outcomes[kind] += 1

    fuzz()
    print(f"\nmalformed scenes the driver refused: {dict(sorted(outcomes.items()))}")
    assert sum(outcomes.values()) >= FUZZ_DRIVER_SCENES
    echo = driver_rig.scenes.apply(_scene_msg(_document("paper_narrowed")))
    assert {o.id for o in echo.obstacles} == {"post", "plate"}


@pytest.mark.slow
def test_a_mechanism_file_with_legs_in_one_layer_keeps_them_apart_without_a_scene(
        module_context, tmp_path):
    # The paper's 3-RPR, its legs in one layer: at the first example's goal
    # legs 1 and 3 cross (the core's reference test measures it).
    document = yaml.safe_load((SCENES.parent / "paper_3rpr.yaml").read_text())
    document["bodies"] = {"leg_layers": [1, 1, 1]}
    path = tmp_path / "coplanar_3rpr.yaml"
    path.write_text(yaml.safe_dump(document))
    running = PlannerUnderTest(module_context, "coplanar_rig", parameter_overrides=[
        Parameter("plan_workers", value=1), Parameter("mechanism_file", value=str(path))])
    try:
        response = running.plan(Q1, Q2)
        assert response.error_code == PlanPath.Response.ERROR_IN_COLLISION, response.error_msg
        assert "goal" in response.error_msg and "leg1" in response.error_msg \
            and "leg3" in response.error_msg
        # Its first example's reverse, from the same goal: the same answer.
        assert running.plan(Q2, Q1).error_code == PlanPath.Response.ERROR_IN_COLLISION
    finally:
        running.close()
