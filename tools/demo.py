"""The main job (make demo): the suite as real processes on loopback DDS.

Starts roadmap_builder, planner, rpr3_driver and trajectory_recorder as
separate processes with the project's localhost Fast DDS profile and the
user's ROS_DOMAIN_ID (unset: a domain of its own), plans the paper's two
examples through the planner's service, executes them on the driver, then
switches the builder to the full 3-DOF roadmap and plans and executes a
motion that needs rho1 to move, records a bag, writes to out/ the field and
roadmap figures and a figure and the JSON of every plan, prints a short
report and shuts everything down with SIGINT.  It talks to the nodes through
:class:`rpr3_gwr_nodes.client.PlannerClient`, as a user's script would.

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
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "out"
LIB = ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes" / "lib" / "rpr3_gwr_nodes"
PROFILE = ROOT / "ros2_ws" / "fastdds_localhost.xml"
os.environ.update(FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE),
                  FASTDDS_DEFAULT_PROFILES_FILE=str(PROFILE),
                  RMW_IMPLEMENTATION="rmw_fastrtps_cpp")
os.environ.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)
# A user's ROS_DOMAIN_ID is kept; unset, this run takes one of its own in
# 1..100 (domains above 101 can collide with ephemeral ports).
if not os.environ.get("ROS_DOMAIN_ID"):
    os.environ["ROS_DOMAIN_ID"] = str(random.SystemRandom().randint(1, 100))

import numpy as np  # noqa: E402
import rclpy  # noqa: E402  (after the DDS environment is set)
from rcl_interfaces.msg import Log  # noqa: E402
from rcl_interfaces.srv import SetParameters  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.wait_for_message import wait_for_message  # noqa: E402
from rosbags.rosbag2 import Reader  # noqa: E402
from rpr3_gwr_core.figures import field_figure, plan_figure, roadmap_figure  # noqa: E402
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file  # noqa: E402
from rpr3_gwr_core.planning.validation import validate_path  # noqa: E402
from rpr3_gwr_msgs.msg import NSolutionField  # noqa: E402
from rpr3_gwr_msgs.srv import PlanPath  # noqa: E402
from rpr3_gwr_nodes.client import PlannerClient, configuration  # noqa: E402
from rpr3_gwr_nodes.conversions import roadmap_from_msgs  # noqa: E402
from rpr3_gwr_nodes.profiles import LATCHED_QOS  # noqa: E402

EXAMPLES = {
    "paper_5_2_two_configurations": ((17.0, 12.0, 18.0, 122.82), (17.0, 10.0, 25.0, -24.24)),
    "paper_5_3_assembly_mode_change": ((17.0, 20.0, 25.0, 29.47), (17.0, 20.0, 25.0, 96.13)),
}
# A pocket: the same legs, two modes of the det Jx < 0 side that no motion at
# fixed rho1 joins; the full 3-DOF roadmap joins them by moving rho1.
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
    return configuration(q[:3], math.radians(q[3]))


def _start(executable, *parameters, log, namespace=None):
    command = [str(LIB / executable), "--ros-args"]
    if namespace:
        command += ["-r", f"__ns:=/{namespace}"]
    for name, value in parameters:
        command += ["-p", f"{name}:={value}"]
    return subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)


def _roadmap(client):
    """The roadmap the client's planner plans on, decoded from the latched
    field and roadmap messages (ready first)."""
    roadmap_msg = client.wait_until_ready(timeout_sec=4 * TIMEOUT)
    got, field_msg = wait_for_message(NSolutionField, client, "field", qos_profile=LATCHED_QOS,
                                      time_to_wait=TIMEOUT)
    if not got:
        raise TimeoutError(f"no field on {client.resolve_topic_name('field')}")
    if field_msg.header.stamp != roadmap_msg.header.stamp:
        raise RuntimeError("the field and the roadmap latched are of two builds")
    return roadmap_from_msgs(field_msg, roadmap_msg)


def _plan_data(response):
    """A plan's waypoints and global paths, as plan_figure and the JSON take them."""
    return {"waypoints": [{"joints": list(p.positions), "pose": list(r.values)}
                          for p, r in zip(response.trajectory.points, response.poses)],
            "global_paths": [list(g.patch_ids) for g in response.global_paths],
            "path_index": response.path_index}


def _save_plan(name, roadmap, data):
    """The plan's JSON and figure in out/, named ``name``."""
    (OUT / f"{name}.json").write_text(json.dumps(data))
    plan_figure(roadmap, data).savefig(OUT / f"{name}.png", dpi=110)
    return f"{name}.png"


def _run_example(name, q1, q2, client, roadmap, figures):
    """Plan from q1 to q2, execute on the driver, print a line and write the
    plan's JSON and figure; returns that data with ``failed`` set if the
    driver failed."""
    begin = time.perf_counter()
    response = client.plan(_configuration(q1), _configuration(q2), max_velocity=2.0,
                           max_acceleration=4.0, timeout_sec=TIMEOUT)
    took = time.perf_counter() - begin
    if not response.success:
        raise RuntimeError(f"{name}: planning failed: {response.error_msg}")
    done = client.reset_driver(_configuration(q1))
    if not done.success:
        raise RuntimeError(f"{name}: driver reset failed: {done.error_msg}")
    feedback = []
    result = client.execute(response.trajectory, feedback.append, timeout_sec=TIMEOUT).result
    points = response.trajectory.points
    duration = points[-1].time_from_start.sec + points[-1].time_from_start.nanosec * 1e-9
    data = _plan_data(response)
    legs = [w["joints"] for w in data["waypoints"]]
    length = sum(math.dist(a, b) for a, b in zip(legs, legs[1:]))
    paths = ", ".join(" -> ".join(map(str, g.patch_ids)) for g in response.global_paths)
    print(f"{name}: global paths [{paths}]; trajectory {len(points)} points, "
          f"{length:.1f} length units of legs, {duration:.1f} s; planned in "
          f"{1e3 * took:.0f} ms; min singularity margin planned "
          f"{response.min_singularity_margin:.4f}, executed "
          f"{result.min_singularity_margin:.4f}; "
          f"driver: {'done' if result.error_code == 0 else result.error_msg} "
          f"({len(feedback)} feedback messages), platform at "
          f"alpha = {math.degrees(result.final_pose.values[2]):.2f} deg")
    figures.append(_save_plan(name, roadmap, data))
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


def _off(values, targets):
    """Largest difference of angles, modulo whole turns [rad]."""
    return max(abs(math.remainder(v - w, 2 * math.pi)) for v, w in zip(values, targets))


def _three_rrr_mode_change(client, figures):
    """Plan the 3-RRR's assembly-mode change through its planner, check the
    trajectory independently, execute it on its driver; 0 when all held."""
    roadmap = _roadmap(client)
    joints, mode_a, mode_b = THREE_RRR
    start, goal = configuration(joints, mode_a), configuration(joints, mode_b)
    begin = time.perf_counter()
    response = client.plan(start, goal, max_velocity=1.0, max_acceleration=2.0,
                           timeout_sec=TIMEOUT)
    took = time.perf_counter() - begin
    if not response.success:
        raise RuntimeError(f"3-RRR: planning failed: {response.error_msg}")
    fixed = ", ".join(f"{n} = {v:g}" for n, v in zip(response.roadmap_fixed_joints,
                                                     response.roadmap_fixed_values))
    data = _plan_data(response)
    path = [w["joints"] for w in data["waypoints"]]
    poses = [w["pose"] for w in data["waypoints"]]
    paths = ", ".join(" -> ".join(map(str, g.patch_ids)) for g in response.global_paths)
    print(f"three_rrr_assembly_mode_change ({fixed}): global paths [{paths}]; trajectory "
          f"{len(path)} points of joints {list(response.trajectory.joint_names)}; planned in "
          f"{1e3 * took:.0f} ms")
    figures.append(_save_plan("three_rrr_assembly_mode_change", roadmap, data))
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
    done = client.reset_driver(start)
    if not done.success:
        raise RuntimeError(f"3-RRR: driver reset failed: {done.error_msg}")
    result = client.execute(response.trajectory, timeout_sec=TIMEOUT).result
    arrived = abs(math.remainder(result.final_pose.values[2] - mode_b, 2 * math.pi)) < 1e-3
    print(f"three_rrr_assembly_mode_change: driver: "
          f"{'done' if result.error_code == 0 else result.error_msg}, min singularity margin "
          f"executed {result.min_singularity_margin:.4f}, platform at alpha = "
          f"{result.final_pose.values[2]:.4f} rad")
    return int(not (ends and validation.ok and sign in ("+", "-") and result.error_code == 0
                    and arrived))


def _five_bar_refusal(client):
    """Ask the five-bar's planner for an assembly-mode change; 0 when it is
    refused as FEASIBILITY_OTHER_ASPECT."""
    joints, plus, minus = FIVE_BAR
    client.wait_until_ready(timeout_sec=2 * TIMEOUT)
    response = client.plan((joints, plus), (joints, minus), timeout_sec=TIMEOUT)
    names = {getattr(PlanPath.Response, n): n for n in dir(PlanPath.Response)
             if n.startswith("FEASIBILITY_")}
    print(f"five_bar_assembly_mode_change: th = {list(joints)}, y = {plus} -> {minus}: "
          f"refused, {names[response.feasibility]}: {response.error_msg}")
    return int(response.success
               or response.feasibility != PlanPath.Response.FEASIBILITY_OTHER_ASPECT)


def _full_roadmap(client):
    """Switch the builder to the full 3-DOF roadmap (first run: a build of
    about 25 s, then the cache) and return it once the planner plans on it."""
    print("switching the builder to the full 3-DOF roadmap (all legs free) ...")
    before = client.roadmap.header.stamp
    switch = client.create_client(SetParameters, "/roadmap_builder/set_parameters")
    if not switch.wait_for_service(timeout_sec=TIMEOUT):
        raise TimeoutError("the builder's parameter service is not available")
    answer = client.wait_for(switch.call_async(SetParameters.Request(
        parameters=[Parameter("full", value=True).to_parameter_msg()])), TIMEOUT,
        what="answer from /roadmap_builder/set_parameters")
    if not answer.results[0].successful:
        raise RuntimeError(f"the builder refused full: {answer.results[0].reason}")
    # The build takes tens of seconds the first time: its progress, which
    # the builder logs, is shown here as it comes.
    relay = client.create_subscription(Log, "/rosout", _builder_progress, 100)
    try:
        client.wait_until_ready(timeout_sec=4 * TIMEOUT, newer_than=before)
    finally:
        client.destroy_subscription(relay)
    return _roadmap(client)


def _builder_progress(entry):
    if entry.name == "roadmap_builder" and entry.msg.startswith("  "):
        print(f"  builder:{entry.msg}", flush=True)


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
    clients = []
    code = 0
    figures = ["field.png", "roadmap.png"]
    try:
        client, rrr_client, five_bar_client = clients = [
            PlannerClient("rpr3_gwr_demo"),
            PlannerClient("rpr3_gwr_demo", namespace="three_rrr"),
            PlannerClient("rpr3_gwr_demo", namespace="five_bar")]
        # The planner takes the roadmap from the same topics, on its own time.
        roadmap = _roadmap(client)
        seg = roadmap.segmentation
        print(f"roadmap received: rho1 = {roadmap.grid.fixed_value(0):g}, "
              f"{seg.n_regions} regions, "
              f"{len(seg.patches)} patches, {len(seg.gates)} gates")
        field_figure(roadmap).savefig(OUT / "field.png", dpi=110)
        roadmap_figure(roadmap).savefig(OUT / "roadmap.png", dpi=110)
        for name, (q1, q2) in EXAMPLES.items():
            data = _run_example(name, q1, q2, client, roadmap, figures)
            code = code or data.pop("failed")
        code = _three_rrr_mode_change(rrr_client, figures) or code
        code = _five_bar_refusal(five_bar_client) or code
        # Stopped before the full 3-DOF roadmap takes both cores.
        code = _stop(others) or code
        roadmap = _full_roadmap(client)
        q1, q2 = FULL_EXAMPLE
        data = _run_example("full_3dof_pocket_rho1_moves", q1, q2, client, roadmap, figures)
        code = code or data.pop("failed")
        rho1 = [w["joints"][0] for w in data["waypoints"]]
        print(f"full_3dof_pocket_rho1_moves: rho1 went from {rho1[0]:g} to between "
              f"{min(rho1):.2f} and {max(rho1):.2f} and back (at fixed rho1 = {q1[0]:g} these "
              f"two modes of the same legs are not connected)")
        if max(rho1) - min(rho1) < 1e-6:
            raise RuntimeError("the full 3-DOF plan kept rho1 fixed, where no path exists")
    finally:
        for client in clients:
            client.destroy_node()
        rclpy.try_shutdown()
        code = _stop(processes + others) or code
        log.close()
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    print(f"bag {bag}: {counts}")
    print(f"figures in {OUT}: " + ", ".join(figures))
    print("all processes stopped" + ("" if code == 0 else " (with errors)"))
    return code


if __name__ == "__main__":
    sys.exit(main())
