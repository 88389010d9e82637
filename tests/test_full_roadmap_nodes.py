"""The full 3-DOF roadmap through the nodes: its messages decode to the same
roadmap, and a builder in full mode feeds a planner that plans with rho1
moving over real DDS."""

import threading
import time

import numpy as np
import pytest
from rclpy.executors import MultiThreadedExecutor
from rclpy.parameter import Parameter
from rpr3_gwr_core import Planner
from rpr3_gwr_msgs.msg import Configuration
from rpr3_gwr_nodes.client import PlannerClient
from rpr3_gwr_nodes.conversions import roadmap_from_msgs, roadmap_to_msgs
from rpr3_gwr_nodes.planner import PlannerNode
from rpr3_gwr_nodes.roadmap_builder import RoadmapBuilder
from std_msgs.msg import Header

# Same legs, one solution in the pocket of the det Jx < 0 side at rho1 = 27.5,
# the other outside it (src/rpr3_gwr_core/test/test_full_roadmap.py).
POCKET = ((27.5, 31.67154934, 2.14117832, -1.7627825445142729),
          (27.5, 31.67154934, 2.14117832, 2.7584625675676517))
TIMEOUT = 120.0


@pytest.mark.slow
def test_the_full_roadmap_decodes_from_its_messages(full_roadmap):
    decoded = roadmap_from_msgs(*roadmap_to_msgs(full_roadmap, Header(frame_id="base")))
    assert decoded.grid == full_roadmap.grid
    a, b = full_roadmap.segmentation, decoded.segmentation
    np.testing.assert_array_equal(a.patch, b.patch)
    np.testing.assert_array_equal(a.field.poses, b.field.poses)
    assert a.gates.keys() == b.gates.keys()
    reference = Planner(full_roadmap).plan(*POCKET)
    plan = Planner(decoded).plan(*POCKET)
    np.testing.assert_array_equal(plan.joints, reference.joints)


def _configuration(values):
    return Configuration(positions=list(values[:3]), mode=values[3])


def test_a_builder_in_full_mode_feeds_a_planner_that_moves_rho1(ros_context, full_roadmap):
    builder = RoadmapBuilder(context=ros_context,
                             parameter_overrides=[Parameter("full", value=True)])
    planner = PlannerNode(context=ros_context)
    executor = MultiThreadedExecutor(num_threads=3, context=ros_context)
    for node in (builder, planner):
        executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    client = PlannerClient("full_client", context=ros_context)
    try:
        start = time.monotonic()
        assert planner.ready.wait(TIMEOUT), "the planner got no full roadmap"
        print(f"full roadmap from the builder (cache) to usable in the planner: "
              f"{time.monotonic() - start:.1f} s")
        assert builder.roadmap.grid == full_roadmap.grid
        client.wait_until_ready(timeout_sec=TIMEOUT)
        response = client.plan(_configuration(POCKET[0]), _configuration(POCKET[1]),
                               skip_smoothing=True, max_velocity=2.0, max_acceleration=4.0,
                               timeout_sec=TIMEOUT)
        assert response.success, response.error_msg
        assert not response.roadmap_fixed_joints and not response.roadmap_fixed_values
        legs = np.array([p.positions for p in response.trajectory.points])
        assert np.ptp(legs[:, 0]) > 1.0  # rho1 moves
        assert np.allclose(legs[0], POCKET[0][:3]) and np.allclose(legs[-1], POCKET[1][:3])
        # A slice request asks the builder for rho1 = 17 again: full is refused no more.
        assert builder.set_parameters([Parameter("full", value=False)])[0].successful
    finally:
        client.destroy_node()
        executor.shutdown(timeout_sec=10.0)
        spinner.join(timeout=10.0)
        for node in (planner, builder):
            node.destroy_node()


def test_full_mode_is_a_declared_parameter(ros_context):
    builder = RoadmapBuilder(context=ros_context, parameter_overrides=[
        Parameter("full", value=False), Parameter("step", value=1.0)])
    try:
        descriptor = builder.describe_parameter("full")
        assert "every joint free" in descriptor.description
        assert builder.get_parameter("full").value is False
    finally:
        builder.destroy_node()
