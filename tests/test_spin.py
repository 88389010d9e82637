"""The nodes' ``main`` spins for as long as a node runs without holding more
with each callback: a node whose timer fires every millisecond holds as many
objects after thousands of callbacks as after a few hundred, on either
executor.  Real rclpy, in this process's main thread (signals are handled
there), stopped by a real SIGINT."""

import gc
import os
import signal

import pytest
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from rpr3_gwr_nodes.spin import run

# Callbacks run before the first count, and between the two.
WARM = 200
TICKS = 2000


class _Ticker(Node):
    """Counts the objects the process holds after ``WARM`` and after
    ``WARM + TICKS`` callbacks of a 1 kHz timer, then sends this process
    SIGINT."""

    def __init__(self):
        super().__init__("spin_ticker")
        self.ticks = 0
        self.held = []
        self.create_timer(0.001, self._tick)

    def _tick(self):
        self.ticks += 1
        if self.ticks in (WARM, WARM + TICKS):
            gc.collect()
            self.held.append(len(gc.get_objects()))
        if self.ticks == WARM + TICKS:
            os.kill(os.getpid(), signal.SIGINT)


@pytest.mark.parametrize("executor_type", [SingleThreadedExecutor, MultiThreadedExecutor])
def test_spinning_holds_nothing_more_per_callback(executor_type):
    nodes = []

    def ticker():
        nodes.append(_Ticker())
        return nodes[-1]

    assert run(ticker, executor_type, ["spin_ticker"], usage="") == 0
    before, after = nodes[0].held
    assert after - before < TICKS // 4, (before, after)
