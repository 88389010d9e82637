"""The planner reports readiness only once its planner is warmed up: until
then requests get ``ERROR_NO_ROADMAP`` (or, after a new roadmap, the previous
roadmap's answer) and ``ready`` stays clear; a first run with a cold numba
cache says it compiles the kernels before it says it is ready.  Real rclpy
and Fast DDS; the first run as a real process."""

import math
import os
import pathlib
import queue
import signal
import subprocess
import threading
import time

import pytest
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.planning import Planner
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_msgs.msg import NSolutionField, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.client import PlannerClient, configuration
from rpr3_gwr_nodes.conversions import roadmap_to_msgs
from rpr3_gwr_nodes.planner import PlannerNode
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from std_msgs.msg import Header

PLANNER = (pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes"
           / "lib" / "rpr3_gwr_nodes" / "planner")
D = math.radians
START = configuration([17.0, 12.0, 18.0], D(122.82))
GOAL = configuration([17.0, 10.0, 25.0], D(-24.24))
TIMEOUT = 60.0


def _plan(client):
    """The answer to the paper's first example, smoothed."""
    return client.plan(START, GOAL, timeout_sec=TIMEOUT)


def _roadmap_messages(sec):
    header = Header(frame_id="rpr3_base")
    header.stamp.sec = sec
    return roadmap_to_msgs(build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.25)), header)


def test_requests_wait_for_the_warm_up_of_each_roadmap(ros_context, monkeypatch):
    started, release = queue.Queue(), threading.Semaphore(0)
    warm_up = Planner.warm_up

    def held_warm_up(planner):
        started.put(planner)
        release.acquire(timeout=TIMEOUT)
        warm_up(planner)

    monkeypatch.setattr(Planner, "warm_up", held_warm_up)
    planner = PlannerNode(context=ros_context, namespace="readiness", parameter_overrides=[
        Parameter("plan_workers", value=0)])
    feeder = Node("roadmap_feeder", context=ros_context, namespace="readiness")
    publishers = (feeder.create_publisher(NSolutionField, "field", LATCHED_QOS),
                  feeder.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS))
    executor = MultiThreadedExecutor(num_threads=4, context=ros_context)
    for node in (planner, feeder):
        executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    client = PlannerClient("readiness_client", context=ros_context, namespace="readiness")
    try:
        for publisher, msg in zip(publishers, _roadmap_messages(1)):
            publisher.publish(msg)
        started.get(timeout=TIMEOUT)
        assert not planner.ready.is_set(), "ready before the warm-up"
        waiting = _plan(client)
        assert waiting.error_code == PlanPath.Response.ERROR_NO_ROADMAP, waiting.error_msg
        release.release()
        assert planner.ready.wait(TIMEOUT)
        first = _plan(client)
        assert first.success and first.roadmap_stamp.sec == 1, first.error_msg
        # A new roadmap: the previous one answers until the new one is warm.
        for publisher, msg in zip(publishers, _roadmap_messages(2)):
            publisher.publish(msg)
        started.get(timeout=TIMEOUT)
        meanwhile = _plan(client)
        assert meanwhile.success and meanwhile.roadmap_stamp.sec == 1, meanwhile.error_msg
        release.release()
        deadline = time.monotonic() + TIMEOUT
        while _plan(client).roadmap_stamp.sec != 2:
            assert time.monotonic() < deadline, "the new roadmap never answered"
            time.sleep(0.05)
    finally:
        release.release()
        client.destroy_node()
        executor.shutdown(timeout_sec=10.0)
        spinner.join(timeout=10.0)
        for node in (feeder, planner):
            node.destroy_node()


@pytest.mark.slow
def test_a_first_run_says_it_compiles_before_it_is_ready(ros_context, tmp_path):
    # An empty numba cache of its own: the planner process compiles every
    # kernel, as on a fresh clone.
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    process = subprocess.Popen([str(PLANNER)], env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    client = PlannerClient("first_run_client", context=ros_context)
    try:
        field_msg, roadmap_msg = _roadmap_messages(1)
        client.create_publisher(NSolutionField, "field", LATCHED_QOS).publish(field_msg)
        client.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS).publish(roadmap_msg)
        # Ready as the demo finds out: the planner answers from that roadmap.
        client.wait_until_ready(timeout_sec=3 * TIMEOUT)
        begin = time.monotonic()
        first = _plan(client)
        print(f"\nfirst plan after readiness on a cold cache: {time.monotonic() - begin:.3f} s")
        assert first.success, first.error_msg
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=TIMEOUT)
    finally:
        client.destroy_node()
        if process.poll() is None:
            process.kill()
            process.communicate(timeout=TIMEOUT)
    assert process.returncode == 0, output
    compiling = output.find("compiling the planner's kernels")
    assert compiling >= 0, output
    assert compiling < output.find("planning on a new roadmap"), output
