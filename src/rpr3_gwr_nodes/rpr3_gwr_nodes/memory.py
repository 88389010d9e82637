"""Giving the memory of a replaced roadmap back to the system (glibc).

A roadmap is mostly large blocks (the field's arrays and the build's
temporaries, 1 to 37 MB on a 401 x 401 grid).  glibc's malloc maps such a
block on its own only until one is freed: it then raises its mmap threshold
to the freed block's size (up to 32 MiB) and its trim threshold to twice
that, and later blocks come from the heap of an arena.  It gives each thread
an arena of its own (up to eight per core), and what a thread frees stays in
its arena, resident: in chunks amid the heap, or at the heap's top below the
trim threshold.  Roadmaps are built in the builder's executor threads and
decoded in the planner's, so every swap left blocks in one arena or another:
over forty swaps of the 401 x 401 grid the builder grew from 537 to 1009 MB
and the planner from 408 to 988 MB (its plan workers, forked from it, too).

``malloc_trim`` gives back the free pages amid every arena's heap but the
free top of the main arena's heap only: after each rebuild it took a builder
with one arena back to 315 MB, while with an arena per thread 150 to 290 MB
stayed free and resident.  So a node allocates from one arena
(:func:`use_one_arena`, at its start) and trims once a roadmap was replaced
(:func:`release_free_memory`).  Keeping large blocks mapped instead (a fixed
``M_MMAP_THRESHOLD``) made every temporary of a build fault its pages in
afresh: a 401 x 401 build took 0.7 to 0.9 s instead of 0.3 to 0.4 s.
"""

import ctypes

__all__ = ["use_one_arena", "release_free_memory"]

# mallopt's parameter number in glibc's malloc.h.
_M_ARENA_MAX = -8


def _libc_function(name, argtypes):
    try:
        function = getattr(ctypes.CDLL(None), name)
    except (OSError, AttributeError):  # not glibc
        return None
    function.argtypes, function.restype = argtypes, ctypes.c_int
    return function


_MALLOPT = _libc_function("mallopt", (ctypes.c_int, ctypes.c_int))
_MALLOC_TRIM = _libc_function("malloc_trim", (ctypes.c_size_t,))


def use_one_arena():
    """Have every thread of the process allocate from malloc's main arena.

    Call it first thing in a node's ``main``: a thread that already
    allocated keeps its arena.  The threads of the suite's nodes mostly run
    Python, one at a time, so they seldom wait for each other in malloc.

    Returns
    -------
    bool
        Whether malloc took it: False with a C library other than glibc.
    """
    return _MALLOPT is not None and _MALLOPT(_M_ARENA_MAX, 1) == 1


def release_free_memory():
    """Give malloc's free pages back to the system (``malloc_trim(0)``).

    Call it once the references to a replaced roadmap and to its messages
    are gone.  It takes a few milliseconds; allocations that reuse those
    pages later fault them in again.

    Returns
    -------
    bool
        Whether any memory was returned: always False with a C library other
        than glibc.
    """
    return _MALLOC_TRIM is not None and _MALLOC_TRIM(0) == 1
