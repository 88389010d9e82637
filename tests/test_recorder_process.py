"""The recorder as a real process: its bag is complete and readable after SIGINT."""

import os
import pathlib
import signal
import subprocess
import time

from rclpy.node import Node
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

RECORDER = (pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes"
            / "lib" / "rpr3_gwr_nodes" / "trajectory_recorder")


def _trajectory(k):
    msg = JointTrajectory(joint_names=["rho1", "rho2", "rho3"])
    msg.points = [JointTrajectoryPoint(positions=[17.0, 10.0 + k + j, 20.0 - j]) for j in range(4)]
    return msg


def test_bag_is_readable_after_sigint(ros_context, tmp_path):
    bag = tmp_path / "bag"
    process = subprocess.Popen([str(RECORDER), "--ros-args", "-p", f"bag_path:={bag}"],
                               env=os.environ.copy())
    node = Node("recorder_feeder", context=ros_context)
    try:
        publisher = node.create_publisher(JointTrajectory, "planned_trajectory", 10)
        deadline = time.monotonic() + 30.0
        while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert publisher.get_subscription_count() == 1, "the recorder did not subscribe"
        for k in range(3):
            publisher.publish(_trajectory(k))
        time.sleep(1.0)
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=20.0) == 0
    finally:
        if process.poll() is None:
            process.kill()
        node.destroy_node()
    assert (bag / "metadata.yaml").exists()
    typestore = get_typestore(Stores.ROS2_JAZZY)
    with Reader(bag) as reader:
        assert [c.topic for c in reader.connections] == ["/planned_trajectory"]
        messages = [typestore.deserialize_cdr(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert [[list(p.positions) for p in m.points] for m in messages] == [
        [list(p.positions) for p in _trajectory(k).points] for k in range(3)]
