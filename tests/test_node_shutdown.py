"""The planner as a real process, stopped by SIGINT while requests are in
flight: the requests it took are answered, it exits with 0, and its log has
no error and no "exception was never retrieved"."""

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

PLANNER = (pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes"
           / "lib" / "rpr3_gwr_nodes" / "planner")
D = math.radians


def test_sigint_with_requests_in_flight_exits_cleanly(ros_context):
    process = subprocess.Popen([str(PLANNER)], env=os.environ.copy(), stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    node = Node("shutdown_test_client", context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    futures = []
    try:
        roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.25))
        field_msg, roadmap_msg = roadmap_to_msgs(roadmap, Header())
        node.create_publisher(NSolutionField, "field", LATCHED_QOS).publish(field_msg)
        node.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS).publish(roadmap_msg)
        client = node.create_client(PlanPath, "plan_path")
        assert client.wait_for_service(timeout_sec=30.0), "the planner did not come up"
        request = PlanPath.Request(
            start=Configuration(rho1=17.0, rho2=12.0, rho3=18.0, alpha=D(122.82)),
            goal=Configuration(rho1=17.0, rho2=10.0, rho3=25.0, alpha=D(-24.24)), smooth=True)
        # The first answer shows the roadmap arrived; then keep it busy.
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline:
            first = client.call_async(request)
            while not first.done() and time.monotonic() < deadline:
                time.sleep(0.02)
            if first.done() and first.result().success:
                break
        assert first.done() and first.result().success, "the planner never planned"
        for _ in range(40):
            futures.append(client.call_async(request))
            time.sleep(0.01)
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=60.0)
    finally:
        if process.poll() is None:
            process.kill()
        executor.shutdown()
        spinner.join(timeout=10.0)
        node.destroy_node()
    assert process.returncode == 0, output
    assert "never retrieved" not in output, output
    assert "[ERROR]" not in output and "Traceback" not in output, output
    answered = [f.result() for f in futures if f.done()]
    assert answered and all(r.success for r in answered), output
