"""The hierarchical planner's strategy: locate, global path, cell path,
repairs, simplification, timing and validation, for one roadmap.

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
   (:meth:`~.cell_search.CellSearch.cheapest_patches`): fewest gates
   can mean a long way round inside one patch;
3. the global paths listed, then longer ones.

Each request is a :class:`~.problem.PlanningProblem`.  The cell search's
path is repaired (:mod:`~.repair`) and simplified (:mod:`~.simplifier`)
until the motion checker (:mod:`~.motion`: the validator by continuation
and, in a scene, the collision check) passes it; when it fails, the next
candidate is tried, and the plan is an error when none passes.  A plan
declares its outcome (:class:`~.request.PlanStatus`): a deadline that cuts
simplification short leaves an approximate solution, valid but not smoothed.
"""

import itertools
import math

import numpy as np

from ..exceptions import (GWRError, InfeasiblePathError, InvalidInputError,
                          PlanningTimeoutError, UndecidedError, ValidationError)
from .cell_search import DEFAULT_CLEARANCE_WEIGHT, CellSearch
from .global_planning import (GlobalPath, PatchGraph, feasibility, global_paths,
                              longer_paths)
from .index import CellSearchIndex
from .locate import DEFAULT_MODE_TOL, locate
from .motion import MotionChecker
from .problem import PlanningProblem
from .repair import PathRepairer, crossed_patches
from .request import DEFAULT_CLEARANCE, Plan, PlanOptions, PlanStatus, Retries
from .simplifier import PathSimplifier
from .termination import NEVER
from .trajectory import time_parameterize
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN

__all__ = ["Planner", "build_cell_search_index"]

def build_cell_search_index(roadmap, clearances=(DEFAULT_CLEARANCE,),
                            clearance_weight=DEFAULT_CLEARANCE_WEIGHT, retries=Retries(),
                            graph_from=None):
    """The :class:`~.index.CellSearchIndex` a :class:`Planner` reads.

    Seconds on the full 3-DOF roadmap.

    Parameters
    ----------
    roadmap : Roadmap
    clearances : sequence of float
        Clearances whose gate distances the index holds.
    clearance_weight : float
        The planner's cell cost weight; the index holds its node costs and
        those of ``retries.detour_weight``.
    retries : Retries
    graph_from : CellSearchIndex, optional
        An index of the same roadmap whose node graph is taken.

    Returns
    -------
    CellSearchIndex

    Raises
    ------
    InvalidInputError
        As :meth:`~.index.CellSearchIndex.build`.
    """
    return CellSearchIndex.build(roadmap, clearances, (clearance_weight, retries.detour_weight),
                                 graph_from)


class Planner:
    """Plans on one roadmap.

    Everything a plan reads is built when the planner is made, or given:
    the roadmap and its cell search index.  A plan changes nothing but the
    lookups of clearances and weights the index lacks, computed on first
    use, so one planner serves requests in several threads at once.

    Parameters
    ----------
    roadmap : Roadmap
    index : CellSearchIndex, optional
        The roadmap's, built or mapped (:mod:`~rpr3_gwr_core.io.cache`);
        by default :func:`build_cell_search_index` of the roadmap, with this
        planner's weights.
    clearance_weight : float
        The paper's boundary cost weight of the cell search (0: shortest
        paths).
    min_margin : float
        Smallest normalised ``|det Jx|`` accepted at start, goal and along a plan.
    max_step : float
        Validator's continuation step [length unit].
    retries : Retries
        How hard a plan tries before it fails.

    Attributes
    ----------
    search_index : CellSearchIndex
        The roadmap's (``index``).
    patch_graph : PatchGraph
        The global searches' graph of patches.
    cell_search : CellSearch
        The searches on the roadmap's node graph.
    checker : MotionChecker
        The verdict every plan passes.
    simplifier : PathSimplifier
    repairer : PathRepairer
    """

    def __init__(self, roadmap, index=None, clearance_weight=DEFAULT_CLEARANCE_WEIGHT,
                 min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP, retries=Retries()):
        self.roadmap = roadmap
        self.retries = retries
        if not (math.isfinite(clearance_weight) and clearance_weight >= 0):
            raise InvalidInputError("clearance_weight must be finite and non-negative")
        if index is None:
            index = build_cell_search_index(roadmap, clearance_weight=clearance_weight,
                                            retries=retries)
        self.search_index = index
        self.patch_graph = PatchGraph(roadmap, index)
        self.cell_search = CellSearch(roadmap, index)
        self.clearance_weight = float(clearance_weight)
        self.checker = MotionChecker(roadmap, min_margin, max_step)
        self.simplifier = PathSimplifier(roadmap, self.checker, retries.split_shortcuts)
        self.repairer = PathRepairer(roadmap, self.cell_search, self.checker, self.simplifier,
                                     retries, clearance_weight)
        self._world_indices = {}

    @property
    def min_margin(self):
        """Smallest normalised ``|det Jx|`` accepted at start, goal and along a plan."""
        return self.checker.min_margin

    @property
    def max_step(self):
        """The validator's continuation step [length unit]."""
        return self.checker.max_step

    def __repr__(self):
        return (f"Planner({self.roadmap!r}, clearance weight {self.clearance_weight:g}, "
                f"min margin {self.min_margin:g})")

    def warm_up(self):
        """Load every compiled kernel a plan can use (or, on a cold numba
        cache, compile them: seconds) now rather than during a first
        request: a plan inside the first patch, smoothed and timed, a
        segment test for the corners that plan may not have, and the least
        costs across each patch between its gates at the default clearance
        (for :meth:`~.cell_search.CellSearch.cheapest_patches`: tens of
        milliseconds on a full 3-DOF roadmap).

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
        self.simplifier.segments_clear(joints[:1], joints[1:], [patch.id], [0.0])
        for (a, b), gate in itertools.islice(seg.gates.items(), 1):
            self.cell_search.cheapest_patches(a, int(gate.faces[0, 0]), b,
                                              int(gate.faces[0, 1]), DEFAULT_CLEARANCE)

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
            path found so far, an approximate solution without the
            smoothing steps not done yet (:attr:`Plan.skipped`), or a
            ``PlanningTimeoutError`` when there is none.
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
            ``"blocked"`` when the roadmap joins them and the scene does not,
            or leaves the grid cell of a clear end no way out) when there is
            no path, ``ValidationError`` when no path passes the validator,
            ``PlanningTimeoutError`` when the deadline passed before one did,
            ``InvalidInputError`` when the limits cannot time the path, or
            the locating errors of :func:`~rpr3_gwr_core.locate.locate`, or
            per-joint limits that are not one per joint.
        """
        n_joints = self.roadmap.mechanism.n_joints
        for name in ("max_velocity", "max_acceleration"):
            limit = getattr(options, name)
            if isinstance(limit, tuple) and len(limit) != n_joints:
                raise InvalidInputError(f"{name} gives {len(limit)} limits for the "
                                        f"{n_joints} joints")
        problem = PlanningProblem(self.locate(start, options.mode_tol),
                                  self.locate(goal, options.mode_tol), options.clearance,
                                  termination, world)
        answer = self._feasibility(problem)
        s, g = problem.start, problem.goal
        paths = global_paths(self.patch_graph, s.patch, g.patch, options.weighted,
                             options.max_paths)
        if options.feasibility_only:
            mechanism = self.roadmap.mechanism
            return Plan(PlanStatus.EXACT_SOLUTION, answer.reason, s, g, paths,
                        joints=np.zeros((0, mechanism.n_joints)),
                        poses=np.zeros((0, mechanism.pose_size)))
        found = None
        if world is not None or (not options.weighted and not self.roadmap.grid.fixed):
            found = self._promising(problem)
        if found is None:
            found = self._along_global_paths(paths, problem)
        path, result, joints, patches = found
        smoothed = False
        skipped = []
        if options.smooth and len(joints) > 2 and not self.roadmap.grid.fixed:
            try:
                taut = self.simplifier.pull_taut(joints, patches, result, problem)
            except PlanningTimeoutError:
                taut = None
                skipped.append("pulling taut")
            if taut is not None:
                result, joints, patches = taut
                smoothed = True
        if options.smooth and len(joints) > 2:
            if termination():
                skipped.append("rounding")
            else:
                rounded = self.simplifier.round(
                    joints, patches, problem,
                    min(result.min_margin, problem.kept_margin(self.min_margin)))
                if rounded is not None:
                    result, joints, patches = rounded
                    smoothed = True
        if path.patches not in {p.patches for p in paths}:
            # A path of the searches that cross any gate: its cells may weave
            # along a gate, in and out of two patches, where the trajectory
            # crosses the patches of its waypoints (when gates join them: a
            # smoothed segment may pass through a patch that has no waypoint).
            crossed = crossed_patches(patches)
            if all(self.patch_graph.weighted.has_edge(a, b)
                   for a, b in zip(crossed, crossed[1:])):
                path = GlobalPath(crossed, self.patch_graph.path_cost(crossed))
            if path.patches not in {p.patches for p in paths}:
                paths.append(path)
        path_index = next(k for k, p in enumerate(paths) if p.patches == path.patches)
        timing = (None, None, None)
        if options.max_velocity is not None:
            timing = time_parameterize(joints, options.max_velocity, options.max_acceleration)
        status = PlanStatus.APPROXIMATE_SOLUTION if skipped else PlanStatus.EXACT_SOLUTION
        return Plan(status, answer.reason, s, g, paths, path_index=path_index, joints=joints,
                    poses=result.poses, patches=patches, times=timing[0],
                    velocities=timing[1], accelerations=timing[2], validation=result,
                    smoothed=smoothed, skipped=tuple(skipped))

    def _feasibility(self, problem):
        """The roadmap's answer on the problem's ends, in its scene.

        Raises
        ------
        CollisionError
            When an end collides or breaks a limit of the scene.
        InfeasiblePathError
            When the roadmap, or the scene, joins no path between them.
        UndecidedError
            When neither does, and thin regions of the ends' aspect are left.
        """
        s, g, world = problem.start, problem.goal, problem.world
        if world is not None:
            self.checker.check_free(s, "start", world)
            self.checker.check_free(g, "goal", world)
        answer = feasibility(self.patch_graph, s.patch, g.patch)
        if answer.feasible and world is not None:
            answer = world.feasibility(s, g)
            if answer.reason == "in_collision":
                # The ends themselves are clear (check_free): the scene is
                # resolved cell by cell, and their cell's solution is not.
                which = "start" if answer.start_part < 0 else "goal"
                raise InfeasiblePathError(
                    f"the {which} is clear of the scene, its grid cell's solution is not (an "
                    "obstacle or a limit lies within a cell of it): on this grid no way leaves "
                    f"the {which}; a finer grid resolves the scene nearer to it", "blocked")
        if answer.reason == "undecided":
            thin = feasibility(self.patch_graph, s.patch, g.patch).thin_patches
            grid = self.roadmap.grid
            raise UndecidedError(
                f"undecided: no chain of gates joins patch {s.patch} to patch {g.patch}, and "
                f"thin regions of their aspect are left ({_patches(thin)}) at the grid's "
                f"finest cell ({_steps(grid, self.roadmap.mechanism)}): a finer cell may join "
                "them", thin, grid.steps)
        if not answer.feasible:
            # The scene is resolved cell by cell: where an obstacle or a limit
            # leaves a band narrower than a cell (along a fold, where the
            # joints barely move as the platform does), the grid sees no way
            # that the platform has.
            raise InfeasiblePathError(
                f"no path from patch {s.patch} to patch {g.patch}: "
                f"{answer.reason.replace('_', ' ')}"
                + (" by the scene on this grid: a way narrower than one of its cells "
                   "is not seen, a finer grid shows one if it exists"
                   if answer.reason == "blocked" else ""), answer.reason)
        return answer

    def _along_global_paths(self, paths, problem):
        """The first global path (:meth:`_attempts`) whose cell path passes
        the motion checker, with that verdict, waypoints and their patches.

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
        s, g = problem.start, problem.goal
        for reroute in (True, False) if self.retries.repairs > 0 else (False,):
            for path in self._attempts(paths, s.patch, g.patch):
                if path.patches in unplanned:
                    continue
                name = f"path {list(path.patches)}{'' if reroute else ' searched whole'}"
                try:
                    if problem.termination():
                        raise PlanningTimeoutError("the time limit passed")
                    result, joints, patches = self.repairer.along(problem, path,
                                                                  reroute=reroute)
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

    def _promising(self, problem):
        """The first path of the two most promising searches that passes,
        each cell search given ``retries.promising_nodes``: the least-cost
        path on the node graph, crossing any gates
        (:meth:`~.cell_search.CellSearch.search` with ``any_gates``), then
        the path through the cheapest patches
        (:meth:`~.cell_search.CellSearch.cheapest_patches`).

        The first search's estimate is only the straight length to the
        goal, so it takes long where the shortest path goes far around; the
        second's patches can be narrow where repairs take long; either way
        the global paths then take over.  In a scene the first search has
        no budget: it is the one that goes wherever the scene leaves a way.

        Returns
        -------
        (GlobalPath, Validation, ndarray, ndarray) or None
            The patches the path crosses, in order (a patch may come back),
            its verdict, waypoints and their patches.
        """
        budget = self.retries.promising_nodes
        in_scene = problem.world is not None
        if budget == 0 and not in_scene:
            return None
        s, g = problem.start, problem.goal
        try:
            result, joints, patches, route = self.repairer.repair(
                problem, None, self.clearance_weight, None if in_scene else budget)
        except (InfeasiblePathError, PlanningTimeoutError):
            result = None
        if result is None or not result.ok:
            route = self.cell_search.cheapest_patches(s.patch, s.cell, g.patch, g.cell,
                                                      problem.clearance)
            if route is None or budget == 0:
                return None
            try:
                result, joints, patches = self.repairer.along(problem, GlobalPath(route, 0.0),
                                                              budget)
            except (InfeasiblePathError, PlanningTimeoutError):
                return None
            if not result.ok:
                return None
        return GlobalPath(route, self.patch_graph.path_cost(route)), result, joints, patches

    def _attempts(self, paths, start_patch, goal_patch):
        """The listed global paths, then longer ones, ``retries.global_paths`` in all;
        a longer path that is tried is appended to ``paths`` so a plan can
        point at it."""
        most = self.retries.global_paths
        yield from paths[:most]
        listed = {p.patches for p in paths}
        extra = (p for p in longer_paths(self.patch_graph, start_patch, goal_patch)
                 if p.patches not in listed)
        for path in itertools.islice(extra, max(0, most - len(paths))):
            paths.append(path)
            yield path

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


def _steps(grid, mechanism):
    """The grid's finest step along each axis, named by joint [joint unit]."""
    return ", ".join(f"{mechanism.joint_names[axis.joint]} step {step:.4g}"
                     for axis, step in zip(grid.axes, grid.steps))


def _patches(ids):
    return f"patch{'es' if len(ids) > 1 else ''} {', '.join(map(str, ids))}"
