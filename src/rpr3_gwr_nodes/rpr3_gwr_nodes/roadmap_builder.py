"""roadmap_builder: builds the global workspace roadmap and publishes it.

Publishes, like nav2's map server (reliable, transient local, keep last 1, so
late joiners get the latest):

* ``field`` (rpr3_gwr_msgs/NSolutionField): every cell's solutions, regions,
  patches and continuation links;
* ``roadmap`` (rpr3_gwr_msgs/WorkspaceRoadmap): patches and gates;
* for RViz and Foxglove, on 2-D grids, in the frame ``joint_space``
  (x = rho2, y = rho3): ``field_count_map`` and ``field_region_map``
  (nav_msgs/OccupancyGrid, as maps) and ``roadmap_markers``
  (visualization_msgs/MarkerArray: patch labels, gates).

Parameters: the geometry (``a1``, ``a2``, ``a3``, ``d1``, ``d3`` [length
unit], ``beta`` [rad], read-only, :mod:`.geometry_parameters`) and the grid
(``rho1``, ``rho2_range``, ``rho3_range``, ``step`` [length unit]), which
may change at run time: a change is checked at once (at least two cells along
each axis, at most the core's ``MAX_GRID_CELLS``, some cell with a
direct-kinematic solution) and refused with a reason, else the roadmap is
rebuilt and republished.  A
rebuilt roadmap without a patch is not published: the parameters go back to
the last published grid, whose roadmap stays latched.

``full`` (default false) builds the full 3-DOF roadmap instead, all three
legs free on the core's adaptive grid (``FULL_BASE_GRID`` refined
``FULL_REFINEMENT`` times; the slice parameters are then unused), through the
core's roadmap cache (``$RPR3_GWR_CACHE``, else ``~/.cache/rpr3-gwr``): about
25 s the first time, 2 to 3 s from the cache.  It is published on the same
topics; the maps and markers, drawn for 2-D grids, are not.
"""

import time

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.exceptions import GWRError
from rpr3_gwr_core.io.cache import cached_roadmap
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT, rho1_slice
from rpr3_gwr_core.workspace import AdaptiveGrid, build_roadmap
from rpr3_gwr_core.workspace.grid import check_roadmap_grid
from nav_msgs.msg import OccupancyGrid
from rpr3_gwr_msgs.msg import NSolutionField, WorkspaceRoadmap
from std_msgs.msg import Header
from visualization_msgs.msg import MarkerArray

from .conversions import roadmap_to_msgs
from .geometry_parameters import declare_geometry
from .memory import release_free_memory, use_one_arena
from .profiles import BASE_FRAME, LATCHED_QOS
from .spin import run
from .visualization import field_maps, roadmap_markers

__all__ = ["RoadmapBuilder", "main"]

_GRID_PARAMETERS = ("rho1", "rho2_range", "rho3_range", "step", "full")


def _length(description, low=0.0, high=1000.0):
    return ParameterDescriptor(description=description,
                               floating_point_range=[FloatingPointRange(from_value=low,
                                                                        to_value=high)])


class RoadmapBuilder(Node):
    """Builds the roadmap with rpr3_gwr_core and publishes field and roadmap."""

    def __init__(self, **kwargs):
        super().__init__("roadmap_builder", **kwargs)
        self.geometry = declare_geometry(self)
        self.declare_parameter("rho1", 17.0, _length("Fixed first leg [length unit]",
                                                     low=0.001))
        self.declare_parameter("rho2_range", [0.0, 50.0], ParameterDescriptor(
            description="Grid range of rho2, [min, max] [length unit]"))
        self.declare_parameter("rho3_range", [0.0, 50.0], ParameterDescriptor(
            description="Grid range of rho3, [min, max] [length unit]"))
        self.declare_parameter("step", 0.125, _length("Grid step [length unit]", low=0.001,
                                                      high=100.0))
        self.declare_parameter("full", False, ParameterDescriptor(
            description="Build the full 3-DOF roadmap (all legs free, adaptive grid, cached) "
                        "instead of the slice at rho1"))
        self.field_pub = self.create_publisher(NSolutionField, "field", LATCHED_QOS)
        self.roadmap_pub = self.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS)
        self.map_pubs = [self.create_publisher(OccupancyGrid, topic, LATCHED_QOS)
                         for topic in ("field_count_map", "field_region_map")]
        self.marker_pub = self.create_publisher(MarkerArray, "roadmap_markers", LATCHED_QOS)
        self.roadmap = None
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._parameters_set)
        # Builds run in a callback of their own, woken by the parameter
        # callback, so parameter services keep answering during a build.
        self._rebuild = self.create_guard_condition(
            self._on_rebuild, callback_group=MutuallyExclusiveCallbackGroup())
        self._rebuild.trigger()

    def _grid(self, overrides=None):
        """The slice the parameters ask for, or None for the full roadmap."""
        values = {name: self.get_parameter(name).value for name in _GRID_PARAMETERS}
        values.update(overrides or {})
        if values["full"]:
            return None
        return rho1_slice(values["rho1"], tuple(values["rho2_range"]),
                          tuple(values["rho3_range"]), values["step"])

    def _check_parameters(self, parameters):
        overrides = {p.name: p.value for p in parameters if p.name in _GRID_PARAMETERS}
        if not overrides:
            return SetParametersResult(successful=True)
        try:
            grid = self._grid(overrides)
            if grid is None:
                return SetParametersResult(successful=True)
        except (GWRError, TypeError, ValueError) as exc:
            return SetParametersResult(successful=False, reason=f"invalid grid: {exc}")
        try:
            check_roadmap_grid(self.geometry, grid)
        except GWRError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _parameters_set(self, parameters):
        if any(p.name in _GRID_PARAMETERS for p in parameters) and (
                self.roadmap is None or self._grid() != self._published_request):
            self._rebuild.trigger()

    @property
    def _published_request(self):
        """What the published roadmap answers: its slice, or None if full."""
        grid = self.roadmap.grid
        return None if isinstance(grid, AdaptiveGrid) and grid.base == FULL_BASE_GRID else grid

    def _on_rebuild(self):
        self._build()
        # The replaced roadmap, the messages and the build's temporaries are
        # freed now; malloc would keep their pages (module memory).
        release_free_memory()

    def _build(self):
        grid = self._grid()
        if grid is None:
            self.get_logger().info("building the full 3-DOF roadmap (all legs free) or "
                                   "loading it from the cache")
        else:
            n2, n3 = grid.shape
            self.get_logger().info(f"building the roadmap: rho1 = {grid.fixed_value(0):g}, "
                                   f"{n2} x {n3} cells")
        start = time.perf_counter()

        def progress(stage, fraction):
            self.get_logger().info(f"  {fraction:4.0%} {stage}")

        try:
            if grid is None:
                roadmap, _ = cached_roadmap(self.geometry, FULL_BASE_GRID, progress=progress,
                                            refinement=FULL_REFINEMENT)
            else:
                roadmap = build_roadmap(self.geometry, grid, progress=progress)
        except Exception as exc:  # a failed build must not take the builder down
            self.get_logger().error(f"building the roadmap failed: {exc!r}")
            self._keep_last_good(grid)
            return
        seg = roadmap.segmentation
        if not seg.patches:
            self.get_logger().error("the roadmap has no patch")
            self._keep_last_good(grid)
            return
        self.roadmap = roadmap
        built = time.perf_counter()
        header = Header(stamp=self.get_clock().now().to_msg(), frame_id=BASE_FRAME)
        field_msg, roadmap_msg = roadmap_to_msgs(roadmap, header)
        packed = time.perf_counter()
        self.field_pub.publish(field_msg)
        self.roadmap_pub.publish(roadmap_msg)
        sent = time.perf_counter()
        maps = field_maps(roadmap, header.stamp)
        if maps is not None:
            for publisher, grid_map in zip(self.map_pubs, maps):
                publisher.publish(grid_map)
            self.marker_pub.publish(roadmap_markers(roadmap, header.stamp))
        self.get_logger().info(
            f"published the roadmap: {seg.n_regions} regions, {len(seg.patches)} patches, "
            f"{len(seg.gates)} gates, built in {built - start:.2f} s, messages packed in "
            f"{packed - built:.2f} s, published in {sent - packed:.2f} s")

    def _keep_last_good(self, grid):
        """Leave the published roadmap latched and the parameters naming its grid."""
        if self.roadmap is None:
            self.get_logger().error("no roadmap is published")
            return
        good = self._published_request
        self.get_logger().error("the published roadmap stays; the grid parameters go back "
                                "to its grid")
        if good is None:
            self.set_parameters_atomically([Parameter("full", value=True)])
            return
        rho2, rho3 = good.axes
        self.set_parameters_atomically([
            Parameter("full", value=False),
            Parameter("rho1", value=good.fixed_value(0)),
            Parameter("rho2_range", value=[rho2.low, rho2.high]),
            Parameter("rho3_range", value=[rho3.low, rho3.high]),
            Parameter("step", value=rho2.step)])


def main(args=None):
    # So that release_free_memory reaches the memory of every thread.
    use_one_arena()
    run(RoadmapBuilder, MultiThreadedExecutor, args)
