"""A MultiThreadedExecutor that takes work only when a thread can start it.

rclpy 7.1 before 7.1.9 (the PyPI wheels) hands every ready callback to its
thread pool at once, and yields a task the pool has queued but not started
again on each turn of its loop (ros2/rclpy#1452, fixed upstream by #1469,
backported to Jazzy in 7.1.9): while all the threads are busy, the spinning
thread loops without waiting and holds the interpreter's lock most of the
time, so the callbacks it is waiting for run many times slower.  A
:class:`BoundedExecutor` waits for a free thread
before it looks for work, so the callbacks that cannot start yet wait where
they arrived (a request in its service's reader, its reception time kept)
and the spinning thread sleeps meanwhile.  With a fixed rclpy it changes
nothing but that wait.
"""

import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor

from rclpy.executors import MultiThreadedExecutor

__all__ = ["BoundedExecutor"]


class _CountedPool(ThreadPoolExecutor):
    """A thread pool that counts the callables it holds, queued or running."""

    def __init__(self, max_workers):
        super().__init__(max_workers)
        self.size = max_workers
        self.held = 0
        self.changed = threading.Condition()

    def submit(self, fn, /, *args, **kwargs):
        with self.changed:
            self.held += 1
        try:
            future = super().submit(fn, *args, **kwargs)
        except BaseException:
            self._release()
            raise
        future.add_done_callback(lambda _: self._release())
        return future

    def _release(self):
        with self.changed:
            self.held -= 1
            self.changed.notify_all()


class BoundedExecutor(MultiThreadedExecutor):
    """A MultiThreadedExecutor whose ``spin_once`` first waits, within its
    timeout, for one of its ``num_threads`` threads to be free.

    Parameters
    ----------
    num_threads : int, optional
        The pool's threads; rclpy's default (the cores this process may run
        on) when None.
    context : rclpy.context.Context, optional
    """

    def __init__(self, num_threads=None, *, context=None):
        super().__init__(num_threads, context=context)
        if num_threads is None:
            num_threads = (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                           else os.cpu_count()) or 2
        # The pool rclpy made has started no thread yet: none is left behind.
        self._executor.shutdown(wait=False)
        self._executor = _CountedPool(num_threads)
        self._stopping = False

    def _spin_once_impl(self, timeout_sec=None, wait_condition=lambda: False):
        # rclpy passes a number or a TimeoutObject (spin_until_future_complete).
        timeout = getattr(timeout_sec, "timeout", timeout_sec)
        if timeout is not None and timeout < 0:
            timeout = None
        pool = self._executor
        began = time.monotonic()
        with pool.changed:
            free = pool.changed.wait_for(
                lambda: pool.held < pool.size or self._stopping, timeout)
        if free:
            if timeout is not None:
                timeout_sec = max(0.0, timeout - (time.monotonic() - began))
            super()._spin_once_impl(timeout_sec, wait_condition)

    def shutdown(self, timeout_sec=None):
        # The spinning thread may wait for a free thread: it goes on to find
        # the executor shut down.
        pool = self._executor
        with pool.changed:
            self._stopping = True
            pool.changed.notify_all()
        return super().shutdown(timeout_sec)
