"""The planner as a real process, stopped by SIGINT or SIGTERM while requests
are in flight: every request sent before the signal is answered, it exits
with 0, and its log has no error and no "exception was never retrieved"; its
plan workers end with it, and also when it is killed."""

import contextlib
import ctypes
import math
import os
import pathlib
import signal
import subprocess
import time

import pytest
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_msgs.msg import Configuration, NSolutionField, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.conversions import roadmap_to_msgs
from rpr3_gwr_nodes.profiles import LATCHED_QOS, SERVICE_QOS
from std_msgs.msg import Header

from process_tree import running, wait_for_children

PLANNER = (pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes"
           / "lib" / "rpr3_gwr_nodes" / "planner")
D = math.radians
REQUEST = PlanPath.Request(
    start=Configuration(positions=[17.0, 12.0, 18.0], mode=D(122.82)),
    goal=Configuration(positions=[17.0, 10.0, 25.0], mode=D(-24.24)))


@contextlib.contextmanager
def _planner_process(node):
    """A planner process fed a roadmap by ``node``, once it planned, its plan
    workers started, and a client: ``(process, workers, client)``."""
    process = subprocess.Popen([str(PLANNER)], env=os.environ.copy(), stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    try:
        roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.25))
        field_msg, roadmap_msg = roadmap_to_msgs(roadmap, Header())
        node.create_publisher(NSolutionField, "field", LATCHED_QOS).publish(field_msg)
        node.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS).publish(roadmap_msg)
        client = node.create_client(PlanPath, "plan_path", qos_profile=SERVICE_QOS)
        assert client.wait_for_service(timeout_sec=30.0), "the planner did not come up"
        # The first plan shows the planner ready: after tens of seconds when
        # a cold numba cache (a first run, a changed core) has it compile.
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline:
            first = client.call_async(REQUEST)
            retry = min(deadline, time.monotonic() + 10.0)  # a first request may be lost
            while not first.done() and time.monotonic() < retry:
                time.sleep(0.02)
            if first.done() and first.result().success:
                break
            if not first.done():
                client.remove_pending_request(first)
            time.sleep(0.1)
        assert first.done() and first.result().success, "the planner never planned"
        workers = wait_for_children(os.cpu_count(), parent=process.pid)
        assert len(workers) == os.cpu_count(), workers
        yield process, workers, client
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate(timeout=60.0)


def _answered(futures, timeout=10.0):
    """The answers of ``futures``, once all are done or after ``timeout`` [s]."""
    deadline = time.monotonic() + timeout
    while not all(f.done() for f in futures) and time.monotonic() < deadline:
        time.sleep(0.02)
    return [f.result() for f in futures if f.done()]


def _ended(pids, timeout=10.0):
    deadline = time.monotonic() + timeout
    while any(running(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not any(running(pid) for pid in pids)


def test_sigint_with_requests_in_flight_exits_cleanly(client_node):
    with _planner_process(client_node) as (process, workers, client):
        futures = []
        for _ in range(40):
            futures.append(client.call_async(REQUEST))
            time.sleep(0.01)
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=60.0)
        answered = _answered(futures)
    assert process.returncode == 0, output
    assert "never retrieved" not in output, output
    assert "[ERROR]" not in output and "Traceback" not in output, output
    assert len(answered) == len(futures), f"{len(answered)} of {len(futures)} answered\n{output}"
    assert all(r.success for r in answered), output
    assert _ended(workers), "plan workers outlived the planner"


@pytest.mark.parametrize("number", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_burst_of_requests_is_answered_whatever_the_signal(client_node, number):
    # The executor takes one request of a service at a time: most of a burst
    # still waits in the service when the signal comes right after it.
    with _planner_process(client_node) as (process, _, client):
        futures = [client.call_async(REQUEST) for _ in range(8)]
        process.send_signal(number)
        output, _ = process.communicate(timeout=60.0)
        answered = _answered(futures)
    assert process.returncode == 0, output
    assert len(answered) == len(futures), f"{len(answered)} of {len(futures)} answered\n{output}"
    assert all(r.success for r in answered), output


def test_a_stop_signal_taken_by_another_thread_stops_the_planner(client_node):
    # The kernel hands a signal sent to a process to any of its threads that
    # does not block it; Python runs the handler in the main thread only.
    with _planner_process(client_node) as (process, _, _):
        tasks = pathlib.Path(f"/proc/{process.pid}/task")
        dds = [int(t.name) for t in tasks.iterdir() if (t / "comm").read_text().startswith("dds.")]
        assert dds, "no DDS thread found"
        assert ctypes.CDLL(None, use_errno=True).tgkill(process.pid, dds[0], signal.SIGTERM) == 0
        output, _ = process.communicate(timeout=30.0)
    assert process.returncode == 0, output


@pytest.mark.slow
def test_plan_workers_end_when_the_planner_is_killed(client_node):
    with _planner_process(client_node) as (process, workers, _):
        process.kill()
        process.communicate(timeout=60.0)
        assert _ended(workers), "plan workers outlived the killed planner"
