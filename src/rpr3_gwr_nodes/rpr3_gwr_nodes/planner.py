"""planner: serves plan requests on a roadmap received as messages.

Subscribes to ``field`` and ``roadmap`` (reliable, transient local) and builds
its planning state from them, computing nothing that the builder computed: a
roadmap from another builder or from a bag serves as well.  A new pair of
messages replaces the state atomically once the new planner is warmed up
(every compiled kernel a plan uses loaded, or compiled on a first run);
requests in flight finish on the state they started with.  Until the first
roadmap is warmed up, requests are answered ``ERROR_NO_ROADMAP``: a client
knows the planner is ready when a request gets another answer (the node logs
"planning on a new roadmap" then).

Serves ``plan_path`` (rpr3_gwr_msgs/PlanPath), and ``assembly_modes``
(rpr3_gwr_msgs/AssemblyModes: the modes of given joints, located, and which a
path reaches from a start mode), from a reentrant callback group
on a multithreaded executor, so several requests run at once.  Once ready,
the node builds the roadmap's planning index (the gate distances of its
``clearance``: seconds on the full 3-DOF roadmap, during which requests are
planned without it), writes both to a folder in the roadmap cache and starts
``plan_workers`` processes that map them, as the node then does too
(:mod:`.plan_workers`).  Requests are planned in the workers, or in the
node's own process until they are ready, with ``plan_workers`` 0, when a
worker dies or hangs for the request it had, and for good once every worker
did.  Every step of a
request, the conversion of the request and of the answer to messages
included, runs inside the error mapping: an error of the core becomes the
response's error code and message, anything else ``ERROR_INTERNAL``, and the
node never dies on a request.  The mechanism comes with the roadmap
messages: requests give its joints (by name, or in its order) and mode
coordinate, and trajectories carry its joint names.  With ``mechanism_file``
(read-only, as the builder's) roadmaps of another mechanism are ignored
and scenes are checked with the file's ``bodies`` (widths and layers: legs
in one layer may not cross); empty (the default), any mechanism is planned
on, each leg in a layer of its own.  Each response names the
roadmap that answered it (its stamp and the joints it fixes).  Each planned
trajectory is also published on ``planned_trajectory``
(trajectory_msgs/JointTrajectory) and, with the plan's start and goal, on
``planned_path`` (rpr3_gwr_msgs/PlannedPath) for recording, and drawn on
``planned_path_markers`` (visualization_msgs/MarkerArray: the platform's
track in ``base``, the joint path in ``joint_space``).

Plans keep the mechanism's bodies off the obstacles of the latest scene
received on ``scene`` (rpr3_gwr_msgs/Scene, reliable, transient local) and
within its limits.  A new scene is applied to the roadmap
(``Planner.apply_scene``: a second for the paper's slice the first time,
then tenths; ten seconds and then a few for the full 3-DOF roadmap) in the
updates' callback group while requests go on with the previous scene on the
other executor threads; the new one replaces it atomically with the
planning state, and a new roadmap takes the current scene before it is
planned on.  A scene that cannot be read or that does not fit the roadmap
(a limit naming a joint the mechanism lacks) is refused with an error in
the log and the previous one stays; one without obstacles and joint ranges
means no scene.  The scene planned with is echoed on ``~/current_scene``
(same QoS; its header stamp is the received one, empty when planning
without a scene).  A start or goal that collides answers
``ERROR_IN_COLLISION``, ends the roadmap joins and the scene does not (or
clear ends whose grid cell the scene leaves no way out)
``ERROR_INFEASIBLE`` with ``FEASIBILITY_BLOCKED``.  Ends in two components
of one aspect with thin regions of that aspect left (the roadmap cannot say
that no path exists) answer ``ERROR_UNDECIDED`` with
``FEASIBILITY_UNDECIDED``, the thin regions and the grid's finest steps; a
builder with a larger ``thin_refinement`` asks at a finer cell.  The plan
workers apply each scene too, and plan in it once all of them have it;
meanwhile its requests are planned in the node's process.
"""

import itertools
import math
import os
import threading
import time

from numba.core import event as numba_event
import numpy as np
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rpr3_gwr_core.exceptions import (GWRError, InfeasiblePathError, InvalidInputError,
                                      PlanningTimeoutError, UndecidedError)
from rpr3_gwr_core.io.cache import find_cached_planning
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.io.paths import default_cache_dir
from rpr3_gwr_core.planning import (DEFAULT_CLEARANCE, CellSearchIndex, PlanOptions, Planner,
                                    PlanStatus, PoseEnd, Retries, Termination, assembly_modes,
                                    build_cell_search_index, resolve_ends, working_modes)
from rpr3_gwr_msgs.msg import (AssemblyMode, Configuration, GlobalPath, NSolutionField,
                               PlannedPath, Scene, WorkspaceRoadmap)
from rpr3_gwr_msgs.msg import WorkingMode as WorkingModeMsg
from rpr3_gwr_msgs.srv import AssemblyModes, InverseKinematics, PlanPath
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import MarkerArray

from .conversions import (MAX_DURATION, configuration_from_msg, duration_msg, grid_from_msg,
                          is_empty_scene, mechanism_from_msg, pose_from_msg, pose_msg,
                          roadmap_from_msgs, roadmap_matches_msgs, scene_from_msg,
                          scene_msg_from_bytes, scene_to_msg)
from .core_threads import core_threads
from .mechanism_parameters import kept_scene
from .memory import release_free_memory, use_one_arena
from .plan_workers import PlanWorkers, WorkerFailed, WorkersClosed
from .profiles import BASE_FRAME, LATCHED_QOS, SERVICE_QOS
from .receipt import ReceiptExecutor, request_age
from .spin import run
from .visualization import path_markers

__all__ = ["PlannerNode", "ERROR_CODES", "FEASIBILITY", "plan_to_trajectory", "received_roadmap",
           "main", "USAGE"]

USAGE = """\
usage: ros2 run rpr3_gwr_nodes planner [-h] [--ros-args ...]

Plans singularity-free joint trajectories on the roadmap it receives (it
computes none): answers ERROR_NO_ROADMAP until the first one is loaded.

Subscribes  field, roadmap (the builder's, latched), scene (latched)
Serves      plan_path (rpr3_gwr_msgs/srv/PlanPath: ends as joints or as
            platform poses), assembly_modes (rpr3_gwr_msgs/srv/AssemblyModes),
            inverse_kinematics (rpr3_gwr_msgs/srv/InverseKinematics)
Publishes   planned_trajectory, planned_path (with the plan's ends),
            planned_path_markers, ~/current_scene
Parameters  clearance (0.02), default_max_velocity (1.0),
            default_max_acceleration (2.0), joint_limits.<joint>.max_velocity
            and .max_acceleration (0: the defaults), default_time_limit (10.0 s),
            plan_workers (one per core, read-only), mechanism_file ('' takes
            any roadmap's mechanism, read-only), promising_nodes,
            retry_global_paths, retry_repairs, retry_split_shortcuts,
            detour_weight, detour_inflation (read-only)
Example     ros2 run rpr3_gwr_nodes planner --ros-args -p plan_workers:=0 -p clearance:=0.05
"""

ERROR_CODES = {
    "INVALID_INPUT": PlanPath.Response.ERROR_INVALID_INPUT,
    "OUT_OF_GRID": PlanPath.Response.ERROR_OUT_OF_GRID,
    "FIXED_JOINT_MISMATCH": PlanPath.Response.ERROR_FIXED_JOINT_MISMATCH,
    "NO_SOLUTION": PlanPath.Response.ERROR_NO_SOLUTION,
    "NO_ASSEMBLY_MODE": PlanPath.Response.ERROR_NO_ASSEMBLY_MODE,
    "SINGULAR": PlanPath.Response.ERROR_SINGULAR,
    "INFEASIBLE": PlanPath.Response.ERROR_INFEASIBLE,
    "VALIDATION_FAILED": PlanPath.Response.ERROR_VALIDATION_FAILED,
    "TIMEOUT": PlanPath.Response.ERROR_TIMEOUT,
    "IN_COLLISION": PlanPath.Response.ERROR_IN_COLLISION,
    "UNDECIDED": PlanPath.Response.ERROR_UNDECIDED,
}
FEASIBILITY = {
    "same_patch": PlanPath.Response.FEASIBILITY_SAME_PATCH,
    "connected": PlanPath.Response.FEASIBILITY_CONNECTED,
    "other_aspect": PlanPath.Response.FEASIBILITY_OTHER_ASPECT,
    "unreachable": PlanPath.Response.FEASIBILITY_UNREACHABLE,
    "undecided": PlanPath.Response.FEASIBILITY_UNDECIDED,
    # In a scene: one part of a patch (part of the same patch), and cut apart
    # by the scene.
    "same_part": PlanPath.Response.FEASIBILITY_SAME_PATCH,
    "blocked": PlanPath.Response.FEASIBILITY_BLOCKED,
}
# How an undecided answer is asked at a finer cell: by the builder, whose
# roadmap this planner only receives.
_FINER = ("a roadmap builder with a larger thin_refinement parameter (finer cells where "
          "thin regions are; default 4, 0 for the grid alone) asks at a finer cell")
PLAN_STATUS = {
    PlanStatus.EXACT_SOLUTION: PlanPath.Response.PLAN_STATUS_EXACT_SOLUTION,
    PlanStatus.APPROXIMATE_SOLUTION: PlanPath.Response.PLAN_STATUS_APPROXIMATE_SOLUTION,
}


def received_roadmap(field_msg, roadmap_msg, cache_dir=None):
    """The roadmap two messages describe and a planning index of it.

    The roadmap cache's entry of it when the cache (``cache_dir``, by
    default the user's) holds one, value for value: a builder on this
    machine loaded or built it there, and its entry is mapped with the full
    index, gate distances included.  Else the messages decoded, with an
    index of the node graph only, which plans at once (gate distances then
    come with the full index).

    Returns
    -------
    roadmap : Roadmap
    index : CellSearchIndex
    cached : bool
        Whether they are the cache's.

    Raises
    ------
    GWRError
        If the messages are inconsistent or do not belong together.
    """
    cached = None
    try:
        mechanism, grid = mechanism_from_msg(field_msg.mechanism), grid_from_msg(field_msg.grid)
    except GWRError:
        pass  # roadmap_from_msgs says what is wrong
    else:
        with core_threads() as pool:
            cached = find_cached_planning(mechanism, grid, cache_dir, workers=pool.map)
    if cached is not None and roadmap_matches_msgs(cached[0], field_msg, roadmap_msg):
        return (*cached, True)
    received = roadmap_from_msgs(field_msg, roadmap_msg)
    return received, CellSearchIndex.build(received), False


def plan_to_trajectory(plan, joint_names, header):
    """A core plan's joint path as a JointTrajectory of the mechanism's
    ``joint_names`` with times, velocities and accelerations.

    Raises
    ------
    InvalidInputError
        If the plan's times do not fit builtin_interfaces/Duration (limits
        far too low); they are whole nanoseconds (the core's timing).
    """
    times = np.asarray(plan.times, dtype=float)
    if times[-1] >= MAX_DURATION:
        raise InvalidInputError(
            f"the limits give a trajectory of {times[-1]:.3g} s, beyond the "
            f"{MAX_DURATION} s that builtin_interfaces/Duration holds: raise them")
    trajectory = JointTrajectory(header=header, joint_names=list(joint_names))
    for k, joints in enumerate(plan.joints):
        trajectory.points.append(JointTrajectoryPoint(
            positions=[float(v) for v in joints],
            velocities=[float(v) for v in plan.velocities[k]],
            accelerations=[float(v) for v in plan.accelerations[k]],
            time_from_start=duration_msg(float(times[k]))))
    return trajectory


# Cores of the machine: one plan worker each by default, two executor threads.
_CORES = os.cpu_count() or 1
# Longest wait for a plan from a worker that is not hung [s]: the full 3-DOF
# roadmap's slowest plans take seconds.
_WORKER_TIMEOUT = 120.0
# The parameter each per-joint limit falls back on.
_JOINT_LIMIT_DEFAULTS = {"max_velocity": "default_max_velocity",
                         "max_acceleration": "default_max_acceleration"}


class _State:
    """A planner, the stamp of the roadmap messages it was built from, the
    workers planning on it (None: plan in this process), its roadmap
    restricted to the current scene (None: no scene) and the key that names
    that scene to the workers, swapped as one reference."""

    def __init__(self, planner, stamp, workers=None, world=None, scene_key=None):
        self.planner = planner
        self.stamp = stamp
        self.workers = workers
        self.world = world
        self.scene_key = scene_key


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
        self.declare_parameter("clearance", DEFAULT_CLEARANCE, ParameterDescriptor(
            description="Margin (normalised |det Jx|) that paths keep from the singular "
                        "locus wherever the roadmap allows, traded for length (larger keeps "
                        "farther and is longer, 0 the shortest); they keep a quarter of it "
                        "in validation, or half the start's or goal's margin where less",
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=0.5)]))
        self.declare_parameter("default_time_limit", 10.0, ParameterDescriptor(
            description="Longest time to plan a request that gives no time_limit, from its "
                        "reception: past it the answer is the valid path found so far or "
                        "ERROR_TIMEOUT [s]",
            floating_point_range=[FloatingPointRange(from_value=1e-3, to_value=3600.0)]))
        self.declare_parameter("plan_workers", _CORES, ParameterDescriptor(
            description="Processes that plan requests, started with each new roadmap and "
                        "mapping it; 0 plans in the node's process",
            integer_range=[IntegerRange(from_value=0, to_value=64, step=1)], read_only=True))
        defaults = Retries()
        self.declare_parameter("retry_global_paths", defaults.global_paths, ParameterDescriptor(
            description="Global paths tried, shortest first, before a request fails",
            integer_range=[IntegerRange(from_value=1, to_value=1000, step=1)], read_only=True))
        self.declare_parameter("retry_repairs", defaults.repairs, ParameterDescriptor(
            description="Local re-plans around a step the validator refused, per global path "
                        "and clearance weight",
            integer_range=[IntegerRange(from_value=0, to_value=100, step=1)], read_only=True))
        self.declare_parameter("retry_split_shortcuts", defaults.split_shortcuts,
                               ParameterDescriptor(
            description="Refused shortcuts split into shorter ones before the cell path is "
                        "restored (also corners put back when smoothing)",
            integer_range=[IntegerRange(from_value=0, to_value=100, step=1)], read_only=True))
        self.declare_parameter("detour_weight", defaults.detour_weight, ParameterDescriptor(
            description="The paper's clearance weight w (cell cost 1 + w / d) of the paths "
                        "tried when the shortest ones cannot be repaired",
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1000.0)],
            read_only=True))
        self.declare_parameter("detour_inflation", defaults.detour_inflation, ParameterDescriptor(
            description="Factor on the estimate of those paths' searches (weighted A*): they "
                        "cost at most this many times the least and settle far fewer nodes; "
                        "1 gives least-cost paths",
            integer_range=[IntegerRange(from_value=1, to_value=100, step=1)], read_only=True))
        self.declare_parameter("promising_nodes", defaults.promising_nodes, ParameterDescriptor(
            description="Nodes each local search may settle, on a roadmap of all the joints, "
                        "in the two most promising searches tried before the global paths "
                        "(any gates, then the cheapest patches); 0 tries the global paths only",
            integer_range=[IntegerRange(from_value=0, to_value=100_000_000, step=1)],
            read_only=True))
        self._retries = Retries(
            promising_nodes=self.get_parameter("promising_nodes").value,
            global_paths=self.get_parameter("retry_global_paths").value,
            repairs=self.get_parameter("retry_repairs").value,
            split_shortcuts=self.get_parameter("retry_split_shortcuts").value,
            detour_weight=self.get_parameter("detour_weight").value,
            detour_inflation=self.get_parameter("detour_inflation").value)
        self.declare_parameter("mechanism_file", "", ParameterDescriptor(
            description="Mechanism file (as the builder's); given, roadmaps of another "
                        "mechanism are ignored with an error; empty, the planner plans on the "
                        "mechanism each roadmap carries", read_only=True))
        path = self.get_parameter("mechanism_file").value
        described = load_mechanism_file(path) if path else None
        self.mechanism = None if described is None else described.mechanism
        if self.mechanism is not None:
            self._declare_joint_limits(self.mechanism.joint_names)
        # The widths and layers of the bodies a scene is checked with: the
        # file's, else the defaults (each leg in a layer of its own).
        self.bodies = None if described is None else described.bodies
        self._state = None
        self._messages = {}
        # The scene each new roadmap is restricted to, and the header stamp it
        # came with (None: no scene).
        self._scene = None
        self._scene_stamp = None
        # Names each scene applied, for the plan workers.
        self._scene_keys = itertools.count(1)
        # Scene messages refused (unreadable, or not fitting the roadmap).
        self.refused_scenes = 0
        # Roadmaps and scenes are taken one at a time (they replace the
        # planning state); requests go on on the executor's other threads.
        updates = MutuallyExclusiveCallbackGroup()
        self.create_subscription(NSolutionField, "field", self._on_field, LATCHED_QOS,
                                 callback_group=updates)
        self.create_subscription(WorkspaceRoadmap, "roadmap", self._on_roadmap, LATCHED_QOS,
                                 callback_group=updates)
        # Raw: a message too long to be a scene is refused unread.
        self.create_subscription(Scene, "scene", self._on_scene, LATCHED_QOS,
                                 callback_group=updates, raw=True)
        self.scene_pub = self.create_publisher(Scene, "~/current_scene", LATCHED_QOS)
        self.trajectory_pub = self.create_publisher(JointTrajectory, "planned_trajectory", 10)
        # The same with the plan's ends: a recorded plan replays alone.
        self.path_pub = self.create_publisher(PlannedPath, "planned_path", 10)
        self.marker_pub = self.create_publisher(MarkerArray, "planned_path_markers", 10)
        self.create_service(PlanPath, "plan_path", self._on_plan, qos_profile=SERVICE_QOS,
                            callback_group=ReentrantCallbackGroup())
        self.create_service(AssemblyModes, "assembly_modes", self._on_assembly_modes,
                            qos_profile=SERVICE_QOS, callback_group=ReentrantCallbackGroup())
        self.create_service(InverseKinematics, "inverse_kinematics",
                            self._on_inverse_kinematics, qos_profile=SERVICE_QOS,
                            callback_group=ReentrantCallbackGroup())
        # Set once a first roadmap is planned on.
        self.ready = threading.Event()
        # Set once the latest roadmap's planning index is built and its
        # workers started (or failed to).
        self.indexed = threading.Event()
        # Until a roadmap is loaded every request answers NO_ROADMAP: say why.
        self.get_logger().info(
            f"waiting for a roadmap on {self.resolve_topic_name('roadmap')} and "
            f"{self.resolve_topic_name('field')} (from a roadmap_builder); "
            f"{self.resolve_service_name('plan_path')} answers ERROR_NO_ROADMAP until then")

    @property
    def planner(self):
        """The planning state requests use now (None before a roadmap)."""
        state = self._state
        return None if state is None else state.planner

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
        # A cold numba cache (a first run, or a changed core) turns loading
        # the kernels into seconds of compiling: say so, or the wait for
        # readiness looks like a hang.
        with numba_event.install_listener("numba:compile", _CompileNotice(self.get_logger())):
            try:
                received, index, cached = received_roadmap(field, roadmap)
                if cached:
                    self.get_logger().info("the roadmap is in the roadmap cache: its entry, "
                                           "with its planning index, is mapped")
                if self.mechanism is not None and received.mechanism != self.mechanism:
                    raise InvalidInputError(f"the roadmap is the {received.mechanism.kind}'s "
                                            f"{received.mechanism.to_dict()}, not the "
                                            f"mechanism file's {self.mechanism.to_dict()}")
                planner = Planner(received, index, retries=self._retries)
            except GWRError as exc:
                self.get_logger().error(f"ignoring an inconsistent roadmap: {exc}")
                return
            del received, index
            self._messages.clear()
            try:
                planner.warm_up()
            except Exception as exc:  # a bug there must not take the node down
                self.get_logger().error(f"the warm-up failed: {exc!r}")
        try:
            self._declare_joint_limits(planner.roadmap.mechanism.joint_names)
        except ParameterException as exc:
            # A parameters file's value out of range: requests get the defaults.
            self.get_logger().error(f"joint limits of the roadmap's joints: {exc}")
        world = self._world_for(planner)
        # One reference assignment: atomic for the service threads, and a
        # request keeps the state it started with.
        previous, self._state = self._state, _State(planner, roadmap.header.stamp, world=world)
        # Set with the state, not after the logs: a request answered from the
        # new roadmap comes from a ready planner.
        first = not self.ready.is_set()
        self.ready.set()
        self.indexed.clear()
        self._echo_scene()
        stamp = roadmap.header.stamp
        self.get_logger().info(
            f"planning on a new roadmap (stamp {stamp.sec}.{stamp.nanosec:09d}): "
            f"{_describe(planner.roadmap)}, {len(planner.roadmap.graph)} patches, ready in "
            f"{time.perf_counter() - start:.3f} s")
        if first:
            self.get_logger().info(f"ready: serving {self.resolve_service_name('plan_path')} on "
                                   f"a roadmap of {_describe(planner.roadmap)}")
        if previous is not None and previous.workers is not None:
            previous.workers.close()
        # The replaced state goes here, unless a request in flight still
        # holds it; malloc would keep its pages (module memory).
        del previous, planner
        release_free_memory()
        try:
            self._start_workers(stamp)
        finally:
            self.indexed.set()

    def _start_workers(self, stamp):
        """Index the roadmap now in use and start the workers on it, which
        then take its requests (or plan with the index here)."""
        count = self.get_parameter("plan_workers").value
        begin = time.perf_counter()
        roadmap = self._state.planner.roadmap
        try:
            index = build_cell_search_index(roadmap, (self.get_parameter("clearance").value,),
                                   retries=self._retries,
                                   graph_from=self._state.planner.search_index)
        except Exception as exc:  # plans go on without the index
            self.get_logger().error(f"the planning index failed: {exc!r}")
            return
        state = None
        if count:
            try:
                workers = PlanWorkers(roadmap, index, count, _WORKER_TIMEOUT,
                                      os.path.join(default_cache_dir(), "planners"),
                                      retries=self._retries)
                state = _State(workers.planner, stamp, workers)
            except Exception as exc:  # plans go on in this process
                self.get_logger().error(f"no plan workers, planning in the node's process: "
                                        f"{exc!r}")
        if state is None:
            state = _State(Planner(roadmap, index, retries=self._retries), stamp)
        # A scene is applied to this planner's roadmap (the mapped one, with
        # workers), with what the first planner computed for scenes on it:
        # seconds on a full roadmap.
        try:
            state.planner.adopt_scene_indices(self._state.planner)
        except GWRError as exc:  # the scene's index is then computed again
            self.get_logger().error(f"the scene index does not move to the indexed roadmap: "
                                    f"{exc}")
        state.world = self._world_for(state.planner)
        if state.workers is not None and state.world is not None:
            self._apply_in_workers(state)
        # Updates are mutually exclusive: no other roadmap came meanwhile.
        # With workers, the node's planner reads the mapped files too, and
        # the received roadmap's memory goes with the replaced state.
        self._state = state
        del roadmap, index, state
        release_free_memory()
        self.get_logger().info(
            f"planning index ready, {self._state.workers.count if self._state.workers else 0} "
            f"plan worker(s) started in {time.perf_counter() - begin:.3f} s")

    def _world_for(self, planner):
        """The current scene applied to a new roadmap's planner, or None
        without a scene; a scene that does not fit the new roadmap is
        dropped (logged and echoed as no scene)."""
        scene = kept_scene(self._scene, self.bodies)
        if scene is None:
            return None
        try:
            return planner.apply_scene(scene, self.bodies)
        except Exception as exc:  # a bug there must not take the node down either
            self.refused_scenes += 1
            self.get_logger().error(f"dropping the scene, which does not fit the new roadmap, "
                                    f"and planning without one: {exc}")
            self._scene = self._scene_stamp = None
            self._echo_scene()
            return None

    def _on_scene(self, data):
        begin = time.perf_counter()
        try:
            msg = scene_msg_from_bytes(data)
            scene = scene_from_msg(msg)
            if is_empty_scene(scene):
                scene = None
            state = self._state
            # Until a roadmap comes, the scene waits for it (_world_for).
            kept = kept_scene(scene, self.bodies)
            world = None if kept is None or state is None else state.planner.apply_scene(
                kept, self.bodies)
        except Exception as exc:  # GWRError: a bad scene; anything else a bug
            self.refused_scenes += 1
            self.get_logger().error(f"refusing a scene, planning on in the previous one: "
                                    f"{exc if isinstance(exc, GWRError) else repr(exc)}")
            return
        self._scene, self._scene_stamp = scene, msg.header.stamp
        if state is None:
            self.get_logger().info("keeping the scene for the first roadmap")
            return
        # Requests started before go on in the previous scene.
        self._state = _State(state.planner, state.stamp, state.workers, world,
                             None if world is None else next(self._scene_keys))
        if state.workers is not None:
            self._apply_in_workers(self._state)
        self._echo_scene()
        self.get_logger().info(
            "planning without a scene" if scene is None else
            f"planning in a new scene: {len(scene.polygons) + len(scene.discs)} obstacle(s), "
            f"{len(scene.limits.strokes)} stroke(s), {len(scene.limits.passive)} passive "
            f"range(s), ready in {time.perf_counter() - begin:.3f} s")

    def _apply_in_workers(self, state):
        """Give the state's workers its scene (or none) and its key; until
        they all have it, its requests are planned in this process."""
        if state.world is not None and state.scene_key is None:
            state.scene_key = next(self._scene_keys)
        begin = time.perf_counter()
        try:
            state.workers.apply_scene(state.scene_key, kept_scene(self._scene, self.bodies),
                                      self.bodies)
        except WorkersClosed:
            return  # a newer roadmap came meanwhile, or every worker failed
        except Exception as exc:  # GWRError, WorkerFailed; anything else a bug
            self.get_logger().error(f"the plan workers could not take the scene, requests in "
                                    f"it are planned in the node's process: {exc!r}")
            return
        if state.world is not None:
            self.get_logger().info(f"plan workers planning in the scene, ready in "
                                   f"{time.perf_counter() - begin:.3f} s")

    def _echo_scene(self):
        """Publish the scene planned with on ``~/current_scene``."""
        header = Header(stamp=self._scene_stamp or self.get_clock().now().to_msg(),
                        frame_id=BASE_FRAME)
        self.scene_pub.publish(Scene(header=header) if self._scene is None
                               else scene_to_msg(self._scene, header))

    def _plan(self, state, start, goal, options, termination):
        """A plan from the state's workers, or from its planner here when it
        has none, the worker planning it failed (killed, not replaced: it
        might fail again) or the workers do not plan in the state's scene
        (yet, or any more)."""
        workers = state.workers
        if workers is not None:
            try:
                return workers.plan(start, goal, options, termination, state.scene_key)
            except WorkersClosed:
                pass  # a newer roadmap or scene came meanwhile, or every worker failed
            except WorkerFailed as exc:
                left = workers.count
                if not left:
                    state.workers = None
                self.get_logger().error(
                    f"{exc}; killed, its request plans in the node's process" + (
                        f", {left} worker(s) go on" if left else
                        ", and so does every request until the next roadmap"))
        return state.planner.plan(start, goal, options, termination, world=state.world)

    def destroy_node(self):
        state = self._state
        if state is not None and state.workers is not None:
            state.workers.close()
        return super().destroy_node()

    def _options(self, request, joint_names):
        """PlanOptions of a request: its limits for all joints, or when both
        are 0 the node's ``joint_limits.<joint>.*`` parameters where nonzero
        and its defaults; then its limits of single joints."""
        limits = (request.max_velocity, request.max_acceleration)
        if 0.0 in limits and limits != (0.0, 0.0):
            raise InvalidInputError(f"give both max_velocity and max_acceleration, or neither: "
                                    f"got max_velocity = {limits[0]}, "
                                    f"max_acceleration = {limits[1]}")
        if limits == (0.0, 0.0):
            per_joint = [[self._joint_limit(name, kind) or self.get_parameter(default).value
                          for name in joint_names]
                         for kind, default in _JOINT_LIMIT_DEFAULTS.items()]
        else:
            per_joint = [[value] * len(joint_names) for value in limits]
        named = set()
        for entry in request.joint_limits:
            if entry.joint_name not in joint_names or entry.joint_name in named:
                raise InvalidInputError(
                    f"joint_limits: {entry.joint_name!r:.40} is not a joint of the mechanism "
                    f"({', '.join(joint_names)}), or is named twice")
            named.add(entry.joint_name)
            at = joint_names.index(entry.joint_name)
            for values, value in zip(per_joint, (entry.max_velocity, entry.max_acceleration)):
                if not (math.isfinite(value) and value >= 0.0):
                    raise InvalidInputError(f"joint_limits: {entry.joint_name}'s limits must be "
                                            f"0 or positive and finite, got {value}")
                values[at] = value or values[at]
        # One value for all joints times the path as before per-joint limits.
        velocity, acceleration = (values[0] if len(set(values)) == 1 else tuple(values)
                                  for values in per_joint)
        tolerance = {"mode_tol": request.mode_tolerance} if request.mode_tolerance else {}
        return PlanOptions(smooth=not request.skip_smoothing, weighted=request.weighted,
                           feasibility_only=request.feasibility_only, max_velocity=velocity,
                           max_acceleration=acceleration,
                           clearance=self.get_parameter("clearance").value, **tolerance)

    def _joint_limit(self, joint, kind):
        """The node's ``joint_limits.<joint>.<kind>`` parameter (0: none)."""
        name = f"joint_limits.{joint}.{kind}"
        return self.get_parameter(name).value if self.has_parameter(name) else 0.0

    def _declare_joint_limits(self, joint_names):
        """Declare ``joint_limits.<joint>.max_velocity`` and
        ``.max_acceleration`` for joints that have none yet: a parameters
        file's values given at start are taken when declared."""
        for joint in joint_names:
            for kind, default in _JOINT_LIMIT_DEFAULTS.items():
                name = f"joint_limits.{joint}.{kind}"
                if not self.has_parameter(name):
                    unit = "[joint unit/s]" if kind == "max_velocity" else "[joint unit/s^2]"
                    self.declare_parameter(name, 0.0, ParameterDescriptor(
                        description=f"{kind} of joint {joint} for requests that give no "
                                    f"limits for all joints; 0 takes {default} {unit}",
                        floating_point_range=[FloatingPointRange(from_value=0.0,
                                                                 to_value=1e6)]))

    def _on_plan(self, request, response):
        state = self._state
        # A time limit counts from the request's reception: the time it
        # waited for a free executor thread is the caller's too.
        begin = time.monotonic() - request_age()
        try:
            if state is None:
                return _error(response, PlanPath.Response.ERROR_NO_ROADMAP,
                              "no roadmap received yet on 'field' and 'roadmap'")
            return self._answer(request, state, begin)
        except UndecidedError as exc:
            response = _error(_named(state), PlanPath.Response.ERROR_UNDECIDED,
                              f"{exc}; {_FINER}", PlanPath.Response.FEASIBILITY_UNDECIDED)
            response.undecided_patches = list(exc.thin_patches)
            response.undecided_steps = list(exc.steps)
            return response
        except GWRError as exc:
            code = ERROR_CODES.get(exc.code, PlanPath.Response.ERROR_INTERNAL)
            return _error(_named(state), code, str(exc),
                          FEASIBILITY.get(exc.reason if isinstance(exc, InfeasiblePathError)
                                          else None, PlanPath.Response.FEASIBILITY_UNKNOWN))
        except Exception as exc:  # a bug must not take the service down
            self.get_logger().error(f"internal error on a plan request: {exc!r}")
            return _error(_named(state), PlanPath.Response.ERROR_INTERNAL,
                          f"internal error: {exc!r}")

    def _answer(self, request, state, begin):
        options = self._options(request, state.planner.roadmap.mechanism.joint_names)
        limit = request.time_limit or self.get_parameter("default_time_limit").value
        if not (math.isfinite(limit) and limit > 0):
            raise InvalidInputError(f"time_limit must be positive and finite (or 0 for the "
                                    f"planner's default), got {request.time_limit}")
        termination = Termination(begin + limit)
        if termination():
            raise PlanningTimeoutError(
                f"the request waited {time.monotonic() - begin:.3g} s for the planner, longer "
                f"than its time limit of {limit:g} s: nothing was tried")
        mechanism = state.planner.roadmap.mechanism
        ends = [_plan_end(mechanism, *end) for end in (
            ("start", request.start, request.start_is_pose, request.start_pose,
             request.start_working_mode),
            ("goal", request.goal, request.goal_is_pose, request.goal_pose,
             request.goal_working_mode))]
        resolved = resolve_ends(state.planner, *ends, options.mode_tol)
        plan = self._plan(state, resolved.start, resolved.goal, options, termination)
        response = _named(state)
        response.start_working_mode, response.goal_working_mode = (
            "" if mode is None else mode.label
            for mode in (resolved.start_mode, resolved.goal_mode))
        response.feasibility = FEASIBILITY[plan.reason]
        response.global_paths = [GlobalPath(patch_ids=list(g.patches), cost=g.cost)
                                 for g in plan.global_paths]
        if not options.feasibility_only:
            response.path_index = plan.path_index
            response.trajectory = plan_to_trajectory(plan, mechanism.joint_names,
                                                     self._header())
            response.poses = [pose_msg(mechanism, p) for p in plan.poses]
            response.min_singularity_margin = float(plan.validation.min_margin)
            response.plan_status = PLAN_STATUS[plan.status]
            response.skipped_steps = list(plan.skipped)
        response.success = True
        response.error_code = PlanPath.Response.ERROR_NONE
        # Converting messages for no one would cost every request.
        if not options.feasibility_only and self.trajectory_pub.get_subscription_count():
            self.trajectory_pub.publish(response.trajectory)
        if not options.feasibility_only and self.path_pub.get_subscription_count():
            self.path_pub.publish(PlannedPath(
                header=response.trajectory.header, start=request.start, goal=request.goal,
                trajectory=response.trajectory, poses=response.poses))
        if not options.feasibility_only and self.marker_pub.get_subscription_count():
            self.marker_pub.publish(path_markers(state.planner.roadmap.grid, plan.joints,
                                                 plan.poses, response.trajectory.header.stamp))
        return response

    def _header(self):
        return Header(stamp=self.get_clock().now().to_msg(), frame_id=BASE_FRAME)

    def _on_assembly_modes(self, request, response):
        def fill(planner):
            mechanism = planner.roadmap.mechanism
            *joints, mode = configuration_from_msg(mechanism, request.joints)
            modes = assembly_modes(planner, joints, mode if request.with_start else None,
                                   request.mode_tolerance or None)
            response.modes = [_assembly_mode_msg(mechanism, m) for m in modes]

        return self._query(AssemblyModes, "assembly modes", response, fill)

    def _on_inverse_kinematics(self, request, response):
        def fill(planner):
            mechanism = planner.roadmap.mechanism
            modes = working_modes(planner, pose_from_msg(mechanism, request.pose))
            response.modes = [_working_mode_msg(mechanism, m) for m in modes]

        return self._query(InverseKinematics, "inverse kinematics", response, fill)

    def _query(self, service, what, response, fill):
        """A query of the current roadmap answered: ``fill(planner)`` fills
        the response, and what it raises (message conversion included) is
        mapped to the service's ERROR_ constant of its code, a bug to
        ERROR_INTERNAL, so that the service keeps serving."""
        state = self._state
        try:
            if state is None:
                return _failed(response, service.Response.ERROR_NO_ROADMAP,
                               "no roadmap received yet on 'field' and 'roadmap'")
            fill(state.planner)
            response.success = True
            response.error_code = service.Response.ERROR_NONE
            return response
        except GWRError as exc:
            code = getattr(service.Response, f"ERROR_{exc.code}",
                           service.Response.ERROR_INTERNAL)
            return _failed(service.Response(), code, str(exc))
        except Exception as exc:  # a bug must not take the service down
            self.get_logger().error(f"internal error on an {what} request: {exc!r}")
            return _failed(service.Response(), service.Response.ERROR_INTERNAL,
                           f"internal error: {exc!r}")


def _plan_end(mechanism, which, configuration, is_pose, pose, working_mode):
    """One end of a plan request: its configuration, or its pose (a
    :class:`~rpr3_gwr_core.planning.PoseEnd`) with its working mode."""
    if not is_pose:
        if working_mode:
            raise InvalidInputError(f"{which}_working_mode is for a {which} given as a pose "
                                    f"({which}_is_pose)")
        return configuration_from_msg(mechanism, configuration)
    return PoseEnd(pose_from_msg(mechanism, pose), working_mode or None)


def _working_mode_msg(mechanism, mode):
    """A core :class:`~rpr3_gwr_core.planning.WorkingMode` as a message."""
    *joints, coordinate = mode.configuration
    located = mode.patch is not None
    return WorkingModeMsg(
        working_mode=mode.label,
        configuration=Configuration(joint_names=list(mechanism.joint_names),
                                    positions=[float(v) for v in joints], mode=coordinate),
        aspect=mode.aspect, signed_margin=float(mode.margin), in_box=bool(mode.in_box),
        on_slice=bool(mode.on_slice), located=located,
        patch=int(mode.patch) if located else 0, unlocated=mode.unlocated)


class _CompileNotice(numba_event.Listener):
    """Logs the first compilation numba starts."""

    def __init__(self, logger):
        self._logger = logger
        self._said = False

    def on_start(self, event):
        if not self._said:
            self._said = True
            # 9 s on a quiet 2-core machine, 14 s on a busy one.
            self._logger.info("compiling the planner's kernels (a first run, or the core "
                              "changed): 10 to 20 s, then they are cached")

    def on_end(self, event):
        pass


def _named(state):
    """An empty response naming the roadmap that answers it."""
    response = PlanPath.Response()
    if state is not None:
        response.roadmap_stamp = state.stamp
        roadmap = state.planner.roadmap
        names = roadmap.mechanism.joint_names
        response.roadmap_fixed_joints = [names[joint] for joint, _ in roadmap.grid.fixed]
        response.roadmap_fixed_values = [float(value) for _, value in roadmap.grid.fixed]
    return response


def _describe(roadmap):
    grid, names = roadmap.grid, roadmap.mechanism.joint_names
    if not grid.fixed:
        return f"the {roadmap.mechanism.kind}, every joint free, {grid.size} cells"
    fixed = ", ".join(f"{names[joint]} = {value:g}" for joint, value in grid.fixed)
    return f"the {roadmap.mechanism.kind}, {fixed}"


_MODE_FEASIBILITY = {
    None: AssemblyMode.FEASIBILITY_UNKNOWN,
    "start": AssemblyMode.FEASIBILITY_START,
    "same_patch": AssemblyMode.FEASIBILITY_SAME_PATCH,
    "connected": AssemblyMode.FEASIBILITY_CONNECTED,
    "other_aspect": AssemblyMode.FEASIBILITY_OTHER_ASPECT,
    "unreachable": AssemblyMode.FEASIBILITY_UNREACHABLE,
    "undecided": AssemblyMode.FEASIBILITY_UNDECIDED,
}


def _assembly_mode_msg(mechanism, mode):
    """A core :class:`~rpr3_gwr_core.planning.AssemblyMode` as a message."""
    *joints, coordinate = mode.configuration
    located = mode.patch is not None
    return AssemblyMode(
        configuration=Configuration(joint_names=list(mechanism.joint_names),
                                    positions=[float(v) for v in joints], mode=coordinate),
        pose=pose_msg(mechanism, mode.pose), aspect=mode.aspect, signed_margin=mode.margin,
        located=located, patch=mode.patch if located else 0,
        region=mode.region if located else 0, layer=mode.layer if located else 0,
        unlocated=mode.unlocated, feasibility=_MODE_FEASIBILITY[mode.feasibility])


def _failed(response, code, message):
    response.success = False
    response.error_code = code
    response.error_msg = message
    return response


def _error(response, code, message, feasibility=PlanPath.Response.FEASIBILITY_UNKNOWN):
    response.success = False
    response.error_code = code
    response.error_msg = message
    response.feasibility = feasibility
    return response


def main(args=None):
    # So that release_free_memory reaches the memory of every thread.
    use_one_arena()
    # Two threads per core: a thread waits while a worker plans, and converts
    # the plan to messages while the worker plans the next request (8
    # clients on 2 cores: 188 requests/s with 2 threads, 242 with 4, 243 with 6).
    return run(PlannerNode, ReceiptExecutor, args, usage=USAGE, num_threads=2 * _CORES)
