"""The motion checker, as OMPL's ``MotionValidator``: the one place where a
joint path's two verdicts meet, the singularity verdict of the independent
validator (:func:`~.validation.validate_path`, by continuation) and, in a
scene, the continuous collision check's.
"""

import dataclasses

import numpy as np

from ..exceptions import CollisionError, InvalidInputError
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN, validate_path

__all__ = ["MotionChecker"]

# A followed pose this far from its waypoint's solution [scale] is on another sheet.
_STRAYED = 1e-4


class MotionChecker:
    """Checks joint paths of one roadmap's mechanism.

    Parameters
    ----------
    roadmap : Roadmap
    min_margin : float
        Smallest normalised ``|det Jx|`` a finished path keeps.
    max_step : float
        The validator's continuation step [joint unit].

    Raises
    ------
    InvalidInputError
        If ``min_margin`` is negative or ``max_step`` not positive.
    """

    def __init__(self, roadmap, min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP):
        if not (np.isfinite(min_margin) and min_margin >= 0):
            raise InvalidInputError(f"min_margin must be finite and non-negative, got "
                                    f"{min_margin!r}")
        if not (np.isfinite(max_step) and max_step > 0):
            raise InvalidInputError(f"max_step must be positive and finite, got {max_step!r}")
        self.roadmap = roadmap
        self.min_margin = float(min_margin)
        self.max_step = float(max_step)
        self._free = list(roadmap.grid.axis_joints)

    def check(self, joints, problem, min_margin, known=None):
        """:meth:`check_between` the problem's located start and goal, in its scene.

        Parameters
        ----------
        joints : ndarray, shape (n, n_joints)
            Waypoints [joint unit], from the start's joints to the goal's.
        problem : PlanningProblem
        min_margin : float
            Smallest margin magnitude accepted along the path.
        known : (Validation, int), optional
            As :meth:`check_between`'s.

        Returns
        -------
        Validation
        """
        return self.check_between(joints, problem.start.pose, problem.goal.pose, min_margin,
                                  problem.world, known)

    def check_between(self, joints, start_pose, goal_pose, min_margin, world=None, known=None):
        """The validator's verdict on ``joints`` followed from ``start_pose``
        to ``goal_pose`` and, in a scene, the continuous collision check's: a
        path that collides fails at the segment where it does.

        Parameters
        ----------
        joints : ndarray, shape (n, n_joints)
            Waypoints [joint unit].
        start_pose, goal_pose : ndarray, shape (pose_size,)
            The platform's pose at the first and at the last waypoint.
        min_margin : float
            Smallest margin magnitude accepted along the path.
        world : SceneRoadmap, optional
        known : (Validation, int), optional
            This checker's earlier verdict on a path from the same start
            whose first ``k + 1`` waypoints are these, and ``k``: the
            validator resumes there (:func:`~.validation.validate_path`);
            the collision check covers the whole path all the same.

        Returns
        -------
        Validation
        """
        mechanism = self.roadmap.mechanism
        result = validate_path(mechanism, joints, start_pose, goal_pose, min_margin,
                               self.max_step, known)
        if not result.ok or world is None:
            return result
        from ..world import path_collisions  # the world's kernels load only with a scene

        hit = path_collisions(mechanism, world.scene, joints, start_pose, world.index.model)
        if hit is None:
            return result
        return dataclasses.replace(result, ok=False, reason=f"collision {hit.message}",
                                   failed_segment=min(int(hit.index) + 1, len(joints) - 1))

    def resumable(self, earlier, checked, joints):
        """What :meth:`check_between`'s ``known`` is for ``joints`` after
        ``earlier``, its verdict on ``checked`` from the same start at the
        same margin: the last waypoint of the start they share that the
        platform reached.

        Parameters
        ----------
        earlier : Validation
        checked, joints : ndarray, shape (m, n_joints) and (n, n_joints)
            Waypoints [joint unit].

        Returns
        -------
        (Validation, int) or None
            None when they share no segment the platform was followed along.
        """
        shared = min(len(checked), len(joints))
        differ = np.flatnonzero(np.any(checked[:shared] != joints[:shared], axis=1))
        shared = int(differ[0]) if differ.size else shared
        last = min(shared, earlier.reached()) - 1
        return (earlier, last) if last >= 1 else None

    def check_free(self, location, which, world):
        """Refuse a located end that collides or breaks a limit of the scene.

        Parameters
        ----------
        location : Location
        which : str
            ``"start"`` or ``"goal"``, for the message.
        world : SceneRoadmap

        Raises
        ------
        CollisionError
            If it does.
        """
        from ..world import configuration_collision

        hit = configuration_collision(self.roadmap.mechanism, world.scene, location.joints,
                                      location.pose, world.index.model)
        if hit is not None:
            raise CollisionError(f"the {which} is blocked: {hit.message}")

    def failed_segment(self, result, joints, patches):
        """Where a refused path failed: the index k of the segment from
        waypoint k - 1 to waypoint k.

        For a path that ends in another assembly mode (the validator names
        no segment), it is the segment after the last waypoint where the
        followed pose is still its patch's solution at the waypoint's cell:
        the platform strayed onto another sheet after it.

        Parameters
        ----------
        result : Validation
            The checker's verdict on ``joints``.
        joints : ndarray, shape (n, n_joints)
            The checked waypoints [joint unit].
        patches : ndarray of int, shape (n,)
            The patch of each waypoint.

        Returns
        -------
        int
            -1 when the path passed.
        """
        if result.ok or result.failed_segment >= 1:
            return result.failed_segment
        grid = self.roadmap.grid
        cells = grid.cells_of(joints[:, self._free])
        seg = self.roadmap.segmentation
        member = seg.patch[cells] == patches[:, None]
        sheet = seg.field.poses[cells, np.argmax(member, axis=1)]
        mechanism = self.roadmap.mechanism
        verifiable = np.all(np.abs(joints - grid.nearest_joints(joints, grid.joints_at(cells)))
                            < 1e-9, axis=1) & member.any(axis=1)
        off = verifiable & (mechanism.pose_distance(result.poses, sheet)
                            > _STRAYED * mechanism.scale)
        off[0] = False
        first_off = int(np.argmax(off)) if off.any() else len(joints) - 1
        on = np.flatnonzero(verifiable[:first_off] & ~off[:first_off])
        return 1 + int(on.max(initial=0))
