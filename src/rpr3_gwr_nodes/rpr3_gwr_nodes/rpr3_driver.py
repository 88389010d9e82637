"""rpr3_driver: a simulated 3-RPR that replays leg trajectories.

Like the real mechanism, the platform follows the commanded legs by
continuation of the constraint equations (it is never looked up in a table),
so it stays in its assembly mode unless a singularity is crossed.

* ``joint_states`` (sensor_msgs/JointState, best effort, ``rate`` Hz): the
  active legs rho1..rho3 (positions and velocities) and the passive angles
  theta1..theta3;
* ``platform_pose`` (rpr3_gwr_msgs/PlatformPose, same rate);
* ``/diagnostics`` (diagnostic_msgs/DiagnosticArray, 1 Hz): the normalised
  det(Jx) margin, WARN below ``warn_margin``;
* ``execute_trajectory`` (rpr3_gwr_msgs/ExecuteTrajectory action): replays a
  JointTrajectory in real time (scaled by ``time_scale``); it must start at
  the current legs.  Before each control step the driver checks where the
  platform would go: if the margin would fall below ``abort_margin``, det(Jx)
  would change sign, or the platform could not follow, it aborts the goal and
  holds still at the last safe legs;
* ``reset`` (rpr3_gwr_msgs/ResetDriver): puts the platform at a configuration.
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
from rclpy.qos import qos_profile_sensor_data
from rpr3_gwr_core.exceptions import GWRError
from rpr3_gwr_core.geometry import PAPER_GEOMETRY
from rpr3_gwr_core.kinematics import direct_kinematics, passive_angles, singularity_margin
from rpr3_gwr_core.mechanism import Mechanism
from rpr3_gwr_core.validation import DEFAULT_MAX_STEP
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import PlatformPose
from rpr3_gwr_msgs.srv import ResetDriver
from sensor_msgs.msg import JointState

from .conversions import duration_msg
from .spin import run
from .planner import JOINT_NAMES

__all__ = ["Rpr3Driver", "main"]

_Result = ExecuteTrajectory.Result


def _seconds(duration):
    return duration.sec + duration.nanosec * 1e-9


def _slope(times, positions, t):
    """Velocity of the piecewise-linear leg path at time t [length unit/s]."""
    if len(times) < 2 or t >= times[-1]:
        return np.zeros(3)
    k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
    return (positions[k + 1] - positions[k]) / (times[k + 1] - times[k])


class Rpr3Driver(Node):
    """The simulated manipulator."""

    def __init__(self, **kwargs):
        super().__init__("rpr3_driver", **kwargs)

        def positive(description, value, high=1e6):
            self.declare_parameter(value[0], value[1], ParameterDescriptor(
                description=description,
                floating_point_range=[FloatingPointRange(from_value=1e-9, to_value=high)]))

        positive("Joint state publishing rate [Hz]", ("rate", 100.0), 1000.0)
        # Half the planner's validation margin (1e-3): validated plans pass
        # even where the driver's steps sample the margin differently.
        positive("Smallest normalised |det Jx| allowed; below it a goal aborts",
                 ("abort_margin", 5e-4), 1.0)
        positive("Normalised |det Jx| below which diagnostics warn", ("warn_margin", 0.02), 1.0)
        positive("Largest distance of a trajectory's first point from the current legs "
                 "[length unit]", ("start_tolerance", 1e-3))
        positive("Playback speed factor: 2 replays twice as fast", ("time_scale", 1.0), 1000.0)
        self.declare_parameter("initial_configuration", [17.0, 12.0, 18.0, math.radians(122.82)],
                               ParameterDescriptor(
                                   description="Initial (rho1, rho2, rho3 [length unit], "
                                               "alpha [rad])", read_only=True))
        self.geometry = PAPER_GEOMETRY
        self.mechanism = Mechanism(self.geometry)
        self._lock = threading.Lock()
        self._busy = threading.Lock()
        rho1, rho2, rho3, alpha = self.get_parameter("initial_configuration").value
        self.rho, self.pose, self.margin = self._assembly((rho1, rho2, rho3), alpha)
        self.velocity = np.zeros(3)
        self.joint_pub = self.create_publisher(JointState, "joint_states", qos_profile_sensor_data)
        self.pose_pub = self.create_publisher(PlatformPose, "platform_pose", qos_profile_sensor_data)
        self.diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        timers = MutuallyExclusiveCallbackGroup()
        self.create_timer(1.0 / self.get_parameter("rate").value, self._publish_state,
                          callback_group=timers)
        self.create_timer(1.0, self._publish_diagnostics, callback_group=timers)
        self.create_service(ResetDriver, "reset", self._on_reset)
        self._action = ActionServer(
            self, ExecuteTrajectory, "execute_trajectory", self._execute,
            goal_callback=lambda _: GoalResponse.ACCEPT,
            cancel_callback=lambda _: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup())

    def _assembly(self, rho, alpha):
        """Legs, pose and margin of the assembly mode nearest ``alpha``."""
        poses = direct_kinematics(np.asarray(rho, dtype=float), self.geometry)
        if len(poses) == 0:
            raise GWRError(f"no real solution at rho = {tuple(rho)}")
        k = int(np.argmin(np.abs(np.angle(np.exp(1j * (poses[:, 2] - alpha))))))
        return np.asarray(rho, dtype=float), poses[k], float(singularity_margin(poses[k]))

    def state(self):
        """``(rho, pose, margin)`` under the lock."""
        with self._lock:
            return self.rho.copy(), self.pose.copy(), self.margin

    def _publish_state(self):
        rho, pose, _ = self.state()
        with self._lock:
            velocity = self.velocity.copy()
        msg = JointState()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.name = list(JOINT_NAMES) + ["theta1", "theta2", "theta3"]
        msg.position = [float(v) for v in rho] + [float(v) for v in passive_angles(pose)]
        msg.velocity = [float(v) for v in velocity] + [math.nan] * 3
        self.joint_pub.publish(msg)
        self.pose_pub.publish(PlatformPose(x=float(pose[0]), y=float(pose[1]), alpha=float(pose[2])))

    def _publish_diagnostics(self):
        _, pose, margin = self.state()
        warn = self.get_parameter("warn_margin").value
        status = DiagnosticStatus(
            name="rpr3_driver: singularity", hardware_id="rpr3_sim",
            level=DiagnosticStatus.OK if abs(margin) >= warn else DiagnosticStatus.WARN,
            message="regular" if abs(margin) >= warn else "near a parallel singularity",
            values=[KeyValue(key="singularity_margin", value=f"{abs(margin):.6f}"),
                    KeyValue(key="aspect", value=str(int(np.sign(margin)))),
                    KeyValue(key="alpha", value=f"{pose[2]:.6f}")])
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self.diag_pub.publish(array)

    def _on_reset(self, request, response):
        c = request.configuration
        values = (c.rho1, c.rho2, c.rho3, c.alpha)
        if not all(math.isfinite(v) for v in values) or min(values[:3]) < 0:
            response.error_code = ResetDriver.Response.ERROR_INVALID_INPUT
            response.error_msg = f"configuration must be finite with non-negative legs: {values}"
            return response
        if not self._busy.acquire(blocking=False):
            response.error_code = ResetDriver.Response.ERROR_BUSY
            response.error_msg = "a trajectory is executing"
            return response
        try:
            try:
                rho, pose, margin = self._assembly(values[:3], values[3])
            except GWRError as exc:
                response.error_code = ResetDriver.Response.ERROR_NO_SOLUTION
                response.error_msg = str(exc)
                return response
            if abs(math.remainder(pose[2] - values[3], 2 * math.pi)) > math.radians(1.0):
                response.error_code = ResetDriver.Response.ERROR_NO_ASSEMBLY_MODE
                response.error_msg = f"no assembly mode within 1 deg of alpha = {values[3]:.4f} rad"
                return response
            if abs(margin) < self.get_parameter("abort_margin").value:
                response.error_code = ResetDriver.Response.ERROR_SINGULAR
                response.error_msg = f"configuration is singular (margin {abs(margin):.2e})"
                return response
            with self._lock:
                self.rho, self.pose, self.margin = rho, pose, margin
                self.velocity = np.zeros(3)
            response.success = True
            response.pose = PlatformPose(x=float(pose[0]), y=float(pose[1]), alpha=float(pose[2]))
            return response
        finally:
            self._busy.release()

    def _check(self, trajectory):
        """Why a trajectory cannot be executed, as (code, reason), or None."""
        if list(trajectory.joint_names) != JOINT_NAMES:
            return _Result.INVALID_TRAJECTORY, f"joint names must be {JOINT_NAMES}"
        points = trajectory.points
        if not points:
            return _Result.INVALID_TRAJECTORY, "the trajectory has no points"
        if any(len(p.positions) != 3 for p in points):
            return _Result.INVALID_TRAJECTORY, "every point needs 3 positions"
        positions = np.array([list(p.positions) for p in points])
        if not np.all(np.isfinite(positions)) or np.any(positions < 0):
            return _Result.INVALID_TRAJECTORY, "positions must be finite and non-negative"
        times = np.array([_seconds(p.time_from_start) for p in points])
        if len(points) > 1 and not np.all(np.diff(times) > 0):
            return _Result.INVALID_TRAJECTORY, "time_from_start must increase strictly"
        rho, _, _ = self.state()
        gap = float(np.max(np.abs(positions[0] - rho)))
        if gap > self.get_parameter("start_tolerance").value:
            return _Result.START_MISMATCH, (
                f"the trajectory starts {gap:.4g} away from the current legs {rho.tolist()}")
        return None

    def _execute(self, goal_handle):
        result = _Result()
        if not self._busy.acquire(blocking=False):
            goal_handle.abort()
            result.error_code, result.reason = _Result.INVALID_TRAJECTORY, "another goal is executing"
            return self._finish(result)
        try:
            return self._run(goal_handle, result)
        finally:
            with self._lock:
                self.velocity = np.zeros(3)
            self._busy.release()

    def _run(self, goal_handle, result):
        trajectory = goal_handle.request.trajectory
        problem = self._check(trajectory)
        if problem is not None:
            result.error_code, result.reason = problem
            goal_handle.abort()
            return self._finish(result)
        positions = np.array([list(p.positions) for p in trajectory.points])
        times = np.array([_seconds(p.time_from_start) for p in trajectory.points])
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
                result.error_code, result.reason = _Result.CANCELED, "canceled"
                return self._finish(result, smallest)
            previous = elapsed
            elapsed = min((time.monotonic() - begin) * scale, times[-1])
            target = np.array([np.interp(elapsed, times, positions[:, j]) for j in range(3)])
            # A late control step must still pass through the waypoints in
            # between: the path, not a chord, is what was validated.
            between = (times > previous) & (times < elapsed)
            rho, pose, _ = self.state()
            followed = self._follow(pose, rho, list(positions[between]) + [target])
            if followed is None:
                return self._abort(goal_handle, result, _Result.SINGULARITY_ABORT,
                                   "the platform cannot follow the legs: singularity", smallest)
            (x, y, alpha), margin, extreme = followed
            new_pose = (x, y, math.atan2(math.sin(alpha), math.cos(alpha)))
            if math.copysign(1.0, extreme) != sign:
                return self._abort(goal_handle, result, _Result.ASSEMBLY_MODE_LEFT,
                                   "det(Jx) would change sign: the platform would leave its "
                                   "assembly mode", smallest)
            if abs(extreme) < abort_margin:
                return self._abort(goal_handle, result, _Result.SINGULARITY_ABORT,
                                   f"singularity margin would fall to {abs(extreme):.2e} "
                                   f"< {abort_margin:g}", min(smallest, abs(extreme)))
            smallest = min(smallest, abs(extreme))
            with self._lock:
                self.velocity = _slope(times, positions, elapsed)
                self.rho, self.pose, self.margin = target, np.array(new_pose), margin
            feedback.progress = float(elapsed / times[-1]) if times[-1] > 0 else 1.0
            feedback.singularity_margin = abs(margin)
            feedback.time_from_start = duration_msg(elapsed)
            feedback.pose = PlatformPose(x=new_pose[0], y=new_pose[1], alpha=new_pose[2])
            goal_handle.publish_feedback(feedback)
            if elapsed >= times[-1]:
                break
            time.sleep(period)
        goal_handle.succeed()
        result.error_code = _Result.SUCCESS
        return self._finish(result, smallest)

    def _follow(self, pose, rho, points):
        """Follow the legs from ``rho`` through ``points`` in steps no longer
        than the planner's validator takes; ``(pose, margin, extreme)`` with
        the most critical margin of the whole way, or None."""
        extreme = None
        for point in points:
            substeps = max(1, math.ceil(float(np.max(np.abs(point - rho))) / DEFAULT_MAX_STEP))
            followed = self.mechanism.follow(pose, rho, point, substeps=substeps)
            if followed is None:
                return None
            pose, margin, step_extreme = followed
            if (extreme is None or (step_extreme > 0) != (extreme > 0)
                    or abs(step_extreme) < abs(extreme)):
                extreme = step_extreme
            rho = point
        return pose, margin, extreme

    def _abort(self, goal_handle, result, code, reason, smallest):
        self.get_logger().warning(f"aborting the trajectory and holding still: {reason}")
        goal_handle.abort()
        result.error_code, result.reason = code, reason
        return self._finish(result, smallest)

    def _finish(self, result, smallest=None):
        _, pose, margin = self.state()
        result.final_pose = PlatformPose(x=float(pose[0]), y=float(pose[1]), alpha=float(pose[2]))
        result.min_singularity_margin = float(abs(margin) if smallest is None else smallest)
        return result


def main(args=None):
    run(Rpr3Driver, MultiThreadedExecutor, args, num_threads=4)
