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

Each worker has pipes of its own and is handed one request at a time: with a
task queue shared by all of them, a worker stopped (SIGSTOP, a debugger)
while reading it kept the queue's lock and stalled every other worker.  Its
answer is read as it arrives, length first, so that a worker stopped halfway
through writing it is found hung like any other.  A worker is hung when its
heartbeat, stamped by a thread of its own, is older than a few seconds: a
stopped or dead process's threads stamp nothing, while a busy worker's thread
goes on stamping however long its plan takes (the compiled searches release
the interpreter's lock), so a long plan is not taken for a hang.  A hung
worker is killed (SIGKILL ends a stopped process too), its request is given
back to the caller to plan, and the other workers go on.  It is not replaced:
what made it fail (a signal, a lack of memory, a bug) may fail a new one as
well; the next roadmap forks a full set.
"""

import collections
import math
import mmap
import multiprocessing
import os
import pickle
import select
import signal
import struct
import threading
import time
import warnings

from rpr3_gwr_core.exceptions import PlanningTimeoutError

__all__ = ["PlanWorkers", "WorkerFailed", "WorkersClosed"]

# How often a worker stamps its heartbeat, and looks for its node's process
# [s]; how often a caller looks at the heartbeat of the worker it waits for.
_BEAT_PERIOD = 0.1
# Age of the last heartbeat that makes a worker hung [s]: many periods, as
# a loaded machine may not run the heartbeat's thread for a while.
_HANG_AFTER = 2.0
# An answer's length ahead of it on the answer pipe, and the most read at once.
_LENGTH = struct.Struct("<Q")
_STAMP = struct.Struct("d")
_CHUNK = 1 << 20


class WorkersClosed(Exception):
    """The workers were closed (a newer roadmap replaced their planner, or
    every worker failed)."""


class WorkerFailed(Exception):
    """The worker planning a request hung or died: it was killed, and the
    request was not planned."""


class PlanWorkers:
    """Worker processes planning on one planner.

    Parameters
    ----------
    planner : rpr3_gwr_core.planning.Planner
        Warmed up (:meth:`~rpr3_gwr_core.planning.Planner.warm_up`).
    count : int
        Number of worker processes, 1 at least.
    timeout : float
        Longest wait for a plan from a worker that keeps its heartbeat [s].
    """

    def __init__(self, planner, count, timeout):
        self.timeout = timeout
        self._changed = threading.Condition()
        self._idle = collections.deque()
        self._closed = False
        context = multiprocessing.get_context("fork")
        try:
            with warnings.catch_warnings():
                # Python 3.12 warns of any fork from a threaded process: the
                # module doc says why this one is safe.
                warnings.simplefilter("ignore", DeprecationWarning)
                for _ in range(count):
                    self._idle.append(_Worker(context, planner))
        except BaseException:
            self.close()
            raise
        self._count = count

    @property
    def count(self):
        """Workers not killed."""
        return self._count

    def plan(self, start, goal, options, termination):
        """``Planner.plan`` in an idle worker, once there is one.

        Raises
        ------
        GWRError
            What the planner raises; ``PlanningTimeoutError`` also when no
            worker is idle before ``termination``'s deadline.
        WorkersClosed
            After :meth:`close`, or once every worker failed.
        WorkerFailed
            When the worker hung, died, or gave no plan within ``timeout``.
        """
        worker = self._take(termination)
        try:
            worker.send((start, goal, options, termination))
            planned, answer = worker.receive(self.timeout)
        except (OSError, EOFError, WorkerFailed) as exc:
            self._retire(worker)
            if isinstance(exc, WorkerFailed):
                raise
            raise WorkerFailed(f"plan worker {worker.pid} died") from exc
        self._give_back(worker)
        if planned:
            return answer
        try:
            raise answer
        finally:
            # The error's traceback holds this frame: without this frame's
            # reference to the error, no cycle keeps the request's planner
            # state alive until a full collection.
            del answer

    def close(self):
        """Stop the workers once the plans asked of them are done; returns at once."""
        with self._changed:
            self._closed = True
            idle, self._idle = list(self._idle), collections.deque()
            self._changed.notify_all()
        for worker in idle:
            worker.kill()

    def _take(self, termination):
        with self._changed:
            while not self._idle:
                if self._closed:
                    raise WorkersClosed("the plan workers are closed")
                if termination():
                    raise PlanningTimeoutError("the time limit passed before a plan worker "
                                               "was free")
                remaining = termination.remaining()
                self._changed.wait(None if math.isinf(remaining) else remaining)
            return self._idle.popleft()

    def _give_back(self, worker):
        with self._changed:
            if not self._closed:
                self._idle.append(worker)
                self._changed.notify()
                return
        worker.kill()

    def _retire(self, worker):
        worker.kill()
        with self._changed:
            self._count -= 1
            if not self._count:
                self._closed = True
            self._changed.notify_all()


class _Worker:
    """A worker process, the node's end of its pipe and its heartbeat."""

    def __init__(self, context, planner):
        # A time.monotonic() stamp in a mapping of this worker's own: a
        # block of multiprocessing's shared heap, freed with an earlier
        # worker, could be handed out again while a process forked from it
        # still stamps it.
        self.beat = mmap.mmap(-1, _STAMP.size)
        _STAMP.pack_into(self.beat, 0, time.monotonic())
        # Requests go down a pipe, answers come up another, read as they
        # arrive: a worker stopped halfway through writing a large answer
        # would leave a blocking read waiting for its end for ever.
        requests, self.requests = context.Pipe(duplex=False)
        self.answers, answering = os.pipe()
        self.process = context.Process(target=_serve, daemon=True,
                                       args=(planner, requests, answering, self.beat,
                                             os.getpid()))
        self.process.start()
        self.pid = self.process.pid
        requests.close()
        os.close(answering)

    def send(self, request):
        self.requests.send(request)

    def receive(self, timeout):
        """The worker's answer: ``(True, plan)`` or ``(False, exception)``."""
        deadline = time.monotonic() + timeout
        received = bytearray()
        size = None
        while size is None or len(received) < _LENGTH.size + size:
            if not select.select([self.answers], [], [], _BEAT_PERIOD)[0]:
                silent = time.monotonic() - _STAMP.unpack_from(self.beat)[0]
                if silent > _HANG_AFTER:
                    raise WorkerFailed(f"plan worker {self.pid} hung (stopped or dead): no "
                                       f"heartbeat for {silent:.1f} s")
                if time.monotonic() > deadline:
                    raise WorkerFailed(f"plan worker {self.pid} gave no plan within "
                                       f"{timeout:g} s")
                continue
            chunk = os.read(self.answers, _CHUNK)
            if not chunk:
                raise WorkerFailed(f"plan worker {self.pid} died")
            received += chunk
            if size is None and len(received) >= _LENGTH.size:
                (size,) = _LENGTH.unpack_from(received)
        return pickle.loads(received[_LENGTH.size:])

    def kill(self):
        self.process.kill()
        self.process.join()
        self.requests.close()
        os.close(self.answers)
        self.beat.close()


def _serve(planner, requests, answers, beat, node_process):
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    threading.Thread(target=_beat, args=(beat, node_process), daemon=True).start()
    while True:
        try:
            start, goal, options, termination = requests.recv()
        except EOFError:
            return
        try:
            answer = True, planner.plan(start, goal, options, termination)
        except Exception as exc:  # the caller raises it
            answer = False, exc
        data = pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
        view = memoryview(_LENGTH.pack(len(data)) + data)
        while view:
            view = view[os.write(answers, view):]


def _beat(beat, node_process):
    # An orphan's parent is another process; its pipe would never close,
    # as the other workers may hold copies of its end.
    while os.getppid() == node_process:
        _STAMP.pack_into(beat, 0, time.monotonic())
        time.sleep(_BEAT_PERIOD)
    os._exit(0)
