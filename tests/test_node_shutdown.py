"""The planner as a real process, stopped by SIGINT while requests are in
flight: the requests it took are answered, it exits with 0, and its log has
no error and no "exception was never retrieved"; its plan workers end with
it, and also when it is killed."""

import contextlib
import math
import os
import pathlib
import signal
import subprocess
import threading
import time

from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_msgs.msg import Configuration, NSolutionField, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.conversions import roadmap_to_msgs
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from std_msgs.msg import Header

from process_tree import running, wait_for_children

PLANNER = (pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes"
           / "lib" / "rpr3_gwr_nodes" / "planner")
D = math.radians
REQUEST = PlanPath.Request(
    start=Configuration(rho1=17.0, rho2=12.0, rho3=18.0, alpha=D(122.82)),
    goal=Configuration(rho1=17.0, rho2=10.0, rho3=25.0, alpha=D(-24.24)), smooth=True)


@contextlib.contextmanager
def _planner_process(context):
    """A planner process fed a roadmap, once it planned, its plan workers
    started, and a client: ``(process, workers, client)``."""
    process = subprocess.Popen([str(PLANNER)], env=os.environ.copy(), stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    node = Node("shutdown_test_client", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.25))
        field_msg, roadmap_msg = roadmap_to_msgs(roadmap, Header())
        node.create_publisher(NSolutionField, "field", LATCHED_QOS).publish(field_msg)
        node.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS).publish(roadmap_msg)
        client = node.create_client(PlanPath, "plan_path")
        assert client.wait_for_service(timeout_sec=30.0), "the planner did not come up"
        # The first answer shows the roadmap arrived.
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline:
            first = client.call_async(REQUEST)
            while not first.done() and time.monotonic() < deadline:
                time.sleep(0.02)
            if first.done() and first.result().success:
                break
        assert first.done() and first.result().success, "the planner never planned"
        workers = wait_for_children(os.cpu_count(), parent=process.pid)
        assert len(workers) == os.cpu_count(), workers
        yield process, workers, client
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate(timeout=60.0)
        executor.shutdown()
        spinner.join(timeout=10.0)
        node.destroy_node()


def _ended(pids, timeout=10.0):
    deadline = time.monotonic() + timeout
    while any(running(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not any(running(pid) for pid in pids)


def test_sigint_with_requests_in_flight_exits_cleanly(ros_context):
    with _planner_process(ros_context) as (process, workers, client):
        futures = []
        for _ in range(40):
            futures.append(client.call_async(REQUEST))
            time.sleep(0.01)
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=60.0)
    assert process.returncode == 0, output
    assert "never retrieved" not in output, output
    assert "[ERROR]" not in output and "Traceback" not in output, output
    answered = [f.result() for f in futures if f.done()]
    assert answered and all(r.success for r in answered), output
    assert _ended(workers), "plan workers outlived the planner"


def test_plan_workers_end_when_the_planner_is_killed(ros_context):
    with _planner_process(ros_context) as (process, workers, _):
        process.kill()
        process.communicate(timeout=60.0)
        assert _ended(workers), "plan workers outlived the killed planner"
