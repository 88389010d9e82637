"""The one exception hierarchy of :mod:`rpr3_gwr_core`.

Every public function raises a subclass of :class:`GWRError`; each class
carries a stable ``code`` string so that callers (the CLI, the ROS nodes) can
map an error to their own error constants without parsing messages.
"""

__all__ = [
    "GWRError",
    "InvalidInputError",
    "OutOfGridError",
    "FixedJointMismatchError",
    "NoSolutionError",
    "AssemblyModeError",
    "SingularityError",
    "InfeasiblePathError",
    "CollisionError",
    "ValidationError",
    "PlanningTimeoutError",
]


class GWRError(Exception):
    """Base class of every error raised by :mod:`rpr3_gwr_core`."""

    code = "ERROR"


class InvalidInputError(GWRError, ValueError):
    """An argument is malformed: NaN, infinite, negative, wrong shape."""

    code = "INVALID_INPUT"


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
    """The roadmap connects no path between two configurations."""

    code = "INFEASIBLE"


class CollisionError(GWRError, ValueError):
    """A configuration collides with the scene or breaks one of its limits."""

    code = "IN_COLLISION"


class ValidationError(GWRError):
    """A computed plan failed the independent trajectory validator."""

    code = "VALIDATION_FAILED"


class PlanningTimeoutError(GWRError):
    """Planning reached its time limit before any path passed the validator."""

    code = "TIMEOUT"
