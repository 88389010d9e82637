"""A BoundedExecutor whose threads are all busy waits for one to be free,
without spinning: the callbacks it is waiting for keep the interpreter, its
spin_once keeps its timeout, and its shutdown ends the spinning.  Real rclpy
(its 7.1.5 wheels loop without waiting there, ros2/rclpy#1452)."""

import resource
import threading
import time

import pytest
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from rpr3_gwr_nodes.executors import BoundedExecutor
from std_msgs.msg import Empty

# How long the first callback keeps the executor's one thread [s].
HOLD = 1.0
TIMEOUT = 10.0


def _cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


@pytest.fixture
def one_busy_thread(ros_context):
    """A node on a one-thread BoundedExecutor, whose guard condition's
    callback holds that thread for HOLD seconds, and a subscription, in a
    callback group of its own, that a message may make ready meanwhile:
    (executor, holding, order, a callable that publishes the message)."""
    node = Node("bounded_executor_test", context=ros_context)
    holding = threading.Event()
    order = []

    def hold():
        order.append("hold")
        holding.set()
        time.sleep(HOLD)
        order.append("held")

    busy = node.create_guard_condition(hold, MutuallyExclusiveCallbackGroup())
    publisher = node.create_publisher(Empty, "bounded_executor_test", 1)
    node.create_subscription(Empty, "bounded_executor_test",
                             lambda _: order.append("received"), 1,
                             callback_group=MutuallyExclusiveCallbackGroup())
    executor = BoundedExecutor(num_threads=1, context=ros_context)
    executor.add_node(node)
    busy.trigger()
    try:
        yield executor, holding, order, lambda: publisher.publish(Empty())
    finally:
        executor.shutdown(timeout_sec=TIMEOUT)
        node.destroy_node()


@pytest.mark.filterwarnings("ignore:MultiThreadedExecutor is used with a single thread")
def test_a_spinning_thread_waits_for_a_free_thread_without_using_a_core(one_busy_thread):
    executor, holding, order, publish = one_busy_thread
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        assert holding.wait(TIMEOUT)
        publish()
        used = _cpu_seconds()
        time.sleep(0.8 * HOLD)
        # The holding callback sleeps: what this process used meanwhile is
        # the spinning thread's (and DDS's), a core's worth when it loops.
        assert _cpu_seconds() - used < 0.25 * HOLD
        deadline = time.monotonic() + TIMEOUT
        while "received" not in order and time.monotonic() < deadline:
            time.sleep(0.01)
        assert order == ["hold", "held", "received"]
    finally:
        executor.shutdown(timeout_sec=TIMEOUT)
        spinner.join(timeout=TIMEOUT)
    assert not spinner.is_alive()


@pytest.mark.filterwarnings("ignore:MultiThreadedExecutor is used with a single thread")
def test_spin_once_on_busy_threads_returns_by_its_timeout(one_busy_thread):
    executor, holding, _, publish = one_busy_thread
    executor.spin_once(timeout_sec=TIMEOUT)
    assert holding.wait(TIMEOUT)
    publish()
    began = time.monotonic()
    executor.spin_once(timeout_sec=0.1)
    assert time.monotonic() - began < 0.5 * HOLD


@pytest.mark.filterwarnings("ignore:MultiThreadedExecutor is used with a single thread")
def test_a_shutdown_ends_a_spin_that_waits_for_a_busy_thread(one_busy_thread):
    executor, holding, order, publish = one_busy_thread
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    assert holding.wait(TIMEOUT)
    publish()
    time.sleep(0.1)
    executor.shutdown(timeout_sec=0)
    spinner.join(timeout=0.5 * HOLD)
    assert not spinner.is_alive()
    assert "held" not in order
