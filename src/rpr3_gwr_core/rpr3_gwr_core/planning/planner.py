"""The hierarchical planner: locate, global path, local path, shortcutting,
smoothing, timing and validation, for one roadmap.

A :class:`Planner` precomputes the lookups of its roadmap once; each
:meth:`Planner.plan` call then answers one request.  Feasibility and the
global paths reported come from the roadmap (fewest gates, as in the
paper).  On a slice, the paper's setting, the path follows them in their
order.  On a roadmap of all the joints, the path followed is searched in
order of promise:

1. the least-cost path on the whole node graph, free to cross any gate and
   to come back to a patch, given a budget of work
   (``Retries.promising_nodes``): on a full 3-DOF roadmap, whose few patches
   are large and folded, the shortest way often leaves a patch and comes
   back, which no sequence of distinct patches allows;
2. the sequence of patches whose gates promise the cheapest search
   (:meth:`~.local_planning.LocalPlanner.cheapest_patches`): fewest gates
   can mean a long way round inside one patch;
3. the global paths listed, then longer ones.

The local planner's cell path runs from face to face, so it is shortcut to
straight segments that cross its patches in the same order, which makes it
close to the shortest path that keeps the requested clearance.  Every plan
returned has passed :func:`~rpr3_gwr_core.validation.validate_path`; when
the shortcut path fails it, the cell path is tried, then the next candidate,
and the plan is an error when none passes.
"""

import dataclasses
from dataclasses import dataclass, field as dataclass_field
import functools
import itertools
import math
import numbers

import numpy as np

from ..exceptions import (CollisionError, GWRError, InfeasiblePathError, InvalidInputError,
                          PlanningTimeoutError, ValidationError)
from .global_planning import GlobalPath, RoadmapIndex, feasibility, global_paths, longer_paths
from .index import PlanningIndex
from .local_planning import DEFAULT_CLEARANCE_WEIGHT, LocalPlanner
from .locate import DEFAULT_MODE_TOL, locate
from .segments import Sheets, segments_clear, shortcut_path
from .termination import NEVER
from .trajectory import corner_cuts, cut_corners, time_parameterize
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN, validate_path

__all__ = ["PlanOptions", "Plan", "Planner", "Retries", "planning_index"]

# Margin [normalised |det Jx|] that paths keep from the singular locus
# wherever the roadmap allows.
DEFAULT_CLEARANCE = 2e-2
# Shortcuts are checked at this many points per grid step.
_SAMPLES_PER_CELL = 5
# A followed pose this far from its waypoint's solution [scale] is on another sheet.
_STRAYED = 1e-4
# A repair searches again the cell path's stretch from this many cells before
# the refused step to as many after it, times the repair's number: as far as
# the box of blocked cells around the step grows.
_REPAIR_REACH = 8


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
        (:meth:`Planner.plan`); 0 tries the global paths only.  A budget of
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
    max_velocity, max_acceleration : float or None
        Joint limits [joint unit / s, joint unit / s**2]; both given means
        the trajectory is time-parameterised.
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
            if value is not None and not (math.isfinite(value) and value > 0):
                raise InvalidInputError(f"{name} must be positive and finite, got {value}")
        if not (math.isfinite(self.mode_tol) and self.mode_tol > 0):
            raise InvalidInputError(f"mode_tol must be positive, got {self.mode_tol}")
        if int(self.max_paths) < 1:
            raise InvalidInputError("max_paths must be at least 1")
        if not (math.isfinite(self.clearance) and 0 <= self.clearance < 1):
            raise InvalidInputError(f"clearance must lie in [0, 1), got {self.clearance}")


@dataclass(frozen=True, repr=False)
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
        Whether the rounded path was kept.
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

    def __repr__(self):
        if not self.feasible:
            return f"Plan(infeasible: {self.reason})"
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
        return f"Plan({', '.join(parts)})"

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


def _joint_length(joints):
    return float(np.linalg.norm(np.diff(joints, axis=0), axis=1).sum())


def _location_dict(location):
    return {"joints": location.joints.tolist(), "pose": location.pose.tolist(),
            "patch": location.patch, "cell": location.cell, "margin": location.margin}


def planning_index(roadmap, clearances=(DEFAULT_CLEARANCE,),
                   clearance_weight=DEFAULT_CLEARANCE_WEIGHT, retries=Retries(), graph_from=None):
    """The :class:`~.index.PlanningIndex` of a roadmap with the gate distances
    of ``clearances`` and the node costs of every clearance weight a
    :class:`Planner` with these ``clearance_weight`` and ``retries`` plans
    with (seconds on the full 3-DOF roadmap); the node graph of
    ``graph_from``, an index of the same roadmap, when given."""
    return PlanningIndex.build(roadmap, clearances, (clearance_weight, retries.detour_weight),
                               graph_from)


class Planner:
    """Plans on one roadmap.

    Everything a plan reads is built when the planner is made, or given:
    the roadmap and its planning index.  A plan changes nothing but the
    lookups of clearances and weights the index lacks, computed on first
    use, so one planner serves requests in several threads at once.

    Parameters
    ----------
    roadmap : Roadmap
    index : PlanningIndex, optional
        The roadmap's, built or mapped (:mod:`~rpr3_gwr_core.io.cache`);
        by default :func:`planning_index` of the roadmap, with this
        planner's weights.
    clearance_weight : float
        The paper's boundary cost weight of the local planner (0: shortest
        paths).
    min_margin : float
        Smallest normalised ``|det Jx|`` accepted at start, goal and along a plan.
    max_step : float
        Validator's continuation step [length unit].
    retries : Retries
        How hard a plan tries before it fails.
    """

    def __init__(self, roadmap, index=None, clearance_weight=DEFAULT_CLEARANCE_WEIGHT,
                 min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP, retries=Retries()):
        self.roadmap = roadmap
        self.retries = retries
        if not (math.isfinite(clearance_weight) and clearance_weight >= 0):
            raise InvalidInputError("clearance_weight must be finite and non-negative")
        if index is None:
            index = planning_index(roadmap, clearance_weight=clearance_weight, retries=retries)
        self.planning_index = index
        self.global_index = RoadmapIndex(roadmap, index)
        self.local = LocalPlanner(roadmap, index)
        self.clearance_weight = float(clearance_weight)
        self.min_margin = float(min_margin)
        self.max_step = float(max_step)
        self._free = list(roadmap.grid.axis_joints)
        seg, mechanism = roadmap.segmentation, roadmap.mechanism
        self._world_indices = {}
        self._sheets = Sheets(roadmap.grid.lattice, roadmap.grid.step, _SAMPLES_PER_CELL,
                              seg.patch, seg.field.margin, seg.field.poses,
                              np.where(mechanism.angular, mechanism.scale, 0.0))

    def __repr__(self):
        return (f"Planner({self.roadmap!r}, clearance weight {self.clearance_weight:g}, "
                f"min margin {self.min_margin:g})")

    def warm_up(self):
        """Load every compiled kernel a plan can use (or, on a cold numba
        cache, compile them: seconds) now rather than during a first
        request: a plan inside the first patch, smoothed and timed, and a
        segment test for the corners that plan may not have.

        """
        seg = self.roadmap.segmentation
        patch = seg.patches[min(seg.patches)]
        cells = patch.cells[[patch.cells.size // 3, 2 * patch.cells.size // 3]]
        slots = patch.slots[[patch.cells.size // 3, 2 * patch.cells.size // 3]]
        k = self.roadmap.mechanism.mode_coordinate
        start, goal = ((*self.roadmap.grid.joints_of(int(cell)),
                        float(seg.field.poses[cell, slot, k])) for cell, slot in zip(cells, slots))
        try:
            self.plan(start, goal, PlanOptions(smooth=True, max_velocity=1.0,
                                               max_acceleration=1.0))
        except GWRError:
            pass  # the kernels it reached are loaded all the same
        joints = self.roadmap.grid.joints_at(cells)
        self._clear(joints[:1], joints[1:], [patch.id], [0.0])

    def locate(self, configuration, mode_tol=DEFAULT_MODE_TOL):
        """:func:`~rpr3_gwr_core.planning.locate.locate` of a configuration:
        the joints, then the mode coordinate (the 3-RPR's
        ``(rho1, rho2, rho3, alpha)``)."""
        return locate(self.roadmap, configuration, mode_tol=mode_tol,
                      min_margin=self.min_margin, max_step=self.max_step)

    def plan(self, start, goal, options=PlanOptions(), termination=NEVER, world=None):
        """Plan from one configuration to another.

        Parameters
        ----------
        start, goal : sequence of float
            The joints, then the mode coordinate (the 3-RPR's
            ``(rho1, rho2, rho3, alpha)`` [length unit x 3, rad]).
        options : PlanOptions
        termination : Termination
            Where planning stops: past its deadline the plan is the valid
            path found so far, unsmoothed if smoothing was not done yet, or
            a ``PlanningTimeoutError`` when there is none.
        world : SceneRoadmap, optional
            The roadmap restricted to a scene (:meth:`apply_scene`): the plan
            keeps its bodies off the obstacles, within the limits, and
            ``obstacle_clearance`` away where it can; without one, the
            mechanism moves in empty space.

        Returns
        -------
        Plan

        Raises
        ------
        GWRError
            ``CollisionError`` when the start or the goal collides or breaks
            a limit of the scene, ``InfeasiblePathError`` (with ``.reason``,
            ``"blocked"`` when the roadmap joins them and the scene does not)
            when there is no path, ``ValidationError`` when no path passes the validator,
            ``PlanningTimeoutError`` when the deadline passed before one did,
            ``InvalidInputError`` when the limits cannot time the path, or
            the locating errors of :func:`~rpr3_gwr_core.locate.locate`.
        """
        s = self.locate(start, options.mode_tol)
        g = self.locate(goal, options.mode_tol)
        if world is not None:
            self._check_free(world, s, "start")
            self._check_free(world, g, "goal")
        answer = feasibility(self.global_index, s.patch, g.patch)
        if answer.feasible and world is not None:
            answer = world.feasibility(s, g)
            if answer.reason == "in_collision":
                raise CollisionError(
                    "the scene blocks the grid cell solution of the "
                    f"{'start' if answer.start_part < 0 else 'goal'} (an obstacle or a limit "
                    "lies within a cell of it)")
        if not answer.feasible:
            # The scene is resolved cell by cell: where an obstacle or a limit
            # leaves a band narrower than a cell (along a fold, where the
            # joints barely move as the platform does), the grid sees no way
            # that the platform has.
            error = InfeasiblePathError(
                f"no path from patch {s.patch} to patch {g.patch}: "
                f"{answer.reason.replace('_', ' ')}"
                + (" by the scene on this grid: a way narrower than one of its cells "
                   "is not seen, a finer grid shows one if it exists"
                   if answer.reason == "blocked" else ""))
            error.reason = answer.reason
            raise error
        paths = global_paths(self.global_index, s.patch, g.patch, options.weighted,
                             options.max_paths)
        if options.feasibility_only:
            mechanism = self.roadmap.mechanism
            return Plan(True, answer.reason, s, g, paths,
                        joints=np.zeros((0, mechanism.n_joints)),
                        poses=np.zeros((0, mechanism.pose_size)))
        found = None
        if world is not None or (not options.weighted and not self.roadmap.grid.fixed):
            found = self._promising(s, g, options.clearance, termination, world)
        if found is None:
            found = self._along_global_paths(paths, s, g, options.clearance, termination, world)
        path, result, joints, patches = found
        smoothed = False
        if options.smooth and len(joints) > 2 and not self.roadmap.grid.fixed:
            taut = self._pulled_taut(joints, patches, result, s, g, options.clearance,
                                     termination, world)
            if taut is not None:
                result, joints, patches = taut
                smoothed = True
        if options.smooth and len(joints) > 2 and not termination():
            rounded = self._round(joints, patches, s, g, options.clearance,
                                  min(result.min_margin,
                                      self._kept_margin(s, g, options.clearance)), world)
            if rounded is not None:
                result, joints, patches = rounded
                smoothed = True
        if path.patches not in {p.patches for p in paths}:
            # A path of the searches that cross any gate: its cells may weave
            # along a gate, in and out of two patches, where the trajectory
            # crosses the patches of its waypoints (when gates join them: a
            # smoothed segment may pass through a patch that has no waypoint).
            crossed = tuple(int(p) for k, p in enumerate(patches) if k == 0 or p != patches[k - 1])
            if all(self.global_index.weighted.has_edge(a, b)
                   for a, b in zip(crossed, crossed[1:])):
                path = GlobalPath(crossed, self.global_index.path_cost(crossed))
            if path.patches not in {p.patches for p in paths}:
                paths.append(path)
        path_index = next(k for k, p in enumerate(paths) if p.patches == path.patches)
        timing = (None, None, None)
        if options.max_velocity is not None:
            timing = time_parameterize(joints, options.max_velocity, options.max_acceleration)
        return Plan(True, answer.reason, s, g, paths, path_index=path_index, joints=joints,
                    poses=result.poses, patches=patches, times=timing[0],
                    velocities=timing[1], accelerations=timing[2], validation=result,
                    smoothed=smoothed)

    def _along_global_paths(self, paths, s, g, clearance, termination, world):
        """The first global path (:meth:`_attempts`) whose local path passes
        the validator, with that validation, legs and waypoint patches.

        Repairs first search again only a stretch of the refused path, and
        the detour weight's searches inflate their estimate; when no global
        path passes that way, they are all tried again with least-cost
        searches of whole paths, which find ways round that leave the
        stretch or that the greedier searches miss (seldom needed, and
        several times the work).

        Raises
        ------
        ValidationError
            When none does, with what each one failed on.
        PlanningTimeoutError
            When the deadline passes first.
        """
        failures = []
        unplanned = set()
        for reroute in (True, False) if self.retries.repairs > 0 else (False,):
            for path in self._attempts(paths, s.patch, g.patch):
                if path.patches in unplanned:
                    continue
                name = f"path {list(path.patches)}{'' if reroute else ' searched whole'}"
                try:
                    if termination():
                        raise PlanningTimeoutError("the time limit passed")
                    result, joints, patches = self._validated_path(
                        path, s, g, clearance, termination, world=world, reroute=reroute)
                except InfeasiblePathError as exc:
                    unplanned.add(path.patches)
                    failures.append(f"{name}: {exc}")
                    continue
                except PlanningTimeoutError as exc:
                    raise PlanningTimeoutError(
                        f"{exc} after {len(failures)} global path(s) without a valid "
                        "trajectory" + "".join(f"; {f}" for f in failures)) from None
                if result.ok:
                    return path, result, joints, patches
                failures.append(f"{name}: {result.reason}")
        raise ValidationError("no global path gave a valid trajectory: " + "; ".join(failures))

    def _promising(self, s, g, clearance, termination, world=None):
        """The first path of the two most promising searches that validates,
        each local search given ``retries.promising_nodes``: the least-cost path on the
        node graph, crossing any gates (:meth:`~.local_planning.LocalPlanner.plan`
        with ``any_gates``), then the path through the cheapest patches
        (:meth:`~.local_planning.LocalPlanner.cheapest_patches`).

        The first search's estimate is only the straight length to the
        goal, so it takes long where the shortest path goes far around; the
        second's patches can be narrow where repairs take long; either way
        the global paths then take over.  In a scene (``world``) the first
        search has no budget: it is the one that goes wherever the scene
        leaves a way.

        Returns
        -------
        (GlobalPath, Validation, ndarray, ndarray) or None
            The patches the path crosses, in order (a patch may come back),
            its validation, legs and waypoint patches.
        """
        budget = self.retries.promising_nodes
        if budget == 0 and world is None:
            return None
        try:
            result, joints, patches, route = self._repaired_path(
                None, s, g, clearance, self.clearance_weight, termination,
                None if world is not None else budget, world)
        except (InfeasiblePathError, PlanningTimeoutError):
            result = None
        if result is None or not result.ok:
            route = self.local.cheapest_patches(s.patch, s.cell, g.patch, g.cell, clearance)
            if route is None or budget == 0:
                return None
            try:
                result, joints, patches = self._validated_path(
                    GlobalPath(route, 0.0), s, g, clearance, termination, budget, world)
            except (InfeasiblePathError, PlanningTimeoutError):
                return None
            if not result.ok:
                return None
        return GlobalPath(route, self.global_index.path_cost(route)), result, joints, patches

    def _weights(self):
        """The clearance weights a global path's local path is tried with,
        each with the inflation of its searches' estimate."""
        weights = {self.clearance_weight: 1}
        weights.setdefault(self.retries.detour_weight, self.retries.detour_inflation)
        return weights

    def _attempts(self, paths, start_patch, goal_patch):
        """The listed global paths, then longer ones, ``retries.global_paths`` in all;
        a longer path that is tried is appended to ``paths`` so a plan can
        point at it."""
        most = self.retries.global_paths
        yield from paths[:most]
        listed = {p.patches for p in paths}
        extra = (p for p in longer_paths(self.global_index, start_patch, goal_patch)
                 if p.patches not in listed)
        for path in itertools.islice(extra, max(0, most - len(paths))):
            paths.append(path)
            yield path

    def _validated_path(self, path, s, g, clearance, termination, most_settled=None,
                        world=None, reroute=True):
        """Local path along a global path that passes the validator, shortcut
        where the shortcut path passes too; when every repair of the
        shortest path fails, the same for the path the paper's clearance
        weight keeps in the middle of its patches; with ``reroute``, repairs
        search stretches and the detour's searches inflate their estimate
        (:meth:`_repaired_path`), else every search is a least-cost one of
        the whole path."""
        for weight, inflation in self._weights().items():
            result, joints, patches, _ = self._repaired_path(
                path, s, g, clearance, weight, termination, most_settled, world,
                inflation if reroute else 1, reroute)
            if result.ok:
                break
        return result, joints, patches

    def _repaired_path(self, path, s, g, clearance, weight, termination, most_settled=None,
                       world=None, inflation=1, reroute=True):
        """Local path along a global path (through any gates when None),
        repaired where the validator refuses it; ``inflation`` as the local
        planner's.

        The path's cells keep the clearance where they can, but between two
        cell centres next to a cusp point, or over a singular sliver thinner
        than a cell, the sheet can dip far lower, even below ``min_margin``.
        The path must therefore keep a quarter of the clearance (or what the start
        and goal allow) in the validator; where it does not, the cells
        around the step where it dipped are blocked, in a box growing with
        each repair, and the stretch of the cell path around them planned
        again (with ``reroute``; else, or when the stretch finds no way
        round, the whole path), a few times, before a path that keeps
        ``min_margin`` will do.

        Returns the validation, the legs and patches of the waypoints, and
        the patches the cell path crosses, in order.
        """
        keep = self._kept_margin(s, g, clearance)
        blocked = set()
        tried = []
        free = list(self.roadmap.grid.axis_joints)
        search = functools.partial(self.local.plan, clearance=clearance,
                                   clearance_weight=weight, termination=termination,
                                   any_gates=path is None, most_settled=most_settled,
                                   world=world, inflation=inflation)
        route = (s.patch, g.patch) if path is None else path.patches
        cell_path = stretch = None
        for repair in range(self.retries.repairs + 1):
            if termination():
                raise PlanningTimeoutError("the time limit passed")
            try:
                if stretch is not None and reroute:
                    cell_path = _rerouted(search, *cell_path, stretch, blocked, path is None)
                else:
                    cell_path = None
                if cell_path is None:
                    local = search(route, s.cell, g.cell, blocked)
                    cell_path = local.cells, local.patches
            except InfeasiblePathError:
                if not blocked:
                    raise
                break  # the blocked cells cut the patches
            cells, cell_patches = cell_path
            joints, patches, origin = self._waypoints(s, g, cells, cell_patches)
            result, kept = self._shortcut_validated(joints, patches, s, g, clearance, keep,
                                                    world)
            tried.append((joints, patches, kept))
            if result.ok:
                return result, joints[kept], patches[kept], _crossed(patches)
            k = self._failed_segment(result, joints[kept], patches[kept])
            if k < 1:
                break
            a, b = kept[k - 1], kept[k]
            middle = 0.5 * (joints[a, free] + joints[b, free])
            around = self.local.cells_around(middle, 0.5 + repair).tolist()
            ends = origin[[a, b]]
            blocked.update(set(around + cells[ends[ends >= 0]].tolist())
                           - {s.cell, g.cell})
            first = ends[0] if ends[0] >= 0 else 0
            last = ends[1] if ends[1] >= 0 else cells.size - 1
            reach = _REPAIR_REACH * (repair + 1)
            stretch = (max(0, first - reach), min(cells.size - 1, last + reach))
        # Blocking steps can also lead somewhere worse: the last path, else
        # the first, if it keeps min_margin, shortcut as it was tried (it
        # missed only the clearance's quarter), else whole.
        for joints, patches, kept in (tried[-1], tried[0])[:len(tried)]:
            for waypoints in (kept, np.arange(len(joints))):
                result = self._validate(joints[waypoints], s, g, self.min_margin, world)
                if result.ok:
                    return result, joints[waypoints], patches[waypoints], _crossed(patches)
        return result, joints, patches, _crossed(patches)

    def _shortcut_validated(self, joints, patches, s, g, clearance, keep, world=None):
        """The shortcut path's validation and kept waypoints; a shortcut the
        validator refuses is replaced by shorter ones over the same cells (the
        stretch shortcut again without its direct jump), a few times, then
        the cell path is restored whole (its turns: points inside a straight
        run add nothing).  A failure is then one of the cell path's own
        steps."""
        kept = np.arange(len(joints))
        margins = self._waypoint_margins(joints, patches)
        if len(joints) > 2:
            kept = self._shortcut(joints, patches, margins, clearance)
        splits = self.retries.split_shortcuts
        for attempt in range(splits + 2):
            result = self._validate(joints[kept], s, g, keep, world)
            k = self._failed_segment(result, joints[kept], patches[kept])
            if result.ok or k < 1 or kept[k] - kept[k - 1] == 1:
                break
            a, b = kept[k - 1], kept[k] + 1
            restored = a + self._shortcut(joints[a:b], patches[a:b], margins[a:b], clearance,
                                          split=True)
            if attempt == splits:
                restored = _turns(joints)
            kept = np.union1d(kept, restored)
        return result, kept

    def _pulled_taut(self, joints, patches, result, s, g, clearance, termination, world):
        """The validated path with straight joint segments jumping as far
        ahead as the validator lets them, found by bisection: between two
        waypoints the segment must keep the clearance, or what the stretch
        it replaces keeps where that is less.

        The sheet shortcuts only join cells of the path's patches in their
        order; on a roadmap of all the joints the patches fold over each
        other, and a straight segment the platform follows well often
        leaves that order.  Returns the validation, legs and patches of the
        shorter path, or None when nothing shorter validates (or the
        deadline passes first).
        """
        mechanism = self.roadmap.mechanism
        poses = result.poses
        margins = np.abs(mechanism.margin(poses, joints))

        def straight(a, b):
            floor = self._floor(margins[a:b + 1], clearance)
            return self._validate_between(joints[[a, b]], poses[a], poses[b], floor, world).ok

        kept, at = [0], 0
        while at < len(joints) - 1:
            if termination():
                return None
            low, high = at + 1, len(joints) - 1
            if high > low and straight(at, high):
                low = high
            while high - low > 1:
                middle = (low + high) // 2
                if straight(at, middle):
                    low = middle
                else:
                    high = middle
            kept.append(low)
            at = low
        if len(kept) == len(joints):
            return None
        kept = np.array(kept)
        taut = self._validate(joints[kept], s, g, self.min_margin, world)
        return (taut, joints[kept], patches[kept]) if taut.ok else None

    def _failed_segment(self, result, joints, patches):
        """Index k of the segment from waypoint k - 1 to k where a refused path
        failed.  For a path that ends in another assembly mode, it is the
        segment after the last waypoint where the followed pose is still its
        patch's solution at the waypoint's cell (the platform strayed onto
        another sheet after it)."""
        if result.ok or result.failed_segment >= 1:
            return result.failed_segment
        cells = self.roadmap.grid.cells_of(joints[:, self._free])
        seg = self.roadmap.segmentation
        member = seg.patch[cells] == patches[:, None]
        sheet = seg.field.poses[cells, np.argmax(member, axis=1)]
        mechanism = self.roadmap.mechanism
        grid = self.roadmap.grid
        verifiable = np.all(np.abs(joints - grid.nearest_joints(joints, grid.joints_at(cells)))
                            < 1e-9, axis=1) & member.any(axis=1)
        off = verifiable & (mechanism.pose_distance(result.poses, sheet)
                            > _STRAYED * mechanism.scale)
        off[0] = False
        first_off = int(np.argmax(off)) if off.any() else len(joints) - 1
        on = np.flatnonzero(verifiable[:first_off] & ~off[:first_off])
        return 1 + int(on.max(initial=0))

    def _kept_margin(self, s, g, clearance):
        return max(self.min_margin, min(0.25 * clearance, abs(s.margin), abs(g.margin)))

    def _validate(self, joints, s, g, min_margin, world=None):
        """:meth:`_validate_between` the located start and goal."""
        return self._validate_between(joints, s.pose, g.pose, min_margin, world)

    def _validate_between(self, joints, start_pose, goal_pose, min_margin, world=None):
        """The validator's verdict on ``joints`` followed from ``start_pose``
        to ``goal_pose``, and in a scene the continuous collision check's: a
        path that collides fails at the segment where it does."""
        mechanism = self.roadmap.mechanism
        result = validate_path(mechanism, joints, start_pose, goal_pose, min_margin,
                               self.max_step)
        if not result.ok or world is None:
            return result
        from ..world import path_collisions  # the world's kernels load only with a scene

        hit = path_collisions(mechanism, world.scene, joints, start_pose, world.index.model)
        if hit is None:
            return result
        return dataclasses.replace(result, ok=False, reason=f"collision {hit.message}",
                                   failed_segment=min(int(hit.index) + 1, len(joints) - 1))

    def _check_free(self, world, location, which):
        """Raise ``CollisionError`` when a located configuration collides or
        breaks a limit of the scene."""
        from ..world import configuration_collision

        hit = configuration_collision(self.roadmap.mechanism, world.scene, location.joints,
                                      location.pose, world.index.model)
        if hit is not None:
            raise CollisionError(f"the {which} is blocked: {hit.message}")

    def apply_scene(self, scene, model=None):
        """The roadmap restricted to a scene, for :meth:`plan`'s ``world``.

        The first call for a body model computes what every scene reads
        (:class:`~rpr3_gwr_core.world.WorldIndex`: about a second on the
        paper's slice, ten on a full 3-DOF roadmap) and keeps it; each
        scene then takes tenths of a second, without the field or the gates
        being computed again.

        Parameters
        ----------
        scene : Scene
        model : BodyModel, optional
            Widths and layers of the bodies (default: each leg in a layer of
            its own).

        Returns
        -------
        SceneRoadmap
        """
        from ..world import WorldIndex

        key = None if model is None else repr(model)
        index = self._world_indices.get(key)
        if index is None:
            index = self._world_indices[key] = WorldIndex(self.roadmap, model)
        return index.apply(scene)

    def adopt_scene_indices(self, other):
        """Take what :meth:`apply_scene` computed once per body model on
        another planner of an equal roadmap (for example the roadmap
        received, before this planner mapped it from its planning files),
        so that scenes applied here do not compute it again.

        Parameters
        ----------
        other : Planner

        Raises
        ------
        InvalidInputError
            If the other planner's roadmap differs from this one's.
        """
        for key, index in other._world_indices.items():
            self._world_indices.setdefault(key, index.on_roadmap(self.roadmap))

    def _waypoints(self, s, g, cells, patches):
        """Exact start, the centres of a cell path's ``cells`` (of ``patches``),
        exact goal; repeated points dropped; continuous along periodic axes
        (from the start's values, so the goal's may differ from those asked
        by whole turns).

        Returns the legs, the patch of each waypoint and its index in
        ``cells`` (-1 for the exact start and goal)."""
        joints = np.vstack([s.joints, self.roadmap.grid.joints_at(cells), g.joints])
        if self.roadmap.grid.periodic:
            joints = self.roadmap.grid.unwrap(joints)
        patches = np.concatenate([[s.patch], patches, [g.patch]])
        origin = np.concatenate([[-1], np.arange(len(cells)), [-1]])
        keep = np.ones(len(joints), dtype=bool)
        keep[1:] = np.any(np.abs(np.diff(joints, axis=0)) > 1e-12, axis=1)
        return joints[keep], patches[keep], origin[keep]

    def _waypoint_margins(self, joints, patches):
        """Margin of each waypoint's patch solution at its cell, 0 where that
        cell has none (the exact start and goal may lie in such a cell; the
        validator checks the margin there)."""
        return self._patch_margin(patches, self.roadmap.grid.cells_of(joints[:, self._free]))

    @staticmethod
    def _floor(margins, clearance):
        """Margin a straight segment must keep over a stretch of the path
        (``margins`` of its waypoints): the clearance, or less where the
        stretch itself passes closer."""
        return min(clearance, float(margins[margins > 0].min(initial=clearance)))

    def _patch_margin(self, patches, cells):
        """Margin magnitude of the given patches' solutions at cells, 0 where
        the patch has none."""
        seg = self.roadmap.segmentation
        member = seg.patch[cells] == np.asarray(patches)[:, None]
        slots = np.argmax(member, axis=1)
        return np.where(member.any(axis=1), np.abs(seg.field.margin[cells, slots]), 0.0)

    def _clear(self, starts, ends, patches, floors):
        """Whether each straight joint segment from ``starts[k]`` to
        ``ends[k]`` stays on patch ``patches[k]`` with margins of at least
        ``floors[k]`` (sampled), all segments at once.

        Returns
        -------
        ndarray of bool, shape (len(starts),)
        """
        return segments_clear(
            np.ascontiguousarray(np.asarray(starts)[:, self._free]),
            np.ascontiguousarray(np.asarray(ends)[:, self._free]),
            np.asarray(patches, dtype=np.int64), np.asarray(floors, dtype=float), self._sheets)

    def _shortcut(self, joints, patches, margins, clearance, split=False):
        """Indices of the waypoints kept when the path is shortcut by straight
        segments crossing its patches in order (:func:`~.segments.shortcut_path`);
        with ``split``, the jump from the first waypoint
        straight to the last is not allowed.  ``margins`` are the waypoints'
        (:meth:`_waypoint_margins`)."""
        return shortcut_path(np.ascontiguousarray(joints[:, self._free]),
                             np.asarray(patches, dtype=np.int64), margins, clearance, split,
                             self._sheets)

    def _round(self, joints, patches, s, g, clearance, keep, world=None):
        """The path with its corners cut (Chaikin) where the cut keeps to the
        corner's patch and the margin the stretch keeps; corners next to
        where the validator refuses the cut path are put back, a few times.

        Returns the validation, legs and patches of the rounded path, or
        None when no corner could be cut."""
        margins = self._waypoint_margins(joints, patches)
        inner = np.arange(1, len(joints) - 1)
        inner = inner[(patches[inner - 1] == patches[inner])
                      & (patches[inner] == patches[inner + 1])]
        # A cut corner is three segments to check.
        before, after = corner_cuts(joints, inner)
        floors = [self._floor(margins[i - 1:i + 2], clearance) for i in inner]
        clear = self._clear(np.concatenate([joints[inner - 1], before, after]),
                            np.concatenate([before, after, joints[inner + 1]]),
                            np.tile(patches[inner], 3), np.tile(floors, 3))
        corners = np.zeros(len(joints), dtype=bool)
        corners[inner] = clear.reshape(3, -1).all(axis=0)
        for _ in range(self.retries.split_shortcuts + 1):
            if not corners.any():
                return None
            rounded, origin = cut_corners(joints, corners)
            result = self._validate(rounded, s, g, keep, world)
            if result.ok:
                return result, rounded, patches[origin]
            k = max(result.failed_segment, 1)
            corners[origin[k - 1]:origin[min(k, len(origin) - 1)] + 1] = False
        return None


def _crossed(patches):
    """The patches a waypoint path crosses, in order, as a tuple of ids."""
    patches = np.asarray(patches)
    return tuple(int(p) for p in patches[np.concatenate([[True], patches[1:] != patches[:-1]])])


def _rerouted(search, cells, patches, stretch, blocked, any_gates):
    """A cell path (``cells`` of ``patches``) with its stretch from index
    ``stretch[0]`` to ``stretch[1]`` searched again around the blocked cells
    with ``search`` (the local planner's ``plan``, through any gates with
    ``any_gates``); the cells and their patches, or None when the stretch is
    the whole path or has no way round."""
    first, last = stretch
    if first == 0 and last == cells.size - 1:
        return None
    through = _crossed(patches[first:last + 1])
    if any_gates:
        through = (through[0], through[-1])
    try:
        local = search(through, cells[first], cells[last],
                       blocked - {int(cells[first]), int(cells[last])})
    except InfeasiblePathError:
        return None
    return (np.concatenate([cells[:first], local.cells, cells[last + 1:]]),
            np.concatenate([patches[:first], local.patches, patches[last + 1:]]))


def _turns(points):
    """Indices of a polyline's ends and of the points where it turns."""
    step = np.diff(points, axis=0)
    length = np.linalg.norm(step, axis=1, keepdims=True)
    direction = step / np.where(length > 0, length, 1.0)
    straight = np.all(np.abs(direction[1:] - direction[:-1]) < 1e-9, axis=1)
    return np.flatnonzero(np.concatenate([[True], ~straight, [True]]))
