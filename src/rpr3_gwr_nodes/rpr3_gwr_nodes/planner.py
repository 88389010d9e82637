"""planner: serves plan requests on a roadmap received as messages.

Subscribes to ``field`` and ``roadmap`` (reliable, transient local) and builds
its planning state from them, computing nothing that the builder computed: a
roadmap from another builder or from a bag serves as well.  A new pair of
messages replaces the state atomically; requests in flight finish on the
state they started with.

Serves ``plan_path`` (rpr3_gwr_msgs/PlanPath) from a reentrant callback group
on a multithreaded executor, so several requests run at once.  Every error of
the core becomes the response's error code and message; the node never dies
on a request.  Each planned trajectory is also published on
``planned_trajectory`` (trajectory_msgs/JointTrajectory) for recording and
display.
"""

import math
import threading
import time

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rpr3_gwr_core.exceptions import GWRError
from rpr3_gwr_core.planner import PlanOptions, Planner
from rpr3_gwr_msgs.msg import GlobalPath, NSolutionField, PlatformPose, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import PlanPath
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from .conversions import duration_msg, roadmap_from_msgs
from .spin import run
from .roadmap_builder import LATCHED_QOS

__all__ = ["PlannerNode", "ERROR_CODES", "JOINT_NAMES", "plan_to_trajectory", "main"]

JOINT_NAMES = ["rho1", "rho2", "rho3"]
ERROR_CODES = {
    "INVALID_INPUT": PlanPath.Response.ERROR_INVALID_INPUT,
    "OUT_OF_GRID": PlanPath.Response.ERROR_OUT_OF_GRID,
    "RHO1_MISMATCH": PlanPath.Response.ERROR_RHO1_MISMATCH,
    "NO_SOLUTION": PlanPath.Response.ERROR_NO_SOLUTION,
    "NO_ASSEMBLY_MODE": PlanPath.Response.ERROR_NO_ASSEMBLY_MODE,
    "SINGULAR": PlanPath.Response.ERROR_SINGULAR,
    "INFEASIBLE": PlanPath.Response.ERROR_INFEASIBLE,
    "VALIDATION_FAILED": PlanPath.Response.ERROR_VALIDATION_FAILED,
}


def plan_to_trajectory(plan, header):
    """A core plan's leg path as a JointTrajectory (times, velocities and
    accelerations when the plan is time-parameterised)."""
    trajectory = JointTrajectory(header=header, joint_names=list(JOINT_NAMES))
    for k, rho in enumerate(plan.rho):
        point = JointTrajectoryPoint(positions=[float(v) for v in rho])
        if plan.times is not None:
            point.velocities = [float(v) for v in plan.velocities[k]]
            point.accelerations = [float(v) for v in plan.accelerations[k]]
            point.time_from_start = duration_msg(float(plan.times[k]))
        trajectory.points.append(point)
    return trajectory


class PlannerNode(Node):
    """Plans on the latest roadmap received."""

    def __init__(self, **kwargs):
        super().__init__("planner", **kwargs)
        positive = [FloatingPointRange(from_value=1e-6, to_value=1e6)]
        self.declare_parameter("default_max_velocity", 1.0, ParameterDescriptor(
            description="Joint speed limit used when a request gives none [length unit/s]",
            floating_point_range=positive))
        self.declare_parameter("default_max_acceleration", 2.0, ParameterDescriptor(
            description="Joint acceleration limit used when a request gives none "
                        "[length unit/s^2]", floating_point_range=positive))
        self._planner = None
        self._messages = {}
        updates = MutuallyExclusiveCallbackGroup()
        self.create_subscription(NSolutionField, "field", self._on_field, LATCHED_QOS,
                                 callback_group=updates)
        self.create_subscription(WorkspaceRoadmap, "roadmap", self._on_roadmap, LATCHED_QOS,
                                 callback_group=updates)
        self.trajectory_pub = self.create_publisher(JointTrajectory, "planned_trajectory", 10)
        self.create_service(PlanPath, "plan_path", self._on_plan,
                            callback_group=ReentrantCallbackGroup())
        self.ready = threading.Event()

    @property
    def planner(self):
        """The planning state requests use now (None before a roadmap)."""
        return self._planner

    def _on_field(self, msg):
        self._messages["field"] = msg
        self._try_swap()

    def _on_roadmap(self, msg):
        self._messages["roadmap"] = msg
        self._try_swap()

    def _try_swap(self):
        field, roadmap = self._messages.get("field"), self._messages.get("roadmap")
        if field is None or roadmap is None or field.header.stamp != roadmap.header.stamp:
            return
        start = time.perf_counter()
        try:
            planner = Planner(roadmap_from_msgs(field, roadmap))
        except GWRError as exc:
            self.get_logger().error(f"ignoring an inconsistent roadmap: {exc}")
            return
        self._planner = planner  # one reference assignment: atomic for the service threads
        self._messages.clear()
        grid = planner.roadmap.grid
        self.get_logger().info(
            f"planning on a new roadmap: rho1 = {grid.rho1:g}, {len(planner.roadmap.graph)} "
            f"patches, ready in {time.perf_counter() - start:.3f} s")
        self.ready.set()

    def _options(self, request):
        limits = (request.max_velocity, request.max_acceleration)
        if limits == (0.0, 0.0):
            limits = (self.get_parameter("default_max_velocity").value,
                      self.get_parameter("default_max_acceleration").value)
        tolerance = request.alpha_tolerance or math.radians(1.0)
        return PlanOptions(smooth=request.smooth, weighted=request.weighted,
                           feasibility_only=request.feasibility_only, max_velocity=limits[0],
                           max_acceleration=limits[1], alpha_tol=tolerance)

    def _on_plan(self, request, response):
        planner = self._planner
        if planner is None:
            response.error_code = PlanPath.Response.ERROR_NO_ROADMAP
            response.error_msg = "no roadmap received yet on 'field' and 'roadmap'"
            return response
        try:
            options = self._options(request)
            start = (request.start.rho1, request.start.rho2, request.start.rho3, request.start.alpha)
            goal = (request.goal.rho1, request.goal.rho2, request.goal.rho3, request.goal.alpha)
            plan = planner.plan(start, goal, options)
        except GWRError as exc:
            response.error_code = ERROR_CODES.get(exc.code, PlanPath.Response.ERROR_INTERNAL)
            response.error_msg = str(exc)
            response.feasibility = getattr(exc, "reason", "")
            return response
        except Exception as exc:  # a bug must not take the service down
            self.get_logger().error(f"internal error on a plan request: {exc!r}")
            response.error_code = PlanPath.Response.ERROR_INTERNAL
            response.error_msg = f"internal error: {exc!r}"
            return response
        response.success = True
        response.error_code = PlanPath.Response.ERROR_NONE
        response.feasibility = plan.reason
        response.global_paths = [GlobalPath(patch_ids=list(g.patches), cost=g.cost)
                                 for g in plan.global_paths]
        if options.feasibility_only:
            return response
        response.path_index = plan.path_index
        response.trajectory = plan_to_trajectory(plan, self._header())
        response.poses = [PlatformPose(x=float(p[0]), y=float(p[1]), alpha=float(p[2]))
                          for p in plan.poses]
        response.min_singularity_margin = float(plan.validation.min_margin)
        self.trajectory_pub.publish(response.trajectory)
        return response

    def _header(self):
        return Header(stamp=self.get_clock().now().to_msg(), frame_id="rpr3_base")


def main(args=None):
    run(PlannerNode, MultiThreadedExecutor, args, num_threads=4)
