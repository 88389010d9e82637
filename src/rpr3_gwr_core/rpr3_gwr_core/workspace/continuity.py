"""Which solution of a cell continues into which solution of a neighbour.

Two solutions of face-adjacent cells belong to the same sheet when the
platform can follow the legs from one cell to the other without a jump: the
pose of the first cell is carried to the neighbour's legs by the validator's
continuation (:func:`~rpr3_gwr_core.mechanisms.continuation.follow_segments`:
predictor-corrector steps of *all* task variables, so degenerate
orientations, where two assembly modes share alpha, cannot merge sheets,
each step short enough for its margin that the corrector cannot reach
another branch), and must land on a solution of the neighbour with the same
aspect.  A branch that ends in a fold inside the face, where a corrector
left to itself lands on a solution born there, is not followed and links
nothing.  A link is kept only when the continuation works in both
directions and the two directions agree, so the relation is a partial
bijection and gates come out symmetric.

Most faces are far from any fold, and there the links are the identity on
the ordered solutions: a compiled screen settles them first, with one Euler
prediction per solution and direction (the mechanism's
:attr:`~rpr3_gwr_core.mechanisms.base.Mechanism.predict_kernel`), and only
the faces it leaves unsure are tracked.

"""

import numba
import numpy as np

from ..mechanisms.base import compiled_pose_distance
from ..mechanisms.continuation import FOLLOWED, follow_segments


__all__ = ["neighbour_pairs", "match_solutions"]

_CHUNK = 65536
# The finest margin magnitude the continuation across a face resolves: a
# solution that comes closer to the singular locus there is not linked.
_FOLLOW_MARGIN = 1e-6
# A continued pose that lands within this distance (relative to the
# geometry's scale, orientation measured as arc length at that scale) of a
# neighbour's solution is that solution.
_LAND_TOL = 1e-6
_SCREEN_TOL = 1e-2
_SCREEN_RATIO = 10.0


def neighbour_pairs(shape):
    """Face-adjacent cell pairs of a row-major grid of any dimension.

    Parameters
    ----------
    shape : tuple of int
        Cells along each axis.

    Returns
    -------
    list of (ndarray, ndarray)
        One ``(lower, upper)`` pair of flat-index arrays per axis, with
        ``upper = lower + stride`` of that axis.
    """
    index = np.arange(int(np.prod(shape))).reshape(shape)
    pairs = []
    for axis in range(len(shape)):
        lower = np.take(index, np.arange(shape[axis] - 1), axis=axis).ravel()
        upper = np.take(index, np.arange(1, shape[axis]), axis=axis).ravel()
        pairs.append((lower, upper))
    return pairs


def _continue_into(field, joints, src, dst):
    """Target slot in ``dst`` of every solution of ``src``, shape (n, max_solutions),
    -1 if none."""
    target = np.full((len(src), field.max_solutions), -1, dtype=np.int8)
    rows, slots = np.nonzero(field.valid[src])
    if rows.size == 0:
        return target
    mechanism = field.mechanism
    # Across a periodic axis' seam the move is one step, not a turn back.
    joints_dst = field.grid.nearest_joints(joints[src[rows]], joints[dst[rows]])
    pose = np.array(field.poses[src[rows], slots], dtype=float)
    status = follow_segments(mechanism, joints[src[rows]], joints_dst, pose, _FOLLOW_MARGIN)
    dist = mechanism.pose_distance(field.poses[dst[rows]], pose[:, None, :])
    dist = np.where(np.isnan(dist), np.inf, dist)
    best = np.argmin(dist, axis=1)
    landed = dist[np.arange(rows.size), best] < _LAND_TOL * mechanism.scale
    # The source and the landing solution must share an aspect: the
    # continuation stops before a fold, where the margin would change sign.
    same_aspect = (np.sign(field.margin[src[rows], slots])
                   == np.sign(field.margin[dst[rows], best]))
    ok = (status == FOLLOWED) & landed & same_aspect
    target[rows[ok], slots[ok]] = best[ok]
    return target


def match_solutions(field, lower, upper, screen=True):
    """Continuation links between the solutions of face-adjacent cells.

    Parameters
    ----------
    field : NSolutionField
    lower, upper : ndarray of int, shape (n,)
        Flat indices of adjacent cells.
    screen : bool
        Settle the unambiguous faces with the screen (module doc) and track
        only the others; the links are the same.

    Returns
    -------
    ndarray of int8, shape (n, max_solutions)
        ``m[k, i] = j`` when solution i of ``lower[k]`` continues into solution
        j of ``upper[k]`` and back; -1 when solution i has no continuation.
    """
    joints = field.grid.joints()
    lower, upper = np.asarray(lower), np.asarray(upper)
    match = np.full((len(lower), field.max_solutions), -1, dtype=np.int8)
    if screen:
        settled = _screened(field, joints, lower, upper)
        match[settled] = np.where(field.valid[lower[settled]], np.arange(field.max_solutions),
                                  -1)
        todo = np.flatnonzero(~settled)
    else:
        todo = np.arange(len(lower))
    # A link needs a solution at both ends; the faces left are followed
    # together, in one compiled loop.
    todo = todo[(field.count[lower[todo]] > 0) & (field.count[upper[todo]] > 0)]
    # Chunks bound the tracking's temporaries, which scale with faces.
    for start in range(0, todo.size, _CHUNK):
        part = todo[start:start + _CHUNK]
        match[part] = _track_both_ways(field, joints, lower[part], upper[part])
    return match


def _track_both_ways(field, joints, lower, upper):
    forward = _continue_into(field, joints, lower, upper)
    backward = _continue_into(field, joints, upper, lower)
    rows = np.arange(len(lower))[:, None]
    back_of_forward = np.where(forward >= 0, backward[rows, np.maximum(forward, 0)], -1)
    agree = back_of_forward == np.arange(field.max_solutions)
    return np.where(agree, forward, -1).astype(np.int8)


def _screened(field, joints, lower, upper):
    """Faces whose links are surely the identity on the ordered solutions."""
    mechanism = field.mechanism
    kernel, parameters = mechanism.predict_kernel
    periods = np.zeros(mechanism.n_joints)
    for axis in field.grid.axes:
        periods[axis.joint] = axis.period
    solutions = (field.count, field.poses, field.margin, field.separation)
    metric = (np.array(mechanism.angular, dtype=np.bool_), float(mechanism.scale))
    faces = (np.ascontiguousarray(lower, dtype=np.int64),
             np.ascontiguousarray(upper, dtype=np.int64))
    return _screen(kernel, parameters, faces, solutions, (joints, periods), metric)


@numba.njit(cache=True, nogil=True)
def _screen(predict, parameters, faces, solutions, space, metric):
    """:func:`_screened`'s loop: a face is settled when its cells have as many
    solutions, slot by slot of one aspect, and each solution, predicted
    across the face in either direction, lands within ``_SCREEN_TOL`` of the
    same slot and far nearer it than any other solution of that cell."""
    lower, upper = faces
    joints, periods = space
    count, poses, margin, separation = solutions
    angular, scale = metric
    settled = np.zeros(lower.size, dtype=np.bool_)
    predicted = np.empty(poses.shape[1:])
    target = np.empty(joints.shape[1])
    for k in range(lower.size):
        n = count[lower[k]]
        if n == 0 or count[upper[k]] != n:
            continue
        sure = True
        for slot in range(n):
            # np.sign's comparison: a NaN margin settles nothing.
            if not np.sign(margin[lower[k], slot]) == np.sign(margin[upper[k], slot]):
                sure = False
        for source, destination in ((lower[k], upper[k]), (upper[k], lower[k])):
            if not sure:
                break
            # Across a periodic axis' seam the move is one step, not a turn back.
            for j in range(target.size):
                target[j] = joints[destination, j]
                if periods[j] > 0:
                    target[j] -= periods[j] * np.round(
                        (target[j] - joints[source, j]) / periods[j])
            predict(parameters, poses[source, :n], joints[source], target, predicted[:n])
            for slot in range(n):
                err = compiled_pose_distance(poses[destination, slot], predicted[slot], angular,
                                             scale) / scale
                gap = separation[destination, slot] / scale
                if not (err < _SCREEN_TOL and gap > _SCREEN_RATIO * err):
                    sure = False
                    break
        settled[k] = sure
    return settled
