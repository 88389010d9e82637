"""Find, plan and execute an assembly-mode change of a robot through the nodes.

With the suite running on the robot's file (``suite --mechanism-file FILE``,
or ``ros2 launch``), in another shell of the same ROS_DOMAIN_ID::

    python docs/howto/own_robot/mode_change.py FILE [--joints Q1 Q2 Q3] [--ros-args ...]

It asks the planner for the assembly modes of the joints (the file's home
by default; the first one on the builder's slice), starts from the mode
nearest the home's that a singularity-free path joins to another one,
plans to that one, puts the driver at the start and executes the
trajectory.  Joints are in the file's units
[length unit, or rad].
"""

import argparse
import math
import sys

import rclpy
from rclpy.utilities import remove_ros_args

from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_msgs.msg import AssemblyMode
from rpr3_gwr_nodes.client import PlannerClient

TIMEOUT = 120.0
FEASIBILITY = {getattr(AssemblyMode, name): name[len("FEASIBILITY_"):].lower()
               for name in dir(AssemblyMode) if name.startswith("FEASIBILITY_")}


def _shown(mode):
    joints = ", ".join(f"{v:.6g}" for v in mode.configuration.positions)
    return (f"[{joints}] mode {mode.configuration.mode:.6g} (aspect {mode.aspect:+d}, patch "
            f"{mode.patch}, region {mode.region}: {FEASIBILITY[mode.feasibility]})")


def _change(client, joints, home_mode):
    """Plan and execute the change; the exit status."""
    listed = client.assembly_modes(joints, timeout_sec=TIMEOUT)
    if not listed.success:
        print(f"assembly_modes refused: {listed.error_msg}")
        return 1
    located = [m for m in listed.modes if m.located]
    if not located:
        print("no assembly mode of these joints lies on the roadmap")
        return 1
    located.sort(key=lambda m: abs(math.remainder(m.configuration.mode - home_mode,
                                                  2 * math.pi)))
    for start in located:
        modes = client.assembly_modes(joints, start.configuration.mode,
                                      timeout_sec=TIMEOUT).modes
        reachable = [m for m in modes if m.feasibility in (
            AssemblyMode.FEASIBILITY_SAME_PATCH, AssemblyMode.FEASIBILITY_CONNECTED)]
        if reachable:
            break
    else:
        print("no two assembly modes of these joints are joined without a singularity")
        return 1
    for mode in modes:
        print(_shown(mode))
    goal = reachable[0]
    plan = client.plan(start.configuration, goal.configuration, timeout_sec=TIMEOUT)
    if not plan.success:
        print(f"the plan failed: {plan.error_msg}")
        return 1
    print(f"planned {len(plan.trajectory.points)} points from mode "
          f"{start.configuration.mode:.6g} to {goal.configuration.mode:.6g}")
    reset = client.reset_driver(start.configuration)
    if not reset.success:
        print(f"the driver refused the start: {reset.error_msg}")
        return 1
    done = client.execute(plan.trajectory, timeout_sec=TIMEOUT).result
    pose = ", ".join(f"{name} {value:.6g}"
                     for name, value in zip(done.final_pose.names, done.final_pose.values))
    print(f"executed: error_code {done.error_code} {done.error_msg or '(success)'}; final pose "
          f"{pose}; smallest margin {done.min_singularity_margin:.4g}")
    return 0 if done.error_code == done.SUCCESS else 1


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mechanism_file")
    parser.add_argument("--joints", type=float, nargs="+",
                        help="the joints whose modes to change between (default: the home's)")
    argv = sys.argv if argv is None else argv
    args = parser.parse_args(remove_ros_args(args=argv)[1:])
    home = load_mechanism_file(args.mechanism_file).default_home()
    joints = args.joints or list(home[:-1])
    rclpy.init(args=argv)
    client = PlannerClient()
    try:
        client.wait_until_ready(timeout_sec=TIMEOUT)
        return _change(client, joints, home[-1])
    finally:
        client.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
