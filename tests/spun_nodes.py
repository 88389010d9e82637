"""The shape of the integration tests' rigs: their nodes spun by an executor
in a thread of its own, beside a ``PlannerClient`` that spins itself."""

import threading

from rclpy.executors import MultiThreadedExecutor
from rpr3_gwr_nodes.client import PlannerClient


class SpunNodes:
    """Spin ``nodes`` on a four-thread executor in a daemon thread and make
    ``client``, a :class:`PlannerClient` named ``client_name`` in
    ``namespace``; :meth:`close` destroys the client, stops the executor,
    then destroys the nodes, the last first."""

    def __init__(self, context, nodes, client_name, namespace=""):
        self.nodes = list(nodes)
        self.executor = MultiThreadedExecutor(num_threads=4, context=context)
        for node in self.nodes:
            self.executor.add_node(node)
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()
        self.client = PlannerClient(client_name, context=context, namespace=namespace)

    def close(self):
        self.client.destroy_node()
        self.executor.shutdown(timeout_sec=10.0)
        self.thread.join(timeout=10.0)
        for node in reversed(self.nodes):
            node.destroy_node()
