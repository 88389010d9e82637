"""When a planner must stop: a deadline on the monotonic clock.

As OMPL's ``PlannerTerminationCondition``, a :class:`Termination` is passed
to :meth:`~rpr3_gwr_core.planning.Planner.plan`, which checks it between its
steps; its compiled searches check the same deadline every few thousand
nodes, through :func:`monotonic`, the process's ``CLOCK_MONOTONIC`` read
from compiled code (``time.monotonic`` in Python reads the same clock).
"""

import math
import time

from llvmlite import ir
import numba
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ..exceptions import InvalidInputError

__all__ = ["Termination", "NEVER", "monotonic"]

# POSIX's CLOCK_MONOTONIC, the clock of time.monotonic on Linux.
_CLOCK_MONOTONIC = 1


class Termination:
    """A deadline: planning stops once the monotonic clock reaches it.

    Parameters
    ----------
    deadline : float
        [s] on ``time.monotonic``'s clock; infinite (the default) never stops.
    """

    __slots__ = ("deadline",)

    def __init__(self, deadline=math.inf):
        self.deadline = float(deadline)

    @classmethod
    def after(cls, seconds):
        """The condition that stops ``seconds`` from now.

        Raises
        ------
        InvalidInputError
            If ``seconds`` is negative or NaN.
        """
        seconds = float(seconds)
        if not seconds >= 0:
            raise InvalidInputError(f"a time limit must be non-negative, got {seconds}")
        return cls(time.monotonic() + seconds)

    def __call__(self):
        """Whether planning must stop now."""
        return time.monotonic() >= self.deadline

    def remaining(self):
        """Seconds left, 0 once passed, infinite without a deadline."""
        return max(0.0, self.deadline - time.monotonic())

    def __repr__(self):
        return f"Termination(remaining={self.remaining():.3g} s)"


NEVER = Termination()


@intrinsic
def _clock_gettime(typingctx):
    """``CLOCK_MONOTONIC`` in seconds, from compiled code; the call names the
    C library's symbol, so functions using it stay cacheable."""
    def codegen(context, builder, signature, args):
        i64 = ir.IntType(64)
        timespec = ir.LiteralStructType([i64, i64])
        function = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.IntType(32), [ir.IntType(32),
                                                             timespec.as_pointer()]),
            "clock_gettime")
        spec = cgutils.alloca_once(builder, timespec)
        builder.call(function, [ir.Constant(ir.IntType(32), _CLOCK_MONOTONIC), spec])
        seconds = builder.sitofp(builder.load(cgutils.gep_inbounds(builder, spec, 0, 0)),
                                 ir.DoubleType())
        nanoseconds = builder.sitofp(builder.load(cgutils.gep_inbounds(builder, spec, 0, 1)),
                                     ir.DoubleType())
        return builder.fadd(seconds, builder.fmul(nanoseconds, ir.Constant(ir.DoubleType(),
                                                                            1e-9)))
    return types.float64(), codegen


@numba.njit(cache=True, nogil=True)
def monotonic():
    """``time.monotonic()`` [s], callable from compiled code."""
    return _clock_gettime()
