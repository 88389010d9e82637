"""The installed executables as a user runs them: ``--help`` and ``-h`` print
the node's usage and exit 0 without joining the graph, and a started node
says what it waits for and when it is ready; env.sh, the tests, the demo
and the service benchmark keep a user's ROS_DOMAIN_ID.  Real processes on
the test run's ROS domain and loopback DDS profile."""

import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
LIB = ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes" / "lib" / "rpr3_gwr_nodes"
NODES = {
    "roadmap_builder": ["roadmap", "field", "mechanism_file", "fixed_value", "full"],
    "planner": ["plan_path", "roadmap", "clearance", "plan_workers", "default_time_limit"],
    "rpr3_driver": ["execute_trajectory", "reset", "joint_states", "time_scale"],
    "trajectory_recorder": ["planned_trajectory", "bag_path", "storage"],
    "scene_publisher": ["scene", "scene_file"],
}
TIMEOUT = 120.0


@pytest.mark.parametrize("executable", sorted(NODES))
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_prints_the_usage_and_exits_without_a_node(executable, flag):
    # A parameter after --ros-args does not hide the flag before it.
    done = subprocess.run([str(LIB / executable), flag, "--ros-args", "-p", "rate:=5.0"],
                          env=os.environ.copy(), capture_output=True, text=True, timeout=60.0)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.startswith(f"usage: ros2 run rpr3_gwr_nodes {executable} "), done.stdout
    for name in NODES[executable]:
        assert name in done.stdout, (name, done.stdout)
    assert "--ros-args" in done.stdout and "-p NAME:=VALUE" in done.stdout
    # No node started: rclpy logs nothing, the node says nothing.
    assert "[INFO]" not in done.stdout + done.stderr, done.stderr
    assert not done.stderr, done.stderr


def test_help_after_the_ros_arguments_is_the_programs_too_a_value_is_not():
    done = subprocess.run([str(LIB / "planner"), "--ros-args", "-p", "plan_workers:=0", "--",
                           "--help"], env=os.environ.copy(), capture_output=True, text=True,
                          timeout=60.0)
    assert done.returncode == 0 and done.stdout.startswith("usage: "), done.stdout
    process = subprocess.Popen([str(LIB / "scene_publisher"), "--ros-args", "-r",
                                "__ns:=/usage_test", "-p", "scene_file:=-h"],
                               env=os.environ.copy(), stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    lines = _Lines(process)
    try:
        lines.wait_for("not publishing a scene: cannot read scene -h", TIMEOUT)
    finally:
        _stop(process)
    assert process.returncode == 0, lines.text()
    assert "usage:" not in lines.text()


class _Lines:
    """The output of a process, read by a thread of its own."""

    def __init__(self, process):
        self._lines, self._lock = [], threading.Lock()
        self._reader = threading.Thread(target=self._read, args=(process.stdout,), daemon=True)
        self._reader.start()

    def _read(self, stream):
        for line in stream:
            with self._lock:
                self._lines.append(line)

    def text(self):
        with self._lock:
            return "".join(self._lines)

    def wait_for(self, needle, timeout):
        """The output up to and including ``needle``, waited for at most
        ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while needle not in self.text():
            assert time.monotonic() < deadline, f"no {needle!r} in:\n{self.text()}"
            time.sleep(0.05)
        text = self.text()
        return text[:text.index(needle) + len(needle)]


def _stop(process):
    """SIGINT, then wait (kill after the timeout)."""
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=60.0)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(timeout=10.0)


def test_each_node_says_what_it_waits_for_and_when_it_is_ready():
    # The planner first: it waits for the builder's roadmap.
    namespace = ["--ros-args", "-r", "__ns:=/startup"]
    planner = subprocess.Popen([str(LIB / "planner"), *namespace, "-p", "plan_workers:=0"],
                               env=os.environ.copy(), stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    processes = [planner]
    try:
        planned = _Lines(planner)
        planned.wait_for("waiting for a roadmap on /startup/roadmap and /startup/field", TIMEOUT)
        builder = subprocess.Popen([str(LIB / "roadmap_builder"), *namespace],
                                   env=os.environ.copy(), stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True)
        processes.append(builder)
        built = _Lines(builder)
        driver = subprocess.Popen([str(LIB / "rpr3_driver"), *namespace],
                                  env=os.environ.copy(), stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)
        processes.append(driver)
        driven = _Lines(driver)
        built.wait_for("ready: published the roadmap on /startup/roadmap and /startup/field",
                       TIMEOUT)
        before = planned.wait_for("ready: serving /startup/plan_path on a roadmap of the "
                                  "3-RPR, rho1 = 17", TIMEOUT)
        assert "ready" not in before.split("waiting for a roadmap")[0]
        driven.wait_for("ready: serving /startup/execute_trajectory, "
                        "/startup/rpr3_driver/follow_joint_trajectory and /startup/reset, "
                        "publishing /startup/joint_states at 100 Hz", TIMEOUT)
    finally:
        for process in processes:
            _stop(process)
    for process in processes:
        assert process.returncode == 0, process.args


@pytest.mark.parametrize("domain", ["7", None], ids=["set", "unset"])
def test_env_sh_keeps_the_users_ros_domain_id_and_invents_none(domain):
    env = {k: v for k, v in os.environ.items() if k != "ROS_DOMAIN_ID"}
    if domain is not None:
        env["ROS_DOMAIN_ID"] = domain
    done = subprocess.run(["bash", "-c", f"source {ROOT / 'ros2_ws' / 'env.sh'} >/dev/null && "
                           "echo ${ROS_DOMAIN_ID-unset}"], env=env, capture_output=True,
                          text=True, timeout=60.0)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == (domain or "unset")


@pytest.mark.parametrize("script", ["tests/conftest.py", "tools/demo.py",
                                    "bench/bench_service.py"])
@pytest.mark.parametrize("domain", ["7", None], ids=["set", "unset"])
def test_the_scripts_pick_a_ros_domain_id_only_when_unset(script, domain):
    env = {k: v for k, v in os.environ.items() if k != "ROS_DOMAIN_ID"}
    if domain is not None:
        env["ROS_DOMAIN_ID"] = domain
    # Loaded as a module: what it sets at import, its main not run.
    load = ("import importlib.util, os, sys; "
            f"spec = importlib.util.spec_from_file_location('loaded', {str(ROOT / script)!r}); "
            "spec.loader.exec_module(importlib.util.module_from_spec(spec)); "
            "print(os.environ['ROS_DOMAIN_ID'])")
    done = subprocess.run([sys.executable, "-c", load], env=env, capture_output=True,
                          text=True, timeout=120.0)
    assert done.returncode == 0, done.stderr
    picked = done.stdout.strip().splitlines()[-1]
    if domain is not None:
        assert picked == domain
    else:
        assert 1 <= int(picked) <= 100
