"""The independent trajectory validator.

It knows nothing of grids, regions or patches: it drives the joints along
the path and follows the platform like the real mechanism would, by
continuation of the constraint equations from the start pose
(:func:`~rpr3_gwr_core.mechanisms.continuation.follow_path`, whose step
control keeps every step on the followed solution branch and samples the
margin densely enough near a singularity that no dip goes unseen).  It fails
a path when

* the platform cannot follow the joints (it would have to jump to another
  solution: the followed branch ends in a fold),
* the sign of the margin changes (a parallel singularity was crossed),
* the margin's magnitude (:meth:`~rpr3_gwr_core.mechanisms.Mechanism.margin`)
  falls below ``min_margin``, or
* the platform does not arrive at the goal pose (another assembly mode).
"""

from dataclasses import dataclass
import numpy as np

from ..exceptions import InvalidInputError
from ..mechanisms.continuation import CANNOT_FOLLOW, CROSSED, TOO_CLOSE, follow_path

__all__ = ["Validation", "validate_path", "DEFAULT_MAX_STEP", "DEFAULT_MIN_MARGIN"]

DEFAULT_MAX_STEP = 0.0625
# Normalised |det Jx| (Mechanism.margin) below which a
# configuration counts as singular: the platform's orientation then moves
# more than about a thousand times faster than at a well-conditioned pose.
DEFAULT_MIN_MARGIN = 1e-3
_GOAL_TOL = 1e-6
# A start pose with a larger residual [scale**2] is corrected before following.
_CONVERGED = 1e-10
_POLISH_ITERATIONS = 3


@dataclass(frozen=True, repr=False)
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

    def __repr__(self):
        return (f"Validation({'ok' if self.ok else self.reason}, {len(self.poses)} waypoints, "
                f"min margin {self.min_margin:.3g}, aspect {self.aspect:+d}, "
                f"{self.steps} steps)")

    def as_dict(self):
        """Plain-data summary (no poses)."""
        return {"ok": self.ok, "reason": self.reason, "min_margin": self.min_margin,
                "aspect": self.aspect, "steps": self.steps}


def validate_path(mechanism, path, start_pose, goal_pose=None,
                  min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP):
    """Follow the platform along a joint path and check it stays regular.

    Steps are at most ``max_step`` and shrink near singularities (see
    :mod:`~rpr3_gwr_core.mechanisms.continuation`).

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
    margin = float(mechanism.margin(pose, path[0]))
    sign = 1 if margin > 0 else -1
    if abs(margin) < min_margin:
        return result(False, f"start is singular (margin {abs(margin):.2e})", abs(margin), sign)
    # Converged first, so that what the corrector moves later is the path's doing.
    followed = pose.copy()
    if residual > _CONVERGED * mechanism.scale**2:
        followed = np.array(mechanism.correct(pose, path[0], _POLISH_ITERATIONS), dtype=float)
    status, k, steps, smallest = follow_path(mechanism, path, followed, min_margin, max_step,
                                             poses)
    if status == CANNOT_FOLLOW:
        return result(False, f"platform cannot follow the joints before waypoint {k}",
                      smallest, sign, steps, k)
    if status == CROSSED:
        return result(False, f"the margin changes sign before waypoint {k}: "
                      "a parallel singularity is crossed", 0.0, sign, steps, k)
    if status == TOO_CLOSE:
        return result(False, f"margin {smallest:.2e} below {min_margin:g} before "
                      f"waypoint {k}", smallest, sign, steps, k)
    pose = followed
    if goal_pose is not None:
        miss = float(np.max(np.abs(mechanism.pose_difference(pose, goal_pose))))
        if miss > _GOAL_TOL * mechanism.scale:
            return result(False, f"platform ends {miss:.3g} away from the goal pose: "
                          "another assembly mode", smallest, sign, steps)
    return result(True, "ok", smallest, sign, steps)
