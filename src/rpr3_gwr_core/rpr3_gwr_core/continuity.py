"""Which solution of a cell continues into which solution of a neighbour.

Two solutions of face-adjacent cells belong to the same sheet when the
platform can follow the legs from one cell to the other without a jump: the
pose of the first cell is carried to the neighbour's legs by an Euler
predictor and Newton corrector on the constraint equations (continuity of
*all* task variables x, y and alpha, so degenerate orientations, where two
assembly modes share alpha, cannot merge sheets), and must land on a solution
of the neighbour with the same aspect.  A link is kept only when the
continuation works in both directions and the two directions agree, so the
relation is a partial bijection and gates come out symmetric.

"""

import numpy as np

from .kinematics import MAX_SOLUTIONS, _newton, _predict, _singularity_margin, wrap_angle

__all__ = ["neighbour_pairs", "match_solutions"]

_CORRECTOR_STEPS = 4
_SUBSTEPS = (1, 16)
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


def _track(pose, rho_src, rho_dst, geometry, substeps):
    """Carry poses from legs ``rho_src`` to ``rho_dst`` in equal substeps."""
    for k in range(1, substeps + 1):
        rho_from = rho_src + (rho_dst - rho_src) * ((k - 1) / substeps)
        rho_to = rho_src + (rho_dst - rho_src) * (k / substeps)
        pose = _predict(pose, rho_from, rho_to, geometry)
        pose = _newton(pose, rho_to, geometry, _CORRECTOR_STEPS)
    return pose


def _continue_into(field, rho, src, dst):
    """Target slot in ``dst`` of every solution of ``src``, shape (n, 6), -1 if none."""
    target = np.full((len(src), MAX_SOLUTIONS), -1, dtype=np.int8)
    rows, slots = np.nonzero(field.valid[src])
    geometry = field.geometry
    # Near a fold the two merging solutions move fast: what one step cannot
    # follow is tried again in finer substeps before it counts as a break.
    for substeps in _SUBSTEPS:
        if rows.size == 0:
            break
        pose = _track(field.poses[src[rows], slots], rho[src[rows]], rho[dst[rows]],
                      geometry, substeps)
        diff = field.poses[dst[rows]] - pose[:, None, :]
        diff[..., 2] = wrap_angle(diff[..., 2]) * geometry.scale
        dist = np.linalg.norm(diff, axis=-1)
        dist = np.where(np.isnan(dist), np.inf, dist)
        best = np.argmin(dist, axis=1)
        landed = dist[np.arange(rows.size), best] < _LAND_TOL * geometry.scale
        # The source, the tracked pose and the landing solution must share an
        # aspect: a step that jumped across a fold lands on the other sign.
        target_sign = np.sign(field.margin[dst[rows], best])
        same_aspect = ((np.sign(field.margin[src[rows], slots]) == target_sign)
                       & (np.sign(_singularity_margin(pose, geometry)) == target_sign))
        ok = landed & same_aspect
        target[rows[ok], slots[ok]] = best[ok]
        rows, slots = rows[~ok], slots[~ok]
    return target


def match_solutions(field, lower, upper, screen=True):
    """Continuation links between the solutions of face-adjacent cells.

    Parameters
    ----------
    field : NSolutionField
    lower, upper : ndarray of int, shape (n,)
        Flat indices of adjacent cells.
    screen : bool
        Settle the unambiguous faces with the screening test (module doc)
        and track only the others; the links are the same.

    Returns
    -------
    ndarray of int8, shape (n, 6)
        ``m[k, i] = j`` when solution i of ``lower[k]`` continues into solution
        j of ``upper[k]`` and back; -1 when solution i has no continuation.
    """
    rho = field.grid.rho()
    lower, upper = np.asarray(lower), np.asarray(upper)
    match = np.full((len(lower), MAX_SOLUTIONS), -1, dtype=np.int8)
    if screen:
        settled = _screened(field, rho, lower, upper)
        match[settled] = np.where(field.valid[lower[settled]], np.arange(MAX_SOLUTIONS), -1)
        todo = np.flatnonzero(~settled)
    else:
        todo = np.arange(len(lower))
    if todo.size:
        match[todo] = _track_both_ways(field, rho, lower[todo], upper[todo])
    return match


def _track_both_ways(field, rho, lower, upper):
    forward = _continue_into(field, rho, lower, upper)
    backward = _continue_into(field, rho, upper, lower)
    rows = np.arange(len(lower))[:, None]
    back_of_forward = np.where(forward >= 0, backward[rows, np.maximum(forward, 0)], -1)
    agree = back_of_forward == np.arange(MAX_SOLUTIONS)
    return np.where(agree, forward, -1).astype(np.int8)


def _alpha_gap(alpha, count, rows, slots):
    """Cyclic alpha distance from solution ``slots`` of cells ``rows`` to the
    nearest other solution of its cell; solutions are sorted by alpha, so that
    is the previous or the next one, wrapping around."""
    n = np.maximum(count[rows].astype(np.int64), 1)
    here = alpha[rows, slots]
    gap = np.full(rows.size, np.inf)
    for neighbour in ((slots + 1) % n, (slots - 1) % n):
        other = alpha[rows, neighbour]
        d = np.abs(wrap_angle(other - here))
        gap = np.minimum(gap, np.where(neighbour != slots, d, np.inf))
    return gap


def _screened(field, rho, lower, upper):
    """Faces whose links are surely the identity on the sorted solutions."""
    geometry, scale = field.geometry, field.geometry.scale
    same = np.flatnonzero((field.count[lower] == field.count[upper]) & (field.count[lower] > 0))
    rows, slots = np.nonzero(field.valid[lower[same]])
    bad = np.sign(field.margin[lower[same]][rows, slots]) != np.sign(
        field.margin[upper[same]][rows, slots])
    for src, dst in ((lower[same], upper[same]), (upper[same], lower[same])):
        pose = _predict(field.poses[src[rows], slots], rho[src[rows]], rho[dst[rows]], geometry)
        diff = field.poses[dst[rows], slots] - pose
        diff[:, 2] = wrap_angle(diff[:, 2]) * scale
        err = np.linalg.norm(diff, axis=-1) / scale
        gap = _alpha_gap(field.poses[..., 2], field.count, dst[rows], slots)
        bad |= ~(err < _SCREEN_TOL) | ~(gap > _SCREEN_RATIO * err)
    unsure = np.zeros(same.size, dtype=bool)
    unsure[rows[bad]] = True
    settled = np.zeros(len(lower), dtype=bool)
    settled[same[~unsure]] = True
    return settled
