"""Memory over roadmap swaps: a builder process rebuilt forty times (rho1
17 <-> 14, the default 401 x 401 grid) and a planner process taking up each
roadmap hold, after the fortieth swap, within 20 % of their resident memory
after the first, and so do the planner's plan workers.  The two causes of
growth found have a test each, without ROS: memory a thread freed that glibc
kept resident in the thread's arena (:mod:`rpr3_gwr_nodes.memory`), and a
planner's error re-raised from a plan worker in a reference cycle that kept
the replaced planner state alive until a full collection."""

import contextlib
import ctypes
import gc
import math
import os
import pathlib
import subprocess
import sys
import textwrap
import time

import pytest
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rpr3_gwr_core.exceptions import GWRError
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.planning import NEVER, CellSearchIndex, PlanOptions
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_nodes.client import PlannerClient, configuration
from rpr3_gwr_nodes.plan_workers import PlanWorkers

from process_tree import children, wait_for_children

LIB = pathlib.Path(__file__).resolve().parents[1] / "ros2_ws" / "install" / "rpr3_gwr_nodes" \
    / "lib" / "rpr3_gwr_nodes"
D = math.radians


def _request(rho1, legs, alphas):
    """The start and the goal of an assembly-mode change."""
    return tuple(configuration([rho1, *legs], D(alpha)) for alpha in alphas)


# An assembly-mode change on each roadmap (the paper's at rho1 = 17): planned
# by the roadmap of its rho1, refused (FIXED_JOINT_MISMATCH) by the other, as a
# client's requests would be while the planner swaps; either answer names
# the roadmap that gave it.
REQUESTS = {17.0: _request(17.0, (20.0, 25.0), (29.47, 96.13)),
            14.0: _request(14.0, (20.0, 25.0), (26.59, 114.27))}
SWAPS = 40
GROWTH = 1.2
TIMEOUT = 120.0


def _rss(pid):
    """Resident memory of a process [MB]."""
    for line in pathlib.Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise AssertionError(f"no VmRSS for process {pid}")


@contextlib.contextmanager
def _process(name, log):
    process = subprocess.Popen([str(LIB / name)], env=os.environ.copy(), stdout=log,
                               stderr=subprocess.STDOUT)
    try:
        yield process
    finally:
        if process.poll() is None:
            process.terminate()
            try:
                process.wait(timeout=30.0)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=30.0)


class _Swapper:
    """Sets the builder's rho1 and waits for the planner to answer from it."""

    def __init__(self, client, planner, log_path):
        self.client = client
        self.planner = planner
        self.log_path = log_path
        self.parameters = AsyncParameterClient(client, "roadmap_builder")
        assert self.parameters.wait_for_services(timeout_sec=TIMEOUT), "no builder"
        self.stamp = None
        self.roadmaps = 0

    def _workers_started(self):
        return self.log_path.read_text().count("plan worker(s) started")

    def swap(self, rho1):
        """Rebuild at ``rho1`` (None: the builder's first roadmap, at 17);
        the pids of the plan workers started with it, once the planner
        planned on it and they are ready."""
        workers = children(self.planner.pid)
        if rho1 is not None:
            result = self.client.wait_for(self.parameters.set_parameters(
                [Parameter("fixed_value", value=rho1)]), TIMEOUT, what="the builder's answer")
            assert result.results[0].successful, result.results[0].reason
        rho1 = 17.0 if rho1 is None else rho1
        deadline = time.monotonic() + TIMEOUT
        # The roadmap rebuilt at rho1, once the planner plans on it.
        self.stamp = self.client.wait_until_ready(timeout_sec=TIMEOUT,
                                                  newer_than=self.stamp).header.stamp
        response = self.client.plan(*REQUESTS[rho1], timeout_sec=TIMEOUT)
        assert response.roadmap_stamp == self.stamp
        assert list(response.roadmap_fixed_values) == [rho1], response.error_msg
        assert response.success, response.error_msg
        # Each roadmap is planned on before the next is built: its workers
        # are the planner's n-th set.
        self.roadmaps += 1
        while self._workers_started() < self.roadmaps:
            assert time.monotonic() < deadline, \
                f"the planner's workers never started: {self.log_path.read_text()[-3000:]}"
            time.sleep(0.05)
        return wait_for_children(os.cpu_count(), earlier=workers, parent=self.planner.pid)


def _settled(pids, seconds=1.0):
    """``{name: RSS [MB]}``, the least of each over ``seconds``: a process
    frees the roadmap it replaced a moment after taking up the new one."""
    least = {}
    deadline = time.monotonic() + seconds
    while True:
        for name, pid in pids.items():
            least[name] = min(least.get(name, math.inf), _rss(pid))
        if time.monotonic() >= deadline:
            return least
        time.sleep(0.1)


@pytest.mark.slow
def test_forty_roadmap_swaps_leave_every_process_within_20_percent(ros_context, tmp_path):
    log_path = tmp_path / "nodes.log"
    client = PlannerClient("swap_client", context=ros_context)
    try:
        with open(log_path, "w") as log, \
                _process("roadmap_builder", log) as builder, \
                _process("planner", log) as planner:
            swapper = _Swapper(client, planner, log_path)
            swapper.swap(None)
            begin = time.monotonic()
            sizes = []
            for k in range(1, SWAPS + 1):
                workers = swapper.swap(14.0 if k % 2 else 17.0)
                if k in (1, SWAPS):
                    assert len(workers) == os.cpu_count(), (workers, log_path.read_text())
                    sizes.append(_settled({
                        "builder": builder.pid, "planner": planner.pid,
                        **{f"plan worker {n}": pid for n, pid in enumerate(sorted(workers))}}))
            print(f"\n{SWAPS} swaps in {time.monotonic() - begin:.1f} s; resident memory "
                  f"[MB] after the first and the last: " + ", ".join(
                      f"{name} {sizes[0][name]:.0f} -> {sizes[1][name]:.0f}"
                      for name in sizes[0]))
    finally:
        client.destroy_node()
    grown = {name: sizes[1][name] / sizes[0][name] for name in sizes[0]}
    assert max(grown.values()) <= GROWTH, (sizes, log_path.read_text()[-3000:])


_FREED_IN_A_THREAD = textwrap.dedent("""
    import ctypes, threading
    from rpr3_gwr_nodes.memory import release_free_memory, use_one_arena

    def resident():
        with open("/proc/self/status") as status:
            return next(int(line.split()[1]) for line in status if line.startswith("VmRSS:"))

    assert use_one_arena()
    libc = ctypes.CDLL(None)
    libc.malloc.argtypes, libc.malloc.restype = (ctypes.c_size_t,), ctypes.c_void_p
    libc.free.argtypes = (ctypes.c_void_p,)

    def build():
        # A freed 20 MiB block raises the mmap threshold to 20 MiB and the
        # trim threshold to 40: the next 32 MiB come from a heap and stay
        # there, freed, as a builder thread's temporaries do.
        libc.free(libc.malloc(20 << 20))
        blocks = [libc.malloc(1 << 20) for _ in range(32)]
        for block in blocks:
            ctypes.memset(block, 1, 1 << 20)
        for block in blocks:
            libc.free(block)

    thread = threading.Thread(target=build)
    thread.start()
    thread.join()
    before = resident()
    release_free_memory()
    print(before - resident())
""")


@pytest.mark.skipif(not hasattr(ctypes.CDLL(None), "malloc_trim"), reason="glibc only")
def test_memory_a_thread_freed_goes_back_to_the_system():
    done = subprocess.run([sys.executable, "-c", _FREED_IN_A_THREAD], capture_output=True,
                          text=True, timeout=60.0)
    assert done.returncode == 0, done.stderr
    # In kB: most of the 32 MiB.
    assert int(done.stdout) >= 24 * 1024, f"only {done.stdout.strip()} kB returned"


def test_a_plan_error_from_a_worker_is_freed_with_its_last_reference(tmp_path):
    roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.5))
    workers = PlanWorkers(roadmap, CellSearchIndex.build(roadmap), 1, TIMEOUT, str(tmp_path))
    wrong_rho1 = ((14.0, 20.0, 25.0, D(29.47)), (14.0, 20.0, 25.0, D(96.13)))
    gc.collect()
    gc.disable()
    gc.set_debug(gc.DEBUG_SAVEALL)
    try:
        with pytest.raises(GWRError):
            workers.plan(*wrong_rho1, PlanOptions(), NEVER)
        gc.collect()
        # Such an error holds the frames of the request, and with them the
        # planner state it was planned on.
        errors = [type(o).__name__ for o in gc.garbage if isinstance(o, BaseException)]
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        gc.enable()
        workers.close()
    assert not errors, f"left to the cyclic collector: {errors}"
