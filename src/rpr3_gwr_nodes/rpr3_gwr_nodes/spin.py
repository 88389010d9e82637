"""The ``main`` of every node of the suite, as in ros2/demos: init, spin until
Ctrl-C or an external shutdown, then always destroy the node and shut down.

One difference: rclpy's own SIGINT and SIGTERM handlers shut the context
down at once, so a service callback still computing could no longer send its
answer (rclpy then logs "exception was never retrieved").  Here a signal only
stops the spinning; callbacks in flight finish and answer, the requests still
waiting in the node's services are answered too, then the node is destroyed
and the context shut down.

``-h`` or ``--help`` among the arguments (not the ROS arguments) prints the
node's usage and exits before ``rclpy.init``: nothing joins the graph.  A
node that cannot start (a mechanism or scene file it cannot take, a
parameter of the wrong type) says why in one error line and exits with
status 1, without a traceback.
"""

import os

import signal
import sys
import threading
import time

import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.logging import get_logger
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args
from rpr3_gwr_core.exceptions import GWRError

__all__ = ["run", "help_requested"]

_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
# Longest delay from a stop signal to its handler [s].
_SIGNAL_PERIOD = 0.1
# How long requests sent just before the signal may take to reach the node's
# services, and how often they are looked for meanwhile [s].
_DRAIN_GRACE = 0.2
_DRAIN_PERIOD = 0.01
# Said after every node's own usage.
_ROS_ARGUMENTS = """\
ROS arguments come after --ros-args:
  -p NAME:=VALUE           set a parameter (repeat for several)
  --params-file FILE       set parameters from a YAML file
  -r __ns:=/NAMESPACE      run in a namespace (relative names resolve in it)
  -r __node:=NAME          rename the node
  --log-level LEVEL        debug, info, warn, error or fatal
The ROS domain is ROS_DOMAIN_ID's (source ros2_ws/env.sh for the suite's
loopback DDS profile).  Running, `ros2 param describe <node> <name>`
describes each parameter.
"""


def help_requested(args=None):
    """Whether ``-h`` or ``--help`` is among the program's own arguments
    (``args``, else ``sys.argv``, without the ROS arguments: those between
    ``--ros-args`` and ``--``)."""
    own = remove_ros_args(sys.argv if args is None else list(args))[1:]
    return "-h" in own or "--help" in own


def run(node_type, executor_type, args=None, *, usage, **executor_options):
    """Create ``node_type()``, spin it on ``executor_type(**executor_options)``
    until SIGINT, SIGTERM or an external shutdown; with ``-h`` or ``--help``
    print ``usage`` (the node's purpose, names and parameters) and return.
    The exit status: 0, or 1 when the node could not start.

    The node is created after ``rclpy.init`` and destroyed in ``finally``
    (the recorder closes its bag there), after the callbacks running in the
    executor's threads have finished; a node whose callbacks run long (the
    driver executing a trajectory) defines ``prepare_shutdown()`` to make
    them end now.
    """
    if help_requested(args):
        print(usage.rstrip() + "\n\n" + _ROS_ARGUMENTS, end="")
        return 0
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    node = executor = spinner = None
    stop, stopped = threading.Event(), threading.Event()
    # The handler runs between two bytecodes of the main thread, which may
    # hold the lock inside an Event at that moment: it appends to a list,
    # which takes no lock (Event.set would wait for the main thread forever).
    signalled = []
    previous = {number: signal.signal(number, lambda number, _: signalled.append(number))
                for number in _STOP_SIGNALS}
    try:
        try:
            node = node_type()
        except (GWRError, OSError, ParameterException) as exc:
            # What the user gave is wrong, not the program: one line, as the CLI's.
            get_logger(os.path.basename(sys.argv[0])).error(f"cannot start: {exc}")
            return 1
        executor = executor_type(**executor_options)
        executor.add_node(node)
        spinner = threading.Thread(target=_spin, args=(executor, stopped, stop), name="spin")
        spinner.start()
        # Signal handlers run in the main thread, and only while it runs
        # Python: it waits here, not in rclpy's wait set.  The kernel may
        # hand the signal to another thread (one of DDS's), which does not
        # interrupt this wait: it wakes up now and then to run the handler.
        while not signalled and not stop.is_set():
            time.sleep(_SIGNAL_PERIOD)
    except KeyboardInterrupt:
        pass
    finally:
        if spinner is not None:
            stopped.set()
            executor.wake()
            spinner.join()
        if executor is not None:
            if hasattr(node, "prepare_shutdown"):
                node.prepare_shutdown()
            # Callbacks still running use the executor's guard condition,
            # which its shutdown destroys: they finish first.
            _wait_for_callbacks(executor)
            _answer_waiting_requests(node)
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        for number, handler in previous.items():
            signal.signal(number, handler)
    return 0


def _spin(executor, stopped, stop):
    """Spin until ``stopped`` is set, then set ``stop``.

    Not ``spin_until_future_complete``: rclpy 7.1 adds a done callback to the
    future at each callback it runs, which a node spun for hours would hold
    by the million.
    """
    try:
        while not stopped.is_set():
            executor.spin_once(timeout_sec=_SIGNAL_PERIOD)
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


def _answer_waiting_requests(node):
    """Answer, in this thread, the requests waiting in the node's services.

    The executor takes one request of a service per callback it starts, so
    when the spinning stops, requests that arrived together (a burst of
    clients) may still wait in the service's reader, and would die with the
    node unanswered whatever the signal.  The take is the executor's own
    (``Executor._take_service``).  The suite's service callbacks are plain
    functions.
    """
    deadline = time.monotonic() + _DRAIN_GRACE
    while True:
        answered = False
        for service in node.services:
            with service.handle:
                request, header = service.handle.service_take_request(service.srv_type.Request)
            if header is not None:
                service.send_response(service.callback(request, service.srv_type.Response()),
                                      header)
                answered = True
        if not answered:
            if time.monotonic() >= deadline:
                return
            time.sleep(_DRAIN_PERIOD)
