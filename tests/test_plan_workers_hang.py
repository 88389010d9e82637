"""A plan worker stopped with SIGSTOP, first while idle, then while its
planner node is under a steady load of concurrent requests: the node finds it
hung within seconds, kills it and plans its request itself, the other worker
(then the node alone) goes on serving, and no request is lost.  Real rclpy,
Fast DDS and worker processes; the clients spin in an executor of their own."""

import math
import os
import pathlib
import signal
import struct
import threading
import time

import numpy as np
import pytest
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.paper import PAPER_GEOMETRY, PAPER_GRID, rho1_slice
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_msgs.msg import Configuration, NSolutionField, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.conversions import roadmap_to_msgs
from rpr3_gwr_nodes.planner import PlannerNode
from rpr3_gwr_nodes.profiles import LATCHED_QOS, SERVICE_QOS
from std_msgs.msg import Header

from process_tree import children, running, wait_for_children

D = math.radians
REQUEST = PlanPath.Request(
    start=Configuration(positions=[17.0, 12.0, 18.0], mode=D(122.82)),
    goal=Configuration(positions=[17.0, 10.0, 25.0], mode=D(-24.24)))
WORKERS = 2
CLIENTS = 4
# Length of the load after a stop [s].
WINDOW = 10.0
# Every answer comes within this [s], far below the 120 s a worker that is
# not hung may take.
ANSWER_TIMEOUT = 30.0
# Answers within WINDOW that show the service is not stalled: a plan of this
# request takes a few milliseconds.
MIN_ANSWERED = 20


def _call(client, timeout):
    """``(response or None, seconds)``; a request unanswered within
    ``timeout`` is withdrawn."""
    begin = time.monotonic()
    future = client.call_async(REQUEST)
    done = threading.Event()
    future.add_done_callback(lambda _: done.set())
    if not done.wait(timeout):
        client.remove_pending_request(future)
        return None, time.monotonic() - begin
    return future.result(), time.monotonic() - begin


class _Load:
    """Each client calling the service again as soon as it is answered."""

    def __init__(self, clients):
        self.stop = threading.Event()
        self.calls = []  # (sent at, response or None, seconds)
        self._threads = [threading.Thread(target=self._run, args=(c,)) for c in clients]

    def _run(self, client):
        while not self.stop.is_set():
            sent = time.monotonic()
            response, seconds = _call(client, ANSWER_TIMEOUT)
            self.calls.append((sent, response, seconds))
            if response is None:
                return

    def __enter__(self):
        for thread in self._threads:
            thread.start()
        return self

    def __exit__(self, *_):
        self.stop.set()
        for thread in self._threads:
            thread.join(ANSWER_TIMEOUT + 10.0)


@pytest.fixture
def loaded_planner(ros_context):
    """A planner with its plan workers, and clients that made their first
    exchange: ``(workers, clients, reference positions)``."""
    earlier = children()
    field_msg, roadmap_msg = roadmap_to_msgs(build_roadmap(PAPER_GEOMETRY, PAPER_GRID), Header())
    planner = PlannerNode(context=ros_context, namespace="hang", parameter_overrides=[
        Parameter("plan_workers", value=WORKERS)])
    feeder = Node("roadmap_feeder", context=ros_context, namespace="hang")
    feeder.create_publisher(NSolutionField, "field", LATCHED_QOS).publish(field_msg)
    feeder.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS).publish(roadmap_msg)
    client_node = Node("hang_test_clients", context=ros_context, namespace="hang")
    clients = [client_node.create_client(PlanPath, "plan_path", qos_profile=SERVICE_QOS)
               for _ in range(CLIENTS)]
    # As the planner's main: two threads per core.
    server = MultiThreadedExecutor(num_threads=2 * WORKERS, context=ros_context)
    server.add_node(planner)
    server.add_node(feeder)
    caller = SingleThreadedExecutor(context=ros_context)
    caller.add_node(client_node)
    spinners = [threading.Thread(target=e.spin, daemon=True) for e in (server, caller)]
    for spinner in spinners:
        spinner.start()
    workers = set()
    try:
        assert planner.ready.wait(60.0), "the planner got no roadmap"
        assert planner.indexed.wait(120.0), "the planner's workers did not start"
        workers = wait_for_children(WORKERS, earlier)
        assert len(workers) == WORKERS, workers
        reference = None
        for client in clients:
            assert client.wait_for_service(timeout_sec=ANSWER_TIMEOUT)
            # A client's very first request may go unanswered (README, DDS).
            for _ in range(3):
                response, _ = _call(client, 10.0)
                if response is not None:
                    break
            assert response is not None and response.success, "no first answer"
            reference = _positions(response)
        yield sorted(workers), clients, reference
    finally:
        for pid in workers:  # a stopped worker the node left behind
            if running(pid):
                os.kill(pid, signal.SIGKILL)
        for executor in (caller, server):
            executor.shutdown(timeout_sec=10.0)
        for spinner in spinners:
            spinner.join(timeout=10.0)
        for node in (client_node, feeder, planner):
            node.destroy_node()


def _positions(response):
    return np.array([p.positions for p in response.trajectory.points])


def _ended(pid, timeout=10.0):
    deadline = time.monotonic() + timeout
    while running(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not running(pid)


def _check(name, load, stopped_at, reference, pid):
    """No request lost, every answer the same plan, the service not stalled,
    the stopped worker gone; prints what the load measured."""
    lost = [c for c in load.calls if c[1] is None]
    assert not lost, f"{name}: {len(lost)} request(s) unanswered within {ANSWER_TIMEOUT} s"
    for _, response, _ in load.calls:
        assert response.success, response.error_msg
        np.testing.assert_allclose(_positions(response), reference, rtol=0, atol=1e-12)
    window = [c for c in load.calls if stopped_at <= c[0] + c[2] <= stopped_at + WINDOW]
    slowest = max(c[2] for c in load.calls)
    print(f"\n{name}: {len(window)} requests answered in the {WINDOW:g} s after the stop "
          f"({len(window) / WINDOW:.0f}/s, {len(load.calls)} in all); slowest answer "
          f"{slowest:.2f} s (the stopped worker's request)")
    assert len(window) >= MIN_ANSWERED, f"{name}: the service stalled"
    assert _ended(pid), f"{name}: the stopped worker {pid} was left behind"


@pytest.mark.slow
def test_a_stopped_worker_holds_up_only_its_own_request(loaded_planner):
    (first, second), clients, reference = loaded_planner
    # Idle: with a queue shared by the workers, the one waiting on it holds
    # its lock.
    os.kill(first, signal.SIGSTOP)
    stopped_at = time.monotonic()
    with _Load(clients) as load:
        time.sleep(WINDOW)
    _check("idle worker stopped", load, stopped_at, reference, first)
    # Planning: the node is left with no worker and plans alone.
    with _Load(clients) as load:
        time.sleep(1.0)
        os.kill(second, signal.SIGSTOP)
        stopped_at = time.monotonic()
        time.sleep(WINDOW)
    _check("busy worker stopped", load, stopped_at, reference, second)


def test_a_worker_stopped_halfway_through_its_answer_is_found_hung(tmp_path):
    """A worker stopped halfway through writing an answer: reading what came
    must not wait for the rest for ever.  A plan's answer fits in one write
    to the pipe, so the first half of a larger one is written into the
    worker's own end of its answer pipe (through /proc) before it is
    stopped."""
    from rpr3_gwr_core.planning import CellSearchIndex
    from rpr3_gwr_nodes.plan_workers import PlanWorkers, WorkerFailed

    roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.5))
    workers = PlanWorkers(roadmap, CellSearchIndex.build(roadmap), 1, ANSWER_TIMEOUT,
                          str(tmp_path))
    worker = workers._idle.popleft()
    try:
        answer_fd = pathlib.Path(f"/proc/{worker.pid}/cmdline").read_bytes().split(b"\0")[4]
        with open(f"/proc/{worker.pid}/fd/{int(answer_fd)}", "wb", buffering=0) as pipe:
            pipe.write(struct.pack("<Q", 1 << 20) + bytes(1000))
        os.kill(worker.pid, signal.SIGSTOP)
        begin = time.monotonic()
        with pytest.raises(WorkerFailed, match="hung"):
            worker.receive(ANSWER_TIMEOUT)
        assert time.monotonic() - begin < ANSWER_TIMEOUT / 2
    finally:
        workers._retire(worker)
        workers.close()
