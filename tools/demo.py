"""The main job (make demo): the suite as real processes on loopback DDS.

Starts roadmap_builder, planner, rpr3_driver and trajectory_recorder as
separate processes with the project's localhost Fast DDS profile and a ROS
domain of its own, plans the paper's two examples through the planner's
service, executes them on the driver, then switches the builder to the full
3-DOF roadmap and plans and executes a motion that needs rho1 to move,
records a bag, writes the figures to out/, prints a short report and shuts
everything down with SIGINT.

Beside them, each in a namespace of its own, the same nodes run on other
mechanism files, between the paper's examples and the full roadmap (and are
stopped before it, which takes both cores): on the 3-RRR
(config/three_rrr.yaml, slice th1 = 0) a builder, a planner and a driver
plan and execute a non-singular assembly-mode change, checked again here by
the core's validator on the trajectory received and by the sign of det Jx
at each of its points; on the five-bar (config/five_bar.yaml, its whole
torus) a builder and a planner refuse an assembly-mode change as
FEASIBILITY_OTHER_ASPECT.
"""

import json
import math
import os
import pathlib
import random
import signal
import subprocess
import sys
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "out"
LIB = ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes" / "lib" / "rpr3_gwr_nodes"
PROFILE = ROOT / "ros2_ws" / "fastdds_localhost.xml"
os.environ.update(FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE),
                  FASTDDS_DEFAULT_PROFILES_FILE=str(PROFILE),
                  RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
                  ROS_DOMAIN_ID=str(random.SystemRandom().randint(1, 100)))
os.environ.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)

import numpy as np  # noqa: E402
import rclpy  # noqa: E402  (after the DDS environment is set)
from rclpy.action import ActionClient  # noqa: E402
from rclpy.executors import MultiThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rosbags.rosbag2 import Reader  # noqa: E402
from rpr3_gwr_core.io.figures import field_figure, plan_figure, roadmap_figure  # noqa: E402
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file  # noqa: E402
from rpr3_gwr_core.planning.validation import validate_path  # noqa: E402
from rpr3_gwr_msgs.action import ExecuteTrajectory  # noqa: E402
from rpr3_gwr_msgs.msg import Configuration, NSolutionField, WorkspaceRoadmap  # noqa: E402
from rcl_interfaces.srv import SetParameters  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rpr3_gwr_msgs.srv import PlanPath, ResetDriver  # noqa: E402
from rpr3_gwr_nodes.conversions import roadmap_from_msgs  # noqa: E402
from rpr3_gwr_nodes.profiles import LATCHED_QOS  # noqa: E402

EXAMPLES = {
    "paper_5_2_two_configurations": ((17.0, 12.0, 18.0, 122.82), (17.0, 10.0, 25.0, -24.24)),
    "paper_5_3_assembly_mode_change": ((17.0, 20.0, 25.0, 29.47), (17.0, 20.0, 25.0, 96.13)),
}
# Issue 10's pocket: the same legs, two modes of the det Jx < 0 side that no
# motion at fixed rho1 joins; the full 3-DOF roadmap joins them by moving rho1.
FULL_EXAMPLE = ((27.5, 31.67154934, 2.14117832, -101.0),
                (27.5, 31.67154934, 2.14117832, 158.048263))
TIME_SCALE = 10.0
TIMEOUT = 120.0
CONFIG = ROOT / "config"
# The 3-RRR's joints with two assembly modes of one aspect that its slice
# th1 = 0 joins (alpha [rad]); the five-bar's joints with its two modes, of
# opposite aspects (y [m]).
THREE_RRR = ((0.0, 1.2043, 2.2515), 0.6526, 2.1165)
FIVE_BAR = ((3.1, 2.5), 0.11622901, -0.05862426)


def _configuration(q):
    """The paper's (rho1, rho2, rho3, alpha [deg])."""
    return Configuration(positions=list(q[:3]), mode=math.radians(q[3]))


def _joints(joints, mode):
    return Configuration(positions=list(joints), mode=mode)


def _wait(future, timeout=TIMEOUT):
    done = threading.Event()
    future.add_done_callback(lambda _: done.set())
    if not done.wait(timeout):
        raise TimeoutError(f"no answer within {timeout} s")
    return future.result()


def _start(executable, *parameters, log, namespace=None):
    command = [str(LIB / executable), "--ros-args"]
    if namespace:
        command += ["-r", f"__ns:=/{namespace}"]
    for name, value in parameters:
        command += ["-p", f"{name}:={value}"]
    return subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)


def _run_example(name, q1, q2, plan, reset, execute):
    """Plan from q1 to q2, execute on the driver, print a line and write the
    plan's JSON; returns that data with ``failed`` set if the driver failed."""
    request = PlanPath.Request(start=_configuration(q1), goal=_configuration(q2),
                               smooth=True, max_velocity=2.0, max_acceleration=4.0)
    begin = time.perf_counter()
    response = _wait(plan.call_async(request))
    took = time.perf_counter() - begin
    if not response.success:
        raise RuntimeError(f"{name}: planning failed: {response.error_msg}")
    done = _wait(reset.call_async(ResetDriver.Request(configuration=_configuration(q1))))
    if not done.success:
        raise RuntimeError(f"{name}: driver reset failed: {done.error_msg}")
    handle = _wait(execute.send_goal_async(ExecuteTrajectory.Goal(
        trajectory=response.trajectory)))
    result = _wait(handle.get_result_async()).result
    points = response.trajectory.points
    duration = points[-1].time_from_start.sec + points[-1].time_from_start.nanosec * 1e-9
    legs = [list(p.positions) for p in points]
    length = sum(math.dist(a, b) for a, b in zip(legs, legs[1:]))
    paths = ", ".join(" -> ".join(map(str, g.patch_ids)) for g in response.global_paths)
    print(f"{name}: global paths [{paths}]; trajectory {len(points)} points, "
          f"{length:.1f} length units of legs, {duration:.1f} s; planned in "
          f"{1e3 * took:.0f} ms; min singularity margin planned "
          f"{response.min_singularity_margin:.4f}, executed "
          f"{result.min_singularity_margin:.4f}; "
          f"driver: {'done' if result.error_code == 0 else result.error_msg}, platform at "
          f"alpha = {math.degrees(result.final_pose.values[2]):.2f} deg")
    data = {"waypoints": [{"joints": r, "pose": list(p.values)}
                          for r, p in zip(legs, response.poses)],
            "global_paths": [list(g.patch_ids) for g in response.global_paths],
            "path_index": response.path_index}
    (OUT / f"{name}.json").write_text(json.dumps(data))
    return dict(data, failed=int(result.error_code != 0))


# A node stops once its callbacks in flight end: the planner's may be the
# full 3-DOF roadmap's planning index, tens of seconds on a loaded machine.
STOP_TIMEOUT = 60.0


def _stop(processes):
    """SIGINT to each process still running, then wait; 1 if one had to be killed."""
    running = [p for p in processes if p.poll() is None]
    for process in running:
        process.send_signal(signal.SIGINT)
    code = 0
    for process in running:
        try:
            process.wait(timeout=STOP_TIMEOUT)
        except subprocess.TimeoutExpired:
            print(f"{' '.join(map(str, process.args))} did not stop within {STOP_TIMEOUT:g} s: "
                  "killed")
            process.kill()
            code = 1
    return code


def _wait_for_roadmap(plan, probe, name):
    """Ask until the planner answers from a roadmap."""
    deadline = time.monotonic() + 2 * TIMEOUT
    while _wait(plan.call_async(probe)).error_code == PlanPath.Response.ERROR_NO_ROADMAP:
        if time.monotonic() > deadline:
            raise TimeoutError(f"the {name} planner got no roadmap")
        time.sleep(0.2)


def _off(values, targets):
    """Largest difference of angles, modulo whole turns [rad]."""
    return max(abs(math.remainder(v - w, 2 * math.pi)) for v, w in zip(values, targets))


def _three_rrr_mode_change(node):
    """Plan the 3-RRR's assembly-mode change through its planner, check the
    trajectory independently, execute it on its driver; 0 when all held."""
    plan = node.create_client(PlanPath, "/three_rrr/plan_path")
    reset = node.create_client(ResetDriver, "/three_rrr/reset")
    execute = ActionClient(node, ExecuteTrajectory, "/three_rrr/execute_trajectory")
    if not (plan.wait_for_service(timeout_sec=TIMEOUT) and reset.wait_for_service(
            timeout_sec=TIMEOUT) and execute.wait_for_server(timeout_sec=TIMEOUT)):
        raise TimeoutError("the 3-RRR's planner or driver is not available")
    joints, mode_a, mode_b = THREE_RRR
    start, goal = _joints(joints, mode_a), _joints(joints, mode_b)
    _wait_for_roadmap(plan, PlanPath.Request(start=start, goal=goal, feasibility_only=True),
                      "3-RRR")
    begin = time.perf_counter()
    response = _wait(plan.call_async(PlanPath.Request(
        start=start, goal=goal, smooth=True, max_velocity=1.0, max_acceleration=2.0)))
    took = time.perf_counter() - begin
    if not response.success:
        raise RuntimeError(f"3-RRR: planning failed: {response.error_msg}")
    fixed = ", ".join(f"{n} = {v:g}" for n, v in zip(response.roadmap_fixed_joints,
                                                     response.roadmap_fixed_values))
    path = [list(p.positions) for p in response.trajectory.points]
    poses = [list(p.values) for p in response.poses]
    paths = ", ".join(" -> ".join(map(str, g.patch_ids)) for g in response.global_paths)
    print(f"three_rrr_assembly_mode_change ({fixed}): global paths [{paths}]; trajectory "
          f"{len(path)} points of joints {list(response.trajectory.joint_names)}; planned in "
          f"{1e3 * took:.0f} ms")
    # Independently of the planner: the core's validator follows the
    # received joints from the start pose and must reach the goal's pose,
    # and det Jx keeps one sign at every point.
    mechanism = load_mechanism_file(CONFIG / "three_rrr.yaml").mechanism
    validation = validate_path(mechanism, path, poses[0], poses[-1])
    signs = {int(s) for s in mechanism.aspect(np.array(poses), np.array(path))}
    ends = (_off(path[0], joints) < 1e-9 and _off(path[-1], joints) < 1e-9
            and _off([poses[0][2]], [mode_a]) < 1e-3 and _off([poses[-1][2]], [mode_b]) < 1e-3)
    sign = {1: "+", -1: "-"}.get(signs.pop(), "0") if len(signs) == 1 else "CHANGING"
    print(f"three_rrr_assembly_mode_change: endpoints th = {list(joints)} at alpha = "
          f"{poses[0][2]:.4f} and {poses[-1][2]:.4f} rad "
          f"({'the two modes asked' if ends else 'NOT the modes asked'}); independent check: "
          f"validator {'ok' if validation.ok else validation.reason}, min margin "
          f"{validation.min_margin:.4f}, det Jx sign {sign} at all {len(path)} points")
    done = _wait(reset.call_async(ResetDriver.Request(configuration=start)))
    if not done.success:
        raise RuntimeError(f"3-RRR: driver reset failed: {done.error_msg}")
    handle = _wait(execute.send_goal_async(ExecuteTrajectory.Goal(
        trajectory=response.trajectory)))
    result = _wait(handle.get_result_async()).result
    arrived = abs(math.remainder(result.final_pose.values[2] - mode_b, 2 * math.pi)) < 1e-3
    print(f"three_rrr_assembly_mode_change: driver: "
          f"{'done' if result.error_code == 0 else result.error_msg}, min singularity margin "
          f"executed {result.min_singularity_margin:.4f}, platform at alpha = "
          f"{result.final_pose.values[2]:.4f} rad")
    return int(not (ends and validation.ok and sign in ("+", "-") and result.error_code == 0
                    and arrived))


def _five_bar_refusal(node):
    """Ask the five-bar's planner for an assembly-mode change; 0 when it is
    refused as FEASIBILITY_OTHER_ASPECT."""
    plan = node.create_client(PlanPath, "/five_bar/plan_path")
    if not plan.wait_for_service(timeout_sec=TIMEOUT):
        raise TimeoutError("the five-bar's planner is not available")
    joints, plus, minus = FIVE_BAR
    request = PlanPath.Request(start=_joints(joints, plus), goal=_joints(joints, minus))
    _wait_for_roadmap(plan, request, "five-bar")
    response = _wait(plan.call_async(request))
    names = {getattr(PlanPath.Response, n): n for n in dir(PlanPath.Response)
             if n.startswith("FEASIBILITY_")}
    print(f"five_bar_assembly_mode_change: th = {list(joints)}, y = {plus} -> {minus}: "
          f"refused, {names[response.feasibility]}: {response.error_msg}")
    return int(response.success
               or response.feasibility != PlanPath.Response.FEASIBILITY_OTHER_ASPECT)


def main():
    OUT.mkdir(exist_ok=True)
    stamp = time.strftime("%Y%m%d_%H%M%S")
    bag = OUT / f"bag_{stamp}"
    log = open(OUT / "demo_nodes.log", "w", encoding="utf-8")
    processes = [
        _start("roadmap_builder", log=log),
        _start("planner", log=log),
        _start("rpr3_driver", ("time_scale", TIME_SCALE), log=log),
        _start("trajectory_recorder", ("bag_path", str(bag)), ("storage", "mcap"),
               ("record_joint_states", True), ("record_visualization", True), log=log),
    ]
    rrr = ("mechanism_file", CONFIG / "three_rrr.yaml")
    five_bar = ("mechanism_file", CONFIG / "five_bar.yaml")
    others = [
        _start("roadmap_builder", rrr, log=log, namespace="three_rrr"),
        _start("planner", rrr, ("plan_workers", 0), log=log, namespace="three_rrr"),
        _start("rpr3_driver", rrr, ("time_scale", TIME_SCALE), log=log, namespace="three_rrr"),
        _start("roadmap_builder", five_bar, ("full", True), log=log, namespace="five_bar"),
        _start("planner", five_bar, ("plan_workers", 0), log=log, namespace="five_bar"),
    ]
    print(f"started builder, planner, driver and recorder, and in /three_rrr and /five_bar "
          f"the nodes of those mechanism files (ROS_DOMAIN_ID "
          f"{os.environ['ROS_DOMAIN_ID']}, loopback DDS); node logs in {OUT / 'demo_nodes.log'}")
    rclpy.init()
    node = Node("rpr3_gwr_demo")
    executor = MultiThreadedExecutor()
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    code = 0
    try:
        received, both = {}, threading.Event()

        def keep(name):
            def callback(msg):
                received[name] = msg
                if len(received) == 2:
                    both.set()
            return callback

        node.create_subscription(NSolutionField, "field", keep("field"), LATCHED_QOS)
        node.create_subscription(WorkspaceRoadmap, "roadmap", keep("roadmap"), LATCHED_QOS)
        if not both.wait(TIMEOUT):
            raise TimeoutError("no roadmap published")
        roadmap = roadmap_from_msgs(received["field"], received["roadmap"])
        seg = roadmap.segmentation
        print(f"roadmap received: rho1 = {roadmap.grid.fixed_value(0):g}, "
              f"{seg.n_regions} regions, "
              f"{len(seg.patches)} patches, {len(seg.gates)} gates")
        field_figure(roadmap).savefig(OUT / "field.png", dpi=110)
        roadmap_figure(roadmap).savefig(OUT / "roadmap.png", dpi=110)
        plan = node.create_client(PlanPath, "plan_path")
        reset = node.create_client(ResetDriver, "reset")
        execute = ActionClient(node, ExecuteTrajectory, "execute_trajectory")
        if not (plan.wait_for_service(timeout_sec=TIMEOUT) and reset.wait_for_service(
                timeout_sec=TIMEOUT) and execute.wait_for_server(timeout_sec=TIMEOUT)):
            raise TimeoutError("planner or driver not available")
        # The planner takes the roadmap from the same topics, on its own time.
        q1 = EXAMPLES["paper_5_2_two_configurations"][0]
        first = PlanPath.Request(start=_configuration(q1), goal=_configuration(q1),
                                 feasibility_only=True)
        deadline = time.monotonic() + TIMEOUT
        while _wait(plan.call_async(first)).error_code == PlanPath.Response.ERROR_NO_ROADMAP:
            if time.monotonic() > deadline:
                raise TimeoutError("the planner got no roadmap")
            time.sleep(0.1)
        for name, (q1, q2) in EXAMPLES.items():
            data = _run_example(name, q1, q2, plan, reset, execute)
            code = code or data.pop("failed")
            plan_figure(roadmap, data).savefig(OUT / f"{name}.png", dpi=110)
        code = _three_rrr_mode_change(node) or code
        code = _five_bar_refusal(node) or code
        # Stopped before the full 3-DOF roadmap takes both cores.
        code = _stop(others) or code
        # The full 3-DOF roadmap: the builder switches to it (first run: a
        # build of about 25 s, then the cache), the planner swaps roadmaps.
        print("switching the builder to the full 3-DOF roadmap (all legs free) ...")
        switch = node.create_client(SetParameters, "/roadmap_builder/set_parameters")
        if not switch.wait_for_service(timeout_sec=TIMEOUT):
            raise TimeoutError("the builder's parameter service is not available")
        answer = _wait(switch.call_async(SetParameters.Request(
            parameters=[Parameter("full", value=True).to_parameter_msg()])))
        if not answer.results[0].successful:
            raise RuntimeError(f"the builder refused full: {answer.results[0].reason}")
        q1, q2 = FULL_EXAMPLE
        probe = PlanPath.Request(start=_configuration(q1), goal=_configuration(q2),
                                 feasibility_only=True)
        deadline = time.monotonic() + 4 * TIMEOUT
        while _wait(plan.call_async(probe)).error_code in (
                PlanPath.Response.ERROR_RHO1_MISMATCH, PlanPath.Response.ERROR_NO_ROADMAP):
            if time.monotonic() > deadline:
                raise TimeoutError("the planner got no full roadmap")
            time.sleep(0.5)
        data = _run_example("full_3dof_pocket_rho1_moves", q1, q2, plan, reset, execute)
        code = code or data.pop("failed")
        rho1 = [w["joints"][0] for w in data["waypoints"]]
        print(f"full_3dof_pocket_rho1_moves: rho1 went from {rho1[0]:g} to between "
              f"{min(rho1):.2f} and {max(rho1):.2f} and back (at fixed rho1 = {q1[0]:g} these "
              f"two modes of the same legs are not connected)")
        if max(rho1) - min(rho1) < 1e-6:
            raise RuntimeError("the full 3-DOF plan kept rho1 fixed, where no path exists")
    finally:
        executor.shutdown(timeout_sec=10.0)
        spinner.join(timeout=10.0)
        node.destroy_node()
        rclpy.try_shutdown()
        code = _stop(processes + others) or code
        log.close()
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    print(f"bag {bag}: {counts}")
    print(f"figures in {OUT}: field.png, roadmap.png, " + ", ".join(f"{n}.png" for n in EXAMPLES))
    print("all processes stopped" + ("" if code == 0 else " (with errors)"))
    return code


if __name__ == "__main__":
    sys.exit(main())
