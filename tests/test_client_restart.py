"""PlannerClient against a real driver process killed (SIGKILL) and started
again: a call sent once its driver was killed, before the next one started,
is answered by the next one; an execution whose driver dies ends at its
timeout with the result's timeout, not the cancel's; one whose driver is
restarted ends as soon as the new driver says it does not know the goal.
Real rclpy, Fast DDS and processes.

A killed participant stays in the ROS graph until its lease expires (20 s):
a request sent meanwhile goes to it alone, and its successor, discovered
later, never gets it unless the client sends it again."""

import math
import os
import pathlib
import subprocess
import threading
import time

import pytest
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_nodes.client import GoalLostError, PlannerClient
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

DRIVER = (pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes"
          / "lib" / "rpr3_gwr_nodes" / "rpr3_driver")
JOINTS = [17.0, 12.0, 18.0]
MODE = math.radians(122.82)
Q1 = (JOINTS, MODE)
# A driver's start, interpreter and imports included: 1 to 2 s on an idle
# machine.
START_TIMEOUT = 60.0
# Each call after a restart waits for the new driver's start as well.
CALL_TIMEOUT = 30.0
RESTARTS = 4
# The client's wait for a cancel's confirmation after a timeout is 1 s, and a
# loaded machine adds up to a second or more.
EXECUTE_TIMEOUT = 3.0
MARGIN = 3.0


def _line(seconds):
    """A straight trajectory from Q1's joints, ``seconds`` long."""
    end = [JOINTS[0], JOINTS[1] + 0.5, JOINTS[2]]
    return JointTrajectory(joint_names=["rho1", "rho2", "rho3"], points=[
        JointTrajectoryPoint(positions=JOINTS, time_from_start=Duration(sec=0)),
        JointTrajectoryPoint(positions=end, time_from_start=Duration(sec=seconds))])


class _Driver:
    """A driver process in ``namespace``, starting at Q1; its output is read
    by a thread of its own."""

    def __init__(self, namespace):
        self.process = subprocess.Popen(
            [str(DRIVER), "--ros-args", "-r", f"__ns:={namespace}", "-p", "time_scale:=20.0",
             "-p", f"initial_configuration:=[{', '.join(map(repr, [*JOINTS, MODE]))}]"],
            env=os.environ.copy(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.output = []
        self._ready = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.process.stdout:
            self.output.append(line)
            if "ready:" in line:
                self._ready.set()

    def wait_until_ready(self):
        assert self._ready.wait(START_TIMEOUT), "the driver did not start:\n" + \
            "".join(self.output)

    def kill(self):
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(timeout=10.0)
        self._reader.join(timeout=10.0)


@pytest.fixture
def drivers():
    """The drivers a test starts (append them), killed after it."""
    started = []
    try:
        yield started
    finally:
        for driver in started:
            driver.kill()


@pytest.mark.slow
def test_a_call_sent_while_its_driver_restarts_is_answered(ros_context, drivers):
    namespace = "/restarted_driver"
    client = PlannerClient(context=ros_context, namespace=namespace)
    try:
        drivers.append(_Driver(namespace))
        drivers[-1].wait_until_ready()
        assert client.reset_driver(Q1, timeout_sec=CALL_TIMEOUT).success
        took = []
        for restart in range(RESTARTS):
            drivers[-1].kill()
            # The new driver's participant appears a second after this: the
            # request is sent before it is discovered.
            drivers.append(_Driver(namespace))
            begin = time.monotonic()
            if restart % 2 == 0:
                answer = client.reset_driver(Q1, timeout_sec=CALL_TIMEOUT)
                assert answer.success, answer.error_msg
            else:
                outcome = client.execute(_line(1), timeout_sec=CALL_TIMEOUT)
                assert outcome.status == GoalStatus.STATUS_SUCCEEDED
                assert outcome.result.error_code == ExecuteTrajectory.Result.SUCCESS, \
                    outcome.result.error_msg
            took.append(time.monotonic() - begin)
        # Answered once the driver serves: a second call finds it matched.
        begin = time.monotonic()
        assert client.reset_driver(Q1, timeout_sec=CALL_TIMEOUT).success
        assert time.monotonic() - begin < 1.0
    finally:
        client.destroy_node()
    print("calls after a restart answered in", ", ".join(f"{t:.2f}" for t in took), "s")


@pytest.mark.slow
def test_an_execution_whose_driver_dies_ends_at_its_timeout(ros_context, drivers):
    namespace = "/dying_driver"
    client = PlannerClient(context=ros_context, namespace=namespace)
    try:
        drivers.append(_Driver(namespace))
        drivers[-1].wait_until_ready()
        process = drivers[-1].process
        begin = time.monotonic()
        # Killed while executing: its first feedback comes once it executes.
        with pytest.raises(TimeoutError, match="result") as raised:
            client.execute(_line(600), lambda _: process.kill(), timeout_sec=EXECUTE_TIMEOUT)
        took = time.monotonic() - begin
    finally:
        client.destroy_node()
    assert process.poll() is not None, "the driver never executed"
    assert not isinstance(raised.value, GoalLostError)
    assert took < EXECUTE_TIMEOUT + MARGIN, f"{took:.2f} s for a {EXECUTE_TIMEOUT} s timeout"


@pytest.mark.slow
def test_an_execution_whose_driver_restarts_ends_with_the_goal_lost(ros_context, drivers):
    namespace = "/restarting_driver"
    client = PlannerClient(context=ros_context, namespace=namespace)

    def restart(_):
        if len(drivers) == 1:
            drivers[0].process.kill()
            drivers.append(_Driver(namespace))

    try:
        drivers.append(_Driver(namespace))
        drivers[-1].wait_until_ready()
        begin = time.monotonic()
        with pytest.raises(GoalLostError, match="does not know the goal"):
            client.execute(_line(600), restart, timeout_sec=CALL_TIMEOUT)
        took = time.monotonic() - begin
    finally:
        client.destroy_node()
    assert len(drivers) == 2, "the driver never executed"
    assert took < CALL_TIMEOUT
    print(f"the lost goal reported after {took:.2f} s")
