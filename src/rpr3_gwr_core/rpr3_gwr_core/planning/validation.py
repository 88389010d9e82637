"""The independent trajectory validator.

It knows nothing of grids, regions or patches: it drives the joints along
the path in steps of at most ``max_step`` and follows the platform like the
real mechanism would, by continuation (Euler predictor, Newton corrector) of
the constraint equations from the start pose.  It fails a path when

* the corrector does not converge even in steps 256 times smaller (the
  platform would have to jump),
* the sign of the margin changes (a parallel singularity was crossed),
* the margin's magnitude (:meth:`~rpr3_gwr_core.mechanisms.Mechanism.margin`)
  falls below ``min_margin``, or
* the platform does not arrive at the goal pose (another assembly mode).

The steps are sequential and small, so they use the mechanism's scalar
:meth:`~rpr3_gwr_core.mechanisms.Mechanism.step`, and the whole loop runs
compiled when the mechanism has that step compiled
(:attr:`~rpr3_gwr_core.mechanisms.Mechanism.step_kernel`).
"""

from dataclasses import dataclass
import math

import numpy as np

import numba
from numba import types

from ..exceptions import InvalidInputError
from ..mechanisms.base import STEP_KERNEL_SIGNATURE

__all__ = ["Validation", "validate_path", "DEFAULT_MAX_STEP", "DEFAULT_MIN_MARGIN"]

DEFAULT_MAX_STEP = 0.0625
# Normalised |det Jx| (kinematics.singularity_margin) below which a
# configuration counts as singular: the platform's orientation then moves
# more than about a thousand times faster than at a well-conditioned pose.
DEFAULT_MIN_MARGIN = 1e-3
_MAX_HALVINGS = 8
_FINE_MARGIN = 0.05
_GOAL_TOL = 1e-6


@dataclass(frozen=True)
class Validation:
    """Outcome of :func:`validate_path`.

    Attributes
    ----------
    ok : bool
    reason : str
        ``"ok"`` or what failed, with where.
    min_margin : float
        Smallest margin magnitude met.
    aspect : int
        Sign of the margin along the path.
    steps : int
        Continuation steps taken.
    failed_segment : int
        Index k of the segment from waypoint k - 1 to waypoint k where the
        path failed; -1 when it did not fail inside a segment.
    poses : ndarray, shape (n, pose_size)
        The followed platform pose at each waypoint, angles wrapped.
    """

    ok: bool
    reason: str
    min_margin: float
    aspect: int
    steps: int
    poses: np.ndarray
    failed_segment: int = -1

    def as_dict(self):
        """Plain-data summary (no poses)."""
        return {"ok": self.ok, "reason": self.reason, "min_margin": self.min_margin,
                "aspect": self.aspect, "steps": self.steps}


def validate_path(mechanism, path, start_pose, goal_pose=None,
                  min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP):
    """Follow the platform along a joint path and check it stays regular.

    Steps are at most ``max_step``, shrunk in proportion to the margin below
    0.05; where the corrector does not converge the step is halved, up to
    ``2**-8`` of it, before the path fails.

    Parameters
    ----------
    mechanism : Mechanism
    path : array_like, shape (n, n_joints)
        Waypoints of the joints [joint unit]; consecutive waypoints are
        joined by straight segments.
    start_pose : array_like, shape (pose_size,)
        The platform pose at the first waypoint.
    goal_pose : array_like, shape (pose_size,), optional
        The pose the platform must reach at the last waypoint.
    min_margin : float
        Smallest accepted margin magnitude.
    max_step : float
        Largest joint change of one continuation step [joint unit].

    Returns
    -------
    Validation
    """
    path = np.ascontiguousarray(path, dtype=float)
    if path.ndim != 2 or path.shape[1] != mechanism.n_joints or path.shape[0] < 1:
        raise InvalidInputError(f"the path must have shape (n, {mechanism.n_joints}), "
                                f"got {path.shape}")
    pose = np.array(start_pose, dtype=float).ravel()
    if not (np.isfinite(path).all() and np.isfinite(pose).all()) \
            or pose.size != mechanism.pose_size:
        raise InvalidInputError("the path and the start pose must be finite, of the "
                                "mechanism's sizes")
    if not max_step > 0:
        raise InvalidInputError("max_step must be positive")
    poses = np.full((path.shape[0], mechanism.pose_size), np.nan)

    def result(ok, reason, smallest, sign, steps=0, segment=-1):
        return Validation(ok=ok, reason=reason, min_margin=smallest, aspect=sign, steps=steps,
                          poses=poses, failed_segment=segment)

    residual = float(np.max(np.abs(mechanism.residual(pose, path[0]))))
    if residual > 1e-6 * mechanism.scale**2:
        return result(False, f"start pose does not fit the first waypoint (residual "
                      f"{residual:.2e})", 0.0, 0)
    margin = float(mechanism.margin(pose))
    sign = 1 if margin > 0 else -1
    if abs(margin) < min_margin:
        return result(False, f"start is singular (margin {abs(margin):.2e})", abs(margin), sign)
    follow, (kernel, parameters) = _follow, mechanism.step_kernel or (None, None)
    if kernel is None:
        follow, kernel, parameters = _follow.py_func, _interpreted_kernel(mechanism), np.empty(0)
    followed = pose.copy()
    status, k, steps, smallest = follow(
        kernel, parameters, path, followed, margin > 0, abs(margin),
        np.array(mechanism.angular, dtype=np.bool_), max_step, min_margin, poses)
    if status == _CANNOT_FOLLOW:
        return result(False, f"platform cannot follow the joints before waypoint {k}",
                      smallest, sign, steps, k)
    if status == _CROSSED:
        return result(False, f"the margin changes sign before waypoint {k}: "
                      "a parallel singularity is crossed", 0.0, sign, steps, k)
    if status == _TOO_CLOSE:
        return result(False, f"margin {smallest:.2e} below {min_margin:g} before "
                      f"waypoint {k}", smallest, sign, steps, k)
    pose = followed
    if goal_pose is not None:
        miss = float(np.max(np.abs(mechanism.pose_difference(pose, goal_pose))))
        if miss > _GOAL_TOL * mechanism.scale:
            return result(False, f"platform ends {miss:.3g} away from the goal pose: "
                          "another assembly mode", smallest, sign, steps)
    return result(True, "ok", smallest, sign, steps)


def _interpreted_kernel(mechanism):
    """:meth:`Mechanism.step` with the step kernel's calling convention."""
    def kernel(parameters, pose, joints_from, joints_to):
        stepped = mechanism.step(pose, joints_from, joints_to)
        if stepped is None:
            return math.nan
        pose[:] = stepped[0]
        return stepped[1]
    return kernel


_FOLLOWING, _CANNOT_FOLLOW, _CROSSED, _TOO_CLOSE = range(4)


@numba.njit(types.Tuple((types.int64, types.int64, types.int64, types.float64))(
    types.FunctionType(STEP_KERNEL_SIGNATURE), types.float64[::1], types.float64[:, ::1],
    types.float64[::1], types.boolean, types.float64, types.boolean[::1], types.float64,
    types.float64, types.float64[:, ::1]), cache=True, nogil=True)
def _follow(step, parameters, path, pose, sign, smallest, angular, max_step, min_margin, poses):
    """Follow ``pose`` (in place) along ``path`` from its start, where the
    margin is ``smallest`` and positive if ``sign``, writing the pose reached
    at each waypoint to ``poses``: ``(status, waypoint, steps, smallest
    margin)``, the waypoint where it stopped unless the status is
    ``_FOLLOWING``."""
    poses[0] = pose
    trial = np.empty_like(pose)
    steps = 0
    for k in range(1, path.shape[0]):
        start, end = path[k - 1], path[k]
        full = max(1.0, np.max(np.abs(end - start)) / max_step)
        done, h = 0.0, min(1.0, smallest / _FINE_MARGIN) / full
        while done < 1.0:
            h = min(h, 1.0 - done)
            trial[:] = pose
            margin = step(parameters, trial, start + (end - start) * done,
                          start + (end - start) * (done + h))
            if np.isnan(margin):
                # Near a singularity the platform moves fast: refine before giving up.
                if h * full < 2.0**-_MAX_HALVINGS:
                    return _CANNOT_FOLLOW, k, steps, smallest
                h /= 2
                continue
            pose[:] = trial
            done += h
            # Sample finer where the margin is small, so that no dip between
            # two steps goes unseen.
            h = min(2 * h, min(1.0, abs(margin) / _FINE_MARGIN) / full)
            steps += 1
            if (margin > 0) != sign:
                return _CROSSED, k, steps, 0.0
            smallest = min(smallest, abs(margin))
            if smallest < min_margin:
                return _TOO_CLOSE, k, steps, smallest
        poses[k] = pose
        for j in range(pose.size):
            if angular[j]:
                poses[k, j] = math.atan2(math.sin(pose[j]), math.cos(pose[j]))
    return _FOLLOWING, -1, steps, smallest
