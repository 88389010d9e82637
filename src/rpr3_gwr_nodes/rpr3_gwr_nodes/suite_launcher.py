"""Start the suite of launch/suite.launch.py without ros2cli or launch.

With ROS 2 from PyPI wheels there is no ``ros2 launch``.  This program
starts the same nodes as the launch file, each as a process of its own from
the package's executables: the roadmap builder, the planner and the
simulated driver, with ``--record`` the bag recorder and with ``--scene``
the scene publisher.  Each option is the launch argument of the same name
(``--fixed-value`` for ``fixed_value:=``) and, as there, is passed to the
nodes only when given: after ``--ros-args``, the recorder's fixed choices,
then ``--params-file FILE``, then ``-p name:=value`` for each option given,
so an option wins over the file.

Every line a node writes is printed with its name in front.  SIGINT or
SIGTERM is forwarded to every node, which then finishes its work in flight
and exits; a node still running after ``--stop-timeout``, or at a second
signal, is killed with the processes it started.  When a node exits on its
own the others are stopped too, since the suite is incomplete without it.
The exit status is 0 when every node stopped on request, 1 when one exited
with an error or had to be killed.

    ros2_ws/install/rpr3_gwr_nodes/lib/rpr3_gwr_nodes/suite \\
        --mechanism-file config/three_rrr.yaml --params-file config/params/suite.yaml
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time

import yaml

__all__ = ["NODES", "ARGUMENTS", "parameter_value", "main"]

# The launch arguments that are node parameters of the same name: name ->
# (type, help).  Empty, or not given, leaves the parameter to the node (its
# own default, or the params file's value).
ARGUMENTS = {
    "mechanism_file": (str, "mechanism file of the builder, the planner and the driver (YAML, "
                            "as config/*.yaml); the paper's 3-RPR when not given"),
    "fixed_value": (float, "value of the first joint at which the builder's slice fixes it; "
                           "the mechanism file's home when not given [joint unit]"),
    "step": (float, "grid step of the roadmap; the mechanism file's when not given "
                    "[joint unit]"),
    "full": (bool, "build the full roadmap (every joint free) instead of the slice"),
    "initial_configuration": (list, "the driver's start: joints then mode coordinate; the "
                                    "mechanism file's home when not given [joint unit, mode "
                                    "unit]"),
    "time_scale": (float, "playback speed factor of the simulated driver"),
    "bag_path": (str, "directory of the bag the recorder writes (must not exist)"),
    "scene_file": (str, "scene the scene publisher publishes (YAML, as config/scenes/*.yaml)"),
}

# The suite: executable (also the node's name), the switch that starts it
# (None: always started), the ARGUMENTS it takes, and the parameters it
# always gets, below the params file (the suite records to MCAP with
# everything).  The launch file starts the nodes of this table too.
NODES = (
    ("roadmap_builder", None, ("mechanism_file", "fixed_value", "step", "full"), {}),
    ("planner", None, ("mechanism_file",), {}),
    ("rpr3_driver", None, ("mechanism_file", "initial_configuration", "time_scale"), {}),
    ("trajectory_recorder", "record", ("bag_path",),
     {"storage": "mcap", "record_joint_states": True, "record_visualization": True}),
    ("scene_publisher", "scene", ("scene_file",), {}),
)

# Exit status of a node that stopped on request: spin.run returns normally.
_STOPPED = 0
# Longest wait for the nodes to exit after a stop signal [s]: the planner
# finishes its callbacks in flight first, which on the full 3-DOF roadmap
# can be the build of its planning index, tens of seconds on a loaded
# machine.
_STOP_TIMEOUT = 60.0
# How often the nodes and the stop request are looked at [s].
_POLL_PERIOD = 0.1
# Longest wait for a node's last lines once it has exited [s]: the processes
# it started hold its output open until they end.
_OUTPUT_TIMEOUT = 5.0


def parameter_value(name, text):
    """The value of ARGUMENTS' ``name`` from the text of a launch argument
    (``"13"``, ``"true"``, ``"[0.0, 1.2, 2.25, 0.65]"``), typed as its node
    declares it."""
    kind = ARGUMENTS[name][0]
    if kind is bool:
        return {"true": True, "false": False}[text.strip().lower()]
    if kind is list:
        values = yaml.safe_load(text)
        return [float(v) for v in (values if isinstance(values, list) else [values])]
    return kind(text)


def _command(executable, lib, fixed, params_file, given):
    """The command line of a node: its ``fixed`` parameters, the params
    file, then the options ``given``, each later one winning (values as
    JSON, which is YAML: a path stays a string, 13.0 a double)."""
    command = [os.path.join(lib, executable), "--ros-args"]
    for name, value in fixed.items():
        command += ["-p", f"{name}:={json.dumps(value)}"]
    if params_file:
        command += ["--params-file", params_file]
    for name, value in given.items():
        command += ["-p", f"{name}:={json.dumps(value)}"]
    return command


# The nodes' lines and the launcher's own are printed whole, one at a time.
_PRINTING = threading.Lock()


def _print(name, line):
    """Print ``line`` (bytes, ending in a newline) with ``name`` in front."""
    with _PRINTING:
        sys.stdout.buffer.write(f"[{name}] ".encode() + line)
        sys.stdout.buffer.flush()


def _forward_output(name, stream):
    """Print each line of ``stream`` with ``name`` in front, until it ends."""
    for line in iter(stream.readline, b""):
        _print(name, line)
    stream.close()


def _parser():
    parser = argparse.ArgumentParser(
        prog="suite", description=__doc__.split("\n\n    ")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="example: suite --mechanism-file config/three_rrr.yaml "
               "--params-file config/params/suite.yaml --record --time-scale 10")
    for name, (kind, text) in ARGUMENTS.items():
        option = "--" + name.replace("_", "-")
        if kind is bool:
            parser.add_argument(option, action="store_const", const=True, help=text)
        elif kind is list:
            parser.add_argument(option, nargs="+", type=float, metavar="VALUE", help=text)
        else:
            parser.add_argument(option, type=kind, metavar=name.split("_")[-1].upper(),
                                help=text)
    parser.add_argument("--params-file", metavar="FILE",
                        help="ROS parameter file (YAML, a section per node, as "
                             "config/params/suite.yaml) applied to every node")
    parser.add_argument("--record", action="store_true", help="also start the bag recorder")
    parser.add_argument("--scene", action="store_true", help="also start the scene publisher")
    parser.add_argument("--stop-timeout", type=float, default=_STOP_TIMEOUT, metavar="SECONDS",
                        help="longest wait for the nodes to exit after SIGINT or SIGTERM "
                             "before they are killed (default %(default)g)")
    return parser


def _lib():
    """The package's directory of executables, where this script is too."""
    from ament_index_python.packages import get_package_prefix

    return os.path.join(get_package_prefix("rpr3_gwr_nodes"), "lib", "rpr3_gwr_nodes")


def _stop(processes, number, timeout, hurry):
    """Send signal ``number`` to each node still running, wait up to
    ``timeout`` [s] or until ``hurry()``, then kill the process group of each
    left; the names of those killed."""
    for process in processes.values():
        if process.poll() is None:
            process.send_signal(number)
    deadline = time.monotonic() + timeout
    while (any(p.poll() is None for p in processes.values())
           and time.monotonic() < deadline and not hurry()):
        time.sleep(_POLL_PERIOD)
    killed = [name for name, process in processes.items() if process.poll() is None]
    for name in killed:
        # The group: a planner's plan workers go with it.
        os.killpg(processes[name].pid, signal.SIGKILL)
        processes[name].wait()
    return killed


def main(args=None):
    options = _parser().parse_args(args)
    lib = _lib()
    requested = []
    # Signals are only recorded here: the main loop forwards them, outside
    # any call the handler could interrupt.
    previous = {number: signal.signal(number, lambda number, _: requested.append(number))
                for number in (signal.SIGINT, signal.SIGTERM)}
    # Python nodes buffer a pipe's output; unbuffered, each line comes as written.
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    processes, readers = {}, []
    status = 0
    try:
        for executable, switch, arguments, fixed in NODES:
            if switch and not getattr(options, switch):
                continue
            given = {name: getattr(options, name) for name in arguments
                     if getattr(options, name) is not None}
            command = _command(executable, lib, fixed, options.params_file, given)
            # A group of its own: a terminal's Ctrl-C reaches the launcher
            # only, which forwards it once, and a kill takes the node's own
            # processes with it.
            process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                       stderr=subprocess.STDOUT, env=env, process_group=0)
            processes[executable] = process
            reader = threading.Thread(target=_forward_output,
                                      args=(executable, process.stdout), daemon=True)
            reader.start()
            readers.append(reader)
        _print("suite", f"started {', '.join(processes)}; Ctrl-C stops them\n".encode())
        ended = {}
        while not requested and not ended:
            time.sleep(_POLL_PERIOD)
            ended = {n: p.returncode for n, p in processes.items() if p.poll() is not None}
        for name, code in ended.items():
            _print("suite", f"{name} exited on its own with status {code}\n".encode())
            status = max(status, int(code != 0))
        # A node that ended alone leaves the suite incomplete: the others stop
        # as on Ctrl-C.  A second signal meanwhile kills them at once.
        signals = len(requested)
        killed = _stop(processes, requested[0] if requested else signal.SIGINT,
                       options.stop_timeout, lambda: len(requested) > signals)
        for name in killed:
            _print("suite", f"{name} did not stop: killed\n".encode())
            status = 1
        for name, process in processes.items():
            if name not in ended and name not in killed and process.returncode != _STOPPED:
                _print("suite", f"{name} exited with status {process.returncode}\n".encode())
                status = 1
    finally:
        for process in processes.values():
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        for reader in readers:
            reader.join(timeout=_OUTPUT_TIMEOUT)
        for number, handler in previous.items():
            signal.signal(number, handler)
    return status


if __name__ == "__main__":
    sys.exit(main())
