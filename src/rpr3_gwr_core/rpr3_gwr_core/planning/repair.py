"""The repair loop: a cell path along a global path, turned into waypoints,
simplified, and searched again around the step the motion checker refuses.

The path's cells keep the clearance where they can, but between two cell
centres next to a cusp point, or over a singular sliver thinner than a
cell, the sheet can dip far lower, even below ``min_margin``.  The path must
therefore keep a quarter of the clearance (or half the margin of the
start or goal when that is less) in the motion checker; where it does not,
the cells around the step where it dipped are blocked, in a box growing
with each repair, and the stretch of the cell path around them searched
again (or the whole path), a few times, before a path that keeps
``min_margin`` will do.
"""

import functools
from typing import NamedTuple

import numpy as np

from ..exceptions import InfeasiblePathError, PlanningTimeoutError

__all__ = ["PathRepairer", "RepairedPath", "crossed_patches", "rerouted_stretch"]

# A repair searches again the cell path's stretch from this many cells before
# the refused step to as many after it, times the repair's number: as far as
# the box of blocked cells around the step grows.
_REPAIR_REACH = 8


def crossed_patches(patches):
    """The patches a waypoint path crosses, in order (a patch may come back).

    Parameters
    ----------
    patches : array_like of int, shape (n,)
        The patch of each waypoint, n >= 1.

    Returns
    -------
    tuple of int
    """
    patches = np.asarray(patches)
    return tuple(int(p) for p in patches[np.concatenate([[True], patches[1:] != patches[:-1]])])


def rerouted_stretch(search, cells, patches, stretch, blocked, any_gates):
    """A cell path with one stretch searched again around blocked cells.

    Parameters
    ----------
    search : callable
        The cell search (:meth:`~.cell_search.CellSearch.search` with the
        request's settings bound), called as ``search(patches, start_cell,
        goal_cell, blocked)``.
    cells, patches : ndarray of int, shape (n,)
        The cell path and the patch of each cell.
    stretch : (int, int)
        First and last index of the stretch.
    blocked : set of int
        Cells the new stretch must not enter.
    any_gates : bool
        Whether the search crosses any gates (then only the stretch's end
        patches are passed), or the patches the stretch crosses in order.

    Returns
    -------
    (ndarray, ndarray) or None
        The cells and their patches, or None when the stretch is the whole
        path or has no way round.
    """
    first, last = stretch
    if first == 0 and last == cells.size - 1:
        return None
    through = crossed_patches(patches[first:last + 1])
    if any_gates:
        through = (through[0], through[-1])
    try:
        local = search(through, cells[first], cells[last],
                       blocked - {int(cells[first]), int(cells[last])})
    except InfeasiblePathError:
        return None
    return (np.concatenate([cells[:first], local.cells, cells[last + 1:]]),
            np.concatenate([patches[:first], local.patches, patches[last + 1:]]))


class RepairedPath(NamedTuple):
    """The outcome of a repair loop.

    Attributes
    ----------
    validation : Validation
        The motion checker's verdict on the waypoints (it may be a refusal).
    joints : ndarray, shape (n, n_joints)
        Waypoints [joint unit].
    patches : ndarray of int, shape (n,)
        The patch of each waypoint.
    crossed : tuple of int
        The patches the cell path crosses, in order.
    """

    validation: object
    joints: np.ndarray
    patches: np.ndarray
    crossed: tuple


class PathRepairer:
    """Runs the repair loop on one roadmap.

    Parameters
    ----------
    roadmap : Roadmap
    cell_search : CellSearch
    checker : MotionChecker
    simplifier : PathSimplifier
    retries : Retries
    clearance_weight : float
        The planner's cell cost weight, tried first.
    """

    def __init__(self, roadmap, cell_search, checker, simplifier, retries, clearance_weight):
        self.roadmap = roadmap
        self.cell_search = cell_search
        self.checker = checker
        self.simplifier = simplifier
        self.retries = retries
        self.clearance_weight = float(clearance_weight)

    def weights(self):
        """The clearance weights a global path's cell path is tried with,
        each with the inflation of its searches' estimate.

        Returns
        -------
        dict of float to int
        """
        weights = {self.clearance_weight: 1}
        weights.setdefault(self.retries.detour_weight, self.retries.detour_inflation)
        return weights

    def along(self, problem, path, most_settled=None, reroute=True):
        """A path along a global path that passes the motion checker,
        shortcut where the shortcut path passes too; when every repair of
        the shortest cell path fails, the same for the cell path the detour
        weight keeps in the middle of its patches.

        Parameters
        ----------
        problem : PlanningProblem
        path : GlobalPath
        most_settled : int, optional
            Budget of each cell search (nodes settled).
        reroute : bool
            Repairs search stretches and the detour's searches inflate their
            estimate (:meth:`repair`); else every search is a least-cost
            one of the whole path.

        Returns
        -------
        (Validation, ndarray, ndarray)
            The verdict (the last refusal when none passes), waypoints and
            their patches.

        Raises
        ------
        InfeasiblePathError
            If the cell search finds no way through the path's patches.
        PlanningTimeoutError
            If the deadline passes, or a budget is spent, first.
        """
        for weight, inflation in self.weights().items():
            result, joints, patches, _ = self.repair(
                problem, path, weight, most_settled, inflation if reroute else 1, reroute)
            if result.ok:
                break
        return result, joints, patches

    def repair(self, problem, path, weight, most_settled=None, inflation=1, reroute=True):
        """The cell path along a global path (through any gates when None),
        repaired where the motion checker refuses it (module doc).

        Parameters
        ----------
        problem : PlanningProblem
        path : GlobalPath or None
        weight : float
            Clearance weight of the cell searches.
        most_settled : int, optional
            Budget of each cell search (nodes settled).
        inflation : int
            Factor on the cell searches' estimate.
        reroute : bool
            Search again only a stretch around the refused step, else the
            whole path.

        Returns
        -------
        RepairedPath

        Raises
        ------
        InfeasiblePathError
            If the first cell search finds no way.
        PlanningTimeoutError
            If the deadline passes, or a budget is spent, first.
        """
        s, g = problem.start, problem.goal
        keep = problem.kept_margin(self.checker.min_margin)
        blocked = set()
        tried = []
        free = list(self.roadmap.grid.axis_joints)
        search = functools.partial(self.cell_search.search, clearance=problem.clearance,
                                   clearance_weight=weight, termination=problem.termination,
                                   any_gates=path is None, most_settled=most_settled,
                                   world=problem.world, inflation=inflation)
        route = (s.patch, g.patch) if path is None else path.patches
        cell_path = stretch = None
        for repair in range(self.retries.repairs + 1):
            if problem.termination():
                raise PlanningTimeoutError("the time limit passed")
            try:
                if stretch is not None and reroute:
                    cell_path = rerouted_stretch(search, *cell_path, stretch, blocked,
                                                 path is None)
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
            joints, patches, origin = self.waypoints(problem, cells, cell_patches)
            earlier = None
            if tried:
                last_joints, _, last_kept, last_result = tried[-1]
                earlier = last_result, last_joints[last_kept]
            result, kept = self.simplifier.shortcut(joints, patches, problem, keep, earlier)
            tried.append((joints, patches, kept, result))
            if result.ok:
                return RepairedPath(result, joints[kept], patches[kept],
                                    crossed_patches(patches))
            k = self.checker.failed_segment(result, joints[kept], patches[kept])
            if k < 1:
                break
            a, b = kept[k - 1], kept[k]
            middle = 0.5 * (joints[a, free] + joints[b, free])
            around = self.cell_search.cells_around(middle, 0.5 + repair).tolist()
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
        for joints, patches, kept, _ in (tried[-1], tried[0])[:len(tried)]:
            for waypoints in (kept, np.arange(len(joints))):
                result = self.checker.check(joints[waypoints], problem, self.checker.min_margin)
                if result.ok:
                    return RepairedPath(result, joints[waypoints], patches[waypoints],
                                        crossed_patches(patches))
        return RepairedPath(result, joints, patches, crossed_patches(patches))

    def waypoints(self, problem, cells, patches):
        """Waypoints of a cell path: the exact start, the centres of the
        cells, the exact goal; repeated points dropped; continuous along
        periodic axes (from the start's values, so the goal's may differ
        from those asked by whole turns).

        Parameters
        ----------
        problem : PlanningProblem
        cells, patches : ndarray of int, shape (m,)
            The cell path and the patch of each cell.

        Returns
        -------
        (ndarray, ndarray, ndarray)
            The waypoints [joint unit], the patch of each and its index in
            ``cells`` (-1 for the exact start and goal).
        """
        s, g = problem.start, problem.goal
        grid = self.roadmap.grid
        joints = np.vstack([s.joints, grid.joints_at(cells), g.joints])
        if grid.periodic:
            joints = grid.unwrap(joints)
        patches = np.concatenate([[s.patch], patches, [g.patch]])
        origin = np.concatenate([[-1], np.arange(len(cells)), [-1]])
        keep = np.ones(len(joints), dtype=bool)
        keep[1:] = np.any(np.abs(np.diff(joints, axis=0)) > 1e-12, axis=1)
        return joints[keep], patches[keep], origin[keep]
