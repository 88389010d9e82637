"""control_msgs and tf2_msgs are the ROS 2 Jazzy packages, on the wire.

Where ROS has them (every apt install) the suite uses the installed ones;
where it lacks them (the wheels) the workspace builds them from their
published definitions (ros2_ws/standard_interfaces).  Either way the
interfaces the suite uses must hash as the published ones do: the RIHS01
type hash covers every field's name, type and order down to the nested
types, and DDS discovery compares it between endpoints.

The reference hashes below were computed by rosidl_generator_type_description
4.6.6 (`rosidl hash`, this environment's ROS 2 Jazzy) from the published
definition files, fetched unchanged from
- ros-controls/control_msgs, branch jazzy, commit
  f901df2662f22a39a06aa04a85a34602c47e3cc0 (release 5.8.0):
  control_msgs/action/FollowJointTrajectory.action,
  control_msgs/msg/JointTolerance.msg, control_msgs/msg/JointComponentTolerance.msg;
- ros2/geometry2, branch jazzy, commit 646342c6164e837d69460e3d28e7a025396544f6
  (release 0.36.4): tf2_msgs/msg/TFMessage.msg.
An independent implementation of RIHS01, that of rosbags 0.11.9, given the
same files and its ROS 2 Jazzy type store for the types they reference, gave
the same hashes for the messages (the Goal, Result and Feedback and the two
tolerances).  TFMessage's is also the hash of rosbags' ROS 2 Jazzy type store
(checked below) and the one `ros2 topic info --verbose /tf` shows on Jazzy.
"""

import importlib
import json
import os
import pathlib
import sys
import time

import pytest
from ament_index_python.packages import get_package_prefix, get_package_share_directory

ROOT = pathlib.Path(__file__).resolve().parents[1]

ACTION = "control_msgs/action/FollowJointTrajectory"
REFERENCE = {
    ACTION: "RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6",
    f"{ACTION}_Goal": "RIHS01_8a9060704b269608f5a340934cc26e66869dd14bdac29e2e7fd9ec8b9882d205",
    f"{ACTION}_Result": "RIHS01_8002e99ed2c14c6faa522f2a93c26d744c5982f254f9e98ff9c6f19789bdb220",
    f"{ACTION}_Feedback":
        "RIHS01_3fd0aaecf71725121ae1ff7f01098a5e0da581e672be18a6b2c286cb43d96b49",
    f"{ACTION}_FeedbackMessage":
        "RIHS01_80398fcb9674a79081a9906e2ccf0c804dd7cb15e22e362e606ee87186beab71",
    f"{ACTION}_SendGoal":
        "RIHS01_b13789dddc325a7a962825c45e28c77d37237ec129dd0c34dc5994562938c57f",
    f"{ACTION}_SendGoal_Request":
        "RIHS01_179c93691f1f6d1d115881ff88c3917b7cc6eac2ba4bf56766cc7c4389e19ef1",
    f"{ACTION}_SendGoal_Response":
        "RIHS01_e6a48ba740ae254500129a877f0b071be8663a115da1a539b74599cc97921fbf",
    f"{ACTION}_SendGoal_Event":
        "RIHS01_906dd566308db02673c73c654f69bdd84738589629c1bc2841ddb49059ed1c6f",
    f"{ACTION}_GetResult":
        "RIHS01_e3ceb38e3e1867c8dc0f46014df26e90eb93422f27e9e97f936e07f94be4bc8b",
    f"{ACTION}_GetResult_Request":
        "RIHS01_ecf7ea8463d3beec7084bca75216d0b01b87b6e1e4e09679bb26093041efcbe9",
    f"{ACTION}_GetResult_Response":
        "RIHS01_08eefbaa146ce02ba45898d5e99160afd6c4c54a30d159aee0f2ca6035b1580f",
    f"{ACTION}_GetResult_Event":
        "RIHS01_43161a489e52daaa5bbc2fa74f73f1804d099574fcf8f819170807d75472662a",
    "control_msgs/msg/JointTolerance":
        "RIHS01_c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648",
    "control_msgs/msg/JointComponentTolerance":
        "RIHS01_739ea7566931944d33830fa10f1bf5e7a7fbdc3172bce7a7eaac642bd6e3ffa4",
    "tf2_msgs/msg/TFMessage":
        "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
}
# Constants are not hashed: the published values, checked one by one.
RESULT_CODES = {"SUCCESSFUL": 0, "INVALID_GOAL": -1, "INVALID_JOINTS": -2,
                "OLD_HEADER_TIMESTAMP": -3, "PATH_TOLERANCE_VIOLATED": -4,
                "GOAL_TOLERANCE_VIOLATED": -5}
COMPONENTS = {"X_AXIS": 1, "Y_AXIS": 2, "Z_AXIS": 3, "TRANSLATION": 4, "ROTATION": 5}
# Bounded waits of the DDS tests.
DISCOVERY_S = 10.0


def _described_hashes(interface):
    """``{type name: hash}`` of the type description file ``interface``
    (``"<pkg>/<kind>/<Name>"``) that the package installed."""
    package, kind, name = interface.split("/")
    path = pathlib.Path(get_package_share_directory(package)) / kind / f"{name}.json"
    return {entry["type_name"]: entry["hash_string"]
            for entry in json.loads(path.read_text(encoding="utf-8"))["type_hashes"]}


def _underlay():
    """The ROS install the workspace builds on: /opt/ros/jazzy, or the
    virtual environment that holds the wheels."""
    system = pathlib.Path("/opt/ros/jazzy")
    return system if (system / "setup.bash").exists() else pathlib.Path(sys.prefix)


@pytest.mark.parametrize("package", ["control_msgs", "tf2_msgs"])
def test_each_package_comes_from_ros_where_ros_has_it(package):
    prefix = pathlib.Path(get_package_prefix(package))
    module = pathlib.Path(importlib.import_module(package).__file__)
    underlay = _underlay()
    if (underlay / "share" / "ament_index" / "resource_index" / "packages" / package).exists():
        assert prefix == underlay
    else:
        assert prefix.parent.name == "install" and prefix.name == package
        assert prefix.is_relative_to(ROOT / "ros2_ws")
    # The module imported is that package's, not a copy elsewhere on the path.
    assert module.is_relative_to(prefix)


def test_the_action_and_its_parts_hash_as_the_published_definition():
    # The action's description lists the hashes of the action, its Goal,
    # Result and Feedback, its services and messages, and the tolerances.
    described = _described_hashes(ACTION)
    control = {name: value for name, value in described.items()
               if name.startswith("control_msgs/")}
    assert control == {name: value for name, value in REFERENCE.items()
                       if name.startswith("control_msgs/")}


@pytest.mark.parametrize("interface", ["control_msgs/msg/JointTolerance",
                                       "control_msgs/msg/JointComponentTolerance",
                                       "tf2_msgs/msg/TFMessage"])
def test_each_message_hashes_as_the_published_definition(interface):
    assert _described_hashes(interface)[interface] == REFERENCE[interface]


def test_tfmessage_hashes_as_rosbags_jazzy_type_store_computes():
    from rosbags.typesys import Stores, get_typestore

    jazzy = get_typestore(Stores.ROS2_JAZZY)
    assert jazzy.hash_rihs01("tf2_msgs/msg/TFMessage") == REFERENCE["tf2_msgs/msg/TFMessage"]


def test_the_constants_have_the_published_values():
    from control_msgs.action import FollowJointTrajectory
    from control_msgs.msg import JointComponentTolerance

    assert {name: getattr(FollowJointTrajectory.Result, name)
            for name in RESULT_CODES} == RESULT_CODES
    assert {name: getattr(JointComponentTolerance, name) for name in COMPONENTS} == COMPONENTS


def _goal():
    from builtin_interfaces.msg import Duration
    from control_msgs.action import FollowJointTrajectory
    from control_msgs.msg import JointComponentTolerance, JointTolerance
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    names = ["rho1", "rho2", "rho3"]
    points = [JointTrajectoryPoint(positions=[17.0, 12.0, 18.0 + k], velocities=[0.0, 0.1, 0.2],
                                   time_from_start=Duration(sec=k, nanosec=250_000_000))
              for k in range(3)]
    trajectory = JointTrajectory(joint_names=names, points=points)
    trajectory.header.frame_id = "base"
    return FollowJointTrajectory.Goal(
        trajectory=trajectory,
        path_tolerance=[JointTolerance(name=n, position=0.05, velocity=-1.0) for n in names],
        component_path_tolerance=[JointComponentTolerance(
            joint_name="platform", component=JointComponentTolerance.ROTATION, position=0.01)],
        goal_tolerance=[JointTolerance(name="rho2", position=0.001, acceleration=2.5)],
        goal_time_tolerance=Duration(sec=1, nanosec=500_000_000))


def _tf_message(child="platform"):
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage

    transforms = []
    for k, frame in enumerate(["link_1", child]):
        transform = TransformStamped(child_frame_id=frame)
        transform.header.frame_id = "base"
        transform.header.stamp.sec = 1_700_000_000 + k
        transform.header.stamp.nanosec = 123_456_789
        transform.transform.translation.x = 0.5 * (k + 1)
        transform.transform.translation.y = -2.25
        transform.transform.rotation.z = 0.6
        transform.transform.rotation.w = 0.8
        transforms.append(transform)
    return TFMessage(transforms=transforms)


@pytest.mark.parametrize("make", [_goal, _tf_message], ids=["FollowJointTrajectory.Goal",
                                                            "TFMessage"])
def test_a_message_survives_serialization(make):
    from rclpy.serialization import deserialize_message, serialize_message

    message = make()
    data = serialize_message(message)
    back = deserialize_message(data, type(message))
    assert back == message
    assert back != type(message)()


def test_tfmessage_cdr_is_that_of_rosbags_jazzy_definition():
    """Another implementation of CDR, with Jazzy's definitions, reads what
    rclpy writes, and writes what rclpy reads (byte for byte but for the
    alignment padding, which rclpy's serializer does not clear)."""
    from rclpy.serialization import deserialize_message, serialize_message
    from rosbags.typesys import Stores, get_typestore
    from tf2_msgs.msg import TFMessage

    jazzy = get_typestore(Stores.ROS2_JAZZY)
    message = _tf_message()
    data = serialize_message(message)
    read = jazzy.deserialize_cdr(data, "tf2_msgs/msg/TFMessage")
    assert [(t.header.frame_id, t.child_frame_id, t.header.stamp.sec, t.header.stamp.nanosec,
             t.transform.translation.x, t.transform.translation.y, t.transform.rotation.z,
             t.transform.rotation.w) for t in read.transforms] == [
        (t.header.frame_id, t.child_frame_id, t.header.stamp.sec, t.header.stamp.nanosec,
         t.transform.translation.x, t.transform.translation.y, t.transform.rotation.z,
         t.transform.rotation.w) for t in message.transforms]
    written = bytes(jazzy.serialize_cdr(read, "tf2_msgs/msg/TFMessage"))
    assert len(written) == len(data)
    assert deserialize_message(written, TFMessage) == message


def _spin_until(executor, condition, timeout):
    deadline = time.monotonic() + timeout
    while not condition() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    return condition()


def test_tf_reaches_a_default_subscriber_and_is_discovered_with_the_published_hash(ros_context):
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from tf2_msgs.msg import TFMessage

    # The frame name tells this test's message from any other run's on /tf.
    child = f"platform_{os.getpid()}_{time.monotonic_ns()}"
    sent = _tf_message(child)
    received = []
    executor = SingleThreadedExecutor(context=ros_context)
    talker = Node("test_tf_talker", context=ros_context)
    listener = Node("test_tf_listener", context=ros_context)
    try:
        publisher = talker.create_publisher(TFMessage, "/tf", 10)
        listener.create_subscription(
            TFMessage, "/tf",
            lambda m: received.append(m) if m.transforms[-1].child_frame_id == child else None, 10)
        executor.add_node(talker)
        executor.add_node(listener)
        assert _spin_until(executor, lambda: publisher.get_subscription_count() >= 1, DISCOVERY_S)
        publishers = listener.get_publishers_info_by_topic("/tf")
        hashes = {str(info.topic_type_hash) for info in publishers
                  if info.node_name == "test_tf_talker"}
        assert hashes == {REFERENCE["tf2_msgs/msg/TFMessage"]}
        deadline = time.monotonic() + DISCOVERY_S
        while not received and time.monotonic() < deadline:
            publisher.publish(sent)
            _spin_until(executor, lambda: bool(received), 0.5)
        assert received and received[0] == sent
    finally:
        executor.shutdown()
        talker.destroy_node()
        listener.destroy_node()


def test_a_followjointtrajectory_server_s_feedback_is_discovered_with_the_published_hash(
        ros_context):
    from control_msgs.action import FollowJointTrajectory
    from rclpy.action import ActionServer
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node

    executor = SingleThreadedExecutor(context=ros_context)
    server_node = Node("test_fjt_server", context=ros_context)
    observer = Node("test_fjt_observer", context=ros_context)
    action = f"/test_fjt_{os.getpid()}/follow_joint_trajectory"
    server = ActionServer(server_node, FollowJointTrajectory, action,
                          lambda handle: FollowJointTrajectory.Result())
    try:
        executor.add_node(server_node)
        executor.add_node(observer)

        def feedback_hashes():
            return {str(info.topic_type_hash) for info in observer.get_publishers_info_by_topic(
                f"{action}/_action/feedback")}

        assert _spin_until(executor, feedback_hashes, DISCOVERY_S)
        assert feedback_hashes() == {REFERENCE[f"{ACTION}_FeedbackMessage"]}
    finally:
        server.destroy()
        executor.shutdown()
        server_node.destroy_node()
        observer.destroy_node()
