"""The shape of the integration tests' rigs: their nodes spun by an executor
in a thread of its own, beside a ``PlannerClient`` that spins itself."""

import threading

from rclpy.executors import MultiThreadedExecutor
from rpr3_gwr_nodes.client import PlannerClient

# The longest a spin waits before it looks whether it should stop [s].
_STOP_PERIOD = 0.1


class SpunNodes:
    """Spin ``nodes`` on a ``num_threads`` executor in a daemon thread and
    make ``client``, a :class:`PlannerClient` named ``client_name`` in
    ``namespace``; :meth:`add` spins one more node; :meth:`close` destroys
    the client, stops the spin, waits for the callbacks running, then
    destroys the executor and the nodes, the last first."""

    def __init__(self, context, nodes, client_name="planner_client", namespace="",
                 num_threads=4):
        self.nodes = list(nodes)
        self.executor = MultiThreadedExecutor(num_threads=num_threads, context=context)
        for node in self.nodes:
            self.executor.add_node(node)
        self._stopped = threading.Event()
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()
        self.client = PlannerClient(client_name, context=context, namespace=namespace)

    def add(self, node):
        """Spin ``node`` too, and destroy it first; returns it."""
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def _spin(self):
        while not self._stopped.is_set():
            self.executor.spin_once(timeout_sec=_STOP_PERIOD)

    def close(self):
        self.client.destroy_node()
        # rclpy 7.1's shutdown destroys the executor's guard condition
        # without waiting for the callbacks in its thread pool (the driver's
        # state timer's), which trigger it when done: one still running
        # failed, and its task, never retrieved once the spin had stopped,
        # said so when collected ("cannot use Destroyable because destruction
        # was requested").  So the spin stops between two callbacks, the pool
        # finishes those started (as spin.run does), then the executor goes.
        self._stopped.set()
        self.executor.wake()
        self.thread.join(timeout=10.0)
        self.executor._executor.shutdown(wait=True)
        self.executor.shutdown(timeout_sec=10.0)
        for node in reversed(self.nodes):
            node.destroy_node()
