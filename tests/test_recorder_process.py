"""The recorder as a real process: its bag is complete and readable after
SIGINT, and after SIGKILL it is recovered with all but the last moment."""

import os
import signal
import subprocess
import time

import pytest
from node_processes import LIB, exit_status, traced_environment
from rclpy.node import Node
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from rpr3_gwr_nodes.bag_recovery import BagRecoveryError, recover_bag
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

RECORDER = LIB / "trajectory_recorder"


def _trajectory(k):
    msg = JointTrajectory(joint_names=["rho1", "rho2", "rho3"])
    msg.points = [JointTrajectoryPoint(positions=[17.0, 10.0 + k + j, 20.0 - j]) for j in range(4)]
    return msg


def _publisher_to_the_recorder(node, depth):
    publisher = node.create_publisher(JointTrajectory, "planned_trajectory", depth)
    deadline = time.monotonic() + 30.0
    while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.1)
    assert publisher.get_subscription_count() == 1, "the recorder did not subscribe"
    return publisher


def test_bag_is_readable_after_sigint(ros_context, tmp_path):
    bag, log = tmp_path / "bag", tmp_path / "recorder.log"
    with open(log, "wb") as output:
        process = subprocess.Popen([str(RECORDER), "--ros-args", "-p", f"bag_path:={bag}"],
                                   env=traced_environment(), stdout=output,
                                   stderr=subprocess.STDOUT)
    node = Node("recorder_feeder", context=ros_context)
    try:
        publisher = _publisher_to_the_recorder(node, 10)
        for k in range(3):
            publisher.publish(_trajectory(k))
        time.sleep(1.0)
        process.send_signal(signal.SIGINT)
        assert exit_status(process, 20.0, log) == 0, log.read_text()
    finally:
        if process.poll() is None:
            process.kill()
        node.destroy_node()
    assert (bag / "metadata.yaml").exists()
    typestore = get_typestore(Stores.ROS2_JAZZY)
    with Reader(bag) as reader:
        assert sorted(c.topic for c in reader.connections) == ["/planned_path",
                                                              "/planned_trajectory"]
        messages = [typestore.deserialize_cdr(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert [[list(p.positions) for p in m.points] for m in messages] == [
        [list(p.positions) for p in _trajectory(k).points] for k in range(3)]


def _start_recorder(bag, *parameters):
    arguments = [f"bag_path:={bag}", *parameters]
    return subprocess.Popen([str(RECORDER), "--ros-args",
                             *[x for a in arguments for x in ("-p", a)]], env=os.environ.copy())


def _recorded(bag):
    typestore = get_typestore(Stores.ROS2_JAZZY)
    with Reader(bag) as reader:
        return [typestore.deserialize_cdr(raw, c.msgtype) for c, _, raw in reader.messages()]


# The recorder's default flush period is 0.5 s; a second covers it and the
# time a message takes from the publisher to the writer thread.
MOST_LOST = 1.0


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_killed_recorder_loses_at_most_the_last_second(ros_context, tmp_path, storage):
    bag = tmp_path / "bag"
    process = _start_recorder(bag, f"storage:={storage}")
    node = Node("recorder_feeder", context=ros_context)
    sent = []
    try:
        publisher = _publisher_to_the_recorder(node, 100)
        # The recorder's side of the match may lag behind ours under load.
        time.sleep(0.5)
        start = time.monotonic()
        while time.monotonic() - start < 3.0:
            publisher.publish(_trajectory(len(sent)))
            sent.append(time.monotonic())
            time.sleep(0.02)
        process.send_signal(signal.SIGKILL)
        killed = time.monotonic()
        process.wait(timeout=20.0)
    finally:
        if process.poll() is None:
            process.kill()
        node.destroy_node()
    assert not (bag / "metadata.yaml").exists()
    assert recover_bag(bag) > 0
    first_points = [m.points[0].positions[1] - 10.0 for m in _recorded(bag)]
    kept = sorted(int(round(k)) for k in first_points)
    assert kept == list(range(kept[0], kept[0] + len(kept))), "gaps or duplicates"
    old_enough = sum(1 for t in sent if killed - t > MOST_LOST)
    lost = len(sent) - 1 - kept[-1]
    print(f"\n{storage}: {len(sent)} published over 3 s, {len(kept)} recovered, the last "
          f"{lost} lost ({killed - sent[kept[-1] + 1] if lost else 0.0:.2f} s before SIGKILL)")
    assert kept[-1] + 1 >= old_enough


def test_recovering_a_complete_bag_is_refused(ros_context, tmp_path):
    bag = tmp_path / "bag"
    process = _start_recorder(bag)
    try:
        deadline = time.monotonic() + 30.0
        while not bag.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=20.0) == 0
    finally:
        if process.poll() is None:
            process.kill()
    with pytest.raises(BagRecoveryError):
        recover_bag(bag)
