"""One planning request, as OMPL's ``ProblemDefinition``: the located start
and goal, the clearance asked for, when to stop, and the scene.

:meth:`~rpr3_gwr_core.planning.Planner.plan` builds one per request, and
every step of the plan (the searches, the repairs, the motion checks, the
simplification) reads it instead of being handed its parts one by one.
"""

from dataclasses import dataclass
import math

from ..exceptions import InvalidInputError
from .locate import Location
from .termination import NEVER, Termination

__all__ = ["PlanningProblem"]


@dataclass(frozen=True)
class PlanningProblem:
    """The ends and the conditions of one plan.

    Attributes
    ----------
    start, goal : Location
        The located ends (:func:`~.locate.locate`).
    clearance : float
        Margin (normalised ``|det Jx|``) the path keeps from the singular
        locus wherever the roadmap allows.
    termination : Termination
        When planning must stop.
    world : SceneRoadmap or None
        The roadmap restricted to a scene, or None in empty space.

    Raises
    ------
    InvalidInputError
        If an end is not a :class:`~.locate.Location`, the clearance does
        not lie in ``[0, 1)`` or the termination is not a
        :class:`~.termination.Termination`.
    """

    start: Location
    goal: Location
    clearance: float
    termination: Termination = NEVER
    world: object = None

    def __post_init__(self):
        if not (isinstance(self.start, Location) and isinstance(self.goal, Location)):
            raise InvalidInputError("the start and the goal must be located (Location)")
        if not (math.isfinite(self.clearance) and 0 <= self.clearance < 1):
            raise InvalidInputError(f"clearance must lie in [0, 1), got {self.clearance}")
        if not isinstance(self.termination, Termination):
            raise InvalidInputError(f"termination must be a Termination, got "
                                    f"{self.termination!r:.80}")

    def kept_margin(self, min_margin):
        """Margin [normalised ``|det Jx|``] a path must keep in the motion
        checker before a repair gives up on it: a quarter of the clearance,
        or half an end's own margin where that is less (a path leaving an
        end that lies near the singular locus dips below the end's margin
        wherever the margin falls towards the other end), but never below
        ``min_margin``."""
        return max(min_margin, min(0.25 * self.clearance, 0.5 * abs(self.start.margin),
                                   0.5 * abs(self.goal.margin)))
