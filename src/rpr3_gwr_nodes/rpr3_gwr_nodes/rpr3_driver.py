"""rpr3_driver: a simulated 3-RPR that replays leg trajectories.

Like the real mechanism, the platform follows the commanded legs by
continuation of the constraint equations (it is never looked up in a table),
so it stays in its assembly mode unless a singularity is crossed.

* ``joint_states`` (sensor_msgs/JointState, reliable as
  joint_state_broadcaster's, so that readers of any reliability get them,
  ``rate`` Hz): the active legs rho1..rho3 (positions and velocities) and the
  passive angles theta1..theta3;
* ``platform_pose`` (rpr3_gwr_msgs/PlatformPose, same rate and QoS);
* ``mechanism_markers`` (visualization_msgs/MarkerArray, same rate, stamp
  and QoS as the joint states, frame ``base``): base points, legs and
  platform, coloured from green (margin ``warn_margin`` and above) to red
  (``abort_margin``);
* ``/diagnostics`` (diagnostic_msgs/DiagnosticArray, same QoS, 1 Hz and at
  once on an abort): the normalised det(Jx) margin m with level OK when
  ``|m| >= warn_margin``, WARN when ``abort_margin <= |m| < warn_margin``,
  ERROR when ``|m| < abort_margin`` or while the driver holds after an abort
  (until a reset or a goal that succeeds);
* ``execute_trajectory`` (rpr3_gwr_msgs/ExecuteTrajectory action): replays a
  JointTrajectory in real time (scaled by ``time_scale``).  As ros2_controllers'
  joint_trajectory_controller does, a goal is validated when it arrives and
  rejected there, with the reason in the log: no points, wrong joint names,
  a point without one position per joint, velocities or accelerations
  neither empty nor one per joint, efforts (the legs are position
  controlled), legs not finite or outside ``leg_limits``, velocities or
  accelerations not finite, time stamps not normalised (``nanosec`` of a
  second or more), negative or not strictly increasing, a joint faster than
  ``max_velocity``, a first point farther than ``start_tolerance`` from the
  current legs, or another goal executing.  Before each control step the
  driver checks where the platform would go: if the margin would fall below
  ``abort_margin``, det(Jx) would change sign, or the platform could not
  follow, it aborts the goal, says why and with which margin, and holds still
  at the last safe legs;
* ``reset`` (rpr3_gwr_msgs/ResetDriver): puts the platform at a configuration.

The geometry parameters are the builder's (:mod:`.geometry_parameters`).
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
from rpr3_gwr_core.mechanisms.continuation import CANNOT_FOLLOW, CROSSED, follow_path
from rpr3_gwr_core.planning import DEFAULT_MAX_STEP
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import PlatformPose
from rpr3_gwr_msgs.srv import ResetDriver
from sensor_msgs.msg import JointState
from visualization_msgs.msg import MarkerArray

from .conversions import duration_msg
from .geometry_parameters import declare_geometry
from .profiles import JOINT_NAMES, PASSIVE_JOINT_NAMES, STATE_QOS
from .spin import run
from .visualization import mechanism_markers

__all__ = ["Rpr3Driver", "main"]

_Result = ExecuteTrajectory.Result
_Reset = ResetDriver.Response


def _seconds(duration):
    return duration.sec + duration.nanosec * 1e-9


def _slope(times, positions, t):
    """Velocity of the piecewise-linear leg path at time t [length unit/s]."""
    if len(times) < 2 or t >= times[-1]:
        return np.zeros(3)
    k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
    return (positions[k + 1] - positions[k]) / (times[k + 1] - times[k])


def _pose_msg(pose):
    return PlatformPose(x=float(pose[0]), y=float(pose[1]), alpha=float(pose[2]))


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
                 "the current legs [length unit]")
        positive("time_scale", 1.0, "Playback speed factor: 2 replays twice as fast", 1000.0)
        positive("max_velocity", 50.0, "Fastest joint speed a trajectory may ask for, as it is "
                 "timed [length unit/s]")
        self.declare_parameter("leg_limits", [0.0, 50.0], ParameterDescriptor(
            description="Shortest and longest leg [length unit]", read_only=True))
        self.declare_parameter("initial_configuration", [17.0, 12.0, 18.0, math.radians(122.82)],
                               ParameterDescriptor(
                                   description="Initial (rho1, rho2, rho3 [length unit], "
                                               "alpha [rad])", read_only=True))
        self.geometry = declare_geometry(self)
        self.leg_limits = tuple(float(v) for v in self.get_parameter("leg_limits").value)
        self._lock = threading.Lock()
        self._active = False  # a goal is accepted or executing (under _lock)
        self._holding = ""  # why the driver holds after an abort, "" when it does not
        self._stopping = threading.Event()
        self.rho, self.pose, self.margin = self._assembly(
            self.get_parameter("initial_configuration").value)
        self.velocity = np.zeros(3)
        self.joint_pub = self.create_publisher(JointState, "joint_states", STATE_QOS)
        self.pose_pub = self.create_publisher(PlatformPose, "platform_pose", STATE_QOS)
        self.marker_pub = self.create_publisher(MarkerArray, "mechanism_markers", STATE_QOS)
        self.diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", STATE_QOS)
        timers = MutuallyExclusiveCallbackGroup()
        self.create_timer(1.0 / self.get_parameter("rate").value, self._publish_state,
                          callback_group=timers)
        self.create_timer(1.0, self._publish_diagnostics, callback_group=timers)
        self.create_service(ResetDriver, "reset", self._on_reset)
        self._action = ActionServer(
            self, ExecuteTrajectory, "execute_trajectory", self._execute,
            goal_callback=self._on_goal, cancel_callback=lambda _: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup())

    # --- state -------------------------------------------------------------------------------

    def _assembly(self, configuration):
        """Legs, pose and margin of the assembly mode nearest alpha in
        ``(rho1, rho2, rho3, alpha)``.

        Raises
        ------
        _Refused
            With the reset's error code when the configuration is not valid.
        """
        values = tuple(float(v) for v in configuration)
        if len(values) != 4 or not all(math.isfinite(v) for v in values) or min(values[:3]) < 0:
            raise _Refused(_Reset.ERROR_INVALID_INPUT, "a configuration is (rho1, rho2, rho3, "
                           f"alpha), finite, with non-negative legs: got {values}")
        low, high = self.leg_limits
        if not all(low <= v <= high for v in values[:3]):
            raise _Refused(_Reset.ERROR_OUT_OF_RANGE,
                           f"legs {values[:3]} outside the leg limits [{low:g}, {high:g}]")
        rho, alpha = np.array(values[:3]), values[3]
        poses = self.geometry.direct_kinematics(rho)
        if len(poses) == 0:
            raise _Refused(_Reset.ERROR_NO_SOLUTION, f"no real solution at rho = {values[:3]}")
        off = np.abs(np.remainder(poses[:, 2] - alpha + np.pi, 2 * np.pi) - np.pi)
        k = int(np.argmin(off))
        if off[k] > math.radians(1.0):
            raise _Refused(_Reset.ERROR_NO_ASSEMBLY_MODE,
                           f"no assembly mode within 1 deg of alpha = "
                           f"{math.degrees(math.remainder(alpha, 2 * math.pi)):.2f} deg")
        margin = float(self.geometry.margin(poses[k]))
        if abs(margin) < self.get_parameter("abort_margin").value:
            raise _Refused(_Reset.ERROR_SINGULAR, f"configuration is singular (margin "
                           f"{abs(margin):.2e})")
        return rho, poses[k], margin

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
        msg.name = JOINT_NAMES + PASSIVE_JOINT_NAMES
        msg.position = [float(v) for v in rho] + [
            float(v) for v in self.geometry.passive_angles(pose)]
        msg.velocity = [float(v) for v in velocity] + [math.nan] * 3
        self.joint_pub.publish(msg)
        self.pose_pub.publish(_pose_msg(pose))
        self.marker_pub.publish(mechanism_markers(
            self.geometry, pose, margin, self.get_parameter("warn_margin").value,
            self.get_parameter("abort_margin").value, msg.header.stamp))

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
        return DiagnosticStatus(
            name="rpr3_driver: singularity", hardware_id="rpr3_sim", level=level, message=message,
            values=[KeyValue(key="singularity_margin", value=f"{size:.6f}"),
                    KeyValue(key="aspect", value=str(int(np.sign(margin)))),
                    KeyValue(key="alpha", value=f"{pose[2]:.6f}")])

    def _publish_diagnostics(self):
        array = DiagnosticArray(status=[self.diagnostic_status()])
        array.header.stamp = self.get_clock().now().to_msg()
        self.diag_pub.publish(array)

    # --- reset -------------------------------------------------------------------------------

    def _on_reset(self, request, response):
        try:
            c = request.configuration
            rho, pose, margin = self._assembly((c.rho1, c.rho2, c.rho3, c.alpha))
            with self._lock:
                if self._active:
                    raise _Refused(_Reset.ERROR_BUSY, "a trajectory is executing")
                self.rho, self.pose, self.margin = rho, pose, margin
                self.velocity = np.zeros(3)
                self._holding = ""
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
        response.pose = _pose_msg(pose)
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
        if list(trajectory.joint_names) != JOINT_NAMES:
            return f"joint names must be {JOINT_NAMES}, got {list(trajectory.joint_names)}"
        points = trajectory.points
        if not points:
            return "the trajectory has no points"
        joints = len(JOINT_NAMES)
        if any(len(p.positions) != joints for p in points):
            return f"every point needs {joints} positions"
        for field in ("velocities", "accelerations"):
            # Empty, as joint_trajectory_controller allows: not given.
            if any(len(getattr(p, field)) not in (0, joints) for p in points):
                return f"{field} must be empty or {joints} per point"
            if not all(math.isfinite(v) for p in points for v in getattr(p, field)):
                return f"{field} must be finite"
        if any(len(p.effort) for p in points):
            return "the legs are position controlled: effort must be empty"
        positions = np.array([list(p.positions) for p in points])
        if not np.all(np.isfinite(positions)):
            return "positions must be finite"
        low, high = self.leg_limits
        if np.any(positions < low) or np.any(positions > high):
            return f"legs must lie within the leg limits [{low:g}, {high:g}]"
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
                return f"a joint would move at {speed:.3g} length unit/s, above max_velocity " \
                       f"{limit:g}"
        return self._start_gap(positions[0])

    def _start_gap(self, first):
        rho, _, _ = self.state()
        gap = float(np.max(np.abs(first - rho)))
        if gap > self.get_parameter("start_tolerance").value:
            return f"the trajectory starts {gap:.4g} away from the current legs {rho.tolist()}"
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
                self.velocity = np.zeros(3)
                self._active = False

    def _run(self, goal_handle, result):
        trajectory = goal_handle.request.trajectory
        positions = np.array([list(p.positions) for p in trajectory.points])
        times = np.array([_seconds(p.time_from_start) for p in trajectory.points])
        # A reset may have moved the platform since the goal was accepted.
        moved = self._start_gap(positions[0])
        if moved is not None:
            return self._abort(goal_handle, result, _Result.START_MISMATCH, moved, None)
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
            target = np.array([np.interp(elapsed, times, positions[:, j]) for j in range(3)])
            # A late control step must still pass through the waypoints in
            # between: the path, not a chord, is what was validated.
            between = (times > previous) & (times < elapsed)
            rho, pose, _ = self.state()
            followed = self._follow(pose, rho, list(positions[between]) + [target],
                                    abort_margin)
            at = f"at t = {elapsed:.3f} s"
            if followed is None:
                return self._abort(goal_handle, result, _Result.SINGULARITY_ABORT,
                                   f"the platform cannot follow the legs {at}: a singularity "
                                   f"(margin {smallest:.2e} before it)", smallest)
            (x, y, alpha), margin, extreme = followed
            if math.copysign(1.0, extreme) != sign:
                return self._abort(goal_handle, result, _Result.ASSEMBLY_MODE_LEFT,
                                   f"det(Jx) would change sign {at} (margin {extreme:+.2e}): "
                                   "the platform would leave its assembly mode", smallest)
            if abs(extreme) < abort_margin:
                return self._abort(goal_handle, result, _Result.SINGULARITY_ABORT,
                                   f"singularity margin would fall to {abs(extreme):.2e} "
                                   f"< abort_margin {abort_margin:g} {at}",
                                   min(smallest, abs(extreme)))
            smallest = min(smallest, abs(extreme))
            new_pose = np.array([x, y, math.atan2(math.sin(alpha), math.cos(alpha))])
            with self._lock:
                self.velocity = _slope(times, positions, elapsed)
                self.rho, self.pose, self.margin = target, new_pose, margin
            feedback.progress = float(elapsed / times[-1]) if times[-1] > 0 else 1.0
            feedback.singularity_margin = abs(margin)
            feedback.time_from_start = duration_msg(elapsed)
            feedback.pose = _pose_msg(new_pose)
            goal_handle.publish_feedback(feedback)
            if elapsed >= times[-1]:
                break
            time.sleep(period)
        goal_handle.succeed()
        with self._lock:
            self._holding = ""
        result.error_code = _Result.SUCCESS
        return self._finish(result, smallest)

    def _follow(self, pose, rho, points, abort_margin):
        """Follow the legs from ``rho`` through ``points`` as the validator
        does (:func:`~rpr3_gwr_core.mechanisms.continuation.follow_path`, the
        same step control, stopping below ``abort_margin``); ``(pose, margin,
        extreme)`` with the most critical margin of the whole way (of the
        other sign if det(Jx) changed sign), or None when the platform cannot
        follow."""
        followed = np.array(pose, dtype=float)
        start = float(self.geometry.margin(followed))
        status, _, _, smallest = follow_path(
            self.geometry, np.array([rho, *points], dtype=float), followed, abort_margin,
            DEFAULT_MAX_STEP)
        if status == CANNOT_FOLLOW:
            return None
        extreme = math.copysign(smallest, start) if status != CROSSED \
            else -math.copysign(abort_margin, start)
        return tuple(followed), float(self.geometry.margin(followed)), extreme

    def _abort(self, goal_handle, result, code, reason, smallest):
        self.get_logger().warning(f"aborting the trajectory and holding still: {reason}")
        if code in (_Result.SINGULARITY_ABORT, _Result.ASSEMBLY_MODE_LEFT):
            with self._lock:
                self._holding = f"holding after an abort: {reason}"
        goal_handle.abort()
        result.error_code, result.error_msg = code, reason
        self._publish_diagnostics()
        return self._finish(result, smallest)

    def _finish(self, result, smallest):
        _, pose, margin = self.state()
        result.final_pose = _pose_msg(pose)
        result.min_singularity_margin = float(abs(margin) if smallest is None else smallest)
        return result

    def prepare_shutdown(self):
        """End a trajectory in execution now (called by ``main`` on SIGINT)."""
        self._stopping.set()


def main(args=None):
    run(Rpr3Driver, MultiThreadedExecutor, args, num_threads=4)
