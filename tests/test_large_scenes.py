"""Scenes as large as anyone on the domain may publish: a polygon of 10,000
vertices and 10,000 discs, far more than a scene may hold, are refused by
the planner and the driver at once, and the largest scene allowed (a
polygon of rpr3_gwr_core.world.scene.MAX_VERTICES vertices in the paper's
workspace, beside MAX_OBSTACLES - 1 discs) is taken; meanwhile the driver
publishes joint states at its rate and the planner answers plan requests.
Real rclpy and Fast DDS; the builder, the planner and the driver are
processes, as a user runs them (in one process they would share one
interpreter lock, and a MultiThreadedExecutor spinning the driver beside a
subscriber fires its 100 Hz timer at half that rate or less).  The driver's rate is
counted by the stamps of its joint states, which a reliable listener in
this process keeps however late it takes them."""

import math
import time

from geometry_msgs.msg import Point, Point32, Polygon
import pytest
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from rclpy.time import Time
from rpr3_gwr_core.world.scene import MAX_OBSTACLES, MAX_VERTICES
from rpr3_gwr_msgs.msg import Obstacle, Scene
from rpr3_gwr_nodes.client import configuration
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from sensor_msgs.msg import JointState

from node_processes import node_processes
from spun_nodes import SpunNodes

TIMEOUT = 60.0
RATE = 100.0
# How long each scene is watched [s].
WATCH = 3.0
# The longest the driver may go without publishing its joint state [s]: a
# scene read in the driver's thread stopped it for minutes, and on a loaded
# two-core runner its timer has been seen a second late.
MAX_GAP = 2.0
# Deep enough to hold every joint state of a watch.
STAMPS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                        reliability=ReliabilityPolicy.RELIABLE)
START = configuration([17.0, 12.0, 18.0], math.radians(122.82))
GOAL = configuration([17.0, 10.0, 25.0], math.radians(-24.24))


def _polygon(oid, count, center, radius):
    """A regular polygon of ``count`` vertices."""
    return Obstacle(id=oid, type=Obstacle.POLYGON, polygon=Polygon(points=[
        Point32(x=center[0] + radius * math.cos(2 * math.pi * k / count),
                y=center[1] + radius * math.sin(2 * math.pi * k / count))
        for k in range(count)]))


def _discs(count, first=0):
    """Small discs on a line below the base, clear of the mechanism."""
    return [Obstacle(id=f"disc{first + k}", type=Obstacle.DISC,
                     center=Point(x=-40.0 + 80.0 * k / count, y=-30.0), radius=0.01)
            for k in range(count)]


SCENES = {
    "a polygon of 10,000 vertices": (Scene(obstacles=[_polygon("ring", 10_000, (8.0, 30.0), 6.0)]),
                                     False),
    # A 560 KB message, refused unread.
    "10,000 discs": (Scene(obstacles=_discs(10_000)), False),
    "the largest scene allowed": (Scene(obstacles=[_polygon("ring", MAX_VERTICES, (8.0, 30.0),
                                                            6.0), *_discs(MAX_OBSTACLES - 1)]),
                                  True),
}


NAMESPACE = "large_scenes"
NODES = (("roadmap_builder", []), ("planner", ["plan_workers:=0"]),
         ("rpr3_driver", [f"rate:={RATE}"]))


class _Rig(SpunNodes):
    def __init__(self, context):
        listener = Node("large_scenes_listener", context=context, namespace=NAMESPACE)
        self.stamps = []
        self.scene_pub = listener.create_publisher(Scene, "scene", LATCHED_QOS)
        # The driver's own stamps, kept however late this process takes them:
        # the rate is the driver's, not this process's.
        listener.create_subscription(
            JointState, "joint_states",
            lambda msg: self.stamps.append(Time.from_msg(msg.header.stamp).nanoseconds * 1e-9),
            STAMPS_QOS)
        super().__init__(context, [listener], "large_scenes_client", namespace=NAMESPACE)
        self.client.wait_until_ready(timeout_sec=TIMEOUT)
        deadline = time.monotonic() + TIMEOUT
        while not self.stamps:
            assert time.monotonic() < deadline, "no joint states from the driver"
            time.sleep(0.05)


def _refusals(folder):
    """Scenes the planner and the driver refused, by their logs."""
    return tuple((folder / f"{name}.log").read_text().count("refusing a scene")
                 for name in ("planner", "rpr3_driver"))


def _watch(rig, publish=None):
    """Plan now and then for ``WATCH`` seconds, ``publish()`` called first;
    the joint states received and the longest gap between two, and the
    longest plan's latency [s]."""
    begin = rig.client.get_clock().now().nanoseconds * 1e-9
    if publish is not None:
        publish()
    latencies = []
    while rig.client.get_clock().now().nanoseconds * 1e-9 - begin < WATCH:
        sent = time.monotonic()
        rig.client.plan(START, GOAL, timeout_sec=TIMEOUT)
        latencies.append(time.monotonic() - sent)
        time.sleep(0.1)
    # The last stamps of the watch may still be on their way.
    time.sleep(0.5)
    stamps = [begin] + [t for t in rig.stamps if begin <= t < begin + WATCH] + [begin + WATCH]
    return len(stamps) - 2, max(b - a for a, b in zip(stamps, stamps[1:])), max(latencies)


@pytest.mark.slow
def test_large_scenes_stall_neither_the_driver_nor_the_planner(ros_context, tmp_path):
    with node_processes(tmp_path, NODES, NAMESPACE):
        rig = _Rig(ros_context)
        try:
            assert rig.client.plan(START, GOAL, timeout_sec=TIMEOUT).success
            # The rate the machine gives the driver while the planner plans,
            # without a new scene: the test may share the cores.
            baseline, _, _ = _watch(rig)
            for name, (scene, taken) in SCENES.items():
                refused = _refusals(tmp_path)
                scene.header.stamp = rig.client.get_clock().now().to_msg()
                # Serialized before the watch, which it would delay.
                data = serialize_message(scene)
                received, gap, latency = _watch(rig, lambda: rig.scene_pub.publish(data))
                print(f"\n{name}: {received} joint states in {WATCH} s ({baseline} without "
                      f"it), longest gap {gap:.3f} s, slowest plan {latency:.3f} s")
                assert received >= 0.5 * baseline and gap < MAX_GAP, \
                    (name, received, baseline, gap)
                assert latency < 1.0, (name, latency)
                if taken:
                    rig.client.set_scene(scene, timeout_sec=TIMEOUT)
                    assert _refusals(tmp_path) == refused, name
                else:
                    deadline = time.monotonic() + 5.0
                    while _refusals(tmp_path) != (refused[0] + 1, refused[1] + 1):
                        assert time.monotonic() < deadline, (name, _refusals(tmp_path))
                        time.sleep(0.05)
        finally:
            rig.close()
