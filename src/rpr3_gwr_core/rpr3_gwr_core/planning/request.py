"""A planning request's types and its answer: the options (:class:`PlanOptions`),
how hard a plan tries (:class:`Retries`), and the plan with its declared
outcome (:class:`Plan`, :class:`PlanStatus`, as OMPL's ``PlannerStatus``).
"""

from dataclasses import dataclass, field as dataclass_field
import enum
import math
import numbers

import numpy as np

from ..exceptions import InvalidInputError
from .locate import DEFAULT_MODE_TOL

__all__ = ["DEFAULT_CLEARANCE", "PlanOptions", "Plan", "PlanStatus", "Retries"]

# Margin [normalised |det Jx|] that paths keep from the singular locus
# wherever the roadmap allows.
DEFAULT_CLEARANCE = 2e-2


@dataclass(frozen=True)
class Retries:
    """How hard a plan tries before it fails, and so how long the worst
    plans take (a deadline, :class:`~.termination.Termination`, bounds
    them in time as well).

    Attributes
    ----------
    global_paths : int
        Global paths tried, the listed ones first, before a plan fails: when
        every shortest path fails locally, longer ones may still pass.
    promising_nodes : int
        Nodes each local search may settle, on a roadmap of all the joints,
        in the two most promising searches tried before the global paths
        (:meth:`~.planner.Planner.plan`); 0 tries the global paths only.  A budget of
        work rather than time, so that a plan is the same on any machine
        and under any load.
    repairs : int
        Local re-plans around a step the validator refused, per global path
        and clearance weight.
    split_shortcuts : int
        Shortcuts the validator refused that are split into shorter ones, one
        by one, before the whole cell path is restored (also corners put back
        when smoothing).
    detour_weight : float
        The paper's clearance weight ``w`` (cell cost ``1 + w / d``) of the
        paths tried when the shortest ones cannot be repaired: they keep to
        the middle of their patches.
    detour_inflation : int
        Factor on the estimate of those paths' searches (weighted A*): a
        path then costs at most this many times the least, and the search
        settles a fraction of the nodes, since the estimate of the weighted
        costs, from lengths alone, falls far below them; 1 gives least-cost
        paths, as do the searches tried when no global path passes with it.
    """

    global_paths: int = 16
    promising_nodes: int = 50_000
    repairs: int = 4
    split_shortcuts: int = 6
    detour_weight: float = 10.0
    detour_inflation: int = 3

    def __post_init__(self):
        for name in ("global_paths", "repairs", "split_shortcuts", "promising_nodes",
                     "detour_inflation"):
            value = getattr(self, name)
            least = 1 if name in ("global_paths", "detour_inflation") else 0
            if isinstance(value, bool) or not isinstance(value, numbers.Integral) \
                    or value < least:
                raise InvalidInputError(f"{name} must be a whole number of at least "
                                        f"{least}, got {value!r}")
        if not (math.isfinite(self.detour_weight) and self.detour_weight >= 0):
            raise InvalidInputError(f"detour_weight must be finite and non-negative, got "
                                    f"{self.detour_weight!r}")


@dataclass(frozen=True)
class PlanOptions:
    """Options of one planning request.

    Attributes
    ----------
    smooth : bool
        Round the path's corners (kept only if it validates).
    weighted : bool
        Rank global paths by weighted cost instead of fewest gates.
    feasibility_only : bool
        Answer from the roadmap alone, without a trajectory.
    max_velocity, max_acceleration : float, tuple of float or None
        Joint limits [joint unit / s, joint unit / s**2], one for all joints
        or one per joint in the mechanism's order; both given means the
        trajectory is time-parameterised.
    mode_tol : float
        Tolerance on the start's and goal's mode coordinate (the 3-RPR's
        orientation [rad]).
    max_paths : int
        Most global paths reported.
    clearance : float
        Margin (normalised ``|det Jx|``) the path keeps from the singular locus
        wherever the roadmap allows; it passes closer (down to the planner's
        ``min_margin``) only where nothing else leads on.
    """

    smooth: bool = False
    weighted: bool = False
    feasibility_only: bool = False
    max_velocity: float = None
    max_acceleration: float = None
    mode_tol: float = DEFAULT_MODE_TOL
    max_paths: int = 8
    clearance: float = DEFAULT_CLEARANCE

    def __post_init__(self):
        limits = (self.max_velocity, self.max_acceleration)
        if (limits[0] is None) != (limits[1] is None):
            raise InvalidInputError("give both max_velocity and max_acceleration, or neither: "
                                    f"got max_velocity = {limits[0]}, "
                                    f"max_acceleration = {limits[1]}")
        for name, value in zip(("max_velocity", "max_acceleration"), limits):
            if value is None:
                continue
            values = tuple(value) if np.ndim(value) else (value,)
            if not (values and all(isinstance(v, numbers.Real) and not isinstance(v, bool)
                                   and math.isfinite(v) and v > 0 for v in values)):
                raise InvalidInputError(f"{name} must be positive and finite, one for all "
                                        f"joints or one per joint, got {value!r:.80}")
            # Hashable, as the rest of the options.
            object.__setattr__(self, name, tuple(map(float, values)) if np.ndim(value)
                               else float(value))
        if not (math.isfinite(self.mode_tol) and self.mode_tol > 0):
            raise InvalidInputError(f"mode_tol must be positive, got {self.mode_tol}")
        if int(self.max_paths) < 1:
            raise InvalidInputError("max_paths must be at least 1")
        if not (math.isfinite(self.clearance) and 0 <= self.clearance < 1):
            raise InvalidInputError(f"clearance must lie in [0, 1), got {self.clearance}")


class PlanStatus(enum.Enum):
    """The outcome of a plan, as OMPL's ``PlannerStatus``.

    Requests that find no path raise instead (``InfeasiblePathError``,
    ``ValidationError``, ``PlanningTimeoutError``).
    """

    EXACT_SOLUTION = "exact_solution"
    """Every step asked for was done."""
    APPROXIMATE_SOLUTION = "approximate_solution"
    """A valid path, but the deadline cut steps short (:attr:`Plan.skipped`)."""


@dataclass(frozen=True, repr=False)
class Plan:
    """A planning answer.

    Attributes
    ----------
    status : PlanStatus
    reason : str
        The feasibility reason (:class:`~rpr3_gwr_core.global_planning.Feasibility`).
    start, goal : Location
    global_paths : list of GlobalPath
        Best first.
    path_index : int
        Which global path the trajectory follows (-1 without trajectory).
    joints : ndarray, shape (n, n_joints)
        Joint waypoints [joint unit] (empty with ``feasibility_only``).
    poses : ndarray, shape (n, pose_size)
        Platform pose followed along them.
    patches : ndarray of int, shape (n,)
        Patch of each waypoint.
    times, velocities, accelerations : ndarray or None
        Time parameterisation [s, joint unit / s, joint unit / s**2].
    validation : Validation or None
    smoothed : bool
        Whether a pulled-taut or rounded path was kept.
    skipped : tuple of str
        The steps the deadline skipped (``"pulling taut"``, ``"rounding"``),
        empty for an exact solution.
    """

    status: PlanStatus
    reason: str
    start: object
    goal: object
    global_paths: list
    path_index: int = -1
    joints: np.ndarray = dataclass_field(default_factory=lambda: np.zeros((0, 0)))
    poses: np.ndarray = dataclass_field(default_factory=lambda: np.zeros((0, 0)))
    patches: np.ndarray = dataclass_field(default_factory=lambda: np.zeros(0, int))
    times: np.ndarray = None
    velocities: np.ndarray = None
    accelerations: np.ndarray = None
    validation: object = None
    smoothed: bool = False
    skipped: tuple = ()

    def __post_init__(self):
        if not isinstance(self.status, PlanStatus):
            raise InvalidInputError(f"status must be a PlanStatus, got {self.status!r:.80}")
        if (self.status is PlanStatus.APPROXIMATE_SOLUTION) != bool(self.skipped):
            raise InvalidInputError("an approximate solution, and only one, names the steps "
                                    f"it skipped: got {self.status.name} skipping "
                                    f"{list(self.skipped)}")

    @property
    def feasible(self):
        """Whether the roadmap connects the ends: always true, as a request
        whose ends it does not connect raises ``InfeasiblePathError``; the
        CLI's JSON and callers that test it read it."""
        return True

    def __repr__(self):
        path = (" -> ".join(map(str, self.global_paths[self.path_index].patches))
                if self.path_index >= 0 else "none")
        parts = [self.reason, f"global path {path}", f"{len(self.joints)} waypoints"]
        if len(self.joints) > 1:
            parts.append(f"length {_joint_length(self.joints):.4g} [joint unit]")
        if self.times is not None:
            parts.append(f"{self.times[-1]:.3g} s")
        if self.validation is not None:
            parts.append(f"valid, min margin {self.validation.min_margin:.3g}"
                         if self.validation.ok else f"invalid: {self.validation.reason}")
        if self.smoothed:
            parts.append("smoothed")
        if self.skipped:
            parts.append(f"approximate: the deadline skipped {' and '.join(self.skipped)}")
        return f"Plan({', '.join(parts)})"

    def to_dict(self):
        """Plain-data form (the CLI's JSON)."""
        out = {"feasible": self.feasible, "status": self.status.value,
               "skipped": list(self.skipped), "reason": self.reason,
               "start": _location_dict(self.start), "goal": _location_dict(self.goal),
               "global_paths": [list(g.patches) for g in self.global_paths],
               "global_path_costs": [g.cost for g in self.global_paths],
               "path_index": self.path_index, "smoothed": self.smoothed,
               "waypoints": [{"joints": q.tolist(), "pose": p.tolist(), "patch": int(k)}
                             for q, p, k in zip(self.joints, self.poses, self.patches)]}
        if self.times is not None:
            out["times"] = self.times.tolist()
            out["velocities"] = self.velocities.tolist()
            out["accelerations"] = self.accelerations.tolist()
        if self.validation is not None:
            out["validation"] = self.validation.as_dict()
        return out


def _joint_length(joints):
    return float(np.linalg.norm(np.diff(joints, axis=0), axis=1).sum())


def _location_dict(location):
    return {"joints": location.joints.tolist(), "pose": location.pose.tolist(),
            "patch": location.patch, "cell": location.cell, "margin": location.margin}
