"""The one exception hierarchy of :mod:`rpr3_gwr_core`.

Every public function raises a subclass of :class:`GWRError`; each class
carries a stable ``code`` string so that callers (the CLI, the ROS nodes) can
map an error to their own error constants without parsing messages.
"""

__all__ = [
    "GWRError",
    "InvalidInputError",
    "GridSizeError",
    "OutOfGridError",
    "FixedJointMismatchError",
    "NoSolutionError",
    "AssemblyModeError",
    "SingularityError",
    "InfeasiblePathError",
    "INFEASIBLE_REASONS",
    "UndecidedError",
    "CollisionError",
    "ValidationError",
    "PlanningTimeoutError",
]


INFEASIBLE_REASONS = ("other_aspect", "unreachable", "blocked")


class GWRError(Exception):
    """Base class of every error raised by :mod:`rpr3_gwr_core`."""

    code = "ERROR"


class InvalidInputError(GWRError, ValueError):
    """An argument is malformed: NaN, infinite, negative, wrong shape."""

    code = "INVALID_INPUT"


class GridSizeError(InvalidInputError):
    """A grid would have more cells (or lattice points) than its limit.

    Attributes
    ----------
    size : int
        The cells or points it would have.
    limit : int
        The most it may have.
    """

    def __init__(self, message, size, limit):
        super().__init__(message)
        self.size = size
        self.limit = limit


class OutOfGridError(GWRError, ValueError):
    """A configuration lies outside the grid the roadmap was built on."""

    code = "OUT_OF_GRID"


class FixedJointMismatchError(GWRError, ValueError):
    """A configuration's joint differs from the value the roadmap's grid fixes."""

    code = "FIXED_JOINT_MISMATCH"


class NoSolutionError(GWRError, ValueError):
    """The direct kinematics has no real solution at the requested legs."""

    code = "NO_SOLUTION"


class AssemblyModeError(GWRError, ValueError):
    """No assembly mode lies near the requested platform orientation."""

    code = "NO_ASSEMBLY_MODE"


class SingularityError(GWRError, ValueError):
    """A configuration is on, or too near, a parallel singularity."""

    code = "SINGULAR"


class InfeasiblePathError(GWRError):
    """The roadmap connects no path between two configurations.

    Parameters
    ----------
    message : str
    reason : str, optional
        Why, where the roadmap's graph says it: one of
        :data:`INFEASIBLE_REASONS` ("other_aspect": the ends lie in two
        aspects; "unreachable": in two components of one; "blocked": a scene
        cuts every way).  None where the graph joins the ends and no cell
        search does.  Callers (the CLI, the planner node) map it to their
        own feasibility codes.

    Raises
    ------
    ValueError
        If ``reason`` is neither None nor one of :data:`INFEASIBLE_REASONS`.
    """

    code = "INFEASIBLE"

    def __init__(self, message, reason=None):
        if reason is not None and reason not in INFEASIBLE_REASONS:
            raise ValueError(f"an infeasible path's reason is one of {INFEASIBLE_REASONS}, "
                             f"got {reason!r}")
        super().__init__(message)
        self.reason = reason


class UndecidedError(GWRError):
    """The roadmap joins no path between two configurations, and cannot
    claim that none exists.

    The ends lie in two components of one aspect, and thin regions of that
    aspect (gateless patches, strips a few cells wide: the grid sees them
    end where they narrow below a cell) remain at the finest cell the build
    allowed: on a finer grid one may join the ends' components.  Not an
    :class:`InfeasiblePathError`: "no path" is a claim that a finer grid
    must not contradict, and this answer makes none.

    Parameters
    ----------
    message : str
    thin_patches : sequence of int, optional
        The thin regions' patch ids, ascending.
    steps : sequence of float, optional
        The grid's finest step along each of its axes [joint unit].
    """

    code = "UNDECIDED"

    def __init__(self, message, thin_patches=(), steps=()):
        super().__init__(message)
        self.thin_patches = tuple(int(p) for p in thin_patches)
        self.steps = tuple(float(s) for s in steps)


class CollisionError(GWRError, ValueError):
    """A configuration collides with the scene or breaks one of its limits."""

    code = "IN_COLLISION"


class ValidationError(GWRError):
    """A computed plan failed the independent trajectory validator."""

    code = "VALIDATION_FAILED"


class PlanningTimeoutError(GWRError):
    """Planning reached its time limit before any path passed the validator."""

    code = "TIMEOUT"
