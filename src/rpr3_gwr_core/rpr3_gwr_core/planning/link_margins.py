"""The margin a cell search reads at each node: the least of its solution's
and of the middles of its links where the sheet dips between cell centres.

The roadmap knows the margin at cell centres only.  Between two of them a
solution sheet can fold over a singular sliver thinner than a cell, or dip
next to a cusp, and a path along that link is then refused by the motion
checker and repaired round it, the bulk of the work of the slowest plans.
The platform followed from one cell centre to the other with the
mechanism's predictor-corrector step (:attr:`Mechanism.step_kernel`), in
two halves, a step it refuses retried shorter as the validator does, finds
most such links before any plan: a link *dips* when the platform cannot
follow it, lands on another solution than the far end's, changes the sign
of its margin, or keeps less than :data:`DIP_FRACTION` of the lesser end's
margin magnitude (along a link of a smooth sheet it stays near the ends'
mean).  Both ends of a dipping link read the least margin met inside it (0 where
it cannot be followed), so the searches' low-margin cost keeps paths off it.

This weighs the searches only: the links themselves, and so the roadmap's
answers, stay as they are, and the motion checker still decides every path.
"""

from typing import NamedTuple

import numba
import numpy as np

from ..mechanisms.base import compiled_pose_distance

__all__ = ["LinkEnds", "link_margins", "DIP_FRACTION"]

DIP_FRACTION = 0.5
"""A link dips where its middle keeps less than this fraction of the margin
magnitude of its lesser end."""

# A link followed to a pose farther than this from the far end's solution
# [fraction of the mechanism's scale] has reached another solution.
_LANDING_TOL = 1e-6
# Shortest step a link is followed in [fraction of the link]: a step the
# mechanism refuses (its corrector jumps too far for how little the
# prediction moved) is retried shorter, as the validator does, and longer
# again after it.
_FINEST_STEP = 2.0**-12


class LinkEnds(NamedTuple):
    """The node graph's solutions as the link test reads them.

    Attributes
    ----------
    indptr, indices : ndarray
        The node graph's adjacency (:func:`~.astar.adjacency`).
    joints : ndarray, shape (n_nodes, n_joints)
        The joints of each node's cell centre [joint unit].
    periods : ndarray, shape (n_joints,)
        Each joint's period along the grid [joint unit], 0 where it has
        none: a link across the seam of a turning joint goes the short way.
    poses : ndarray, shape (n_nodes, pose_size)
        Each node's solution.
    margin : ndarray, shape (n_nodes,)
        Each node's signed margin.
    angular : ndarray of bool, shape (pose_size,)
        Which pose coordinates are angles.
    """

    indptr: np.ndarray
    indices: np.ndarray
    joints: np.ndarray
    periods: np.ndarray
    poses: np.ndarray
    margin: np.ndarray
    angular: np.ndarray


def link_margins(mechanism, ends):
    """Margin magnitude of each node (module doc).

    A mechanism without a compiled step (:attr:`Mechanism.step_kernel` is
    None) gets its solutions' margins as they are: a step per link from the
    interpreter would take minutes on a large roadmap.

    Parameters
    ----------
    mechanism : Mechanism
    ends : LinkEnds

    Returns
    -------
    ndarray of float64, shape (n_nodes,)
        At most ``abs(ends.margin)``, and 0 next to a link whose steps fail.
    """
    lowest = np.abs(ends.margin).astype(np.float64)
    if mechanism.step_kernel is None:
        return lowest
    step, parameters = mechanism.step_kernel
    _lower_at_dips(step, parameters, ends, float(mechanism.scale), lowest)
    return lowest


@numba.njit(cache=True, nogil=True)
def _lower_at_dips(step, parameters, ends, scale, lowest):
    """Lower ``lowest`` at both ends of each dipping link to the least margin
    met inside it (0 where it cannot be followed)."""
    indptr, indices, joints, periods, poses, margin, angular = ends
    pose = np.empty(poses.shape[1])
    trial = np.empty(poses.shape[1])
    start = np.empty(joints.shape[1])
    change = np.empty(joints.shape[1])
    here = np.empty(joints.shape[1])
    there = np.empty(joints.shape[1])
    for u in range(indptr.size - 1):
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            if v < u:
                continue  # each link once
            for j in range(change.size):
                start[j] = joints[u, j]
                change[j] = joints[v, j] - joints[u, j]
                if periods[j] > 0:
                    change[j] -= periods[j] * np.round(change[j] / periods[j])
            pose[:] = poses[u]
            kept = _followed_margin(step, parameters, pose, start, change, margin[u] > 0,
                                    here, there, trial)
            if kept > 0.0 and (compiled_pose_distance(pose, poses[v], angular, scale)
                               > _LANDING_TOL * scale):
                kept = 0.0
            if kept < DIP_FRACTION * min(abs(margin[u]), abs(margin[v])):
                lowest[u] = min(lowest[u], kept)
                lowest[v] = min(lowest[v], kept)


@numba.njit(cache=True, inline="always")
def _followed_margin(step, parameters, pose, start, change, positive, here, there, trial):
    """Follow ``pose`` from ``start`` along ``change`` in two halves, a refused
    step retried in halves down to ``_FINEST_STEP`` of the link (each step
    after a success twice as long); returns the least margin magnitude met
    inside, or 0 where a step that short is refused or the margin changes
    sign; ``here``, ``there`` and ``trial`` are work space."""
    least = np.inf
    done, h = 0.0, 0.5
    while done < 1.0:
        h = min(h, 1.0 - done)
        for j in range(start.size):
            here[j] = start[j] + change[j] * done
            there[j] = start[j] + change[j] * (done + h)
        trial[:] = pose
        stepped = step(parameters, trial, here, there)
        if np.isnan(stepped):
            if h <= _FINEST_STEP:
                return 0.0
            h *= 0.5
            continue
        if (stepped > 0) != positive:
            return 0.0
        pose[:] = trial
        done += h
        if done < 1.0:
            least = min(least, abs(stepped))
        h *= 2.0
    return least
