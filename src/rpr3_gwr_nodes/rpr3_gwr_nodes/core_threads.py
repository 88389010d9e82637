"""The threads the nodes lend the core's roadmap builds and loads: the core
starts none of its own, its functions take a map-like ``workers``
(:func:`rpr3_gwr_core.workspace.build_roadmap`,
:func:`rpr3_gwr_core.io.cache.cached_roadmap`, ...)."""

from concurrent.futures import ThreadPoolExecutor
import os

__all__ = ["core_threads"]


def core_threads():
    """A pool of a thread per core, four at most, for one build or load:
    its ``map`` is the core's ``workers`` (numpy, CRC-32 and the compiled
    kernels release the interpreter's lock).  Use it in a ``with`` block."""
    return ThreadPoolExecutor(max_workers=min(4, os.cpu_count() or 1),
                              thread_name_prefix="rpr3_gwr_core")
