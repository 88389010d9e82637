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
their own), and do not add the node to another executor.  The first request
of each of its service clients is sent again when unanswered for 10 s: under
load a server can answer it before it has matched the client's response
reader, and that answer is lost.
"""

import collections
import copy
import time
from collections.abc import Mapping

from builtin_interfaces.msg import Time
from rclpy.action import ActionClient
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rpr3_gwr_msgs.action import ExecuteTrajectory
from rpr3_gwr_msgs.msg import Configuration, Scene, WorkspaceRoadmap
from rpr3_gwr_msgs.srv import AssemblyModes, PlanPath, ResetDriver
from std_msgs.msg import Header

from .profiles import LATCHED_QOS, SERVICE_QOS

__all__ = ["PlannerClient", "GoalRejectedError", "configuration"]

# Longest wait for one readiness probe, sent again if unanswered [s].
_PROBE_TIMEOUT = 2.0
# Longest wait for the answer to a service client's first request before it
# is sent again: under load a server may answer before it has matched the
# client's response reader (rmw_fastrtps waits 100 ms for it), and that
# answer is lost; later requests find the match made [s].
_FIRST_ANSWER_TIMEOUT = 10.0
# Period of the checks while waiting for a roadmap, a readiness answer or a
# scene echo [s].
_POLL_PERIOD = 0.1
# Scene echoes kept while waiting for one.
_ECHOES_KEPT = 100
# Longest wait for the driver to confirm the cancel of a goal whose result
# timed out [s].
_CANCEL_TIMEOUT = 5.0


class GoalRejectedError(RuntimeError):
    """The driver rejected a trajectory when it arrived (its log says why)."""


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
    waits at most its ``timeout_sec``.

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
        # The service clients that have had an answer.
        self._answered = set()
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
        self._reset_client = self.create_client(ResetDriver, "reset")
        self._action_client = ActionClient(self, ExecuteTrajectory, "execute_trajectory")
        self._action_name = self.resolve_service_name("execute_trajectory")

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
        deadline = time.monotonic() + timeout_sec
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

    def plan(self, start, goal, *, mode_tolerance=0.0, smooth=True, weighted=False,
             feasibility_only=False, max_velocity=0.0, max_acceleration=0.0, time_limit=0.0,
             timeout_sec=60.0):
        """Ask the planner for a trajectory from ``start`` to ``goal``.

        Parameters
        ----------
        start, goal : rpr3_gwr_msgs.msg.Configuration or (joints, mode)
            The configurations, as messages or as the arguments of
            :func:`configuration`.
        mode_tolerance : float
            Tolerance on their mode coordinates, 0 for the core's default
            [rad, or length unit].
        smooth : bool
            Shortcut and round the path (kept only if it validates).
        weighted : bool
            Rank global paths by weighted cost instead of fewest gates.
        feasibility_only : bool
            Answer from the roadmap alone: global paths, no trajectory.
        max_velocity, max_acceleration : float
            Joint speed [joint unit/s] and acceleration [joint unit/s^2]
            limits; both 0 take the planner's defaults, one alone is an
            ``ERROR_INVALID_INPUT``.
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
            come back here, never as exceptions.

        Raises
        ------
        TimeoutError
            If the service is not there or does not answer within
            ``timeout_sec``.
        """
        request = PlanPath.Request(
            start=_as_configuration(start), goal=_as_configuration(goal),
            mode_tolerance=float(mode_tolerance), smooth=smooth, weighted=weighted,
            feasibility_only=feasibility_only, max_velocity=float(max_velocity),
            max_acceleration=float(max_acceleration), time_limit=float(time_limit))
        return self._call(self._plan_client, request, timeout_sec)

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
        deadline = time.monotonic() + timeout_sec
        name = self._action_name
        if not self._action_client.wait_for_server(timeout_sec=timeout_sec):
            raise TimeoutError(f"no {name} action server within {timeout_sec:g} s: is the "
                               "driver running?")
        future = self._action_client.send_goal_async(
            ExecuteTrajectory.Goal(trajectory=trajectory), feedback_callback=feedback_callback)
        return self.wait_for(future, _left(deadline), what=f"the acceptance of a goal on {name}")

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
        TimeoutError
            If the result does not come within ``timeout_sec``.
        """
        return self.wait_for(handle.get_result_async(), timeout_sec, what="the goal's result")

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
        return self.wait_for(handle.cancel_goal_async(), timeout_sec, what="a cancel")

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
        TimeoutError
            If it is not accepted or has not ended within ``timeout_sec``;
            the goal is then canceled.
        """
        deadline = time.monotonic() + timeout_sec
        handle = self.send_goal(trajectory, feedback_callback, timeout_sec)
        if not handle.accepted:
            raise GoalRejectedError(f"the driver rejected the trajectory on "
                                    f"{self._action_name}; its log says why")
        try:
            return self.get_result(handle, _left(deadline))
        except TimeoutError:
            self.cancel(handle)
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
                time.monotonic() + timeout_sec):
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
        self._executor.spin_until_future_complete(future, timeout_sec=max(timeout_sec, 0.0))
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
        """Call a service within ``timeout_sec``, waiting for it too; the
        client's first request is sent again if unanswered, and a request
        unanswered in time is dropped."""
        deadline = time.monotonic() + timeout_sec
        name = self.resolve_service_name(client.srv_name)
        if not client.wait_for_service(timeout_sec=timeout_sec):
            raise TimeoutError(f"no {name} service within {timeout_sec:g} s")
        while True:
            attempt = _left(deadline)
            if client not in self._answered:
                attempt = min(attempt, _FIRST_ANSWER_TIMEOUT)
            future = client.call_async(request)
            self._executor.spin_until_future_complete(future, timeout_sec=attempt)
            if future.done():
                self._answered.add(client)
                return future.result()
            client.remove_pending_request(future)
            if _left(deadline) <= 0.0:
                raise TimeoutError(f"no answer from {name} within {timeout_sec:g} s")

    def _spin_until(self, condition, deadline):
        """Spin until ``condition()`` holds or the monotonic ``deadline``
        passes; whether it holds."""
        while not condition():
            left = _left(deadline)
            if left <= 0.0:
                return False
            self._executor.spin_once(timeout_sec=min(left, _POLL_PERIOD))
        return True


def _left(deadline):
    """Seconds until the monotonic ``deadline``, 0 once passed."""
    return max(deadline - time.monotonic(), 0.0)

