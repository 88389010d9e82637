"""Plans computed in worker processes, beside the node's own.

The planner's compiled searches release the interpreter's lock, but its
Python steps (locating the ends, setting up shortcuts and validations,
timing) hold it: requests in several threads of one process take turns
there, and a 2-core machine stayed a quarter idle under 8 clients.  Worker
processes each hold the planner and plan whole requests in parallel; the
node's threads wait for them and convert their plans to messages.

The workers are forked from the node's process once its planner is built,
warmed up (every compiled kernel loaded: a child never needs numba's
compiler lock, which another thread may have held at the fork) and its gate
distances computed, so the children share the roadmap, the distances (copy
on write) and the kernels.  The local planner's own lock is renewed in a
child (:mod:`rpr3_gwr_core.planning.local_planning`), as requests may be
using the planner in the node's threads meanwhile.  Workers never touch ROS.
They ignore SIGINT (the node stops them once its requests are answered) and
end when they find the node's process gone (killed, without a shutdown), so
they do not outlive it holding the roadmap's memory.
"""

import concurrent.futures
import multiprocessing
import os
import signal
import threading
import time
import warnings

__all__ = ["PlanWorkers", "WorkersClosed"]

# How often a worker looks for its node's process [s].
_WATCH_PERIOD = 1.0
# The planner a worker serves, set once when it starts.
_planner = None


class WorkersClosed(Exception):
    """The workers were closed (a newer roadmap replaced their planner)."""


class PlanWorkers:
    """Worker processes planning on one planner.

    Parameters
    ----------
    planner : rpr3_gwr_core.planning.Planner
        Warmed up (:meth:`~rpr3_gwr_core.planning.Planner.warm_up`).
    count : int
        Number of worker processes, 1 at least.
    timeout : float
        Longest wait for a plan [s].
    """

    def __init__(self, planner, count, timeout):
        self.timeout = timeout
        self._pool = concurrent.futures.ProcessPoolExecutor(
            count, mp_context=multiprocessing.get_context("fork"), initializer=_adopt,
            initargs=(planner, os.getpid()))
        with warnings.catch_warnings():
            # Python 3.12 warns of any fork from a threaded process: the
            # module doc says why this one is safe.
            warnings.simplefilter("ignore", DeprecationWarning)
            # The first submission forks every worker, from this thread.
            started = [self._pool.submit(_started) for _ in range(count)]
        try:
            for future in started:
                future.result(timeout)
        except BaseException:
            self._pool.shutdown(wait=False, cancel_futures=True)
            raise

    def plan(self, start, goal, options):
        """``Planner.plan`` in a worker.

        Raises
        ------
        GWRError
            What the planner raises.
        WorkersClosed
            After :meth:`close`.
        concurrent.futures.process.BrokenProcessPool, TimeoutError
            When a worker died, or gave no plan within ``timeout``.
        """
        try:
            future = self._pool.submit(_plan, start, goal, options)
        except RuntimeError as exc:
            if isinstance(exc, concurrent.futures.BrokenExecutor):
                raise
            raise WorkersClosed("the plan workers are closed") from exc
        return future.result(self.timeout)

    def close(self):
        """Stop the workers once the plans asked of them are done; returns at once."""
        self._pool.shutdown(wait=False)


def _adopt(planner, node_process):
    global _planner
    _planner = planner
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    threading.Thread(target=_watch, args=(node_process,), daemon=True).start()


def _watch(node_process):
    # An orphan's parent is another process; its queues would never close,
    # as the workers hold their ends too.
    while os.getppid() == node_process:
        time.sleep(_WATCH_PERIOD)
    os._exit(0)


def _started():
    return True


def _plan(start, goal, options):
    return _planner.plan(start, goal, options)
