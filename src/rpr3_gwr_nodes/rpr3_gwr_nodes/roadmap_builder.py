"""roadmap_builder: builds the global workspace roadmap and publishes it.

Publishes, like nav2's map server (reliable, transient local, keep last 1, so
late joiners get the latest):

* ``field`` (rpr3_gwr_msgs/NSolutionField): every cell's solutions, regions,
  patches and continuation links;
* ``roadmap`` (rpr3_gwr_msgs/WorkspaceRoadmap): patches and gates.

Parameters (geometry read-only; rho1 and the grid may change at run time,
which rebuilds and republishes; invalid values are refused with a reason):
``a1``, ``a2``, ``a3`` [length unit], ``d1``, ``d3`` [length unit], ``beta``
[rad], ``rho1``, ``rho2_range``, ``rho3_range``, ``step`` [length unit].
"""

import threading
import time

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rpr3_gwr_core.exceptions import GWRError
from rpr3_gwr_core.field import Grid
from rpr3_gwr_core.geometry import PAPER_GEOMETRY, Geometry
from rpr3_gwr_core.roadmap import build_roadmap
from rpr3_gwr_msgs.msg import NSolutionField, WorkspaceRoadmap
from std_msgs.msg import Header

from .conversions import roadmap_to_msgs
from .spin import run

__all__ = ["RoadmapBuilder", "LATCHED_QOS", "main"]

LATCHED_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
_GRID_PARAMETERS = ("rho1", "rho2_range", "rho3_range", "step")
# Largest grid the builder accepts: about 4 million cells (2001 x 2001).
_MAX_CELLS = 4_000_000


def _length(description, low=0.0, high=1000.0, read_only=False):
    return ParameterDescriptor(description=description, read_only=read_only,
                               floating_point_range=[FloatingPointRange(from_value=low,
                                                                        to_value=high)])


class RoadmapBuilder(Node):
    """Builds the roadmap with rpr3_gwr_core and publishes field and roadmap."""

    def __init__(self, **kwargs):
        super().__init__("roadmap_builder", **kwargs)
        g = PAPER_GEOMETRY
        for name, value in (("a1", g.a1), ("a2", g.a2), ("a3", g.a3)):
            self.declare_parameter(name, list(value), ParameterDescriptor(
                description=f"Base joint {name.upper()} (x, y) [length unit]", read_only=True))
        self.declare_parameter("d1", g.d1, _length("Platform side B1B2 [length unit]",
                                                   read_only=True))
        self.declare_parameter("d3", g.d3, _length("Platform side B1B3 [length unit]",
                                                   read_only=True))
        self.declare_parameter("beta", g.beta, ParameterDescriptor(
            description="Platform angle at B1 [rad]", read_only=True,
            floating_point_range=[FloatingPointRange(from_value=-3.1416, to_value=3.1416)]))
        self.declare_parameter("rho1", 17.0, _length("Fixed first leg [length unit]",
                                                     low=0.001))
        self.declare_parameter("rho2_range", [0.0, 50.0], ParameterDescriptor(
            description="Grid range of rho2, [min, max] [length unit]"))
        self.declare_parameter("rho3_range", [0.0, 50.0], ParameterDescriptor(
            description="Grid range of rho3, [min, max] [length unit]"))
        self.declare_parameter("step", 0.125, _length("Grid step [length unit]", low=0.001,
                                                      high=100.0))
        self.geometry = Geometry(
            a1=tuple(self.get_parameter("a1").value), a2=tuple(self.get_parameter("a2").value),
            a3=tuple(self.get_parameter("a3").value), d1=self.get_parameter("d1").value,
            d3=self.get_parameter("d3").value, beta=self.get_parameter("beta").value)
        self.field_pub = self.create_publisher(NSolutionField, "field", LATCHED_QOS)
        self.roadmap_pub = self.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS)
        self._pending = threading.Event()
        self._pending.set()
        self.roadmap = None
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._parameters_set)
        # Builds run in a timer of their own so parameter services keep answering.
        self._build_timer = self.create_timer(0.05, self._build_if_pending,
                                              callback_group=MutuallyExclusiveCallbackGroup())

    def _grid(self, overrides=None):
        values = {name: self.get_parameter(name).value for name in _GRID_PARAMETERS}
        values.update(overrides or {})
        return Grid(rho1=values["rho1"], rho2_range=tuple(values["rho2_range"]),
                    rho3_range=tuple(values["rho3_range"]), step=values["step"])

    def _check_parameters(self, parameters):
        overrides = {p.name: p.value for p in parameters if p.name in _GRID_PARAMETERS}
        if not overrides:
            return SetParametersResult(successful=True)
        try:
            grid = self._grid(overrides)
        except (GWRError, TypeError, ValueError) as exc:
            return SetParametersResult(successful=False, reason=f"invalid grid: {exc}")
        if grid.size > _MAX_CELLS:
            return SetParametersResult(successful=False, reason=(
                f"grid of {grid.size} cells exceeds the limit of {_MAX_CELLS}"))
        return SetParametersResult(successful=True)

    def _parameters_set(self, parameters):
        if any(p.name in _GRID_PARAMETERS for p in parameters):
            self._pending.set()

    def _build_if_pending(self):
        if not self._pending.is_set():
            return
        self._pending.clear()
        grid = self._grid()
        n2, n3 = grid.shape
        self.get_logger().info(f"building the roadmap: rho1 = {grid.rho1:g}, {n2} x {n3} cells")
        start = time.perf_counter()

        def progress(stage, fraction):
            self.get_logger().info(f"  {fraction:4.0%} {stage}")

        self.roadmap = build_roadmap(self.geometry, grid, progress=progress)
        seg = self.roadmap.segmentation
        header = Header(stamp=self.get_clock().now().to_msg(), frame_id="rpr3_base")
        field_msg, roadmap_msg = roadmap_to_msgs(self.roadmap, header)
        self.field_pub.publish(field_msg)
        self.roadmap_pub.publish(roadmap_msg)
        self.get_logger().info(
            f"published the roadmap: {seg.n_regions} regions, {len(seg.patches)} patches, "
            f"{len(seg.gates)} gates, built in {time.perf_counter() - start:.2f} s")


def main(args=None):
    run(RoadmapBuilder, MultiThreadedExecutor, args)
