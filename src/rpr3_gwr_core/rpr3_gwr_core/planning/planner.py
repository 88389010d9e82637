"""The hierarchical planner: locate, global path, local path, smoothing,
timing and validation, for one roadmap.

A :class:`Planner` precomputes the lookups of its roadmap once; each
:meth:`Planner.plan` call then answers one request.  Every plan returned has
passed :func:`~rpr3_gwr_core.validation.validate_path`; a plan that fails it
is tried along the next global path, and is an error when none passes.
"""

from dataclasses import dataclass, field as dataclass_field
import itertools
import math

import numpy as np

from ..exceptions import InfeasiblePathError, InvalidInputError, ValidationError
from .global_planning import RoadmapIndex, feasibility, global_paths, longer_paths
from .local_planning import DEFAULT_CLEARANCE_WEIGHT, LocalPlanner
from .locate import DEFAULT_MODE_TOL, locate
from .trajectory import chaikin, shortcut, time_parameterize
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN, validate_path

__all__ = ["PlanOptions", "Plan", "Planner"]

# Smoothing keeps this many cells between the path and any patch boundary.
_SMOOTH_CLEARANCE = 3.0
_SAMPLES_PER_CELL = 5
# Local re-plans around steps the validator refused, per global path.
_REPAIRS = 4
# Global paths tried, the listed ones included, before a plan fails: when
# every shortest path fails locally, longer ones may still pass.
_MAX_GLOBAL_ATTEMPTS = 16


@dataclass(frozen=True)
class PlanOptions:
    """Options of one planning request.

    Attributes
    ----------
    smooth : bool
        Shortcut and round the path (kept only if it validates).
    weighted : bool
        Rank global paths by weighted cost instead of fewest gates.
    feasibility_only : bool
        Answer from the roadmap alone, without a trajectory.
    max_velocity, max_acceleration : float or None
        Joint limits [joint unit / s, joint unit / s**2]; both given means
        the trajectory is time-parameterised.
    mode_tol : float
        Tolerance on the start's and goal's mode coordinate (the 3-RPR's
        orientation [rad]).
    max_paths : int
        Most global paths reported.
    """

    smooth: bool = False
    weighted: bool = False
    feasibility_only: bool = False
    max_velocity: float = None
    max_acceleration: float = None
    mode_tol: float = DEFAULT_MODE_TOL
    max_paths: int = 8

    def __post_init__(self):
        limits = (self.max_velocity, self.max_acceleration)
        if (limits[0] is None) != (limits[1] is None):
            raise InvalidInputError("give both max_velocity and max_acceleration, or neither: "
                                    f"got max_velocity = {limits[0]}, "
                                    f"max_acceleration = {limits[1]}")
        for name, value in zip(("max_velocity", "max_acceleration"), limits):
            if value is not None and not (math.isfinite(value) and value > 0):
                raise InvalidInputError(f"{name} must be positive and finite, got {value}")
        if not (math.isfinite(self.mode_tol) and self.mode_tol > 0):
            raise InvalidInputError(f"mode_tol must be positive, got {self.mode_tol}")
        if int(self.max_paths) < 1:
            raise InvalidInputError("max_paths must be at least 1")


@dataclass(frozen=True)
class Plan:
    """A planning answer.

    Attributes
    ----------
    feasible : bool
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
        Whether the smoothed path was kept.
    """

    feasible: bool
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

    def to_dict(self):
        """Plain-data form (the CLI's JSON)."""
        out = {"feasible": self.feasible, "reason": self.reason,
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


def _location_dict(location):
    return {"joints": location.joints.tolist(), "pose": location.pose.tolist(),
            "patch": location.patch, "cell": location.cell, "margin": location.margin}


class Planner:
    """Plans on one roadmap.

    Parameters
    ----------
    roadmap : Roadmap
    clearance_weight : float
        Local planner's boundary cost weight.
    min_margin : float
        Smallest normalised |det Jx| accepted at start, goal and along a plan.
    max_step : float
        Validator's continuation step [length unit].
    """

    def __init__(self, roadmap, clearance_weight=DEFAULT_CLEARANCE_WEIGHT,
                 min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP):
        self.roadmap = roadmap
        self.index = RoadmapIndex(roadmap)
        # Plans must keep min_margin; cells within thrice that are avoided.
        self.local = LocalPlanner(roadmap, clearance_weight, low_margin=3 * min_margin)
        self.min_margin = float(min_margin)
        self.max_step = float(max_step)
        self._joints = roadmap.grid.joints()

    def locate(self, configuration, mode_tol=DEFAULT_MODE_TOL):
        """:func:`~rpr3_gwr_core.planning.locate.locate` of a configuration:
        the joints, then the mode coordinate (the 3-RPR's
        ``(rho1, rho2, rho3, alpha)``)."""
        return locate(self.roadmap, configuration, mode_tol=mode_tol,
                      min_margin=self.min_margin, max_step=self.max_step)

    def plan(self, start, goal, options=PlanOptions()):
        """Plan from one configuration to another.

        Parameters
        ----------
        start, goal : sequence of float
            The joints, then the mode coordinate (the 3-RPR's
            ``(rho1, rho2, rho3, alpha)`` [length unit x 3, rad]).
        options : PlanOptions

        Returns
        -------
        Plan

        Raises
        ------
        GWRError
            ``InfeasiblePathError`` (with ``.reason``) when the roadmap has no
            path, ``ValidationError`` when no path passes the validator,
            ``InvalidInputError`` when the limits cannot time the path, or
            the locating errors of :func:`~rpr3_gwr_core.locate.locate`.
        """
        s = self.locate(start, options.mode_tol)
        g = self.locate(goal, options.mode_tol)
        answer = feasibility(self.index, s.patch, g.patch)
        if not answer.feasible:
            error = InfeasiblePathError(
                f"no path from patch {s.patch} to patch {g.patch}: "
                f"{answer.reason.replace('_', ' ')}")
            error.reason = answer.reason
            raise error
        paths = global_paths(self.index, s.patch, g.patch, options.weighted, options.max_paths)
        if options.feasibility_only:
            mechanism = self.roadmap.mechanism
            return Plan(True, answer.reason, s, g, paths,
                        joints=np.zeros((0, mechanism.n_joints)),
                        poses=np.zeros((0, mechanism.pose_size)))
        failures = []
        for k, path in enumerate(self._attempts(paths, s.patch, g.patch)):
            try:
                result, joints, patches, local = self._validated_path(path, s, g)
            except InfeasiblePathError as exc:
                failures.append(f"path {list(path.patches)}: {exc}")
                continue
            if not result.ok:
                failures.append(f"path {list(path.patches)}: {result.reason}")
                continue
            smoothed = False
            if options.smooth and len(joints) > 2:
                joints_s, patches_s = self._smooth(joints, patches, local)
                result_s = validate_path(self.roadmap.mechanism, joints_s, s.pose, g.pose,
                                         self.min_margin, self.max_step)
                if result_s.ok:
                    joints, patches, result, smoothed = joints_s, patches_s, result_s, True
            timing = (None, None, None)
            if options.max_velocity is not None:
                timing = time_parameterize(joints, options.max_velocity, options.max_acceleration)
            return Plan(True, answer.reason, s, g, paths, path_index=k, joints=joints,
                        poses=result.poses, patches=patches, times=timing[0],
                        velocities=timing[1], accelerations=timing[2], validation=result,
                        smoothed=smoothed)
        raise ValidationError("no global path gave a valid trajectory: " + "; ".join(failures))

    def _attempts(self, paths, start_patch, goal_patch):
        """The listed global paths, then longer ones, ``_MAX_GLOBAL_ATTEMPTS`` in all;
        a longer path that is tried is appended to ``paths`` so a plan can
        point at it."""
        yield from paths[:_MAX_GLOBAL_ATTEMPTS]
        listed = {p.patches for p in paths}
        extra = (p for p in longer_paths(self.index, start_patch, goal_patch)
                 if p.patches not in listed)
        for path in itertools.islice(extra, max(0, _MAX_GLOBAL_ATTEMPTS - len(paths))):
            paths.append(path)
            yield path

    def _validated_path(self, path, s, g):
        """Local path along a global path that passes the validator.

        Between two cell centres a sheet can pass right by a cusp point, where
        the validator refuses the step although both cells are fine; that
        step is then blocked and the local path planned again, a few times.
        """
        blocked = set()
        for _ in range(_REPAIRS + 1):
            local = self.local.plan(path.patches, s.cell, g.cell, blocked)
            joints, patches, cells = self._waypoints(s, g, local)
            result = validate_path(self.roadmap.mechanism, joints, s.pose, g.pose,
                                   self.min_margin, self.max_step)
            k = result.failed_segment
            if result.ok or k < 1 or min(cells[k - 1], cells[k]) < 0:
                break
            blocked.add((int(cells[k - 1]), int(cells[k])))
        return result, joints, patches, local

    def _waypoints(self, s, g, local):
        """Exact start, the cell centres, exact goal; repeated points dropped.

        Returns the legs, the patch of each waypoint and its cell (-1 for
        the exact start and goal)."""
        joints = np.vstack([s.joints, self._joints[local.cells], g.joints])
        patches = np.concatenate([[s.patch], local.patches, [g.patch]])
        cells = np.concatenate([[-1], local.cells, [-1]])
        keep = np.ones(len(joints), dtype=bool)
        keep[1:] = np.any(np.abs(np.diff(joints, axis=0)) > 1e-12, axis=1)
        return joints[keep], patches[keep], cells[keep]

    def _smooth(self, joints, patches, local):
        """Shortcut inside each patch, then round the corners.

        A shortcut or a rounded corner must keep ``_SMOOTH_CLEARANCE`` cells from
        the patch boundary and must not pass over a cell whose solution is
        closer to singular than the worst cell of the stretch it replaces.
        """
        seg = self.roadmap.segmentation
        grid = seg.field.grid
        clearance = {pid: self.local.clearance(pid) for pid in np.unique(patches)}
        cells_of = {pid: seg.patches[pid].cells for pid in clearance}

        def depth(pid, cells):
            k = np.searchsorted(cells_of[pid], cells)
            k = np.minimum(k, cells_of[pid].size - 1)
            inside = cells_of[pid][k] == cells
            return np.where(inside, clearance[pid][k], 0.0)

        def patch_margin(pid, cells):
            member = seg.patch[cells] == pid
            slots = np.argmax(member, axis=1)
            return np.where(member.any(axis=1), np.abs(seg.field.margin[cells, slots]), 0.0)

        free = list(grid.axis_joints)
        path_cells = grid.cells_of(joints[:, free])
        path_margin = np.array([patch_margin(pid, np.array([c]))[0]
                                for pid, c in zip(patches, path_cells)])

        def clear(a, b, pid, floor):
            span = np.max(np.abs(b[free] - a[free])) / grid.step
            t = np.linspace(0.0, 1.0, max(2, int(span * _SAMPLES_PER_CELL)))
            points = a[free] * (1 - t)[:, None] + b[free] * t[:, None]
            cells = grid.cells_of(points)
            if np.any(cells < 0):
                return False
            # Full clearance along the segment; near its ends, which are
            # already on the path, being inside the patch is enough.
            from_ends = np.minimum(t, 1 - t) * span
            need = np.where(from_ends < 1.5, 1.0, _SMOOTH_CLEARANCE)
            return bool(np.all(depth(pid, cells) >= need)
                        and np.all(patch_margin(pid, cells) >= floor))

        def allowed(i, j):
            return bool(np.all(patches[i:j + 1] == patches[i])) and clear(
                joints[i], joints[j], patches[i], path_margin[i:j + 1].min())

        keep = shortcut(joints[:, free], allowed)
        joints_k, patches_k = joints[keep], patches[keep]
        # Round each patch's stretch separately so gate crossings stay in
        # place, and only where the rounded corners keep their clearance.
        pieces, owners = [], []
        bounds = np.flatnonzero(np.diff(patches_k)) + 1
        floors = np.minimum.reduceat(path_margin[keep], np.concatenate([[0], bounds]))
        for piece, owner, floor in zip(np.split(joints_k, bounds), np.split(patches_k, bounds),
                                       floors):
            rounded = chaikin(piece)
            if not all(clear(a, b, owner[0], floor) for a, b in zip(rounded, rounded[1:])):
                rounded = piece
            pieces.append(rounded)
            owners.append(np.full(len(rounded), owner[0]))
        return np.vstack(pieces), np.concatenate(owners)
