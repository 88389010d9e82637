"""Which plan worker processes another one started, read from /proc (Linux)."""

import os
import pathlib
import time

__all__ = ["children", "wait_for_children", "running"]

_WORKER = b"rpr3_gwr_nodes.plan_workers"


def children(parent=None):
    """Running plan workers (:mod:`rpr3_gwr_nodes.plan_workers`) started by
    ``parent`` (this process by default), as a set of pids."""
    parent = os.getpid() if parent is None else parent
    found = set()
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            if (fields[0] != "Z" and int(fields[1]) == parent
                    and _WORKER in (stat.parent / "cmdline").read_bytes().split(b"\0")):
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
