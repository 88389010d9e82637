"""The roadmap builder's run-time parameters: rebuild on a valid change,
refusal with a reason on an invalid one, and the last good roadmap kept when
a grid gives an empty one."""

import threading
import time

import numpy as np
import pytest
from nav_msgs.msg import OccupancyGrid

from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_msgs.msg import NSolutionField
from rpr3_gwr_nodes.profiles import LATCHED_QOS
from rpr3_gwr_nodes import roadmap_builder
from rpr3_gwr_nodes.roadmap_builder import RoadmapBuilder
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

TIMEOUT = 60.0


class BuilderUnderTest:
    """A builder on a coarse grid and a listener of its field, spun by one
    executor thread."""

    def __init__(self, context):
        self.builder = RoadmapBuilder(context=context,
                                      parameter_overrides=[Parameter("step", value=0.5)])
        self.listener = Node("field_listener", context=context)
        self.fields, self.arrived = [], threading.Event()
        self.listener.create_subscription(NSolutionField, "field", self._keep, LATCHED_QOS)
        self.static_transforms = []
        self.listener.create_subscription(TFMessage, "/tf_static",
                                          lambda msg: self.static_transforms.append(msg),
                                          LATCHED_QOS)
        self.executor = MultiThreadedExecutor(context=context)
        self.executor.add_node(self.builder)
        self.executor.add_node(self.listener)
        self.spinner = threading.Thread(target=self.executor.spin, daemon=True)
        self.spinner.start()

    def _keep(self, msg):
        self.fields.append(msg)
        self.arrived.set()

    def close(self):
        self.executor.shutdown(timeout_sec=10.0)
        self.spinner.join(timeout=10.0)
        self.listener.destroy_node()
        self.builder.destroy_node()


@pytest.fixture
def rig(ros_context):
    running = BuilderUnderTest(ros_context)
    try:
        yield running
    finally:
        running.close()


def test_the_joint_space_frame_is_placed_beside_the_base_on_tf_static(rig):
    assert rig.arrived.wait(TIMEOUT), "no field published"
    deadline = time.monotonic() + TIMEOUT
    while not rig.static_transforms:
        assert time.monotonic() < deadline, "nothing on /tf_static"
        time.sleep(0.02)
    (transform,) = rig.static_transforms[-1].transforms
    assert (transform.header.frame_id, transform.child_frame_id) == ("base", "joint_space")
    # Three times the paper's platform's longest side, d3 = 20.84.
    assert transform.transform.translation.x == pytest.approx(3 * 20.84)
    assert transform.transform.rotation.w == 1.0


def test_builder_rebuilds_on_rho1_and_refuses_bad_grids(rig):
    builder, fields, arrived = rig.builder, rig.fields, rig.arrived
    assert arrived.wait(TIMEOUT), "no field published"
    assert fields[-1].grid.fixed[0].value == 17.0 and fields[-1].grid.axes[0].count == 101
    assert fields[-1].mechanism.kind == "3-RPR"
    for bad in (Parameter("step", value=-0.5),
                Parameter("ranges", value=[10.0, 5.0, 0.0, 50.0]),
                Parameter("ranges", value=[0.0, 50.0]),
                Parameter("ranges", value=[-1.0, 50.0, 0.0, 50.0]),
                Parameter("fixed_value", value=-1.0), Parameter("step", value=0.001)):
        result = builder.set_parameters([bad])[0]
        assert not result.successful and result.reason, bad.name
    assert builder.get_parameter("step").value == 0.5
    arrived.clear()
    assert builder.set_parameters([Parameter("fixed_value", value=13.0)])[0].successful
    assert arrived.wait(TIMEOUT), "no field republished after the change"
    assert fields[-1].grid.fixed[0].value == 13.0
    assert builder.roadmap.grid.fixed_value(0) == 13.0


def test_a_slice_refined_around_a_thin_region_is_published_with_its_cusps(rig):
    # At rho1 = 27.5 the rig's 0.5 grid has a thin region, as the default
    # 0.125 one has.
    builder, fields = rig.builder, rig.fields
    assert rig.arrived.wait(TIMEOUT), "no field published"
    assert builder.set_parameters([Parameter("fixed_value", value=27.5)])[0].successful
    deadline = time.monotonic() + TIMEOUT
    while fields[-1].grid.fixed[0].value != 27.5:
        assert time.monotonic() < deadline, "no field republished after the change"
        time.sleep(0.05)
    assert fields[-1].grid.refinement and len(fields[-1].grid.refined_blocks)
    assert fields[-1].cusps and all(cusp.regions for cusp in fields[-1].cusps)


def test_builder_refuses_grids_without_a_roadmap_and_keeps_the_last_good(rig):
    builder, fields, arrived = rig.builder, rig.fields, rig.arrived
    assert arrived.wait(TIMEOUT), "no field published"
    good = fields[-1]
    for bad in ([Parameter("fixed_value", value=0.001)],
                [Parameter("fixed_value", value=1000.0)],
                [Parameter("ranges", value=[12.0, 12.0, 0.0, 50.0])]):
        result = builder.set_parameters(bad)[0]
        assert not result.successful and result.reason, bad
    # Accepted at once (its 8 cells have solutions), but the singular locus
    # splits them into sets too small for a region (solution counts 4, 2,
    # 2, 2 / 2, 4, 2, 2): the built roadmap has no patch, so the
    # parameters go back.
    tiny = [Parameter("ranges", value=[4.0, 4.5, 6.0, 7.5])]
    assert builder.set_parameters_atomically(tiny).successful
    deadline = time.monotonic() + TIMEOUT
    while builder.get_parameter("ranges").value and time.monotonic() < deadline:
        time.sleep(0.05)
    # Back to the published roadmap's: the file's box.
    assert not builder.get_parameter("ranges").value
    time.sleep(0.5)
    assert fields[-1] is good and len(builder.roadmap.segmentation.patches) > 0
    assert (builder.roadmap.grid.axes[0].low, builder.roadmap.grid.axes[0].high) == (0.0, 50.0)


def test_a_roadmap_that_cannot_be_sent_leaves_the_last_one_and_the_builder_serving(
        rig, monkeypatch):
    builder, fields, arrived = rig.builder, rig.fields, rig.arrived
    assert arrived.wait(TIMEOUT), "no field published"
    good, converted = fields[-1], roadmap_builder.roadmap_to_msgs
    failures = []

    def fails_once(roadmap, header):
        if not failures:
            failures.append(roadmap)
            raise RuntimeError("a roadmap no message can carry")
        return converted(roadmap, header)

    monkeypatch.setattr(roadmap_builder, "roadmap_to_msgs", fails_once)
    assert builder.set_parameters([Parameter("fixed_value", value=13.0)])[0].successful
    deadline = time.monotonic() + TIMEOUT
    while not (failures and builder.get_parameter("fixed_value").value == 17.0):
        assert time.monotonic() < deadline, "the parameters did not go back"
        time.sleep(0.05)
    assert fields[-1] is good and builder.roadmap.grid.fixed_value(0) == 17.0
    # Still serving: the next change is built and sent.
    arrived.clear()
    assert builder.set_parameters([Parameter("fixed_value", value=13.0)])[0].successful
    assert arrived.wait(TIMEOUT), "no field after the failed one"
    assert fields[-1].grid.fixed[0].value == 13.0


def test_the_builder_draws_the_field_and_the_roadmap_for_rviz(rig):
    assert rig.arrived.wait(TIMEOUT), "no field published"
    got, done = {}, threading.Event()
    topics = {"field_count_map": OccupancyGrid, "field_region_map": OccupancyGrid,
              "roadmap_markers": MarkerArray}

    def keep(topic):
        def callback(msg):
            got[topic] = msg
            if len(got) == len(topics):
                done.set()
        return callback

    for topic, kind in topics.items():
        rig.listener.create_subscription(kind, topic, keep(topic), LATCHED_QOS)
    assert done.wait(TIMEOUT), f"only {sorted(got)} arrived"
    roadmap = rig.builder.roadmap
    seg, (n2, n3) = roadmap.segmentation, roadmap.grid.shape
    for topic, cells in (("field_count_map", seg.field.count), ("field_region_map", seg.region)):
        grid_map = got[topic]
        assert grid_map.header.frame_id == "joint_space"
        assert (grid_map.info.width, grid_map.info.height, grid_map.info.resolution) == (
            n2, n3, 0.5)
        # Back from x-fastest map order to the grid's row-major cells.
        values = np.array(grid_map.data).reshape(n3, n2).T.ravel()
        np.testing.assert_array_equal(values > 0, cells > 0)
    labels = [m for m in got["roadmap_markers"].markers if m.ns == "patches"]
    assert sorted(int(m.text) for m in labels) == sorted(seg.patches)
    gates = [m for m in got["roadmap_markers"].markers if m.ns == "gates"][0]
    assert len(gates.points) == 4 * len(seg.gates)
