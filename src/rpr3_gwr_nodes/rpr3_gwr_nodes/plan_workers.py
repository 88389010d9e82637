"""Plans computed in worker processes, beside the node's own.

The planner's compiled searches release the interpreter's lock, but its
Python steps (locating the ends, setting up shortcuts and validations,
timing) hold it: requests in several threads of one process take turns
there, and a 2-core machine stayed a quarter idle under 8 clients.  Worker
processes each hold a planner and plan whole requests in parallel; the
node's threads wait for them and convert their plans to messages.

The roadmap and its planning index (gate distances included) are written
once to a folder of the node's own, and the node and every worker map those
files (:func:`rpr3_gwr_core.io.cache.map_planning_files`), so they share one
copy of their pages.  Workers are started as new interpreters
(``python -m rpr3_gwr_nodes.plan_workers``), never forked from the node: a
fork would copy its DDS threads' sockets and the state of locks other
threads held.  A worker loads its planner from the folder, warms it up
(every compiled kernel loaded) and says it is ready; the node waits for all
of them.  Workers never touch ROS.  They ignore SIGINT (the node stops them
once its requests are answered) and end when they find the node's process
gone (killed, without a shutdown), so they do not outlive it holding the
roadmap's memory.  The folder is removed when the workers are closed; one
left by a killed node is removed by the next node that starts workers.

A scene is applied in every worker (:meth:`PlanWorkers.apply_scene`) before
requests in it go to the workers; each worker keeps the latest scene it was
given, restricted to its roadmap, and the index every scene reads for a
body model (the costly part, computed once per worker and roadmap).

Each worker has pipes of its own and is handed one request at a time: with a
task queue shared by all of them, a worker stopped (SIGSTOP, a debugger)
while reading it kept the queue's lock and stalled every other worker.
Messages go as pickles, each behind its length; answers are read as they
arrive, so that a worker stopped halfway through writing one is found hung
like any other.  A worker is hung when its heartbeat, stamped by a thread of
its own into a file of the folder that both map, is older than a few
seconds: a stopped or dead process's threads stamp nothing, while a busy
worker's thread goes on stamping however long its plan takes (the compiled
searches release the interpreter's lock), so a long plan is not taken for a
hang (while a worker starts, loading compiled kernels can hold the
interpreter's lock for seconds: the heartbeat may then be older).  A hung
worker is killed (SIGKILL ends a stopped process too), its
request is given back to the caller to plan, and the other workers go on.
It is not replaced: what made it fail (a signal, a lack of memory, a bug) may
fail a new one as well; the next roadmap starts a full set.
"""

import collections
import math
import mmap
import os
import pickle
import re
import select
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import threading
import time

from rpr3_gwr_core.exceptions import PlanningTimeoutError

from .core_threads import core_threads

__all__ = ["PlanWorkers", "WorkerFailed", "WorkersClosed"]

# How often a worker stamps its heartbeat, and looks for its node's process
# [s]; how often a caller looks at the heartbeat of the worker it waits for.
_BEAT_PERIOD = 0.1
# Age of the last heartbeat that makes a worker hung [s]: many periods, as
# a loaded machine may not run the heartbeat's thread for a while.
_HANG_AFTER = 2.0
# The same while a worker starts (module doc).
_START_HANG_AFTER = 30.0
# The scene key of workers taking a new scene: no request matches it.
_APPLYING = object()
# A message's length ahead of it on a pipe, and the most read at once.
_LENGTH = struct.Struct("<Q")
_STAMP = struct.Struct("d")
_CHUNK = 1 << 20
# A node's folder of planning files: ``planner-<pid>-<random>``.
_FOLDER = re.compile(r"planner-(\d+)-[^/]+")


class WorkersClosed(Exception):
    """The workers were closed (a newer roadmap replaced their planner, or
    every worker failed)."""


class WorkerFailed(Exception):
    """The worker planning a request hung or died: it was killed, and the
    request was not planned."""


class PlanWorkers:
    """Worker processes planning on one roadmap, and the node's planner on
    the same mapped files.

    Parameters
    ----------
    roadmap : Roadmap
    index : CellSearchIndex
        The roadmap's, with the gate distances of the clearances the node
        plans with.
    count : int
        Number of worker processes, 1 at least.
    timeout : float
        Longest wait for a worker to start, or for a plan from a worker
        that keeps its heartbeat [s].
    directory : str
        Where the folder of planning files is made.
    **planner_options
        Keyword arguments of :class:`~rpr3_gwr_core.planning.Planner`
        (``retries``, ``min_margin``, ...), the same in every process.

    Attributes
    ----------
    planner : Planner
        On the mapped files, warmed up: the node's own.
    scene_key : object
        The key of the scene the workers plan in (None: no scene).
    """

    def __init__(self, roadmap, index, count, timeout, directory, **planner_options):
        from rpr3_gwr_core.io.cache import map_planning_files, save_planning_files
        from rpr3_gwr_core.planning import Planner

        self.timeout = timeout
        self._changed = threading.Condition()
        self._idle = collections.deque()
        self._closed = False
        self._count = count
        self.scene_key = None
        os.makedirs(directory, exist_ok=True)
        _remove_orphans(directory)
        self.folder = tempfile.mkdtemp(prefix=f"planner-{os.getpid()}-", dir=directory)
        try:
            save_planning_files(self.folder, roadmap, index)
            with core_threads() as pool:
                mapped = map_planning_files(self.folder, workers=pool.map)
            self.planner = Planner(*mapped, **planner_options)
            self.planner.warm_up()
            started = [_Worker(self.folder, k, planner_options) for k in range(count)]
            self._idle.extend(started)
            failures = []
            for worker in started:
                try:
                    worker.wait_ready(timeout)
                except WorkerFailed as exc:
                    failures.append(str(exc))
                    self._retire(worker)
            if not self._count:
                raise WorkerFailed("; ".join(failures))
        except BaseException:
            self.close()
            raise

    @property
    def count(self):
        """Workers not killed."""
        return self._count

    def plan(self, start, goal, options, termination, scene_key=None):
        """``Planner.plan`` in an idle worker, once there is one.

        Parameters
        ----------
        start, goal, options, termination
            As :meth:`~rpr3_gwr_core.planning.Planner.plan`'s.
        scene_key : object, optional
            The key of the scene to plan in, last given to
            :meth:`apply_scene` (None: no scene).

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
        if scene_key != self.scene_key:
            raise WorkersClosed("the plan workers have another scene, or are taking one")
        planned, answer = self._ask(self._take(termination),
                                    ("plan", scene_key, start, goal, options, termination))
        if planned is None:
            raise WorkersClosed("the plan workers took another scene meanwhile")
        if planned:
            return answer
        try:
            raise answer
        finally:
            # The error's traceback holds this frame: without this frame's
            # reference to the error, no cycle keeps the request's planner
            # state alive until a full collection.
            del answer

    def apply_scene(self, key, scene, model):
        """Apply a scene in every worker, and plan in it from then on; until
        every worker has it, :meth:`plan` raises ``WorkersClosed``.

        Parameters
        ----------
        key : object
            Names the scene for :meth:`plan` (picklable, not None).
        scene : Scene or None
            None: plan without a scene.
        model : BodyModel
            Widths and layers of the mechanism's bodies.

        Raises
        ------
        GWRError
            What ``Planner.apply_scene`` raises in a worker.
        WorkersClosed
            After :meth:`close`, or once every worker failed.
        WorkerFailed
            When a worker hung or died applying it.
        """
        self.scene_key = _APPLYING
        # Every worker is taken, as each comes free, and they apply the
        # scene at once: each first indexes the body model, seconds on a
        # full roadmap.
        taken = []
        with self._changed:
            while len(taken) < self._count and not self._closed:
                if self._idle:
                    taken.append(self._idle.popleft())
                else:
                    self._changed.wait()
        if self._closed:
            for worker in taken:
                self._give_back(worker)
            raise WorkersClosed("the plan workers are closed")
        failure = None
        for worker in taken:
            try:
                self._send(worker, ("scene", key, scene, model))
            except WorkerFailed as exc:
                failure = failure or exc
                taken.remove(worker)
        for worker in taken:
            try:
                applied, error = self._receive(worker, self.timeout, _START_HANG_AFTER)
            except WorkerFailed as exc:
                failure = failure or exc
                continue
            self._give_back(worker)
            failure = failure or (None if applied else error)
        if failure is not None:
            raise failure
        self.scene_key = key if scene is not None else None

    def close(self):
        """Stop the workers once the plans asked of them are done, and remove
        the folder (the node's planner and busy workers keep their
        mappings); returns at once."""
        with self._changed:
            self._closed = True
            idle, self._idle = list(self._idle), collections.deque()
            self._changed.notify_all()
        for worker in idle:
            worker.kill()
        shutil.rmtree(self.folder, ignore_errors=True)

    def _ask(self, worker, message):
        """Send a worker a message and wait for its answer; the worker goes
        back to the idle ones, or is retired when it failed."""
        self._send(worker, message)
        answer = self._receive(worker, self.timeout)
        self._give_back(worker)
        return answer

    def _send(self, worker, message):
        try:
            worker.send(message)
        except OSError as exc:
            self._retire(worker)
            raise WorkerFailed(f"plan worker {worker.pid} died") from exc

    def _receive(self, worker, timeout, hang_after=_HANG_AFTER):
        try:
            return worker.receive(timeout, hang_after)
        except (OSError, EOFError, WorkerFailed) as exc:
            self._retire(worker)
            if isinstance(exc, WorkerFailed):
                raise
            raise WorkerFailed(f"plan worker {worker.pid} died") from exc

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
            if worker in self._idle:
                self._idle.remove(worker)
            self._count -= 1
            if not self._count:
                self._closed = True
            self._changed.notify_all()


def _remove_orphans(directory):
    """Remove the planning folders of nodes no longer running."""
    for name in os.listdir(directory):
        match = _FOLDER.fullmatch(name)
        if match and not os.path.exists(f"/proc/{match.group(1)}"):
            shutil.rmtree(os.path.join(directory, name), ignore_errors=True)


class _Worker:
    """A worker process, the node's ends of its pipes and its heartbeat."""

    def __init__(self, folder, number, planner_options):
        beat_file = os.path.join(folder, f"beat-{number}")
        with open(beat_file, "wb") as stream:
            stream.write(_STAMP.pack(time.monotonic()))
        with open(beat_file, "r+b") as stream:
            self.beat = mmap.mmap(stream.fileno(), _STAMP.size)
        # Requests go down a pipe, answers come up another, read as they
        # arrive: a worker stopped halfway through writing a large answer
        # would leave a blocking read waiting for its end for ever.
        requests, self.requests = os.pipe()
        self.answers, answering = os.pipe()
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-m", __name__, str(requests), str(answering), beat_file,
                 str(os.getpid())],
                pass_fds=(requests, answering), stdin=subprocess.DEVNULL,
                env=dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p)))
        finally:
            os.close(requests)
            os.close(answering)
        self.pid = self.process.pid
        self.send((folder, planner_options))

    def wait_ready(self, timeout):
        """Wait until the worker has loaded and warmed up its planner.

        Raises
        ------
        WorkerFailed
            If it hung, died, failed or took longer than ``timeout`` [s].
        """
        # Loading numba's kernels can hold the interpreter's lock, and so
        # stop the heartbeat, for seconds.
        ready, error = self.receive(timeout, hang_after=_START_HANG_AFTER)
        if not ready:
            raise WorkerFailed(f"plan worker {self.pid} could not load its planner: {error!r}")

    def send(self, message):
        _write(self.requests, message)

    def receive(self, timeout, hang_after=_HANG_AFTER):
        """The worker's answer: ``(True, plan)`` or ``(False, exception)``;
        the worker is hung when its heartbeat is older than ``hang_after`` [s]."""
        deadline = time.monotonic() + timeout
        received = bytearray()
        size = None
        while size is None or len(received) < _LENGTH.size + size:
            if not select.select([self.answers], [], [], _BEAT_PERIOD)[0]:
                silent = time.monotonic() - _STAMP.unpack_from(self.beat)[0]
                if silent > hang_after:
                    raise WorkerFailed(f"plan worker {self.pid} hung (stopped or dead): no "
                                       f"heartbeat for {silent:.1f} s")
                if time.monotonic() > deadline:
                    raise WorkerFailed(f"plan worker {self.pid} gave no answer within "
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
        self.process.wait()
        os.close(self.requests)
        os.close(self.answers)
        self.beat.close()


def _write(fd, message):
    data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(_LENGTH.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _read_exactly(fd, size):
    """``size`` bytes from a pipe, or None at its end."""
    data = bytearray()
    while len(data) < size:
        chunk = os.read(fd, size - len(data))
        if not chunk:
            return None
        data += chunk
    return data


def _serve(requests, answers, beat_file, node_process):
    """A worker's life: load the planner the first message names, say so,
    then answer requests until the node closes the pipe."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with open(beat_file, "r+b") as stream:
        beat = mmap.mmap(stream.fileno(), _STAMP.size)
    threading.Thread(target=_beat, args=(beat, node_process), daemon=True).start()
    planner = None
    scene_key, world = None, None
    while True:
        length = _read_exactly(requests, _LENGTH.size)
        if length is None:
            return
        message = pickle.loads(_read_exactly(requests, _LENGTH.unpack(length)[0]))
        try:
            if planner is None:
                planner = _load_planner(*message)
                answer = True, None
            elif message[0] == "scene":
                _, key, scene, model = message
                scene_key, world = None, None
                if scene is not None:
                    world = planner.apply_scene(scene, model)
                    scene_key = key
                answer = True, None
            elif message[1] != scene_key:
                # Sent before a newer scene came: the caller plans it.
                answer = None, None
            else:
                answer = True, planner.plan(*message[2:], world=world)
        except Exception as exc:  # the caller raises it
            answer = False, exc
        _write(answers, answer)


def _load_planner(folder, planner_options):
    from rpr3_gwr_core.io.cache import map_planning_files
    from rpr3_gwr_core.planning import Planner

    planner = Planner(*map_planning_files(folder), **planner_options)
    planner.warm_up()
    return planner


def _beat(beat, node_process):
    # An orphan's parent is another process (init): the node was killed.
    while os.getppid() == node_process:
        _STAMP.pack_into(beat, 0, time.monotonic())
        time.sleep(_BEAT_PERIOD)
    os._exit(0)


if __name__ == "__main__":
    _serve(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], int(sys.argv[4]))
