"""A client of the suite's planner and driver for scripts and tests, in the
spirit of nav2_simple_commander's ``BasicNavigator``.

:class:`PlannerClient` is a node that spins itself: each of its calls spins
a private single-threaded executor in the calling thread until its answer
comes or its timeout passes, so a script needs no executor of its own::

    import rclpy
    from rpr3_gwr_nodes.client import PlannerClient

    rclpy.init()
    client = PlannerClient()
    try:
        client.wait_until_ready(timeout_sec=60.0)
        response = client.plan(({"rho1": 17.0, "rho2": 12.0, "rho3": 18.0}, 2.14362),
                               ({"rho1": 17.0, "rho2": 10.0, "rho3": 25.0}, -0.42307))
        client.reset_driver(({"rho1": 17.0, "rho2": 12.0, "rho3": 18.0}, 2.14362))
        outcome = client.execute(response.trajectory)
    finally:
        client.destroy_node()
        rclpy.try_shutdown()

Its subscriptions (the latched ``roadmap`` and the planner's
``~/current_scene``) take their messages only while one of its calls spins;
being latched, they lose none meanwhile.  Calls are not thread-safe: make
them from one thread at a time (several clients may call from threads of
their own), and do not add the node to another executor.

Every call survives a restart of its server.  A request reaches only the
servers its writer has matched when it is sent: one sent to a server that
has just been killed, before its successor was discovered, is lost, and so
is the answer of a server that answers before it has matched the client's
response reader.  So a call sends its request again when a server appears in
the ROS graph that was not there when it was sent, and when a server new to
this client leaves it unanswered for 10 s.  Every call ends within its
timeout (:meth:`execute` at most a second after it, for a cancel), raising
:class:`TimeoutError`, or :class:`GoalLostError` for a goal its driver no
longer knows.
"""

import collections
import copy
import math
import numbers
import time
import uuid
from collections.abc import Mapping

from builtin_interfaces.msg import Time
from control_msgs.action import FollowJointTrajectory
from geometry_msgs.msg import PoseStamped
from rclpy.action import ActionClient
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import Configuration, JointLimits, Scene, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import AssemblyModes, InverseKinematics, PlanPath, ResetDriver
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory
from unique_identifier_msgs.msg import UUID

from .conversions import duration_msg
from .profiles import BASE_FRAME, LATCHED_QOS, SERVICE_QOS

__all__ = ["PlannerClient", "GoalRejectedError", "GoalLostError", "configuration",
           "platform_pose"]

# Longest wait for one readiness probe, sent again if unanswered [s].
_PROBE_TIMEOUT = 2.0
# Longest wait for the answer to a request sent to a server that has not
# answered this client yet before it is sent again: under load a server may
# answer before it has matched the client's response reader (rmw_fastrtps
# waits 100 ms for it), and that answer is lost; later requests find the
# match made [s].
_FIRST_ANSWER_TIMEOUT = 10.0
# Period of the checks while waiting for a roadmap, a readiness answer, a
# scene echo, or an answer (whether a new server appeared) [s].
_POLL_PERIOD = 0.1
# Scene echoes kept while waiting for one.
_ECHOES_KEPT = 100
# Default longest wait for the driver to confirm a cancel [s].
_CANCEL_TIMEOUT = 5.0
# Longest wait for that confirmation once the result of the goal of
# :meth:`PlannerClient.execute` has timed out: a dead or hung driver never
# confirms, and the call must end about when its timeout says [s].
_CANCEL_GRACE = 1.0
# Where the driver serves FollowJointTrajectory, and where a ros2_control
# joint_trajectory_controller of the usual name takes trajectories.
_FOLLOW_ACTION = "rpr3_driver/follow_joint_trajectory"
_TRAJECTORY_TOPIC = "/joint_trajectory_controller/joint_trajectory"
# action_msgs/GoalStatus STATUS_UNKNOWN, the status an action server answers
# a result request with for a goal it does not know (this package does not
# depend on action_msgs itself).
_STATUS_UNKNOWN = 0


class GoalRejectedError(RuntimeError):
    """The driver rejected a trajectory when it arrived (its log says why)."""


class GoalLostError(TimeoutError):
    """The driver no longer knows a goal it accepted: it was restarted during
    the execution (or the goal's result expired), and the result will never
    come.  A :class:`TimeoutError`, as the wait for that result would have
    ended."""


def configuration(joints, mode):
    """A ``rpr3_gwr_msgs/Configuration`` from Python values.

    Parameters
    ----------
    joints : mapping or sequence of float
        The joint positions, by name (``{"rho1": 17.0, ...}``) or in the
        mechanism's order [length unit for a prismatic joint, rad for a
        revolute one].
    mode : float
        The mechanism's mode coordinate, which selects its assembly mode (the
        3-RPR's and 3-RRR's alpha [rad], the five-bar's y [length unit]).

    Returns
    -------
    rpr3_gwr_msgs.msg.Configuration
        The configuration; values are not checked here (the nodes check them
        and answer with an error code).
    """
    if isinstance(joints, Mapping):
        return Configuration(joint_names=list(joints),
                             positions=[float(v) for v in joints.values()], mode=float(mode))
    return Configuration(positions=[float(v) for v in joints], mode=float(mode))


def platform_pose(x, y, alpha=0.0):
    """A platform pose as plan requests take it: a geometry_msgs/PoseStamped
    in frame ``base``.

    Parameters
    ----------
    x, y : float
        The platform's point (B1 of the 3-RPR, the 3-RRR and the 3-PRR; the
        five-bar's end point P) [length unit].
    alpha : float
        The platform's angle [rad]; 0 for the five-bar, whose pose has none.

    Returns
    -------
    geometry_msgs.msg.PoseStamped
    """
    msg = PoseStamped()
    msg.header.frame_id = BASE_FRAME
    msg.pose.position.x, msg.pose.position.y = float(x), float(y)
    msg.pose.orientation.z = math.sin(0.5 * float(alpha))
    msg.pose.orientation.w = math.cos(0.5 * float(alpha))
    return msg


def _joint_limits(limits):
    """JointLimits messages from ``{name: (max_velocity, max_acceleration)}``
    or from messages."""
    if isinstance(limits, Mapping):
        return [JointLimits(joint_name=name, max_velocity=float(velocity),
                            max_acceleration=float(acceleration))
                for name, (velocity, acceleration) in limits.items()]
    return list(limits)


def _as_configuration(value):
    """A Configuration message as is, or ``(joints, mode)`` through
    :func:`configuration`."""
    if isinstance(value, Configuration):
        return value
    joints, mode = value
    return configuration(joints, mode)


def _later(stamp, than):
    """Whether the time ``stamp`` is after ``than`` (None: any stamp)."""
    return than is None or (stamp.sec, stamp.nanosec) > (than.sec, than.nanosec)


def _seconds(stamp):
    return stamp.sec + stamp.nanosec * 1e-9


class PlannerClient(Node):
    """Plans through the suite's planner and executes on its driver.

    The node creates its clients and subscriptions here and waits for
    nothing: :meth:`wait_until_ready` waits for the planner, and every call
    waits at most its ``timeout_sec`` (a ``ValueError`` when it is negative
    or NaN).

    Parameters
    ----------
    node_name : str
        Name of this node.
    planner_name : str
        Name of the planner node, whose ``~/current_scene`` echo
        :meth:`set_scene` waits for.
    **kwargs
        Passed to ``rclpy.node.Node``: ``namespace`` (the suite's nodes run
        in it: a relative name such as ``plan_path`` resolves there),
        ``context`` (a private ``rclpy.context.Context``; the executor the
        client spins takes it too), ``start_parameter_services`` (False
        unless given) and the rest.
    """

    def __init__(self, node_name="planner_client", *, planner_name="planner", **kwargs):
        # The executor waits on every entity of the node at each spin: the
        # parameter services a client never needs would cost every call.
        kwargs.setdefault("start_parameter_services", False)
        super().__init__(node_name, **kwargs)
        self._executor = SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self)
        self._roadmap = None
        # The planner's latest echoes: the one set_scene waits for may come
        # after others (a scene publisher's, another client's).
        self._scene_echoes = collections.deque(maxlen=_ECHOES_KEPT)
        # By request topic: the servers its last answered request was sent to.
        self._answered = {}
        self._roadmap_sub = self.create_subscription(WorkspaceRoadmap, "roadmap",
                                                     self._on_roadmap, LATCHED_QOS)
        self._scene_pub = self.create_publisher(Scene, "scene", LATCHED_QOS)
        self._echo_sub = self.create_subscription(
            Scene, f"{planner_name}/current_scene", self._on_echo, LATCHED_QOS)
        # The service's own history (profiles.SERVICE_QOS): with the default
        # 10, clients calling at a high rate had requests lost.
        self._plan_client = self.create_client(PlanPath, "plan_path", qos_profile=SERVICE_QOS)
        self._modes_client = self.create_client(AssemblyModes, "assembly_modes",
                                                qos_profile=SERVICE_QOS)
        self._ik_client = self.create_client(InverseKinematics, "inverse_kinematics",
                                             qos_profile=SERVICE_QOS)
        self._reset_client = self.create_client(ResetDriver, "reset")
        self._action_client = ActionClient(self, ExecuteTrajectory, "execute_trajectory")
        self._action_name = self.resolve_service_name("execute_trajectory")
        # Made on a first use: by action name, (client, resolved name).
        self._follow_clients = {}
        # By topic.
        self._trajectory_pubs = {}

    @property
    def roadmap(self):
        """rpr3_gwr_msgs.msg.WorkspaceRoadmap or None: the latest roadmap
        received on ``roadmap`` (None before one came)."""
        return self._roadmap

    def _on_roadmap(self, msg):
        self._roadmap = msg

    def _on_echo(self, msg):
        self._scene_echoes.append(msg)

    def wait_until_ready(self, timeout_sec=120.0, *, newer_than=None):
        """Wait until the planner plans on the latest roadmap published.

        Waits for a roadmap on the latched ``roadmap`` topic (the builder's),
        for the ``plan_path`` service, then until the planner answers a
        probe from that roadmap (it answers ``ERROR_NO_ROADMAP`` until its
        kernels are loaded: 10 to 20 s on a first run, when numba compiles
        them).  A probe that goes unanswered is sent again.

        Parameters
        ----------
        timeout_sec : float
            Longest wait for the whole [s].
        newer_than : builtin_interfaces.msg.Time, optional
            Wait for a roadmap stamped after this one (the stamp of
            :attr:`roadmap` before a parameter change that rebuilds it).

        Returns
        -------
        rpr3_gwr_msgs.msg.WorkspaceRoadmap
            The roadmap the planner plans on.

        Raises
        ------
        TimeoutError
            If no such roadmap came, the service did not appear or the
            planner did not take the roadmap within ``timeout_sec``; the
            message says which.
        """
        deadline = _deadline(timeout_sec)
        topic = self._roadmap_sub.topic_name
        after = "" if newer_than is None else f" stamped after {_seconds(newer_than):.9f}"

        def received():
            return self._roadmap is not None and _later(self._roadmap.header.stamp, newer_than)

        # A latched roadmap comes at once; say what is awaited only when not.
        if not self._spin_until(received, min(deadline, time.monotonic() + _POLL_PERIOD)):
            self.get_logger().info(f"waiting for a roadmap{after} on {topic}")
            if not self._spin_until(received, deadline):
                raise TimeoutError(f"no roadmap{after} on {topic} within {timeout_sec:g} s: is "
                                   "the roadmap_builder running, in this ROS_DOMAIN_ID?")
        service = self.resolve_service_name(self._plan_client.srv_name)
        if not self._plan_client.wait_for_service(timeout_sec=_left(deadline)):
            raise TimeoutError(f"no {service} service within {timeout_sec:g} s: is the "
                               "planner running?")
        probe = PlanPath.Request(feasibility_only=True)
        answer = None
        while True:
            try:
                answer = self._call(self._plan_client, probe,
                                    min(_PROBE_TIMEOUT, max(_left(deadline), 1e-3)))
            except TimeoutError:
                answer = None
            latest = self._roadmap.header.stamp
            if (answer is not None and answer.error_code != PlanPath.Response.ERROR_NO_ROADMAP
                    and answer.roadmap_stamp == latest):
                self.get_logger().debug(f"the planner plans on the roadmap stamped "
                                        f"{_seconds(latest):.9f}")
                return self._roadmap
            if time.monotonic() >= deadline:
                got = ("no answer" if answer is None else "no roadmap yet"
                       if answer.error_code == PlanPath.Response.ERROR_NO_ROADMAP
                       else f"the roadmap stamped {_seconds(answer.roadmap_stamp):.9f}")
                raise TimeoutError(
                    f"the planner did not take the roadmap stamped {_seconds(latest):.9f} "
                    f"within {timeout_sec:g} s (its last answer: {got}); a planner with "
                    "another mechanism_file ignores it, see its log")
            self._spin_until(lambda: False, time.monotonic() + _POLL_PERIOD)

    def plan(self, start, goal, *, start_working_mode="", goal_working_mode="",
             mode_tolerance=0.0, skip_smoothing=False, weighted=False, feasibility_only=False,
             max_velocity=0.0, max_acceleration=0.0, joint_limits=(), time_limit=0.0,
             timeout_sec=60.0):
        """Ask the planner for a trajectory from ``start`` to ``goal``.

        Parameters
        ----------
        start, goal : Configuration, (joints, mode) or geometry_msgs.msg.PoseStamped
            The configurations, as rpr3_gwr_msgs messages or as the arguments of
            :func:`configuration`, or the platform's poses
            (:func:`platform_pose`).
        start_working_mode, goal_working_mode : str
            For an end given as a pose, its working mode, one sign per leg
            (``"+-+"``, as :meth:`inverse_kinematics` gives them); "" lets
            the planner take the one joined to the other end with the
            largest margin.
        mode_tolerance : float
            Tolerance on their mode coordinates, 0 for the core's default
            [rad, or length unit].
        skip_smoothing : bool
            Return the validated path through the roadmap's cells as it is;
            by default it is shortcut, pulled taut (on a roadmap of all the
            joints) and rounded, each step kept only if it validates.
        weighted : bool
            Rank global paths by weighted cost instead of fewest gates.
        feasibility_only : bool
            Answer from the roadmap alone: global paths, no trajectory.
        max_velocity, max_acceleration : float
            Joint speed [joint unit/s] and acceleration [joint unit/s^2]
            limits; both 0 take the planner's defaults, one alone is an
            ``ERROR_INVALID_INPUT``.
        joint_limits : mapping or sequence of rpr3_gwr_msgs.msg.JointLimits
            Limits of single joints, ``{name: (max_velocity,
            max_acceleration)}`` or messages; a nonzero value replaces the
            one for all joints [joint unit/s, joint unit/s^2].
        time_limit : float
            Longest planning time, 0 for the planner's
            ``default_time_limit`` [s].
        timeout_sec : float
            Longest wait for the answer, the service's included [s].

        Returns
        -------
        rpr3_gwr_msgs.srv.PlanPath.Response
            The answer: ``success``, ``error_code`` (``ERROR_*``),
            ``error_msg``, ``feasibility`` (``FEASIBILITY_*``), the
            trajectory and the roadmap that answered.  Errors of the request
            come back here, never as exceptions.  ``ERROR_INFEASIBLE`` says
            that no path exists; ``ERROR_UNDECIDED`` that the roadmap cannot
            say, with where (``undecided_patches``) and at which cell
            (``undecided_steps``).

        Raises
        ------
        TimeoutError
            If the service is not there or does not answer within
            ``timeout_sec``.
        """
        request = PlanPath.Request(
            mode_tolerance=float(mode_tolerance), skip_smoothing=bool(skip_smoothing),
            weighted=weighted, feasibility_only=feasibility_only, max_velocity=float(max_velocity),
            max_acceleration=float(max_acceleration), joint_limits=_joint_limits(joint_limits),
            time_limit=float(time_limit))
        for end, given, mode in (("start", start, start_working_mode),
                                 ("goal", goal, goal_working_mode)):
            # A working mode of an end that is no pose is the planner's to refuse.
            setattr(request, f"{end}_working_mode", mode)
            if isinstance(given, PoseStamped):
                setattr(request, f"{end}_is_pose", True)
                setattr(request, f"{end}_pose", given)
            else:
                setattr(request, end, _as_configuration(given))
        return self._call(self._plan_client, request, timeout_sec)

    def inverse_kinematics(self, pose, timeout_sec=60.0):
        """Ask the planner for every working mode of a platform pose.

        Parameters
        ----------
        pose : geometry_msgs.msg.PoseStamped
            The platform's pose in frame ``base`` (:func:`platform_pose`).
        timeout_sec : float
            Longest wait for the answer, the service's included [s].

        Returns
        -------
        rpr3_gwr_msgs.srv.InverseKinematics.Response
            ``success``, ``error_code``, ``error_msg`` and the ``modes``
            (``rpr3_gwr_msgs/WorkingMode``: its signs, configuration, aspect,
            margin, and where it lies on the roadmap).

        Raises
        ------
        TimeoutError
            If the service is not there or does not answer within
            ``timeout_sec``.
        """
        return self._call(self._ik_client, InverseKinematics.Request(pose=pose), timeout_sec)

    def assembly_modes(self, joints, start_mode=None, *, mode_tolerance=0.0,
                       timeout_sec=60.0):
        """Ask the planner for every assembly mode of some joints on its
        roadmap: where each lies and, from a start mode, which a
        singularity-free path reaches (plan to it with :meth:`plan`).

        Parameters
        ----------
        joints : mapping or sequence of float
            The joint positions, by name or in the mechanism's order [joint
            unit].
        start_mode : float, optional
            The mode coordinate of the mode to start from.
        mode_tolerance : float
            Tolerance on it, 0 for the core's default [rad, or length unit].
        timeout_sec : float
            Longest wait for the answer, the service's included [s].

        Returns
        -------
        rpr3_gwr_msgs.srv.AssemblyModes.Response
            ``success``, ``error_code`` (``ERROR_*``), ``error_msg`` and the
            ``modes`` (``rpr3_gwr_msgs/AssemblyMode``: its configuration,
            pose, aspect, patch, region and ``feasibility``).

        Raises
        ------
        TimeoutError
            If the service is not there or does not answer within
            ``timeout_sec``.
        """
        request = AssemblyModes.Request(
            joints=configuration(joints, 0.0 if start_mode is None else start_mode),
            with_start=start_mode is not None, mode_tolerance=float(mode_tolerance))
        return self._call(self._modes_client, request, timeout_sec)

    def reset_driver(self, configuration, timeout_sec=10.0):
        """Put the driver's simulated mechanism at ``configuration``.

        Parameters
        ----------
        configuration : rpr3_gwr_msgs.msg.Configuration or (joints, mode)
            Where to put it, as a message or as the arguments of
            :func:`configuration`.
        timeout_sec : float
            Longest wait for the answer, the service's included [s].

        Returns
        -------
        rpr3_gwr_msgs.srv.ResetDriver.Response
            The answer: ``success``, ``error_code`` (``ERROR_*``),
            ``error_msg`` and the platform pose taken.

        Raises
        ------
        TimeoutError
            If the driver's ``reset`` service is not there or does not answer
            within ``timeout_sec``.
        """
        request = ResetDriver.Request(configuration=_as_configuration(configuration))
        return self._call(self._reset_client, request, timeout_sec)

    def send_goal(self, trajectory, feedback_callback=None, timeout_sec=10.0):
        """Send a trajectory to the driver's ``execute_trajectory`` action.

        Parameters
        ----------
        trajectory : trajectory_msgs.msg.JointTrajectory
            The trajectory; its first point must be the driver's current
            joints.
        feedback_callback : callable, optional
            Called with each ``ExecuteTrajectory.Impl.FeedbackMessage``
            (its ``feedback``: progress, margin, time and pose) while this
            client spins, in the thread of the call spinning it.
        timeout_sec : float
            Longest wait for the action server and its acceptance [s].

        Returns
        -------
        rclpy.action.client.ClientGoalHandle
            The goal's handle, ``accepted`` or not (the driver logs why it
            rejects one); wait for its result with :meth:`get_result`.

        Raises
        ------
        TimeoutError
            If the action server is not there or does not answer within
            ``timeout_sec``.
        """
        return self._send_goal(self._action_client, self._action_name,
                               ExecuteTrajectory.Goal(trajectory=trajectory), feedback_callback,
                               timeout_sec, hint=": is the driver running?")

    def get_result(self, handle, timeout_sec=120.0):
        """Wait for the result of an accepted goal.

        Parameters
        ----------
        handle : rclpy.action.client.ClientGoalHandle
            The handle :meth:`send_goal` returned.
        timeout_sec : float
            Longest wait for the result [s].

        Returns
        -------
        rpr3_gwr_msgs.action.ExecuteTrajectory.Impl.GetResultService.Response
            Its ``status`` (an ``action_msgs.msg.GoalStatus`` code) and its
            ``result`` (``error_code``, ``error_msg``, final pose and
            smallest margin met).

        Raises
        ------
        GoalLostError
            If the driver does not know the goal: it was restarted since it
            accepted the goal.
        TimeoutError
            If the result does not come within ``timeout_sec``.
        """
        return self._get_result(self._action_client, self._action_name, handle, timeout_sec)

    def cancel(self, handle, timeout_sec=_CANCEL_TIMEOUT):
        """Cancel a goal.

        Parameters
        ----------
        handle : rclpy.action.client.ClientGoalHandle
            The goal's handle.
        timeout_sec : float
            Longest wait for the driver's answer [s].

        Returns
        -------
        action_msgs.srv.CancelGoal.Response
            The driver's answer; the goal's result then says ``CANCELED``.

        Raises
        ------
        TimeoutError
            If the driver does not answer within ``timeout_sec``.
        """
        return self._cancel(self._action_client, self._action_name, handle, timeout_sec)

    def execute(self, trajectory, feedback_callback=None, timeout_sec=120.0):
        """Execute a trajectory on the driver and wait for its end.

        Parameters
        ----------
        trajectory : trajectory_msgs.msg.JointTrajectory
            The trajectory (a plan's ``trajectory``); its first point must be
            the driver's current joints (see :meth:`reset_driver`).
        feedback_callback : callable, optional
            Called with each ``ExecuteTrajectory.Impl.FeedbackMessage``, as
            in :meth:`send_goal`.
        timeout_sec : float
            Longest wait for the acceptance and the end of the execution,
            which lasts the trajectory's duration divided by the driver's
            ``time_scale`` [s].

        Returns
        -------
        rpr3_gwr_msgs.action.ExecuteTrajectory.Impl.GetResultService.Response
            Its ``status`` (``action_msgs.msg.GoalStatus``: ``STATUS_SUCCEEDED``
            or ``STATUS_ABORTED``) and ``result`` (``error_code``: one of
            ``ExecuteTrajectory.Result``'s codes, ``error_msg`` saying why it
            ended early, the final pose and the smallest margin met).

        Raises
        ------
        GoalRejectedError
            If the driver rejects the trajectory when it arrives.
        GoalLostError
            If the driver was restarted during the execution.
        TimeoutError
            If it is not accepted or has not ended within ``timeout_sec``;
            the goal is then canceled, the confirmation awaited a second at
            most.
        """
        return self._execute(self._action_client, self._action_name,
                             ExecuteTrajectory.Goal(trajectory=trajectory), feedback_callback,
                             timeout_sec, hint=": is the driver running?")

    def follow_joint_trajectory(self, trajectory, action_name=_FOLLOW_ACTION, *,
                                path_tolerance=(), goal_tolerance=(), goal_time_tolerance=0.0,
                                feedback_callback=None, timeout_sec=120.0):
        """Execute a trajectory on any ``control_msgs/action/FollowJointTrajectory``
        server (a ros2_control joint_trajectory_controller's, MoveIt's
        execution's, the suite's driver's) and wait for its end, the
        server's feedback relayed.

        Parameters
        ----------
        trajectory : trajectory_msgs.msg.JointTrajectory
            The trajectory (a plan's ``trajectory``).
        action_name : str
            The server's action, relative names in this client's namespace:
            ``/joint_trajectory_controller/follow_joint_trajectory`` for a
            controller of that name; by default the driver's.
        path_tolerance, goal_tolerance : sequence of control_msgs.msg.JointTolerance
            Passed on in the goal.
        goal_time_tolerance : float
            Passed on in the goal [s]; 0 for the server's default (an
            ``InvalidInputError`` when negative or not finite).
        feedback_callback : callable, optional
            Called with each ``FollowJointTrajectory.Impl.FeedbackMessage``
            (its ``feedback``: desired, actual and error points) while this
            client spins, in the thread of the call spinning it.
        timeout_sec : float
            Longest wait for the acceptance and the end of the execution [s].

        Returns
        -------
        control_msgs.action.FollowJointTrajectory.Impl.GetResultService.Response
            Its ``status`` (``action_msgs.msg.GoalStatus``) and ``result``
            (``error_code``: ``SUCCESSFUL``, ``PATH_TOLERANCE_VIOLATED``, ...,
            and ``error_string``).

        Raises
        ------
        GoalRejectedError
            If the server rejects the goal (joint_trajectory_controller logs
            why).
        GoalLostError
            If the server was restarted during the execution.
        TimeoutError
            If it is not accepted or has not ended within ``timeout_sec``;
            the goal is then canceled, the confirmation awaited a second at
            most.
        """
        client, name = self._follow_client(action_name)
        goal = FollowJointTrajectory.Goal(
            trajectory=trajectory, path_tolerance=list(path_tolerance),
            goal_tolerance=list(goal_tolerance),
            goal_time_tolerance=duration_msg(goal_time_tolerance))
        return self._execute(client, name, goal, feedback_callback, timeout_sec)

    def publish_trajectory(self, trajectory, topic=_TRAJECTORY_TOPIC, timeout_sec=10.0):
        """Publish a trajectory on a controller's ``~/joint_trajectory`` topic
        (trajectory_msgs only: no result, no feedback), once a subscriber is
        there.

        Parameters
        ----------
        trajectory : trajectory_msgs.msg.JointTrajectory
        topic : str
            The topic, relative names in this client's namespace; by default
            ``/joint_trajectory_controller/joint_trajectory``.
        timeout_sec : float
            Longest wait for a subscriber [s].

        Returns
        -------
        int
            The subscribers it was published to.

        Raises
        ------
        TimeoutError
            If no subscriber came within ``timeout_sec``.
        """
        deadline = _deadline(timeout_sec)
        publisher = self._trajectory_pubs.get(topic)
        if publisher is None:
            publisher = self._trajectory_pubs[topic] = self.create_publisher(
                JointTrajectory, topic, 10)
        if not self._spin_until(lambda: publisher.get_subscription_count() > 0, deadline):
            raise TimeoutError(f"no subscriber of {publisher.topic_name} within "
                               f"{timeout_sec:.3g} s")
        publisher.publish(trajectory)
        return publisher.get_subscription_count()

    def _follow_client(self, action_name):
        """The action client of a FollowJointTrajectory server, made once, and
        its resolved name."""
        if action_name not in self._follow_clients:
            self._follow_clients[action_name] = (
                ActionClient(self, FollowJointTrajectory, action_name),
                self.resolve_service_name(action_name))
        return self._follow_clients[action_name]

    def _send_goal(self, client, name, goal, feedback_callback, timeout_sec, hint=""):
        # One goal id for every copy sent: the server rejects a copy of a goal
        # it has (rclpy's ActionServer), so a copy never executes it twice.
        goal_id = UUID(uuid=list(uuid.uuid4().bytes))
        return self._request(
            lambda: client.send_goal_async(goal, feedback_callback=feedback_callback,
                                           goal_uuid=goal_id),
            f"{name}/_action/send_goal", client.server_is_ready, timeout_sec,
            absent=f"no {name} action server", hint=hint,
            what=f"the acceptance of a goal on {name}")

    def _get_result(self, client, name, handle, timeout_sec):
        # rclpy drops a goal's feedback callback with its result requests:
        # kept, a timed out wait leaves the feedback coming.
        response = self._request(
            handle.get_result_async, f"{name}/_action/get_result", client.server_is_ready,
            timeout_sec, absent=f"no {name} action server", what="the goal's result",
            keep_unanswered=True)
        if response.status == _STATUS_UNKNOWN:
            raise GoalLostError(f"the server of {name} does not know the goal: it was "
                                "restarted during the execution")
        return response

    def _cancel(self, client, name, handle, timeout_sec):
        return self._request(
            handle.cancel_goal_async, f"{name}/_action/cancel_goal", client.server_is_ready,
            timeout_sec, absent=f"no {name} action server", what="answer to a cancel")

    def _execute(self, client, name, goal, feedback_callback, timeout_sec, hint=""):
        """Send ``goal`` and wait for its result (see :meth:`execute`)."""
        deadline = _deadline(timeout_sec)
        handle = self._send_goal(client, name, goal, feedback_callback, timeout_sec, hint)
        if not handle.accepted:
            raise GoalRejectedError(f"the server of {name} rejected the goal; its log says "
                                    "why")
        try:
            return self._get_result(client, name, handle, _left(deadline))
        except GoalLostError:
            raise
        except TimeoutError:
            # A dead or hung server never confirms: the timeout is reported
            # without waiting longer for it, and the cancel's own timeout
            # must not replace it.
            try:
                self._cancel(client, name, handle, _CANCEL_GRACE)
            except TimeoutError as unconfirmed:
                self.get_logger().warning(f"the goal whose result timed out may still run: "
                                          f"{unconfirmed}")
            raise

    def set_scene(self, scene, *, wait=True, timeout_sec=30.0):
        """Publish a scene on the latched ``scene`` topic.

        Parameters
        ----------
        scene : rpr3_gwr_msgs.msg.Scene
            The scene; one with a zero header stamp is published stamped now
            (a copy), so that its echo can be told from the previous one's.
        wait : bool
            Wait until the planner echoes it on its ``~/current_scene``,
            that is plans in it (the planner takes a scene once it has a
            roadmap: a second on the paper's slice, ten on the full 3-DOF
            roadmap).
        timeout_sec : float
            Longest wait for the echo [s].

        Returns
        -------
        rpr3_gwr_msgs.msg.Scene
            The scene published.

        Raises
        ------
        TimeoutError
            If ``wait`` and the planner has not echoed it within
            ``timeout_sec`` (it refuses a scene it cannot read or that does
            not fit its roadmap, and logs why).
        """
        if scene.header.stamp == Time():
            scene = copy.copy(scene)
            scene.header = Header(stamp=self.get_clock().now().to_msg(),
                                  frame_id=scene.header.frame_id)
        stamp = scene.header.stamp
        self._scene_pub.publish(scene)
        if wait and not self._spin_until(
                lambda: any(e.header.stamp == stamp for e in self._scene_echoes),
                _deadline(timeout_sec)):
            raise TimeoutError(f"the planner did not echo the scene on "
                               f"{self._echo_sub.topic_name} within {timeout_sec:g} s: it "
                               "refused it (its log says why) or has no roadmap yet")
        return scene

    def wait_for(self, future, timeout_sec, what="an answer"):
        """Spin this client until ``future`` is done.

        Parameters
        ----------
        future : rclpy.task.Future
            A future of one of this node's clients.
        timeout_sec : float
            Longest wait [s].
        what : str
            What the future brings, for the error message.

        Returns
        -------
        object
            The future's result.

        Raises
        ------
        TimeoutError
            If it is not done within ``timeout_sec``.
        """
        self._executor.spin_until_future_complete(future,
                                                  timeout_sec=_left(_deadline(timeout_sec)))
        if not future.done():
            raise TimeoutError(f"no {what} within {timeout_sec:g} s")
        return future.result()

    def destroy_node(self):
        """Shut the private executor down, then destroy the action client
        and the node."""
        self._executor.shutdown()
        self._action_client.destroy()
        super().destroy_node()

    def _call(self, client, request, timeout_sec):
        """Call a service within ``timeout_sec``, waiting for it too (see
        :meth:`_request`)."""
        name = self.resolve_service_name(client.srv_name)
        return self._request(lambda: client.call_async(request), name, client.service_is_ready,
                             timeout_sec, absent=f"no {name} service",
                             what=f"answer from {name}")

    def _request(self, send, service, ready, timeout_sec, *, absent, what, hint="",
                 keep_unanswered=False):
        """Send a request once a server is there and spin until it is
        answered, sending it again to any server that may have missed it.

        Parameters
        ----------
        send : callable
            Sends the request; returns its ``rclpy.task.Future``.
        service : str
            The fully qualified name of the service that takes it (an
            action's ``<name>/_action/get_result`` for instance).
        ready : callable
            Whether a server is there (``Client.service_is_ready``,
            ``ActionClient.server_is_ready``).
        timeout_sec : float
            Longest wait for the server and the answer [s].
        absent, what, hint : str
            The error messages: "``absent`` within ... s``hint``" when no
            server came, "no ``what`` within ... s" when none answered.
        keep_unanswered : bool
            Leave the requests pending when none was answered, instead of
            dropping them.

        Returns
        -------
        object
            The first answer to one of the copies sent; the others are
            dropped.

        Raises
        ------
        TimeoutError
            If no server came or none answered within ``timeout_sec``.
        """
        deadline = _deadline(timeout_sec)
        if not self._spin_until(ready, deadline):
            raise TimeoutError(f"{absent} within {timeout_sec:.3g} s{hint}")
        # The graph knows a service's servers as the readers of its request
        # topic, which the DDS rmws name so.
        topic = f"rq{service}Request"
        futures = []
        try:
            while True:
                servers = self._servers(topic)
                futures.append(send())
                sent = time.monotonic()
                answered = self._answered.get(topic)
                resend = (sent + _FIRST_ANSWER_TIMEOUT
                          if answered is None or not servers <= answered else deadline)
                while True:
                    done = next((f for f in futures if f.done()), None)
                    if done is not None:
                        self._answered[topic] = servers
                        return done.result()
                    left = _left(deadline)
                    if left <= 0.0:
                        raise TimeoutError(f"no {what} within {timeout_sec:.3g} s")
                    self._executor.spin_once(timeout_sec=min(left, _POLL_PERIOD))
                    # A server discovered after the request was sent was
                    # matched after it too and never got it (a restarted
                    # driver); none that is not ready yet could take it.
                    if ((self._servers(topic) - servers or time.monotonic() >= resend)
                            and ready()):
                        self.get_logger().debug(
                            f"sending again, {time.monotonic() - sent:.3f} s after it, a "
                            f"request to {service} ({len(futures)} sent)")
                        break
        finally:
            if not keep_unanswered or any(f.done() for f in futures):
                for future in futures:
                    future.cancel()

    def _servers(self, topic):
        """The endpoint ids of the readers of ``topic`` (a DDS topic name) in
        the ROS graph: the servers of a service by its request topic."""
        return frozenset(bytes(info.endpoint_gid) for info in
                         self.get_subscriptions_info_by_topic(topic, no_mangle=True))

    def _spin_until(self, condition, deadline):
        """Spin until ``condition()`` holds or the monotonic ``deadline``
        passes; whether it holds."""
        while not condition():
            left = _left(deadline)
            if left <= 0.0:
                return False
            self._executor.spin_once(timeout_sec=min(left, _POLL_PERIOD))
        return True


def _deadline(timeout_sec):
    """The monotonic time ``timeout_sec`` from now.

    Raises
    ------
    ValueError
        If ``timeout_sec`` is not a number of seconds: negative or NaN
        (infinite waits for ever).
    """
    if isinstance(timeout_sec, bool) or not isinstance(timeout_sec, numbers.Real) \
            or not timeout_sec >= 0.0:
        raise ValueError(f"timeout_sec is a non-negative number of seconds, got {timeout_sec!r}")
    return time.monotonic() + timeout_sec


def _left(deadline):
    """Seconds until the monotonic ``deadline``, 0 once passed."""
    return max(deadline - time.monotonic(), 0.0)

