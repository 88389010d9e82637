"""Which processes another one forked, read from /proc (Linux)."""

import os
import pathlib
import time

__all__ = ["children", "wait_for_children", "running"]


def children(parent=None):
    """Running processes forked by ``parent`` (this process by default) that
    run its program (the planner's plan workers), as a set of pids."""
    parent = os.getpid() if parent is None else parent
    try:
        program = pathlib.Path(f"/proc/{parent}/cmdline").read_bytes()
    except OSError:
        return set()
    found = set()
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            if (fields[0] != "Z" and int(fields[1]) == parent
                    and (stat.parent / "cmdline").read_bytes() == program):
                found.add(int(stat.parent.name))
        except (OSError, ValueError, IndexError):
            continue  # a process that ended meanwhile
    return found


def wait_for_children(count, earlier=frozenset(), parent=None, timeout=30.0):
    """:func:`children` not in ``earlier``, once there are ``count`` of them,
    or after ``timeout`` [s]."""
    deadline = time.monotonic() + timeout
    while len(children(parent) - earlier) < count and time.monotonic() < deadline:
        time.sleep(0.05)
    return children(parent) - set(earlier)


def running(pid):
    """Whether a process runs (not ended, not a zombie)."""
    try:
        return pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
