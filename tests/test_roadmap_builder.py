"""The roadmap builder's run-time parameters: rebuild on a valid change,
refusal with a reason on an invalid one, and the last good roadmap kept when
a grid gives an empty one."""

import threading
import time

from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_msgs.msg import NSolutionField
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from rpr3_gwr_nodes.roadmap_builder import RoadmapBuilder

TIMEOUT = 60.0


def test_builder_rebuilds_on_rho1_and_refuses_bad_grids(ros_context):
    builder = RoadmapBuilder(context=ros_context,
                             parameter_overrides=[Parameter("step", value=0.5)])
    listener = Node("field_listener", context=ros_context)
    executor = MultiThreadedExecutor(context=ros_context)
    fields, arrived = [], threading.Event()

    def keep(msg):
        fields.append(msg)
        arrived.set()

    listener.create_subscription(NSolutionField, "field", keep, LATCHED_QOS)
    executor.add_node(builder)
    executor.add_node(listener)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        assert arrived.wait(TIMEOUT), "no field published"
        assert fields[-1].grid.fixed[0].value == 17.0 and fields[-1].grid.axes[0].count == 101
        for bad in (Parameter("step", value=-0.5), Parameter("rho2_range", value=[10.0, 5.0]),
                    Parameter("rho1", value=0.0), Parameter("step", value=0.001)):
            result = builder.set_parameters([bad])[0]
            assert not result.successful and result.reason, bad.name
        assert builder.get_parameter("step").value == 0.5
        arrived.clear()
        assert builder.set_parameters([Parameter("rho1", value=13.0)])[0].successful
        assert arrived.wait(TIMEOUT), "no field republished after the change"
        assert fields[-1].grid.fixed[0].value == 13.0
        assert builder.roadmap.grid.fixed_value(0) == 13.0
    finally:
        executor.shutdown(timeout_sec=10.0)
        spinner.join(timeout=10.0)
        listener.destroy_node()
        builder.destroy_node()


def test_builder_refuses_grids_without_a_roadmap_and_keeps_the_last_good(ros_context):
    builder = RoadmapBuilder(context=ros_context,
                             parameter_overrides=[Parameter("step", value=0.5)])
    listener = Node("field_listener", context=ros_context)
    executor = MultiThreadedExecutor(context=ros_context)
    fields, arrived = [], threading.Event()

    def keep(msg):
        fields.append(msg)
        arrived.set()

    listener.create_subscription(NSolutionField, "field", keep, LATCHED_QOS)
    executor.add_node(builder)
    executor.add_node(listener)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        assert arrived.wait(TIMEOUT), "no field published"
        good = fields[-1]
        for bad in ([Parameter("rho1", value=0.001)], [Parameter("rho1", value=1000.0)],
                    [Parameter("rho2_range", value=[12.0, 12.0])]):
            result = builder.set_parameters(bad)[0]
            assert not result.successful and result.reason, bad
        # Accepted at once (its 8 cells have solutions), but the singular locus
        # splits them into sets too small for a region (solution counts 4, 2,
        # 2, 2 / 2, 4, 2, 2): the built roadmap has no patch, so the
        # parameters go back.
        tiny = [Parameter("rho2_range", value=[4.0, 4.5]),
                Parameter("rho3_range", value=[6.0, 7.5])]
        assert builder.set_parameters_atomically(tiny).successful
        deadline = time.monotonic() + TIMEOUT
        while (builder.get_parameter("rho2_range").value != [0.0, 50.0]
               and time.monotonic() < deadline):
            time.sleep(0.05)
        assert builder.get_parameter("rho2_range").value == [0.0, 50.0]
        assert builder.get_parameter("rho3_range").value == [0.0, 50.0]
        time.sleep(0.5)
        assert fields[-1] is good and len(builder.roadmap.segmentation.patches) > 0
        assert (builder.roadmap.grid.axes[0].low, builder.roadmap.grid.axes[0].high) == (0.0, 50.0)
    finally:
        executor.shutdown(timeout_sec=10.0)
        spinner.join(timeout=10.0)
        listener.destroy_node()
        builder.destroy_node()
