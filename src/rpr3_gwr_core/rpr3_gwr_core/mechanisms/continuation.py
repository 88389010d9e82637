"""Following the platform along a joint path, as the real mechanism moves.

Sequential continuation of the constraint equations ``F(q, x) = 0``: the
joints advance along straight segments and each step is one predictor-
corrector step of the mechanism (:meth:`Mechanism.step`, or its compiled
:attr:`Mechanism.step_kernel`).  The validator and the simulated driver both
follow paths with :func:`follow_path`, so what one accepts the other executes.

A step is accepted only when it provably stays on the followed solution
branch and samples the margin densely enough that no dip between two samples
goes unseen:

* the step itself refuses a corrector that lands farther from the prediction
  than the prediction is from the start (it converged onto another branch);
* the pose may move at most ``POSE_STEP * |margin| * scale`` in one step
  (angles counted at ``scale``).  The margin is the distance to the nearest
  parallel singularity in normalised units, so a step that short cannot
  cross one, and the corrector cannot reach another solution of the same
  joints: near a fold, where the pose races ahead of the joints, the joint
  steps shrink with the square of the margin instead of stopping short of it;
* the margin may change by at most ``MARGIN_CHANGE`` of its magnitude in one
  step, which bounds its curvature between samples.

A step that fails any of these is retried shorter; below ``MIN_JOINT_STEP``
the platform cannot follow.
"""

import math

import numba
from numba import types
import numpy as np

__all__ = ["follow_path", "follow_segments", "STEP_KERNEL_SIGNATURE", "FOLLOWED",
           "CANNOT_FOLLOW", "CROSSED", "TOO_CLOSE", "POSE_STEP", "MARGIN_CHANGE",
           "MIN_JOINT_STEP"]

# ``margin = kernel(parameters, pose, joints_from, joints_to)``: one
# predictor-corrector step that overwrites ``pose`` (its coordinates at
# ``joints_from``) with the pose at ``joints_to`` and returns its margin, or
# returns NaN, leaving ``pose`` as it was, when the corrector does not converge
# or converges onto another branch.
STEP_KERNEL_SIGNATURE = types.float64(types.float64[::1], types.float64[::1],
                                      types.float64[::1], types.float64[::1])

# Largest pose step per unit of margin magnitude, as a fraction of ``scale``.
POSE_STEP = 0.1
# Largest change of the margin in one step, relative to its magnitude.
MARGIN_CHANGE = 0.25
# Shortest joint step [joint unit] before the platform counts as unable to follow.
MIN_JOINT_STEP = 1e-10

FOLLOWED, CANNOT_FOLLOW, CROSSED, TOO_CLOSE = range(4)


def follow_path(mechanism, path, pose, min_margin, max_step, poses=None, trace=None):
    """Follow the platform from ``pose`` along a joint path.

    Parameters
    ----------
    mechanism : Mechanism
    path : ndarray of float, shape (n, n_joints), C-contiguous
        Joint waypoints [joint unit]; consecutive ones are joined by straight
        segments.
    pose : ndarray of float, shape (pose_size,)
        The pose at ``path[0]``, converged; overwritten with the pose reached.
    min_margin : float
        Margin magnitude below which following stops (``TOO_CLOSE``); it is
        also the finest margin the step control resolves.
    max_step : float
        Largest joint change of one step [joint unit].
    poses : ndarray of float, shape (n, pose_size), optional
        Receives the pose at each waypoint reached, angles wrapped.
    trace : ndarray of float, shape (n - 1, 2), optional
        Receives, for each segment followed (row k - 1 for the segment from
        waypoint k - 1 to k, the one where following stopped included), the
        smallest margin magnitude met on it, its start included, and the
        steps taken on it.

    Returns
    -------
    status : int
        ``FOLLOWED``, ``CANNOT_FOLLOW``, ``CROSSED`` (the margin changed sign)
        or ``TOO_CLOSE`` (its magnitude fell below ``min_margin``).
    waypoint : int
        Index k of the segment from waypoint k - 1 to k where following
        stopped; -1 when the status is ``FOLLOWED``.
    steps : int
        Steps taken.
    smallest : float
        Smallest margin magnitude met (0 when the margin changed sign).
    """
    if poses is None:
        poses = np.empty((path.shape[0], pose.size))
    if trace is None:
        trace = np.empty((max(path.shape[0] - 1, 0), 2))
    margin = float(mechanism.margin(pose, path[0]))
    kernel, parameters = mechanism.step_kernel or (None, None)
    follow = _follow
    if kernel is None:
        follow, kernel, parameters = _follow.py_func, _interpreted_kernel(mechanism), np.empty(0)
    limits = np.array([mechanism.scale, max_step, min_margin])
    return follow(kernel, parameters, path, pose, margin, np.array(mechanism.angular, np.bool_),
                  limits, poses, trace)


def follow_segments(mechanism, starts, ends, poses, min_margin, max_step=math.inf):
    """Follow the platform along many straight joint segments, each from a
    pose of its own: :func:`follow_path` of each, in one compiled loop.

    Parameters
    ----------
    mechanism : Mechanism
    starts, ends : ndarray of float, shape (m, n_joints)
        Each segment's ends [joint unit].
    poses : ndarray of float, shape (m, pose_size), C-contiguous
        The pose at each segment's start, converged; overwritten with the
        pose reached.
    min_margin, max_step : float
        As :func:`follow_path`'s.

    Returns
    -------
    ndarray of int64, shape (m,)
        Each segment's status (:func:`follow_path`).
    """
    starts = np.ascontiguousarray(starts, dtype=float)
    ends = np.ascontiguousarray(ends, dtype=float)
    status = np.empty(starts.shape[0], np.int64)
    if starts.shape[0] == 0:
        return status
    margins = np.ascontiguousarray(mechanism.margin(poses, starts), dtype=float)
    kernel, parameters = mechanism.step_kernel or (None, None)
    follow = _follow_each
    if kernel is None:
        follow, kernel, parameters = (_follow_each.py_func, _interpreted_kernel(mechanism),
                                      np.empty(0))
    limits = np.array([mechanism.scale, max_step, min_margin])
    follow(kernel, parameters, starts, ends, poses, margins,
           np.array(mechanism.angular, np.bool_), limits, status)
    return status


def _interpreted_kernel(mechanism):
    """:meth:`Mechanism.step` with the step kernel's calling convention."""
    def kernel(parameters, pose, joints_from, joints_to):
        stepped = mechanism.step(pose, joints_from, joints_to)
        if stepped is None:
            return math.nan
        pose[:] = stepped[0]
        return stepped[1]
    return kernel


@numba.njit(types.Tuple((types.int64, types.int64, types.int64, types.float64))(
    types.FunctionType(STEP_KERNEL_SIGNATURE), types.float64[::1], types.float64[:, ::1],
    types.float64[::1], types.float64, types.boolean[::1], types.float64[::1],
    types.float64[:, ::1], types.float64[:, ::1]), cache=True, nogil=True)
def _follow(step, parameters, path, pose, margin, angular, limits, poses, trace):
    """:func:`follow_path`'s loop; ``limits`` is ``(scale, max_step, min_margin)``."""
    scale, max_step, min_margin = limits[0], limits[1], limits[2]
    positive = margin > 0
    smallest = abs(margin)
    poses[0] = pose
    trial = np.empty_like(pose)
    steps = 0
    for k in range(1, path.shape[0]):
        start, end = path[k - 1], path[k]
        span = np.max(np.abs(end - start))
        done, h = 0.0, 1.0 if span == 0.0 else min(1.0, max_step / span)
        trace[k - 1, 0], trace[k - 1, 1] = abs(margin), 0.0
        while done < 1.0:
            h = min(h, 1.0 - done)
            trial[:] = pose
            stepped = step(parameters, trial, start + (end - start) * done,
                           start + (end - start) * (done + h))
            # How much shorter than this step the next may have to be: 1 when
            # within every bound, below 1 when it must be retried shorter.
            fit = 0.5
            if not np.isnan(stepped):
                moved = 0.0
                for j in range(pose.size):
                    d = trial[j] - pose[j]
                    moved += (d * scale) ** 2 if angular[j] else d * d
                floor = max(abs(margin), min_margin)
                fit = min(POSE_STEP * floor * scale / max(math.sqrt(moved), 1e-300),
                          MARGIN_CHANGE * floor / max(abs(stepped - margin), 1e-300))
            if fit < 1.0:
                if h * span < MIN_JOINT_STEP:
                    return CANNOT_FOLLOW, k, steps, smallest
                h *= min(0.5, max(0.1, 0.8 * fit))
                continue
            pose[:] = trial
            margin = stepped
            done += h
            h = min(h * min(2.0, 0.8 * fit), 1.0 if span == 0.0 else max_step / span)
            steps += 1
            trace[k - 1, 1] += 1.0
            if (margin > 0) != positive:
                trace[k - 1, 0] = 0.0
                return CROSSED, k, steps, 0.0
            trace[k - 1, 0] = min(trace[k - 1, 0], abs(margin))
            smallest = min(smallest, abs(margin))
            if smallest < min_margin:
                return TOO_CLOSE, k, steps, smallest
        poses[k] = pose
        for j in range(pose.size):
            if angular[j]:
                poses[k, j] = math.atan2(math.sin(pose[j]), math.cos(pose[j]))
    return FOLLOWED, -1, steps, smallest


@numba.njit(types.void(
    types.FunctionType(STEP_KERNEL_SIGNATURE), types.float64[::1], types.float64[:, ::1],
    types.float64[:, ::1], types.float64[:, ::1], types.float64[::1], types.boolean[::1],
    types.float64[::1], types.int64[::1]), cache=True, nogil=True)
def _follow_each(step, parameters, starts, ends, poses, margins, angular, limits, status):
    """:func:`follow_segments`' loop."""
    path = np.empty((2, starts.shape[1]))
    reached = np.empty((2, poses.shape[1]))
    trace = np.empty((1, 2))
    pose = np.empty(poses.shape[1])
    for i in range(starts.shape[0]):
        path[0], path[1] = starts[i], ends[i]
        pose[:] = poses[i]
        status[i] = _follow(step, parameters, path, pose, margins[i], angular, limits, reached,
                            trace)[0]
        poses[i] = pose
