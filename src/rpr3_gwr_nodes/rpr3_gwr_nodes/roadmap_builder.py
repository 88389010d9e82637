"""roadmap_builder: builds the global workspace roadmap and publishes it.

Publishes, like nav2's map server (reliable, transient local, keep last 1, so
late joiners get the latest):

* ``field`` (rpr3_gwr_msgs/NSolutionField): every cell's solutions, regions,
  patches and continuation links;
* ``roadmap`` (rpr3_gwr_msgs/WorkspaceRoadmap): patches and gates;
* for RViz and Foxglove, on 2-D grids, in the frame ``joint_space``
  (x, y = the two free joints, for the paper's slice rho2 and rho3):
  ``field_count_map`` and ``field_region_map`` (nav_msgs/OccupancyGrid, as
  maps) and ``roadmap_markers`` (visualization_msgs/MarkerArray: patch
  labels, gates), and on ``/tf_static`` (tf2_msgs/TFMessage, as tf2_ros's
  static broadcaster) the transform from ``base`` to ``joint_space``, which
  places the latter beside the mechanism (:func:`.visualization.joint_space_transform`).

Parameters: the mechanism (``mechanism_file``, read-only,
:mod:`.mechanism_parameters`; the paper's 3-RPR by default) and the slice,
which may change at run time: the mechanism's first joint fixed at
``fixed_value`` [joint unit], the others over the file's box, or over
``ranges`` (``[min, max]`` of each free joint, in order) and ``step``
[joint unit] when given.  A change is checked at once (at least two cells
along each axis, at most the core's ``MAX_GRID_CELLS``, some cell with a
direct-kinematic solution, values within the file's box) and refused with a
reason, else the roadmap is rebuilt and republished.  A rebuilt roadmap
without a patch is not published: the parameters go back to those of the
published roadmap, which stays latched.

``full`` (default false) builds the full roadmap instead, every joint free,
through the core's roadmap cache (``$RPR3_GWR_CACHE``, else
``~/.cache/rpr3-gwr``): for the paper's 3-RPR the core's adaptive grid
(``FULL_BASE_GRID`` refined ``FULL_REFINEMENT`` times; about 50 s the first
time, 2 to 3 s from the cache), for another mechanism its file's whole box.
It is published on the same topics; the maps and markers, drawn for 2-D
grids, are not.

A slice's thin regions, strips a few cells wide where the singularity-free
set may go on narrower than a cell, are refined round after round
(:func:`rpr3_gwr_core.workspace.refine_thin_regions`) at ``thin_refinement``
fine points a cell (default 4; 0 builds on the grid alone).  A slice without
thin regions is built once, the same roadmap; a refined one is published on
its adaptive grid, without the maps and markers of a 2-D grid.
"""

import math
import time

from rcl_interfaces.msg import IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.exceptions import GWRError, InvalidInputError
from rpr3_gwr_core.io.cache import cached_roadmap
from rpr3_gwr_core.io.mechanism_file import roadmap_grid
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT, PAPER_GEOMETRY
from rpr3_gwr_core.workspace import build_roadmap, refine_thin_regions
from rpr3_gwr_core.workspace.grid import Axis, Grid, check_roadmap_grid
from rpr3_gwr_core.workspace.thin_regions import DEFAULT_THIN_REFINEMENT
from nav_msgs.msg import OccupancyGrid
from rpr3_gwr_msgs.msg import NSolutionField, WorkspaceRoadmap
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from .conversions import roadmap_to_msgs
from .core_threads import core_threads
from .executors import BoundedExecutor
from .mechanism_parameters import declare_mechanism, home_source
from .memory import release_free_memory, use_one_arena
from .profiles import BASE_FRAME, LATCHED_QOS
from .spin import run
from .visualization import field_maps, joint_space_transform, roadmap_markers

__all__ = ["RoadmapBuilder", "main", "USAGE"]

USAGE = """\
usage: ros2 run rpr3_gwr_nodes roadmap_builder [-h] [--ros-args ...]

Builds the global workspace roadmap of a mechanism (by default the paper's
3-RPR at rho1 = 17) and publishes it, latched, for the planner; a change of
the grid parameters rebuilds and republishes it.

Publishes   field (rpr3_gwr_msgs/msg/NSolutionField), roadmap
            (rpr3_gwr_msgs/msg/WorkspaceRoadmap), both latched; on 2-D grids
            field_count_map, field_region_map, roadmap_markers, /tf_static
Parameters  mechanism_file ('' for the paper's 3-RPR, read-only),
            fixed_value (the first joint's value on the slice), ranges
            ([min, max] of each free joint, [] for the file's box), step (0
            for the file's), full (false; true: every joint free, cached),
            thin_refinement (4: fine points a cell around thin regions, 0 off)
Example     ros2 run rpr3_gwr_nodes roadmap_builder --ros-args -p fixed_value:=13.0
"""

_GRID_PARAMETERS = ("fixed_value", "ranges", "step", "full", "thin_refinement")
# Within a stage of a build, the log says where it stands this often [s].
_PROGRESS_PERIOD = 2.0
# The paper's slice: rho1 = 17.


class RoadmapBuilder(Node):
    """Builds the roadmap with rpr3_gwr_core and publishes field and roadmap."""

    def __init__(self, **kwargs):
        super().__init__("roadmap_builder", **kwargs)
        self.described = declare_mechanism(self)
        self.mechanism = self.described.mechanism
        first = self.mechanism.joint_names[0]
        home = self.described.default_home()
        self.declare_parameter(
            "fixed_value", home[0],
            ParameterDescriptor(description=f"Value at which the slice fixes the mechanism's "
                                            f"first joint, {first}, within the file's box; by "
                                            "default the home's (the mechanism file's home, "
                                            "else the one found for it; the paper's rho1 = 17) "
                                            "[joint unit]"))
        if self.get_parameter("fixed_value").value == home[0]:
            self.get_logger().info(
                f"slice at {first} = {home[0]:g}, from {home_source(self.described)}")
        self.declare_parameter("ranges", None, ParameterDescriptor(
            description="[min, max] of each free joint in order, within the file's box; "
                        "empty for the box (a joint that turns fully: its whole turn) "
                        "[joint unit]", dynamic_typing=True))
        self.declare_parameter("step", 0.0, ParameterDescriptor(
            description="Grid step of the free joints; 0 for the file's steps (with ranges, "
                        "a periodic joint's too) [joint unit]"))
        self.declare_parameter("full", False, ParameterDescriptor(
            description="Build the full roadmap (every joint free, cached: the paper's 3-RPR "
                        "on the core's adaptive grid, another mechanism on its file's box) "
                        "instead of the slice"))
        self.declare_parameter("thin_refinement", DEFAULT_THIN_REFINEMENT, ParameterDescriptor(
            description="Fine points per cell where a slice's thin regions (strips a few "
                        "cells wide that may go on narrower than a cell) are refined, round "
                        "after round; 0 builds on the grid alone, 1 is refused",
            integer_range=[IntegerRange(from_value=0, to_value=16, step=1)]))
        self.field_pub = self.create_publisher(NSolutionField, "field", LATCHED_QOS)
        self.roadmap_pub = self.create_publisher(WorkspaceRoadmap, "roadmap", LATCHED_QOS)
        self.map_pubs = [self.create_publisher(OccupancyGrid, topic, LATCHED_QOS)
                         for topic in ("field_count_map", "field_region_map")]
        self.marker_pub = self.create_publisher(MarkerArray, "roadmap_markers", LATCHED_QOS)
        # As tf2_ros's StaticTransformBroadcaster: the latest, to late joiners.
        self.tf_static_pub = self.create_publisher(TFMessage, "/tf_static", LATCHED_QOS)
        self.roadmap = None
        # The grid parameters of the published roadmap.
        self._published = None
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._parameters_set)
        # Builds run in a callback of their own, woken by the parameter
        # callback, so parameter services keep answering during a build.
        self._rebuild = self.create_guard_condition(
            self._on_rebuild, callback_group=MutuallyExclusiveCallbackGroup())
        self._rebuild.trigger()
        self.get_logger().info(f"building a first roadmap for "
                               f"{self.roadmap_pub.topic_name} and {self.field_pub.topic_name}")

    def _values(self, overrides=None):
        values = {name: self.get_parameter(name).value for name in _GRID_PARAMETERS}
        values["ranges"] = list(values["ranges"] or [])
        values.update(overrides or {})
        return values

    def _grid(self, values, progress=None, workers=map):
        """The grid and refinement the parameter values ask for (a mechanism
        file's whole box refined adaptively when it is large, to fit in
        memory, as the CLI's: its base grid is solved here)."""
        if values["full"]:
            if self.mechanism == PAPER_GEOMETRY:
                return FULL_BASE_GRID, FULL_REFINEMENT
            return roadmap_grid(self.described, progress=progress, workers=workers), None
        first = self.mechanism.joint_names[0]
        box = self.described.grid({first: values["fixed_value"]})
        ranges, step = list(values["ranges"] or []), values["step"]
        if not ranges and not step:
            return box, None
        if ranges and len(ranges) != 2 * len(box.axes):
            raise InvalidInputError(f"ranges gives [min, max] of each of the "
                                    f"{len(box.axes)} free joints, got {len(ranges)} values")
        axes = []
        for k, axis in enumerate(box.axes):
            name = self.mechanism.joint_names[axis.joint]
            if not ranges:
                if axis.periodic:
                    raise InvalidInputError(f"{name} turns fully, in the file's cells: give "
                                            "ranges to sample part of its turn with a step")
                low, high = axis.low, axis.high
            else:
                low, high = ranges[2 * k], ranges[2 * k + 1]
                if not axis.periodic and not axis.low <= low <= high <= axis.high:
                    raise InvalidInputError(f"{name} in [{low:g}, {high:g}] leaves its range "
                                            f"[{axis.low:g}, {axis.high:g}]")
            axes.append(Axis(axis.joint, low, high, step or axis.step))
        return Grid(axes=tuple(axes), fixed=box.fixed), None

    def _check_parameters(self, parameters):
        overrides = {p.name: p.value for p in parameters if p.name in _GRID_PARAMETERS}
        if not overrides:
            return SetParametersResult(successful=True)
        values = self._values(overrides)
        if values["thin_refinement"] == 1:
            return SetParametersResult(successful=False, reason="thin_refinement is 0 (off) or "
                                                                "at least 2 fine points a cell")
        if values["full"]:
            # Whether a file's whole box fits is known once its base grid is
            # solved, too long for this callback: the build says so and keeps
            # the published roadmap.
            return SetParametersResult(successful=True)
        try:
            grid, refinement = self._grid(values)
        except (GWRError, TypeError, ValueError) as exc:
            return SetParametersResult(successful=False, reason=f"invalid grid: {exc}")
        if refinement is not None:
            return SetParametersResult(successful=True)
        try:
            check_roadmap_grid(self.mechanism, grid)
        except GWRError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _parameters_set(self, parameters):
        if any(p.name in _GRID_PARAMETERS for p in parameters) and (
                self.roadmap is None or self._values() != self._published):
            self._rebuild.trigger()

    def _on_rebuild(self):
        self._build()
        # The replaced roadmap, the messages and the build's temporaries are
        # freed now; malloc would keep their pages (module memory).
        release_free_memory()

    def _build(self):
        values = self._values()
        names = self.mechanism.joint_names
        start = time.perf_counter()
        logged = {"stage": None, "at": -math.inf}

        def progress(stage, fraction):
            # A build reports dozens of times a second; its log says each
            # stage once, then where it stands every few seconds.
            now = time.perf_counter()
            if stage == logged["stage"] and now - logged["at"] < _PROGRESS_PERIOD \
                    and fraction < 1.0:
                return
            logged.update(stage=stage, at=now)
            self.get_logger().info(f"  {fraction:4.0%} {stage} ({now - start:.1f} s)")

        if values["full"]:
            self.get_logger().info(f"building the full roadmap of the {self.mechanism.kind} "
                                   "(every joint free) or loading it from the cache")
        with core_threads() as pool:
            try:
                grid, refinement = self._grid(values, progress, pool.map)
            except GWRError as exc:  # given at start-up or a whole box: refused here
                self.get_logger().error(f"invalid grid: {exc}")
                self._keep_last_good()
                return
            if not values["full"]:
                fixed = ", ".join(f"{names[joint]} = {value:g}" for joint, value in grid.fixed)
                self.get_logger().info(f"building the roadmap of the {self.mechanism.kind}: "
                                       f"{fixed}, {' x '.join(map(str, grid.shape))} cells")
            try:
                if values["full"]:
                    roadmap, _ = cached_roadmap(self.mechanism, grid, progress=progress,
                                                refinement=refinement, workers=pool.map)
                elif values["thin_refinement"]:
                    roadmap, report = refine_thin_regions(
                        self.mechanism, grid, values["thin_refinement"], progress=progress,
                        workers=pool.map)
                    if report.rounds:
                        self.get_logger().info(
                            f"refined {report.refined_blocks} blocks around thin regions in "
                            f"{report.rounds} rounds ({report.stopped}"
                            f"{'; still thin: patches ' if report.thin_left else ''}"
                            f"{', '.join(map(str, report.thin_left))})")
                else:
                    roadmap = build_roadmap(self.mechanism, grid, progress=progress,
                                            workers=pool.map)
            except Exception as exc:  # a failed build must not take the builder down
                self.get_logger().error(f"building the roadmap failed: {exc!r}")
                self._keep_last_good()
                return
        seg = roadmap.segmentation
        if not seg.patches:
            self.get_logger().error("the roadmap has no patch")
            self._keep_last_good()
            return
        built = time.perf_counter()
        header = Header(stamp=self.get_clock().now().to_msg(), frame_id=BASE_FRAME)
        try:
            field_msg, roadmap_msg = roadmap_to_msgs(roadmap, header)
        except Exception as exc:  # as a failed build: the builder goes on
            self.get_logger().error(f"converting the roadmap to messages failed: {exc!r}")
            self._keep_last_good()
            return
        first = self.roadmap is None
        self.roadmap, self._published = roadmap, values
        packed = time.perf_counter()
        self.field_pub.publish(field_msg)
        self.roadmap_pub.publish(roadmap_msg)
        sent = time.perf_counter()
        try:
            maps = field_maps(roadmap, header.stamp)
            drawn = None if maps is None else (
                roadmap_markers(roadmap, header.stamp),
                TFMessage(transforms=[joint_space_transform(roadmap, header.stamp)]))
        except Exception as exc:  # the roadmap is out; only its drawings are missing
            self.get_logger().error(f"drawing the roadmap failed: {exc!r}")
            maps = None
        if maps is not None:
            for publisher, grid_map in zip(self.map_pubs, maps):
                publisher.publish(grid_map)
            self.marker_pub.publish(drawn[0])
            self.tf_static_pub.publish(drawn[1])
        self.get_logger().info(
            f"{'ready: ' if first else ''}published the roadmap on "
            f"{self.roadmap_pub.topic_name} and {self.field_pub.topic_name}: "
            f"{seg.n_regions} regions, {len(seg.patches)} patches, "
            f"{len(seg.gates)} gates, built in {built - start:.2f} s, messages packed in "
            f"{packed - built:.2f} s, published in {sent - packed:.2f} s")

    def _keep_last_good(self):
        """Leave the published roadmap latched and the parameters naming its grid."""
        if self.roadmap is None:
            self.get_logger().error("no roadmap is published")
            return
        self.get_logger().error("the published roadmap stays; the grid parameters go back "
                                "to its grid")
        self.set_parameters_atomically([Parameter(name, value=value)
                                        for name, value in self._published.items()])


def main(args=None):
    # So that release_free_memory reaches the memory of every thread.
    use_one_arena()
    return run(RoadmapBuilder, BoundedExecutor, args, usage=USAGE)
