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
  goal executing (:mod:`.goal_checks` makes the checks but the last).  Before
  each control step the driver checks where the platform would go: if the
  margin would fall below ``abort_margin``, det(Jx) would change sign, or
  the platform could not follow, it aborts the goal, says why and with which
  margin, and holds still at the last safe joints.  In a scene, each
  control step's stretch of the path (from the current joints through the
  waypoints passed to the step's target) is then checked continuously with the core
  (``path_collisions``): if a body would come within ``obstacle_clearance``
  of an obstacle, bodies would overlap, or a joint would leave its range,
  the goal aborts with ``COLLISION_ABORT`` before the step, naming the body
  (or joint) and the obstacle (or range), and the driver holds at the last
  free joints;
* ``~/follow_joint_trajectory`` (control_msgs/FollowJointTrajectory action):
  the same replay for code written for ros2_control's
  joint_trajectory_controller, its goals validated as that controller does
  (every joint once in any order, the last point at rest, no multi-DOF
  points, a header stamp whose trajectory has not ended; a future one starts
  then) and by the checks above, an abort on the way ending the goal
  ``PATH_TOLERANCE_VIOLATED`` with the reason;
* ``/tf`` (tf2_msgs/TFMessage, tf2_ros's broadcaster's QoS, ``rate`` Hz): from
  ``base`` to each link's frame and the platform's (:mod:`.frames`), names
  prefixed by ``frame_prefix``;
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
from rclpy.node import Node
from rclpy.parameter import Parameter
from rpr3_gwr_core.exceptions import GWRError, InvalidInputError
from rpr3_gwr_core.mechanisms.continuation import CANNOT_FOLLOW, CROSSED, follow_path
from rpr3_gwr_core.planning import DEFAULT_MAX_STEP
from rpr3_gwr_core.planning.locate import DEFAULT_MODE_TOL
from rpr3_gwr_core.world import configuration_collision, path_collisions
from rpr3_gwr_core.world.collision import INTERFERENCE, OBSTACLE
from control_msgs.action import FollowJointTrajectory
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import PlatformPose, Scene
from rpr3_gwr_msgs.srv import ResetDriver
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import MarkerArray

from .conversions import (configuration_from_msg, duration_msg, is_empty_scene, pose_msg,
                          scene_from_msg, scene_msg_from_bytes, scene_to_msg)
from .executors import BoundedExecutor
from .frames import frame_transforms
from .goal_checks import (CONTROLLER_CODES, check_follow_trajectory, check_trajectory,
                          start_problem, trajectory_fields, whole_turns)
from .mechanism_parameters import declare_mechanism, home_source, kept_scene
from .profiles import BASE_FRAME, LATCHED_QOS, STATE_QOS, TF_QOS
from .spin import run
from .visualization import mechanism_markers, scene_markers

__all__ = ["Rpr3Driver", "main", "USAGE"]

USAGE = """\
usage: ros2 run rpr3_gwr_nodes rpr3_driver [-h] [--ros-args ...]

A simulated parallel mechanism (by default the paper's 3-RPR) that executes
joint trajectories, following its platform by continuation, and aborts
before a singularity, an assembly-mode change or a collision.

Serves      execute_trajectory (rpr3_gwr_msgs/action/ExecuteTrajectory),
            ~/follow_joint_trajectory (control_msgs/action/FollowJointTrajectory),
            reset (rpr3_gwr_msgs/srv/ResetDriver)
Subscribes  scene (latched)
Publishes   joint_states, platform_pose, mechanism_markers, /diagnostics, /tf,
            scene_markers, ~/current_scene
Parameters  mechanism_file ('' for the paper's 3-RPR, read-only),
            initial_configuration (joints then mode coordinate, read-only),
            rate (100 Hz), time_scale (1.0), max_velocity (50 /s),
            start_tolerance (1e-3), abort_margin (5e-4), warn_margin (0.02),
            frame_prefix ('', read-only)
Example     ros2 run rpr3_gwr_nodes rpr3_driver --ros-args -p time_scale:=10.0
"""

_Result = ExecuteTrajectory.Result
_Reset = ResetDriver.Response

# How an execution ends.
_SUCCEEDED, _CANCELED, _SHUT_DOWN, _START_MISMATCH = "succeeded", "canceled", "shut down", \
    "start mismatch"
_SINGULARITY, _MODE_LEFT, _COLLISION, _INTERNAL_ERROR = "singularity", "mode left", \
    "collision", "internal error"
# The aborts after which the driver holds until a reset or a goal that succeeds.
_HOLDING_ENDINGS = (_SINGULARITY, _MODE_LEFT, _COLLISION)
_Follow = FollowJointTrajectory.Result
# As joint_trajectory_controller ends goals: an abort on the way is a path
# tolerance violated (the driver holds where the trajectory left it).
_FOLLOW_CODES = {
    _SUCCEEDED: _Follow.SUCCESSFUL, _CANCELED: _Follow.SUCCESSFUL,
    _SHUT_DOWN: _Follow.INVALID_GOAL, _INTERNAL_ERROR: _Follow.INVALID_GOAL,
    **dict.fromkeys((_START_MISMATCH, _SINGULARITY, _MODE_LEFT, _COLLISION),
                    _Follow.PATH_TOLERANCE_VIOLATED)}
_EXECUTE_CODES = {_SUCCEEDED: _Result.SUCCESS, _CANCELED: _Result.CANCELED,
                  _SHUT_DOWN: _Result.CANCELED, _START_MISMATCH: _Result.START_MISMATCH,
                  _SINGULARITY: _Result.SINGULARITY_ABORT,
                  _MODE_LEFT: _Result.ASSEMBLY_MODE_LEFT, _COLLISION: _Result.COLLISION_ABORT,
                  _INTERNAL_ERROR: _Result.INVALID_TRAJECTORY}


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


def _in_order(trajectory, names):
    """A JointTrajectory's points with their joints in the order ``names``
    (the trajectory names each once, in any order)."""
    order = [list(trajectory.joint_names).index(name) for name in names]

    def picked(values):
        return [values[k] for k in order] if len(values) == len(order) else list(values)

    return JointTrajectory(header=trajectory.header, joint_names=list(names), points=[
        JointTrajectoryPoint(positions=picked(p.positions), velocities=picked(p.velocities),
                             accelerations=picked(p.accelerations), effort=list(p.effort),
                             time_from_start=p.time_from_start)
        for p in trajectory.points])


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
        self.declare_parameter("frame_prefix", "", ParameterDescriptor(
            description="Put before the name of each frame broadcast on /tf (not base), as "
                        "robot_state_publisher's", read_only=True))
        described = declare_mechanism(self)
        self.mechanism = described.mechanism
        # The widths and layers of the bodies a scene is checked with.
        self.bodies = described.bodies
        names = self.mechanism.joint_names
        # Joint ranges are the file's box; a joint that turns fully has none.
        self.limits = [None if a.periodic else (a.low, a.high) for a in described.axes]
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
            self.get_logger().info(f"starting at {home_source(described)}: "
                                   f"{', '.join(f'{v:g}' for v in initial)}")
        self.rho, self.pose, self.margin = self._assembly(initial)
        self.velocity = np.zeros(len(names))
        self.joint_pub = self.create_publisher(JointState, "joint_states", STATE_QOS)
        self.pose_pub = self.create_publisher(PlatformPose, "platform_pose", STATE_QOS)
        self.marker_pub = self.create_publisher(MarkerArray, "mechanism_markers", STATE_QOS)
        self.diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", STATE_QOS)
        self.tf_pub = self.create_publisher(TFMessage, "/tf", TF_QOS)
        timers = MutuallyExclusiveCallbackGroup()
        self.create_timer(1.0 / self.get_parameter("rate").value, self._publish_state,
                          callback_group=timers)
        self.create_timer(1.0, self._publish_diagnostics, callback_group=timers)
        self.create_service(ResetDriver, "reset", self._on_reset)
        self.scene_pub = self.create_publisher(Scene, "~/current_scene", LATCHED_QOS)
        self.scene_marker_pub = self.create_publisher(MarkerArray, "scene_markers", LATCHED_QOS)
        # Raw: a message too long to be a scene is refused unread.
        self.create_subscription(Scene, "scene", self._on_scene, LATCHED_QOS,
                                 callback_group=MutuallyExclusiveCallbackGroup(), raw=True)
        self._action = ActionServer(
            self, ExecuteTrajectory, "execute_trajectory", self._execute,
            goal_callback=self._on_goal, cancel_callback=lambda _: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup())
        # Where joint_trajectory_controller serves it: under the node's name.
        self._follow_action = ActionServer(
            self, FollowJointTrajectory, "~/follow_joint_trajectory", self._execute_follow,
            goal_callback=self._on_follow_goal,
            cancel_callback=lambda _: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup())
        joints = ", ".join(f"{n} = {v:g}" for n, v in zip(names, self.rho))
        self.get_logger().info(
            f"ready: serving {self.resolve_service_name('execute_trajectory')}, "
            f"{self.resolve_service_name('~/follow_joint_trajectory')} and "
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
        self.tf_pub.publish(TFMessage(transforms=frame_transforms(
            self.mechanism, pose, rho, msg.header.stamp,
            self.get_parameter("frame_prefix").value)))
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

    def _on_scene(self, data):
        try:
            msg = scene_msg_from_bytes(data)
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
        return self._take(lambda: self._problem(goal_request.trajectory))

    def _on_follow_goal(self, goal_request):
        """Accept a valid FollowJointTrajectory goal, as joint_trajectory_controller
        validates one, and take the driver for it; reject anything else."""
        return self._take(lambda: self._follow_problem(goal_request))

    def _take(self, find_problem):
        """Take the driver for a goal ``find_problem()`` finds nothing wrong
        with (None), unless another goal has it; else reject, saying why."""
        try:
            problem = find_problem()
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

    def _limits(self):
        """The driver's state and parameters :mod:`.goal_checks` checks a goal with."""
        rho, _, _ = self.state()
        return {"ranges": self.limits, "max_velocity": self.get_parameter("max_velocity").value,
                "current_joints": rho,
                "start_tolerance": self.get_parameter("start_tolerance").value}

    def _problem(self, trajectory):
        """Why a trajectory cannot be executed from here, or None."""
        verdict = check_trajectory(**trajectory_fields(trajectory),
                                   mechanism_joints=self.mechanism.joint_names, **self._limits())
        return None if verdict.accepted else verdict.reason

    def _follow_problem(self, goal):
        """Why a FollowJointTrajectory goal cannot be executed from here, or
        None: joint_trajectory_controller's checks, then :meth:`_problem`'s
        on the trajectory in the mechanism's order
        (:func:`.goal_checks.check_follow_trajectory`)."""
        names = list(self.mechanism.joint_names)
        stamp = goal.trajectory.header.stamp
        verdict = check_follow_trajectory(
            **trajectory_fields(goal.trajectory),
            multi_dof_joints=list(goal.multi_dof_trajectory.joint_names),
            multi_dof_points=len(goal.multi_dof_trajectory.points),
            header_stamp=(stamp.sec, stamp.nanosec),
            now=self.get_clock().now().nanoseconds * 1e-9, mechanism_joints=names,
            **self._limits())
        # The tolerances of a goal the controller's own checks refuse are
        # not worth a warning beside the reason it is refused for.
        if verdict.code not in CONTROLLER_CODES:
            self._warn_about_tolerances(goal, names)
        return None if verdict.accepted else verdict.reason

    def _warn_about_tolerances(self, goal, names):
        """Tolerances of unknown joints, or neither -1 (none), 0 (default)
        nor positive, are ignored with a warning, as joint_trajectory_controller
        does; the simulation follows its trajectory exactly, so others hold."""
        for field in ("path_tolerance", "goal_tolerance"):
            for tolerance in getattr(goal, field):
                values = (tolerance.position, tolerance.velocity, tolerance.acceleration)
                if tolerance.name not in names or not all(
                        v == -1.0 or (math.isfinite(v) and v >= 0.0) for v in values):
                    self.get_logger().warning(f"ignoring the goal's {field}: joint "
                                              f"{tolerance.name!r:.40} {values}")
                    break

    def _turns(self, first):
        """Whole turns that bring the trajectory's ``first`` point nearest the
        current joints (0 for a joint that does not turn fully)."""
        rho, _, _ = self.state()
        return whole_turns(first, rho, self.limits)

    def _start_gap(self, first):
        rho, _, _ = self.state()
        return start_problem(first, rho, self.limits, self.get_parameter("start_tolerance").value)

    def _execute(self, goal_handle):
        result = _Result()
        try:
            trajectory = goal_handle.request.trajectory
            positions = np.array([list(p.positions) for p in trajectory.points])
            times = np.array([_seconds(p.time_from_start) for p in trajectory.points])
            feedback = ExecuteTrajectory.Feedback()

            def publish_feedback(elapsed, pose, margin):
                feedback.progress = float(elapsed / times[-1]) if times[-1] > 0 else 1.0
                feedback.singularity_margin = abs(margin)
                feedback.time_from_start = duration_msg(elapsed)
                feedback.pose = pose_msg(self.mechanism, pose)
                goal_handle.publish_feedback(feedback)

            ending, reason, smallest = self._replay(goal_handle, positions, times,
                                                    publish_feedback)
        except Exception as exc:  # a bug must not take the driver down
            self.get_logger().error(f"internal error executing a trajectory: {exc!r}")
            ending, reason, smallest = _INTERNAL_ERROR, f"internal error: {exc!r}", None
        finally:
            with self._lock:
                self.velocity = np.zeros(self.mechanism.n_joints)
                self._active = False
        self._conclude(goal_handle, ending, reason)
        result.error_code, result.error_msg = _EXECUTE_CODES[ending], reason
        _, pose, margin = self.state()
        result.final_pose = pose_msg(self.mechanism, pose)
        result.min_singularity_margin = float(abs(margin) if smallest is None else smallest)
        return result

    def _execute_follow(self, goal_handle):
        result = FollowJointTrajectory.Result()
        names = list(self.mechanism.joint_names)
        try:
            trajectory = _in_order(goal_handle.request.trajectory, names)
            positions = np.array([list(p.positions) for p in trajectory.points])
            times = np.array([_seconds(p.time_from_start) for p in trajectory.points])
            feedback = FollowJointTrajectory.Feedback(joint_names=names)

            def publish_feedback(elapsed, pose, margin):
                with self._lock:
                    rho, velocity = self.rho.tolist(), self.velocity.tolist()
                feedback.header.stamp = self.get_clock().now().to_msg()
                at = duration_msg(elapsed)
                # The simulation follows the trajectory exactly.
                for point in (feedback.desired, feedback.actual):
                    point.positions, point.velocities, point.time_from_start = rho, velocity, at
                feedback.error.positions = [0.0] * len(rho)
                feedback.error.time_from_start = at
                goal_handle.publish_feedback(feedback)

            ending, reason = self._wait_for_start(goal_handle, trajectory.header.stamp), ""
            if ending is None:
                ending, reason, _ = self._replay(goal_handle, positions, times,
                                                 publish_feedback)
        except Exception as exc:  # a bug must not take the driver down
            self.get_logger().error(f"internal error executing a trajectory: {exc!r}")
            ending, reason = _INTERNAL_ERROR, f"internal error: {exc!r}"
        finally:
            with self._lock:
                self.velocity = np.zeros(self.mechanism.n_joints)
                self._active = False
        self._conclude(goal_handle, ending, reason)
        result.error_code, result.error_string = _FOLLOW_CODES[ending], reason
        return result

    def _wait_for_start(self, goal_handle, stamp):
        """Wait until a trajectory's header ``stamp`` (none when zero, or
        passed); the ending when a cancel or the driver's shutdown came
        first, else None."""
        begin = _seconds(stamp)
        period = 1.0 / self.get_parameter("rate").value
        while begin > self.get_clock().now().nanoseconds * 1e-9:
            if goal_handle.is_cancel_requested:
                return _CANCELED
            if self._stopping.is_set():
                return _SHUT_DOWN
            time.sleep(period)
        return None

    def _replay(self, goal_handle, positions, times, publish_feedback):
        """Move the joints along ``positions`` (shape (n, n_joints)) at
        ``times`` (shape (n,), [s] from the start) in real time scaled by
        ``time_scale``, the platform following, until the end, a cancel, the
        driver's shutdown or an abort (before the step that would reach a
        singularity, leave the assembly mode or collide);
        ``publish_feedback(elapsed [s], pose, margin)`` after each step.

        Returns
        -------
        (str, str, float or None)
            How it ended (``_SUCCEEDED``, ``_CANCELED``, ...), why ("" for a success),
            and the smallest margin met (None before the first step).
        """
        # Counted from the current turn of the joints that turn fully, as the
        # plan's path is continuous.
        positions = positions + self._turns(positions[0])
        # A reset may have moved the platform since the goal was accepted.
        moved = self._start_gap(positions[0])
        if moved is not None:
            return _START_MISMATCH, moved, None
        with self._lock:
            self._collision = None  # the highlight is of the goal that aborted on it
        scale = self.get_parameter("time_scale").value
        abort_margin = self.get_parameter("abort_margin").value
        period = 1.0 / self.get_parameter("rate").value
        _, _, margin0 = self.state()
        sign = math.copysign(1.0, margin0)
        smallest = abs(margin0)
        begin = time.monotonic()
        elapsed = -1.0
        while True:
            if goal_handle.is_cancel_requested:
                return _CANCELED, "canceled", smallest
            if self._stopping.is_set():
                return _SHUT_DOWN, "the driver is shutting down", smallest
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
                return (_SINGULARITY, f"the platform cannot follow the joints {at}: a "
                        f"singularity (margin {smallest:.2e} before it)", smallest)
            new_pose, margin, extreme = followed
            if math.copysign(1.0, extreme) != sign:
                return (_MODE_LEFT, f"det(Jx) would change sign {at} (margin {extreme:+.2e}): "
                        "the platform would leave its assembly mode", smallest)
            if abs(extreme) < abort_margin:
                return (_SINGULARITY, f"singularity margin would fall to {abs(extreme):.2e} "
                        f"< abort_margin {abort_margin:g} {at}", min(smallest, abs(extreme)))
            scene = kept_scene(self._scene, self.bodies)
            if scene is not None:
                hit = path_collisions(self.mechanism, scene,
                                      np.array([rho, *positions[between], target]), pose,
                                      self.bodies)
                if hit is not None:
                    with self._lock:
                        self._collision = hit
                    return (_COLLISION,
                            f"{_collision_reason(hit, scene.limits.obstacle_clearance)} {at}: "
                            "holding at the last free joints", smallest)
            smallest = min(smallest, abs(extreme))
            with self._lock:
                self.velocity = _slope(times, positions, elapsed)
                self.rho, self.pose, self.margin = target, new_pose, margin
            publish_feedback(elapsed, new_pose, margin)
            if elapsed >= times[-1]:
                break
            time.sleep(period)
        with self._lock:
            self._holding = ""
            self._collision = None
        return _SUCCEEDED, "", smallest

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

    def _conclude(self, goal_handle, ending, reason):
        """End the goal as ``ending`` says; after an abort on the way the
        driver holds still, and says why in its log and diagnostics."""
        if ending == _SUCCEEDED:
            goal_handle.succeed()
            return
        if ending == _CANCELED:
            goal_handle.canceled()
            return
        self.get_logger().warning(f"aborting the trajectory and holding still: {reason}")
        if ending in _HOLDING_ENDINGS:
            with self._lock:
                self._holding = f"holding after an abort: {reason}"
        goal_handle.abort()
        self._publish_diagnostics()

    def prepare_shutdown(self):
        """End a trajectory in execution now (called by ``main`` on SIGINT)."""
        self._stopping.set()


def main(args=None):
    return run(Rpr3Driver, BoundedExecutor, args, usage=USAGE, num_threads=4)
