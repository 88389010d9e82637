"""The suite's nodes as processes, as a user runs them."""

import contextlib
import os
import pathlib
import signal
import subprocess

__all__ = ["LIB", "node_processes", "traced_environment", "exit_status"]

LIB = pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes" \
    / "lib" / "rpr3_gwr_nodes"


@contextlib.contextmanager
def node_processes(folder, nodes, namespace):
    """Run each ``(executable, parameters)`` of ``nodes`` (parameters as
    ``NAME:=VALUE`` strings) in ``namespace``, logging to
    ``folder / "<executable>.log"``; SIGTERM them on exit, SIGKILL those
    still running 30 s later."""
    processes = []
    try:
        for name, parameters in nodes:
            with open(folder / f"{name}.log", "wb") as log:
                processes.append(subprocess.Popen(
                    [str(LIB / name), "--ros-args", "-r", f"__ns:=/{namespace}",
                     *(a for p in parameters for a in ("-p", p))],
                    env=os.environ.copy(), stdout=log, stderr=subprocess.STDOUT))
        yield processes
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=30.0)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=30.0)


def traced_environment():
    """The test's environment, with Python's fault handler on: a process
    that gets SIGABRT prints every thread's traceback before it dies."""
    return dict(os.environ, PYTHONFAULTHANDLER="1")


def exit_status(process, timeout, log):
    """The exit status of ``process`` (started with
    :func:`traced_environment`, its output going to the file ``log``), waited
    for at most ``timeout`` seconds.  One still running then gets SIGABRT,
    and the test fails with its output: where each of its threads waits."""
    try:
        return process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGABRT)
        try:
            process.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=10.0)
        raise AssertionError(f"{process.args[0]} still ran {timeout} s later; its output:\n"
                             + pathlib.Path(log).read_text(errors="replace")) from None
