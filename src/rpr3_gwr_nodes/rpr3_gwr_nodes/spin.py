"""The ``main`` of every node of the suite, as in ros2/demos: init, spin until
Ctrl-C or an external shutdown, then always destroy the node and shut down.

One difference: rclpy's own SIGINT and SIGTERM handlers shut the context
down at once, so a service callback still computing could no longer send its
answer (rclpy then logs "exception was never retrieved").  Here a signal only
stops the spinning; callbacks in flight finish and answer, then the node is
destroyed and the context shut down.
"""

import signal
import threading

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

__all__ = ["run"]

_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def run(node_type, executor_type, args=None, **executor_options):
    """Create ``node_type()``, spin it on ``executor_type(**executor_options)``
    until SIGINT, SIGTERM or an external shutdown.

    The node is created after ``rclpy.init`` and destroyed in ``finally``
    (the recorder closes its bag there), after the callbacks running in the
    executor's threads have finished; a node whose callbacks run long (the
    driver executing a trajectory) defines ``prepare_shutdown()`` to make
    them end now.
    """
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    node = executor = spinner = None
    stop, stopped = threading.Event(), Future()
    previous = {number: signal.signal(number, lambda *_: stop.set()) for number in _STOP_SIGNALS}
    try:
        node = node_type()
        executor = executor_type(**executor_options)
        executor.add_node(node)
        spinner = threading.Thread(target=_spin, args=(executor, stopped, stop), name="spin")
        spinner.start()
        # Signal handlers run in the main thread, and only while it runs
        # Python: it waits here, not in rclpy's wait set.
        stop.wait()
    except KeyboardInterrupt:
        pass
    finally:
        if spinner is not None:
            # Completing the future ends the spin between two callbacks.
            stopped.set_result(True)
            spinner.join()
        if executor is not None:
            if hasattr(node, "prepare_shutdown"):
                node.prepare_shutdown()
            # Callbacks still running use the executor's guard condition,
            # which its shutdown destroys: they finish first.
            _wait_for_callbacks(executor)
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        for number, handler in previous.items():
            signal.signal(number, handler)


def _spin(executor, stopped, stop):
    try:
        executor.spin_until_future_complete(stopped)
    except ExternalShutdownException:
        pass
    finally:
        stop.set()


def _wait_for_callbacks(executor):
    """Wait for the callbacks running in a MultiThreadedExecutor's threads.

    rclpy 7.1 (Jazzy)'s ``Executor.shutdown`` skips its own wait for them and
    leaves the thread pool running; upstream rclpy added
    ``shutdown(wait_for_threads=True)`` for this (ros2/rclpy#1309), which
    shuts the pool down the same way.
    """
    pool = getattr(executor, "_executor", None)
    if pool is not None:
        pool.shutdown(wait=True)
