"""The ``main`` of every node of the suite, as in ros2/demos: init, spin until
Ctrl-C or an external shutdown, then always destroy the node and shut down."""

import rclpy
from rclpy.executors import ExternalShutdownException

__all__ = ["run"]


def run(node_type, executor_type, args=None, **executor_options):
    """Create ``node_type()``, spin it on ``executor_type(**executor_options)``.

    The node is created after ``rclpy.init`` and destroyed in ``finally``, so
    its ``destroy_node`` (the recorder closes its bag there) also runs on
    SIGINT.
    """
    rclpy.init(args=args)
    node = None
    try:
        node = node_type()
        executor = executor_type(**executor_options)
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
