"""The path simplifier, as OMPL's ``PathSimplifier``: shortcutting, pulling
taut and rounding a waypoint path, each result kept only where the motion
checker (:class:`~.motion.MotionChecker`) passes it.

A cell path runs from face to face; shortcut by straight segments that
cross its patches in the same order (:func:`~.segments.shortcut_path`,
sampled on the patches' sheets), it comes close to the shortest path that
keeps the requested clearance.  Pulling it taut lets straight segments
leave that order where the platform follows them; rounding cuts its
corners (Chaikin, :func:`~.trajectory.cut_corners`).
"""

import numbers

import numpy as np

from ..exceptions import InvalidInputError, PlanningTimeoutError
from .segments import Sheets, segments_clear, shortcut_path
from .trajectory import corner_cuts, cut_corners
from .validation import joined_validation, validation_part

__all__ = ["PathSimplifier", "polyline_turns", "segment_floor"]

# Shortcuts are checked at this many points per grid step.
_SAMPLES_PER_CELL = 5


def polyline_turns(points):
    """Indices of a polyline's ends and of the points where it turns.

    Parameters
    ----------
    points : ndarray, shape (n, d)
        At least two points [joint unit].

    Returns
    -------
    ndarray of int
        Ascending, 0 and ``n - 1`` included.

    Raises
    ------
    InvalidInputError
        If ``points`` is not a finite (n, d) array with n >= 2.
    """
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or len(points) < 2 or not np.isfinite(points).all():
        raise InvalidInputError(f"a polyline needs at least two finite points in rows, got "
                                f"shape {points.shape}")
    step = np.diff(points, axis=0)
    length = np.linalg.norm(step, axis=1, keepdims=True)
    direction = step / np.where(length > 0, length, 1.0)
    straight = np.all(np.abs(direction[1:] - direction[:-1]) < 1e-9, axis=1)
    return np.flatnonzero(np.concatenate([[True], ~straight, [True]]))


def segment_floor(margins, clearance):
    """Margin a straight segment must keep over a stretch of a path: the
    clearance, or less where the stretch itself passes closer.

    Parameters
    ----------
    margins : ndarray, shape (n,)
        Margin magnitude of the stretch's waypoints, 0 where unknown.
    clearance : float

    Returns
    -------
    float
    """
    margins = np.asarray(margins, dtype=float)
    return min(clearance, float(margins[margins > 0].min(initial=clearance)))


class PathSimplifier:
    """Simplifies waypoint paths on one roadmap.

    Parameters
    ----------
    roadmap : Roadmap
    checker : MotionChecker
        The verdict every simplified path must pass.
    split_shortcuts : int
        Refused shortcuts split into shorter ones (or cut corners put back)
        before giving up.

    Raises
    ------
    InvalidInputError
        If ``split_shortcuts`` is not a whole number of at least 0.
    """

    def __init__(self, roadmap, checker, split_shortcuts):
        if isinstance(split_shortcuts, bool) or not isinstance(split_shortcuts, numbers.Integral) \
                or split_shortcuts < 0:
            raise InvalidInputError(f"split_shortcuts must be a whole number of at least 0, got "
                                    f"{split_shortcuts!r}")
        self.roadmap = roadmap
        self.checker = checker
        self.split_shortcuts = int(split_shortcuts)
        self._free = list(roadmap.grid.axis_joints)
        seg, mechanism = roadmap.segmentation, roadmap.mechanism
        self._sheets = Sheets(roadmap.grid.lattice, roadmap.grid.step, _SAMPLES_PER_CELL,
                              seg.patch, seg.field.margin, seg.field.poses,
                              np.where(mechanism.angular, mechanism.scale, 0.0))

    def waypoint_margins(self, joints, patches):
        """Margin magnitude of each waypoint's patch solution at its cell, 0
        where that cell has none (the exact start and goal may lie in such a
        cell; the motion checker checks the margin there).

        Parameters
        ----------
        joints : ndarray, shape (n, n_joints)
        patches : ndarray of int, shape (n,)

        Returns
        -------
        ndarray, shape (n,)
        """
        seg = self.roadmap.segmentation
        cells = self.roadmap.grid.cells_of(joints[:, self._free])
        member = seg.patch[cells] == np.asarray(patches)[:, None]
        slots = np.argmax(member, axis=1)
        return np.where(member.any(axis=1), np.abs(seg.field.margin[cells, slots]), 0.0)

    def segments_clear(self, starts, ends, patches, floors):
        """Whether each straight joint segment from ``starts[k]`` to
        ``ends[k]`` stays on patch ``patches[k]`` with margins of at least
        ``floors[k]`` (sampled on the sheets), all segments at once.

        Parameters
        ----------
        starts, ends : array_like, shape (m, n_joints)
        patches : array_like of int, shape (m,)
        floors : array_like, shape (m,)

        Returns
        -------
        ndarray of bool, shape (m,)
        """
        return segments_clear(
            np.ascontiguousarray(np.asarray(starts)[:, self._free]),
            np.ascontiguousarray(np.asarray(ends)[:, self._free]),
            np.asarray(patches, dtype=np.int64), np.asarray(floors, dtype=float), self._sheets)

    def _shortcut(self, joints, patches, margins, clearance, split=False):
        """Indices of the waypoints kept when the path is shortcut by straight
        segments crossing its patches in order; with ``split``, the jump from
        the first waypoint straight to the last is not allowed."""
        return shortcut_path(np.ascontiguousarray(joints[:, self._free]),
                             np.asarray(patches, dtype=np.int64), margins, clearance, split,
                             self._sheets)

    def shortcut(self, joints, patches, problem, keep, earlier=None):
        """The shortcut path's verdict and kept waypoints.

        A shortcut the motion checker refuses is replaced by shorter ones
        over the same cells (the stretch shortcut again without its direct
        jump), a few times, then the cell path is restored whole (its
        turns: points inside a straight run add nothing).  A failure is then
        one of the cell path's own steps.

        Parameters
        ----------
        joints : ndarray, shape (n, n_joints)
            Waypoints of a cell path [joint unit], from start to goal.
        patches : ndarray of int, shape (n,)
        problem : PlanningProblem
        keep : float
            Margin the path must keep in the motion checker.
        earlier : (Validation, ndarray), optional
            The motion checker's verdict, at ``keep``, on other waypoints
            from the same start: where they agree, it is not followed again.

        Returns
        -------
        (Validation, ndarray of int)
            The verdict on ``joints[kept]`` and ``kept``, ascending, with
            both ends.
        """
        kept = np.arange(len(joints))
        margins = self.waypoint_margins(joints, patches)
        if len(joints) > 2:
            kept = self._shortcut(joints, patches, margins, problem.clearance)
        for attempt in range(self.split_shortcuts + 2):
            known = None if earlier is None else self.checker.resumable(*earlier, joints[kept])
            result = self.checker.check(joints[kept], problem, keep, known)
            earlier = result, joints[kept]
            k = self.checker.failed_segment(result, joints[kept], patches[kept])
            if result.ok or k < 1 or kept[k] - kept[k - 1] == 1:
                break
            a, b = kept[k - 1], kept[k] + 1
            restored = a + self._shortcut(joints[a:b], patches[a:b], margins[a:b],
                                          problem.clearance, split=True)
            if attempt == self.split_shortcuts:
                restored = polyline_turns(joints)
            kept = np.union1d(kept, restored)
        return result, kept

    def pull_taut(self, joints, patches, result, problem):
        """The path with straight joint segments jumping as far ahead as the
        motion checker lets them, found by bisection: between two waypoints
        the segment must keep the clearance, or what the stretch it
        replaces keeps where that is less.

        The sheet shortcuts only join cells of the path's patches in their
        order; on a roadmap of all the joints the patches fold over each
        other, and a straight segment the platform follows well often
        leaves that order.

        Parameters
        ----------
        joints : ndarray, shape (n, n_joints)
        patches : ndarray of int, shape (n,)
        result : Validation
            The motion checker's passing verdict on ``joints`` (its poses
            are followed).
        problem : PlanningProblem

        Returns
        -------
        (Validation, ndarray, ndarray) or None
            The verdict, waypoints and patches of the shorter path, or None
            when nothing shorter passes.

        Raises
        ------
        PlanningTimeoutError
            If the problem's deadline passes first.
        """
        mechanism = self.roadmap.mechanism
        poses = result.poses
        margins = np.abs(mechanism.margin(poses, joints))

        passed = {}

        def straight(a, b):
            floor = segment_floor(margins[a:b + 1], problem.clearance)
            verdict = self.checker.check_between(joints[[a, b]], poses[a], poses[b], floor,
                                                 problem.world)
            if verdict.ok:
                passed[a, b] = verdict
            return verdict.ok

        kept, at = [0], 0
        while at < len(joints) - 1:
            if problem.termination():
                raise PlanningTimeoutError("the time limit passed while pulling the path taut")
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
        # Each jump passed on its own from the path's pose at its start to
        # the pose at its end, and a step not jumped is the passed path's.
        taut = joined_validation(passed.get((a, b)) or validation_part(result, a, b)
                                 for a, b in zip(kept, kept[1:]))
        kept = np.array(kept)
        return taut, joints[kept], patches[kept]

    def round(self, joints, patches, problem, keep):
        """The path with its corners cut (Chaikin) where the cut keeps to the
        corner's patch and the margin the stretch keeps; corners next to
        where the motion checker refuses the cut path are put back, a few
        times.

        Parameters
        ----------
        joints : ndarray, shape (n, n_joints)
        patches : ndarray of int, shape (n,)
        problem : PlanningProblem
        keep : float
            Margin the rounded path must keep in the motion checker.

        Returns
        -------
        (Validation, ndarray, ndarray) or None
            The verdict, waypoints and patches of the rounded path, or None
            when no corner could be cut.
        """
        margins = self.waypoint_margins(joints, patches)
        inner = np.arange(1, len(joints) - 1)
        inner = inner[(patches[inner - 1] == patches[inner])
                      & (patches[inner] == patches[inner + 1])]
        # A cut corner is three segments to check.
        before, after = corner_cuts(joints, inner)
        floors = [segment_floor(margins[i - 1:i + 2], problem.clearance) for i in inner]
        clear = self.segments_clear(np.concatenate([joints[inner - 1], before, after]),
                                    np.concatenate([before, after, joints[inner + 1]]),
                                    np.tile(patches[inner], 3), np.tile(floors, 3))
        corners = np.zeros(len(joints), dtype=bool)
        corners[inner] = clear.reshape(3, -1).all(axis=0)
        for _ in range(self.split_shortcuts + 1):
            if not corners.any():
                return None
            rounded, origin = cut_corners(joints, corners)
            result = self.checker.check(rounded, problem, keep)
            if result.ok:
                return result, rounded, patches[origin]
            k = max(result.failed_segment, 1)
            corners[origin[k - 1]:origin[min(k, len(origin) - 1)] + 1] = False
        return None
