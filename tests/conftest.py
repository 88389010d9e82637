"""Integration tests: real rclpy, Fast DDS and generated interfaces, no mocks.

Every run uses the project's loopback-only Fast DDS profile and the user's
ROS_DOMAIN_ID, or when it is unset a ROS domain of its own, chosen here
before any test imports rclpy.
"""

import os
import pathlib
import random
import threading

import pytest

_PROFILE = pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "fastdds_localhost.xml"

os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] = str(_PROFILE)
os.environ["FASTDDS_DEFAULT_PROFILES_FILE"] = str(_PROFILE)
os.environ["RMW_IMPLEMENTATION"] = "rmw_fastrtps_cpp"
# LOCALHOST would make rmw_fastrtps override the profile's transports (env.sh).
os.environ.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)
os.environ.pop("ROS_STATIC_PEERS", None)
# A user's ROS_DOMAIN_ID is kept; unset, this run takes one of its own in
# 1..100 (domains above 101 can collide with ephemeral ports).
if not os.environ.get("ROS_DOMAIN_ID"):
    os.environ["ROS_DOMAIN_ID"] = str(random.SystemRandom().randint(1, 100))


def _private_context():
    """A private rclpy context, shut down when the generator closes."""
    import rclpy
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context)
    try:
        yield context
    finally:
        rclpy.try_shutdown(context=context)


@pytest.fixture
def ros_context():
    """A private rclpy context, shut down after the test."""
    yield from _private_context()


@pytest.fixture(scope="module")
def module_context():
    """A private rclpy context for a test module's nodes, shut down after it."""
    yield from _private_context()


@pytest.fixture
def client_node(ros_context):
    """A node of the test's own on a private context, spun by a
    single-threaded executor in a thread of its own, destroyed after the test."""
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node

    node = Node("test_client", context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        yield node
    finally:
        executor.shutdown()
        spinner.join(timeout=10.0)
        node.destroy_node()
