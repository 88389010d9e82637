"""Plans computed in worker processes, beside the node's own.

The planner's compiled searches release the interpreter's lock, but its
Python steps (locating the ends, setting up shortcuts and validations,
timing) hold it: requests in several threads of one process take turns
there, and a 2-core machine stayed a quarter idle under 8 clients.  Worker
processes each hold the planner and plan whole requests in parallel; the
node's threads wait for them and convert their plans to messages.

The workers are forked from the node's process once its planner is built,
warmed up and prepared, by the thread that built it and before any other
thread uses that planner, so none of its locks can be held in a child, and
the children share the roadmap (copy on write) and the compiled kernels.
They never touch ROS.  They ignore SIGINT (the node stops them) and are sent
SIGTERM when the thread that forked them ends (``PR_SET_PDEATHSIG``), so
they do not outlive a node that is killed.
"""

import concurrent.futures
import ctypes
import multiprocessing
import signal
import warnings

__all__ = ["PlanWorkers", "WorkersClosed"]

_PR_SET_PDEATHSIG = 1
# The planner a worker serves, set once when it starts.
_planner = None


class WorkersClosed(Exception):
    """The workers were closed (a newer roadmap replaced their planner)."""


class PlanWorkers:
    """Worker processes planning on one planner.

    Parameters
    ----------
    planner : rpr3_gwr_core.planning.Planner
        Built and warmed up, used by no other thread while this forks.
    count : int
        Number of worker processes, 1 at least.
    timeout : float
        Longest wait for a plan [s].
    """

    def __init__(self, planner, count, timeout):
        self.timeout = timeout
        self._pool = concurrent.futures.ProcessPoolExecutor(
            count, mp_context=multiprocessing.get_context("fork"), initializer=_adopt,
            initargs=(planner,))
        with warnings.catch_warnings():
            # Python 3.12 warns of any fork from a threaded process: the
            # module doc says why this one is safe.
            warnings.simplefilter("ignore", DeprecationWarning)
            # The first submission forks every worker, from this thread.
            started = [self._pool.submit(_started) for _ in range(count)]
        for future in started:
            future.result(timeout)

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


def _adopt(planner):
    global _planner
    _planner = planner
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
    except (OSError, AttributeError):
        pass  # not Linux: the workers end with the pool's shutdown only


def _started():
    return True


def _plan(start, goal, options):
    return _planner.plan(start, goal, options)
