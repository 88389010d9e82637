"""rpr3_driver: a simulated parallel mechanism that replays joint trajectories.

The mechanism is its ``mechanism_file`` (:mod:`.mechanism_parameters`, the
builder's; the paper's 3-RPR by default), whose ``bodies`` (widths and
layers) scenes are checked with: with them, bodies that share a layer are
kept apart even without a scene.  Like the real mechanism, the
platform follows the commanded joints by continuation of the constraint
equations (it is never looked up in a table), so it stays in its assembly
mode unless a singularity is crossed.

* ``joint_states`` (sensor_msgs/JointState, reliable as
  joint_state_broadcaster's, so that readers of any reliability get them,
  ``rate`` Hz): the actuated joints by the mechanism's names (positions and
  velocities; a joint that turns fully counts its turns, as a continuous
  joint), then the passive joints by the names of the mechanism's bodies
  (:meth:`Mechanism.body_outline`, the names a scene's passive ranges
  use: the 3-RPR's ``base1..3`` and ``platform1..3``, the elbows of the
  3-RRR, the 3-PRR and the five-bar), positions only (velocity NaN);
* ``platform_pose`` (rpr3_gwr_msgs/PlatformPose, same rate and QoS);
* ``mechanism_markers`` (visualization_msgs/MarkerArray, same rate, stamp
  and QoS as the joint states, frame ``base``): base points, legs (with
  the elbows or slider joints of the mechanisms that have them) and
  platform, coloured from green (margin ``warn_margin`` and above) to red
  (``abort_margin``), and after a collision abort the body that would have
  collided, magenta;
* ``/diagnostics`` (diagnostic_msgs/DiagnosticArray, same QoS, 1 Hz and at
  once on an abort): the normalised det(Jx) margin m with level OK when
  ``|m| >= warn_margin``, WARN when ``abort_margin <= |m| < warn_margin``,
  ERROR when ``|m| < abort_margin`` or while the driver holds after an abort
  on a singularity or a collision (until a reset or a goal that succeeds);
* ``execute_trajectory`` (rpr3_gwr_msgs/ExecuteTrajectory action): replays a
  JointTrajectory in real time (scaled by ``time_scale``).  As ros2_controllers'
  joint_trajectory_controller does, a goal is validated when it arrives and
  rejected there, with the reason in the log: no points, wrong joint names,
  a point without one position per joint, velocities or accelerations
  neither empty nor one per joint, efforts (the joints are position
  controlled), joints not finite or outside their ranges in the mechanism
  file (a joint that turns fully has none), velocities or accelerations
  not finite, time stamps not normalised (``nanosec`` of a
  second or more), negative or not strictly increasing, a joint faster than
  ``max_velocity``, a first point farther than ``start_tolerance`` from the
  current joints (by whole turns for a joint that turns fully), or another
  goal executing.  Before each control step the
  driver checks where the platform would go: if the margin would fall below
  ``abort_margin``, det(Jx) would change sign, or the platform could not
  follow, it aborts the goal, says why and with which margin, and holds still
  at the last safe joints.  In a scene, each control step's stretch of the
  path (from the current joints through the waypoints passed to the
  step's target) is then checked continuously with the core
  (``path_collisions``): if a body would come within ``obstacle_clearance``
  of an obstacle, bodies would overlap, or a joint would leave its range,
  the goal aborts with ``COLLISION_ABORT`` before the step, naming the body
  (or joint) and the obstacle (or range), and the driver holds at the last
  free joints;
* ``scene`` (rpr3_gwr_msgs/Scene, reliable, transient local, as the
  planner's): the obstacles and limits executions are checked against, from
  the next control step on (one without obstacles and joint ranges: none).
  A scene that cannot be read or names joints the mechanism lacks is
  refused with an error in the log and the previous one stays.  The scene
  in use is echoed on ``~/current_scene`` (same QoS, the received header
  stamp) and drawn on ``scene_markers`` (visualization_msgs/MarkerArray, same
  QoS, frame ``base``);
* ``reset`` (rpr3_gwr_msgs/ResetDriver): puts the platform at a configuration
  (scenes do not restrict it: a simulation may start anywhere).
"""

import math
import threading
import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.exceptions import GWRError, InvalidInputError
from rpr3_gwr_core.mechanisms.continuation import CANNOT_FOLLOW, CROSSED, follow_path
from rpr3_gwr_core.planning import DEFAULT_MAX_STEP
from rpr3_gwr_core.planning.locate import DEFAULT_MODE_TOL
from rpr3_gwr_core.world import configuration_collision, path_collisions
from rpr3_gwr_core.world.collision import INTERFERENCE, OBSTACLE
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import PlatformPose, Scene
from rpr3_gwr_msgs.srv import ResetDriver
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from visualization_msgs.msg import MarkerArray

from .conversions import (configuration_from_msg, duration_msg, is_empty_scene, pose_msg,
                          scene_from_msg, scene_to_msg)
from .mechanism_parameters import declare_mechanism, home_source, kept_scene
from .profiles import BASE_FRAME, LATCHED_QOS, STATE_QOS
from .spin import run
from .visualization import mechanism_markers, scene_markers

__all__ = ["Rpr3Driver", "main", "USAGE"]

USAGE = """\
usage: ros2 run rpr3_gwr_nodes rpr3_driver [-h] [--ros-args ...]

A simulated parallel mechanism (by default the paper's 3-RPR) that executes
joint trajectories, following its platform by continuation, and aborts
before a singularity, an assembly-mode change or a collision.

Serves      execute_trajectory (rpr3_gwr_msgs/action/ExecuteTrajectory),
            reset (rpr3_gwr_msgs/srv/ResetDriver)
Subscribes  scene (latched)
Publishes   joint_states, platform_pose, mechanism_markers, /diagnostics,
            scene_markers, ~/current_scene
Parameters  mechanism_file ('' for the paper's 3-RPR, read-only),
            initial_configuration (joints then mode coordinate, read-only),
            rate (100 Hz), time_scale (1.0), max_velocity (50 /s),
            start_tolerance (1e-3), abort_margin (5e-4), warn_margin (0.02)
Example     ros2 run rpr3_gwr_nodes rpr3_driver --ros-args -p time_scale:=10.0
"""

_Result = ExecuteTrajectory.Result
_Reset = ResetDriver.Response


def _seconds(duration):
    return duration.sec + duration.nanosec * 1e-9


def _collision_reason(hit, clearance):
    """What a core Collision found ahead means for the driver."""
    if hit.kind == OBSTACLE:
        return (f"{hit.body} would come within obstacle_clearance {clearance:g} of obstacle "
                f"{hit.other!r}")
    if hit.kind == INTERFERENCE:
        return f"{hit.body} and {hit.other} would overlap"
    return f"joint {hit.body} would leave its range {hit.other}"


def _slope(times, positions, t):
    """Velocity of the piecewise-linear joint path at time t [joint unit/s]."""
    if len(times) < 2 or t >= times[-1]:
        return np.zeros(positions.shape[1])
    k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
    return (positions[k + 1] - positions[k]) / (times[k + 1] - times[k])


class _Refused(Exception):
    """A request the driver answers with an error code and a reason."""

    def __init__(self, code, reason):
        super().__init__(reason)
        self.code = code


class Rpr3Driver(Node):
    """The simulated manipulator."""

    def __init__(self, **kwargs):
        super().__init__("rpr3_driver", **kwargs)

        def positive(name, value, description, high=1e6):
            self.declare_parameter(name, value, ParameterDescriptor(
                description=description,
                floating_point_range=[FloatingPointRange(from_value=1e-9, to_value=high)]))

        positive("rate", 100.0, "Joint state publishing and control rate [Hz]", 1000.0)
        # Half the planner's validation margin (1e-3): validated plans pass
        # even where the driver's steps sample the margin differently.
        positive("abort_margin", 5e-4, "Smallest normalised |det Jx| allowed: below it a goal "
                 "aborts, and diagnostics say ERROR", 1.0)
        positive("warn_margin", 0.02, "Normalised |det Jx| below which diagnostics say WARN", 1.0)
        positive("start_tolerance", 1e-3, "Largest distance of a trajectory's first point from "
                 "the current joints [joint unit]")
        positive("time_scale", 1.0, "Playback speed factor: 2 replays twice as fast", 1000.0)
        positive("max_velocity", 50.0, "Fastest joint speed a trajectory may ask for, as it is "
                 "timed [joint unit/s]")
        described = declare_mechanism(self)
        self.mechanism = described.mechanism
        # The widths and layers of the bodies a scene is checked with.
        self.bodies = described.bodies
        names = self.mechanism.joint_names
        # Joint ranges are the file's box; a joint that turns fully has none.
        self.limits = [None if a.periodic else (a.low, a.high) for a in described.axes]
        self._periodic = np.array([a.periodic for a in described.axes])
        self.declare_parameter(
            "initial_configuration", Parameter.Type.DOUBLE_ARRAY,
            ParameterDescriptor(
                description=f"Initial joints ({', '.join(names)}) then mode coordinate "
                            f"{self.mechanism.pose_names[self.mechanism.mode_coordinate]} "
                            "[joint unit, mode unit]; by default the mechanism file's home, "
                            "else the one found for it (the paper's first example for the "
                            "paper's 3-RPR)", read_only=True))
        self._lock = threading.Lock()
        self._active = False  # a goal is accepted or executing (under _lock)
        self._holding = ""  # why the driver holds after an abort, "" when it does not
        self._stopping = threading.Event()
        # The scene steps are checked against (None: none), swapped as one
        # reference; the collision a goal aborted on (under _lock, None when
        # there is none to show).
        self._scene = None
        self._collision = None
        # Scene messages refused (unreadable, or naming unknown joints).
        self.refused_scenes = 0
        # Unset unless given.
        initial = self.get_parameter_or("initial_configuration",
                                        Parameter("initial_configuration")).value
        if initial is None:
            initial = described.default_home()
            self.get_logger().info(f"starting at {home_source(described)}")
        self.rho, self.pose, self.margin = self._assembly(initial)
        self.velocity = np.zeros(len(names))
        self.joint_pub = self.create_publisher(JointState, "joint_states", STATE_QOS)
        self.pose_pub = self.create_publisher(PlatformPose, "platform_pose", STATE_QOS)
        self.marker_pub = self.create_publisher(MarkerArray, "mechanism_markers", STATE_QOS)
        self.diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", STATE_QOS)
        timers = MutuallyExclusiveCallbackGroup()
        self.create_timer(1.0 / self.get_parameter("rate").value, self._publish_state,
                          callback_group=timers)
        self.create_timer(1.0, self._publish_diagnostics, callback_group=timers)
        self.create_service(ResetDriver, "reset", self._on_reset)
        self.scene_pub = self.create_publisher(Scene, "~/current_scene", LATCHED_QOS)
        self.scene_marker_pub = self.create_publisher(MarkerArray, "scene_markers", LATCHED_QOS)
        self.create_subscription(Scene, "scene", self._on_scene, LATCHED_QOS,
                                 callback_group=MutuallyExclusiveCallbackGroup())
        self._action = ActionServer(
            self, ExecuteTrajectory, "execute_trajectory", self._execute,
            goal_callback=self._on_goal, cancel_callback=lambda _: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup())
        joints = ", ".join(f"{n} = {v:g}" for n, v in zip(names, self.rho))
        self.get_logger().info(
            f"ready: serving {self.resolve_service_name('execute_trajectory')} and "
            f"{self.resolve_service_name('reset')}, publishing "
            f"{self.joint_pub.topic_name} at {self.get_parameter('rate').value:g} Hz, at "
            f"{joints}; following the scene on {self.resolve_topic_name('scene')}")

    # --- state -------------------------------------------------------------------------------

    def _solutions(self, joints):
        """The direct-kinematic solutions of joints, shape (count, pose_size)."""
        count, poses = self.mechanism.solve(np.asarray(joints, dtype=float)[None])
        return poses[0, :count[0]]

    def _assembly(self, configuration):
        """Joints, pose and margin of the assembly mode nearest the mode
        coordinate in ``(*joints, mode)``.

        Raises
        ------
        _Refused
            With the reset's error code when the configuration is not valid.
        """
        mechanism = self.mechanism
        values = tuple(float(v) for v in configuration)
        if len(values) != mechanism.n_joints + 1 or not all(math.isfinite(v) for v in values):
            raise _Refused(_Reset.ERROR_INVALID_INPUT, f"a configuration is "
                           f"{(*mechanism.joint_names, 'mode')}, finite: got {values}")
        joints, mode = np.array(values[:-1]), values[-1]
        try:
            mechanism.check_joints(joints)
        except InvalidInputError as exc:
            raise _Refused(_Reset.ERROR_INVALID_INPUT, str(exc)) from None
        except GWRError as exc:  # the five-bar's coinciding elbows: a singularity
            raise _Refused(_Reset.ERROR_SINGULAR, str(exc)) from None
        for name, value, limit in zip(mechanism.joint_names, joints, self.limits):
            if limit is not None and not limit[0] <= value <= limit[1]:
                raise _Refused(_Reset.ERROR_OUT_OF_RANGE, f"{name} = {value:g} outside its "
                               f"range [{limit[0]:g}, {limit[1]:g}]")
        poses = self._solutions(joints)
        if len(poses) == 0:
            raise _Refused(_Reset.ERROR_NO_SOLUTION, f"no real solution at {values[:-1]}")
        k = mechanism.mode_coordinate
        off = poses[:, k] - mode
        if mechanism.angular[k]:
            off = np.remainder(off + np.pi, 2 * np.pi) - np.pi
        off = np.abs(off)
        nearest = int(np.argmin(off))
        if off[nearest] > DEFAULT_MODE_TOL:
            raise _Refused(_Reset.ERROR_NO_ASSEMBLY_MODE,
                           f"no assembly mode within {DEFAULT_MODE_TOL:.4g} of "
                           f"{mechanism.pose_names[k]} = {mode:g}")
        margin = float(mechanism.margin(poses[nearest], joints))
        if abs(margin) < self.get_parameter("abort_margin").value:
            raise _Refused(_Reset.ERROR_SINGULAR, f"configuration is singular (margin "
                           f"{abs(margin):.2e})")
        return joints, poses[nearest], margin

    def state(self):
        """``(rho, pose, margin)`` under the lock."""
        with self._lock:
            return self.rho.copy(), self.pose.copy(), self.margin

    def _publish_state(self):
        with self._lock:
            rho, pose, velocity = self.rho.copy(), self.pose.copy(), self.velocity.copy()
            margin = self.margin
        msg = JointState()
        msg.header.stamp = self.get_clock().now().to_msg()
        names = list(self.mechanism.joint_names)
        position = [float(v) for v in rho]
        speed = [float(v) for v in velocity]
        for name, angle in self._passive_joints(pose, rho):
            names.append(name)
            position.append(float(angle))
            speed.append(math.nan)
        msg.name, msg.position, msg.velocity = names, position, speed
        self.joint_pub.publish(msg)
        self.pose_pub.publish(pose_msg(self.mechanism, pose))
        with self._lock:
            collision = self._collision
        self.marker_pub.publish(mechanism_markers(
            self.mechanism, pose, rho, margin, self.get_parameter("warn_margin").value,
            self.get_parameter("abort_margin").value, msg.header.stamp,
            None if collision is None else collision.body))

    def _passive_joints(self, pose, joints):
        """``(name, angle [rad])`` of each passive joint; none for a
        mechanism that does not describe its bodies."""
        try:
            return self.mechanism.body_outline(pose, joints)[2]
        except NotImplementedError:
            return []

    def diagnostic_status(self):
        """The singularity status (the module doc gives its levels)."""
        with self._lock:
            pose, margin, holding = self.pose.copy(), self.margin, self._holding
        size = abs(margin)
        if holding or size < self.get_parameter("abort_margin").value:
            level, message = DiagnosticStatus.ERROR, holding or "at a parallel singularity"
        elif size < self.get_parameter("warn_margin").value:
            level, message = DiagnosticStatus.WARN, "near a parallel singularity"
        else:
            level, message = DiagnosticStatus.OK, "regular"
        mode = self.mechanism.mode_coordinate
        return DiagnosticStatus(
            name="rpr3_driver: singularity", hardware_id=f"{self.mechanism.kind}_sim",
            level=level, message=message,
            values=[KeyValue(key="singularity_margin", value=f"{size:.6f}"),
                    KeyValue(key="aspect", value=str(int(np.sign(margin)))),
                    KeyValue(key=self.mechanism.pose_names[mode], value=f"{pose[mode]:.6f}")])

    def _publish_diagnostics(self):
        array = DiagnosticArray(status=[self.diagnostic_status()])
        array.header.stamp = self.get_clock().now().to_msg()
        self.diag_pub.publish(array)

    # --- scene -------------------------------------------------------------------------------

    def _on_scene(self, msg):
        try:
            scene = scene_from_msg(msg)
            if is_empty_scene(scene):
                scene = None
            kept = kept_scene(scene, self.bodies)
            inside = None
            if kept is not None:
                # Checks the limits' names against the mechanism (and loads
                # the collision kernels before a goal needs them).
                rho, pose, _ = self.state()
                inside = configuration_collision(self.mechanism, kept, rho, pose, self.bodies)
        except Exception as exc:  # GWRError: a bad scene; anything else a bug
            self.refused_scenes += 1
            self.get_logger().error(f"refusing a scene, checking against the previous one: "
                                    f"{exc if isinstance(exc, GWRError) else repr(exc)}")
            return
        self._scene = scene
        header = Header(stamp=msg.header.stamp, frame_id=BASE_FRAME)
        self.scene_pub.publish(Scene(header=header) if scene is None
                               else scene_to_msg(scene, header))
        self.scene_marker_pub.publish(scene_markers(scene, msg.header.stamp))
        if inside is not None:
            self.get_logger().warning(f"the new scene holds the platform where it is: "
                                      f"{inside.message}; goals abort until a reset frees it")

    # --- reset -------------------------------------------------------------------------------

    def _on_reset(self, request, response):
        try:
            try:
                configuration = configuration_from_msg(self.mechanism, request.configuration)
            except InvalidInputError as exc:
                raise _Refused(_Reset.ERROR_INVALID_INPUT, str(exc)) from None
            rho, pose, margin = self._assembly(configuration)
            with self._lock:
                if self._active:
                    raise _Refused(_Reset.ERROR_BUSY, "a trajectory is executing")
                self.rho, self.pose, self.margin = rho, pose, margin
                self.velocity = np.zeros(len(rho))
                self._holding = ""
                self._collision = None
        except _Refused as exc:
            response.error_code, response.error_msg = exc.code, str(exc)
            return response
        except Exception as exc:  # a bug must not take the driver down
            self.get_logger().error(f"internal error on a reset: {exc!r}")
            response.error_code = _Reset.ERROR_INVALID_INPUT
            response.error_msg = f"internal error: {exc!r}"
            return response
        response.success = True
        response.error_code = _Reset.ERROR_NONE
        response.pose = pose_msg(self.mechanism, pose)
        return response

    # --- trajectories ------------------------------------------------------------------------

    def _on_goal(self, goal_request):
        """Accept a valid goal and take the driver for it; reject anything else."""
        try:
            problem = self._problem(goal_request.trajectory)
        except Exception as exc:  # a bug must not take the driver down
            problem = f"internal error: {exc!r}"
        if problem is None:
            with self._lock:
                if self._active:
                    problem = "busy: another trajectory is executing"
                else:
                    self._active = True
        if problem is not None:
            self.get_logger().warning(f"rejecting a trajectory: {problem}")
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _problem(self, trajectory):
        """Why a trajectory cannot be executed from here, or None."""
        names = list(self.mechanism.joint_names)
        if list(trajectory.joint_names) != names:
            return f"joint names must be {names}, got {list(trajectory.joint_names)}"
        points = trajectory.points
        if not points:
            return "the trajectory has no points"
        joints = len(names)
        if any(len(p.positions) != joints for p in points):
            return f"every point needs {joints} positions"
        for field in ("velocities", "accelerations"):
            # Empty, as joint_trajectory_controller allows: not given.
            if any(len(getattr(p, field)) not in (0, joints) for p in points):
                return f"{field} must be empty or {joints} per point"
            if not all(math.isfinite(v) for p in points for v in getattr(p, field)):
                return f"{field} must be finite"
        if any(len(p.effort) for p in points):
            return "the joints are position controlled: effort must be empty"
        positions = np.array([list(p.positions) for p in points])
        if not np.all(np.isfinite(positions)):
            return "positions must be finite"
        for k, (name, limit) in enumerate(zip(names, self.limits)):
            if limit is not None and (np.any(positions[:, k] < limit[0])
                                      or np.any(positions[:, k] > limit[1])):
                return f"{name} must lie within its range [{limit[0]:g}, {limit[1]:g}]"
        # A nanosec field of a second or more would shift the stamp past
        # the checks below (sec -1 and nanosec 2e9 read as +1 s).
        if any(p.time_from_start.nanosec >= 10**9 for p in points):
            return "time_from_start.nanosec must be below 10^9 (a second)"
        times = np.array([_seconds(p.time_from_start) for p in points])
        if np.any(times < 0):
            return "time_from_start must not be negative"
        if np.any(np.diff(times) <= 0):
            return "time_from_start must increase strictly"
        if len(points) > 1:
            speed = np.max(np.abs(np.diff(positions, axis=0)) / np.diff(times)[:, None])
            limit = self.get_parameter("max_velocity").value
            if speed > limit:
                return f"a joint would move at {speed:.3g} joint unit/s, above max_velocity " \
                       f"{limit:g}"
        return self._start_gap(positions[0])

    def _turns(self, first):
        """Whole turns that bring the trajectory's ``first`` point nearest the
        current joints (0 for a joint that does not turn fully)."""
        rho, _, _ = self.state()
        return np.where(self._periodic, 2 * np.pi * np.round((rho - first) / (2 * np.pi)), 0.0)

    def _start_gap(self, first):
        rho, _, _ = self.state()
        gap = float(np.max(np.abs(first + self._turns(first) - rho)))
        if gap > self.get_parameter("start_tolerance").value:
            return f"the trajectory starts {gap:.4g} away from the current joints {rho.tolist()}"
        return None

    def _execute(self, goal_handle):
        result = _Result()
        try:
            return self._run(goal_handle, result)
        except Exception as exc:  # a bug must not take the driver down
            self.get_logger().error(f"internal error executing a trajectory: {exc!r}")
            return self._abort(goal_handle, result, _Result.INVALID_TRAJECTORY,
                               f"internal error: {exc!r}", None)
        finally:
            with self._lock:
                self.velocity = np.zeros(self.mechanism.n_joints)
                self._active = False

    def _run(self, goal_handle, result):
        trajectory = goal_handle.request.trajectory
        positions = np.array([list(p.positions) for p in trajectory.points])
        # Counted from the current turn of the joints that turn fully, as the
        # plan's path is continuous.
        positions += self._turns(positions[0])
        times = np.array([_seconds(p.time_from_start) for p in trajectory.points])
        # A reset may have moved the platform since the goal was accepted.
        moved = self._start_gap(positions[0])
        if moved is not None:
            return self._abort(goal_handle, result, _Result.START_MISMATCH, moved, None)
        with self._lock:
            self._collision = None  # the highlight is of the goal that aborted on it
        scale = self.get_parameter("time_scale").value
        abort_margin = self.get_parameter("abort_margin").value
        period = 1.0 / self.get_parameter("rate").value
        _, _, margin0 = self.state()
        sign = math.copysign(1.0, margin0)
        smallest = abs(margin0)
        feedback = ExecuteTrajectory.Feedback()
        begin = time.monotonic()
        elapsed = -1.0
        while True:
            if goal_handle.is_cancel_requested:
                goal_handle.canceled()
                result.error_code, result.error_msg = _Result.CANCELED, "canceled"
                return self._finish(result, smallest)
            if self._stopping.is_set():
                return self._abort(goal_handle, result, _Result.CANCELED,
                                   "the driver is shutting down", smallest)
            previous = elapsed
            elapsed = min((time.monotonic() - begin) * scale, times[-1])
            target = np.array([np.interp(elapsed, times, positions[:, j])
                               for j in range(positions.shape[1])])
            # A late control step must still pass through the waypoints in
            # between: the path, not a chord, is what was validated.
            between = (times > previous) & (times < elapsed)
            rho, pose, _ = self.state()
            followed = self._follow(pose, rho, list(positions[between]) + [target],
                                    abort_margin)
            at = f"at t = {elapsed:.3f} s"
            if followed is None:
                return self._abort(goal_handle, result, _Result.SINGULARITY_ABORT,
                                   f"the platform cannot follow the joints {at}: a singularity "
                                   f"(margin {smallest:.2e} before it)", smallest)
            new_pose, margin, extreme = followed
            if math.copysign(1.0, extreme) != sign:
                return self._abort(goal_handle, result, _Result.ASSEMBLY_MODE_LEFT,
                                   f"det(Jx) would change sign {at} (margin {extreme:+.2e}): "
                                   "the platform would leave its assembly mode", smallest)
            if abs(extreme) < abort_margin:
                return self._abort(goal_handle, result, _Result.SINGULARITY_ABORT,
                                   f"singularity margin would fall to {abs(extreme):.2e} "
                                   f"< abort_margin {abort_margin:g} {at}",
                                   min(smallest, abs(extreme)))
            scene = kept_scene(self._scene, self.bodies)
            if scene is not None:
                hit = path_collisions(self.mechanism, scene,
                                      np.array([rho, *positions[between], target]), pose,
                                      self.bodies)
                if hit is not None:
                    with self._lock:
                        self._collision = hit
                    return self._abort(goal_handle, result, _Result.COLLISION_ABORT,
                                       f"{_collision_reason(hit, scene.limits.obstacle_clearance)}"
                                       f" {at}: holding at the last free joints", smallest)
            smallest = min(smallest, abs(extreme))
            with self._lock:
                self.velocity = _slope(times, positions, elapsed)
                self.rho, self.pose, self.margin = target, new_pose, margin
            feedback.progress = float(elapsed / times[-1]) if times[-1] > 0 else 1.0
            feedback.singularity_margin = abs(margin)
            feedback.time_from_start = duration_msg(elapsed)
            feedback.pose = pose_msg(self.mechanism, new_pose)
            goal_handle.publish_feedback(feedback)
            if elapsed >= times[-1]:
                break
            time.sleep(period)
        goal_handle.succeed()
        with self._lock:
            self._holding = ""
            self._collision = None
        result.error_code = _Result.SUCCESS
        return self._finish(result, smallest)

    def _follow(self, pose, rho, points, abort_margin):
        """Follow the joints from ``rho`` through ``points`` as the validator
        does (:func:`~rpr3_gwr_core.mechanisms.continuation.follow_path`, the
        same step control, stopping below ``abort_margin``); ``(pose, margin,
        extreme)`` with the most critical margin of the whole way (of the
        other sign if det(Jx) changed sign), or None when the platform cannot
        follow."""
        followed = np.array(pose, dtype=float)
        start = float(self.mechanism.margin(followed, rho))
        status, _, _, smallest = follow_path(
            self.mechanism, np.array([rho, *points], dtype=float), followed, abort_margin,
            DEFAULT_MAX_STEP)
        if status == CANNOT_FOLLOW:
            return None
        extreme = math.copysign(smallest, start) if status != CROSSED \
            else -math.copysign(abort_margin, start)
        return (np.array(self.mechanism.wrap_scalar(followed)),
                float(self.mechanism.margin(followed, points[-1])), extreme)

    def _abort(self, goal_handle, result, code, reason, smallest):
        self.get_logger().warning(f"aborting the trajectory and holding still: {reason}")
        if code in (_Result.SINGULARITY_ABORT, _Result.ASSEMBLY_MODE_LEFT,
                    _Result.COLLISION_ABORT):
            with self._lock:
                self._holding = f"holding after an abort: {reason}"
        goal_handle.abort()
        result.error_code, result.error_msg = code, reason
        self._publish_diagnostics()
        return self._finish(result, smallest)

    def _finish(self, result, smallest):
        _, pose, margin = self.state()
        result.final_pose = pose_msg(self.mechanism, pose)
        result.min_singularity_margin = float(abs(margin) if smallest is None else smallest)
        return result

    def prepare_shutdown(self):
        """End a trajectory in execution now (called by ``main`` on SIGINT)."""
        self._stopping.set()


def main(args=None):
    run(Rpr3Driver, MultiThreadedExecutor, args, usage=USAGE, num_threads=4)
