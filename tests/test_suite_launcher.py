"""The suite launcher (``suite``, rpr3_gwr_nodes.suite_launcher) as a user
runs it: the installed executable in a process of its own, its nodes in
theirs, real Fast DDS on the test's loopback profile and ROS domain (the
children inherit this process's environment).  A PlannerClient on a private
context plans through the planner it started; SIGINT stops every node and
the launcher exits 0; a node that dies makes it exit non-zero, naming it."""

import os
import pathlib
import signal
import subprocess
import time

from rpr3_gwr_msgs.srv import PlanPath
from rpr3_gwr_nodes.client import PlannerClient, configuration

from process_tree import running

ROOT = pathlib.Path(__file__).resolve().parents[1]
SUITE = ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes" / "lib" / "rpr3_gwr_nodes" / "suite"
THREE_RRR = ROOT / "config" / "three_rrr.yaml"
PARAMS = ROOT / "config" / "params" / "suite.yaml"
# The 3-RRR's non-singular assembly-mode change on its slice th1 = 0
# (tests/test_mechanism_nodes.py).
TH, MODE_A, MODE_B = (0.0, 1.2043, 2.2515), 0.6526, 2.1165
# A first run compiles numba's kernels before the builder publishes.
READY_TIMEOUT = 180.0
# The nodes' stop: callbacks in flight end, then the node (and the
# planner's workers) exit.
STOP_TIMEOUT = 60.0


def _start(*options, log):
    return subprocess.Popen([str(SUITE), *options], stdin=subprocess.DEVNULL, stdout=log,
                            stderr=subprocess.STDOUT, cwd=ROOT)


def _descendants(pid):
    """Every running process below ``pid``, read from /proc."""
    parents = {}
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            parents[int(stat.parent.name)] = int(stat.read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue  # a process that ended meanwhile
    found, frontier = set(), {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return {p for p in found if running(p)}


def _stop(process):
    """Kill ``process`` and its process groups' members if still running."""
    for child in _descendants(process.pid):
        try:
            os.kill(child, signal.SIGKILL)
        except ProcessLookupError:
            pass
    if process.poll() is None:
        process.kill()
    process.wait(timeout=STOP_TIMEOUT)


def test_sigint_stops_every_node_after_the_planner_answered(ros_context, tmp_path):
    log_path = tmp_path / "suite.log"
    with open(log_path, "wb") as log:
        launcher = _start("--mechanism-file", str(THREE_RRR), "--params-file", str(PARAMS),
                          log=log)
    client = None
    try:
        client = PlannerClient("suite_launcher_test_client", context=ros_context)
        client.wait_until_ready(timeout_sec=READY_TIMEOUT)
        response = client.plan(configuration(TH, MODE_A), configuration(TH, MODE_B),
                               timeout_sec=READY_TIMEOUT)
        assert response.success, response.error_msg
        assert response.error_code == PlanPath.Response.ERROR_NONE
        children = _descendants(launcher.pid)
        # The three nodes at least (the planner's workers beside them).
        assert len(children) >= 3, children
        launcher.send_signal(signal.SIGINT)
        code = launcher.wait(timeout=STOP_TIMEOUT)
        deadline = time.monotonic() + 10.0
        while any(running(p) for p in children) and time.monotonic() < deadline:
            time.sleep(0.05)
        output = log_path.read_text()
        assert not [p for p in children if running(p)], output[-3000:]
        assert code == 0, output[-3000:]
        for name in ("roadmap_builder", "planner", "rpr3_driver"):
            assert f"[{name}] " in output
    finally:
        if client is not None:
            client.destroy_node()
        _stop(launcher)


def test_a_node_that_dies_makes_the_launcher_fail_naming_it(tmp_path):
    # Only the planner's mechanism file is missing: it alone dies, on its own.
    params = tmp_path / "params.yaml"
    params.write_text(f"planner:\n  ros__parameters:\n"
                      f"    mechanism_file: {tmp_path / 'missing.yaml'}\n")
    log_path = tmp_path / "suite.log"
    with open(log_path, "wb") as log:
        launcher = _start("--params-file", str(params), log=log)
    try:
        code = launcher.wait(timeout=READY_TIMEOUT)
        output = log_path.read_text()
        assert code != 0, output
        # The node's own error, prefixed with its name, and the launcher's word.
        assert "[planner] [ERROR]" in output and "cannot start: " in output, output
        assert "missing.yaml" in output and "Traceback" not in output, output
        assert "[suite] planner exited on its own with status 1" in output, output
    finally:
        _stop(launcher)
