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

from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.planning import Planner
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_msgs.msg import Configuration, NSolutionField, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.conversions import roadmap_to_msgs
from rpr3_gwr_nodes.planner import PlannerNode
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from std_msgs.msg import Header

PLANNER = (pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes"
           / "lib" / "rpr3_gwr_nodes" / "planner")
D = math.radians
REQUEST = PlanPath.Request(
    start=Configuration(positions=[17.0, 12.0, 18.0], mode=D(122.82)),
    goal=Configuration(positions=[17.0, 10.0, 25.0], mode=D(-24.24)), smooth=True)
PROBE = PlanPath.Request(start=REQUEST.start, goal=REQUEST.start, feasibility_only=True)
TIMEOUT = 60.0


def _call(client, request, attempts=3, timeout=10.0):
    """The answer to ``request``, sent again if unanswered (a client's very
    first request may be, README)."""
    for _ in range(attempts):
        future = client.call_async(request)
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        if done.wait(timeout):
            return future.result()
        client.remove_pending_request(future)
    raise AssertionError(f"no answer to {attempts} requests")


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
    client_node = Node("readiness_client", context=ros_context, namespace="readiness")
    client = client_node.create_client(PlanPath, "plan_path")
    executor = MultiThreadedExecutor(num_threads=4, context=ros_context)
    for node in (planner, feeder, client_node):
        executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        assert client.wait_for_service(timeout_sec=TIMEOUT)
        for publisher, msg in zip(publishers, _roadmap_messages(1)):
            publisher.publish(msg)
        started.get(timeout=TIMEOUT)
        assert not planner.ready.is_set(), "ready before the warm-up"
        waiting = _call(client, REQUEST)
        assert waiting.error_code == PlanPath.Response.ERROR_NO_ROADMAP, waiting.error_msg
        release.release()
        assert planner.ready.wait(TIMEOUT)
        first = _call(client, REQUEST)
        assert first.success and first.roadmap_stamp.sec == 1, first.error_msg
        # A new roadmap: the previous one answers until the new one is warm.
        for publisher, msg in zip(publishers, _roadmap_messages(2)):
            publisher.publish(msg)
        started.get(timeout=TIMEOUT)
        meanwhile = _call(client, REQUEST)
        assert meanwhile.success and meanwhile.roadmap_stamp.sec == 1, meanwhile.error_msg
        release.release()
        deadline = time.monotonic() + TIMEOUT
        while _call(client, REQUEST).roadmap_stamp.sec != 2:
            assert time.monotonic() < deadline, "the new roadmap never answered"
            time.sleep(0.05)
    finally:
        release.release()
        executor.shutdown(timeout_sec=10.0)
        spinner.join(timeout=10.0)
        for node in (client_node, feeder, planner):
            node.destroy_node()


def test_a_first_run_says_it_compiles_before_it_is_ready(client_node, tmp_path):
    # An empty numba cache of its own: the planner process compiles every
    # kernel, as on a fresh clone.
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    process = subprocess.Popen([str(PLANNER)], env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    node = client_node
    try:
        field_msg, roadmap_msg = _roadmap_messages(1)
        node.create_publisher(NSolutionField, "field", LATCHED_QOS).publish(field_msg)
        node.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS).publish(roadmap_msg)
        client = node.create_client(PlanPath, "plan_path")
        assert client.wait_for_service(timeout_sec=3 * TIMEOUT), "the planner did not come up"
        # Ready as the demo finds out: an answer other than "no roadmap".
        deadline = time.monotonic() + 3 * TIMEOUT
        while _call(client, PROBE).error_code == PlanPath.Response.ERROR_NO_ROADMAP:
            assert time.monotonic() < deadline, "the planner never got ready"
            time.sleep(0.1)
        begin = time.monotonic()
        first = _call(client, REQUEST)
        print(f"\nfirst plan after readiness on a cold cache: {time.monotonic() - begin:.3f} s")
        assert first.success, first.error_msg
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=TIMEOUT)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate(timeout=TIMEOUT)
    assert process.returncode == 0, output
    compiling = output.find("compiling the planner's kernels")
    assert compiling >= 0, output
    assert compiling < output.find("planning on a new roadmap"), output
