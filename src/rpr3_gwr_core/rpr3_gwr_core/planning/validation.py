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

__all__ = ["Validation", "validate_path", "joined_validation", "validation_part",
           "DEFAULT_MAX_STEP", "DEFAULT_MIN_MARGIN"]

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
    poses : ndarray, shape (n, pose_size)
        The followed platform pose at each waypoint, angles wrapped.
    failed_segment : int
        Index k of the segment from waypoint k - 1 to waypoint k where the
        path failed; -1 when it did not fail inside a segment.
    segment_margins : ndarray, shape (n - 1,)
        Smallest margin magnitude met on each segment, its start included
        (the segment where following stopped up to there); NaN beyond.
    segment_steps : ndarray of int, shape (n - 1,)
        Continuation steps taken on each segment, 0 beyond.
    """

    ok: bool
    reason: str
    min_margin: float
    aspect: int
    steps: int
    poses: np.ndarray
    failed_segment: int = -1
    segment_margins: np.ndarray = None
    segment_steps: np.ndarray = None

    def __repr__(self):
        return (f"Validation({'ok' if self.ok else self.reason}, {len(self.poses)} waypoints, "
                f"min margin {self.min_margin:.3g}, aspect {self.aspect:+d}, "
                f"{self.steps} steps)")

    def as_dict(self):
        """Plain-data summary (no poses)."""
        return {"ok": self.ok, "reason": self.reason, "min_margin": self.min_margin,
                "aspect": self.aspect, "steps": self.steps}

    def reached(self):
        """How many waypoints, from the first, the platform was followed to."""
        if self.failed_segment >= 1:
            return self.failed_segment
        return len(self.poses) if np.isfinite(self.poses).all() else 0


def joined_validation(parts):
    """The verdict on a path made of passed paths laid end to end, each
    starting at the waypoint and pose where the one before ends: the
    continuation of each went on from there, so together they are the
    continuation of the whole.

    Parameters
    ----------
    parts : sequence of Validation
        At least one; all passed, of the same aspect.

    Returns
    -------
    Validation

    Raises
    ------
    InvalidInputError
        If a part failed, the aspects differ or there are none.
    """
    parts = list(parts)
    if not parts or not all(part.ok for part in parts) \
            or len({part.aspect for part in parts}) != 1:
        raise InvalidInputError("joined verdicts must be passed verdicts of one aspect, at "
                                f"least one, got {parts!r}")
    poses = np.concatenate([part.poses[:-1] for part in parts[:-1]] + [parts[-1].poses])
    return Validation(ok=True, reason="ok", min_margin=min(part.min_margin for part in parts),
                      aspect=parts[0].aspect, steps=sum(part.steps for part in parts),
                      poses=poses,
                      segment_margins=np.concatenate([part.segment_margins for part in parts]),
                      segment_steps=np.concatenate([part.segment_steps for part in parts]))


def validation_part(validation, first, last):
    """A passed verdict's part between two of its waypoints: the verdict on
    that stretch of its path followed from the pose it had there.

    Parameters
    ----------
    validation : Validation
        A passed verdict.
    first, last : int
        Waypoint indices, ``0 <= first < last < n``.

    Returns
    -------
    Validation

    Raises
    ------
    InvalidInputError
        If the verdict failed or the indices are out of order or range.
    """
    n = len(validation.poses)
    if not validation.ok or not 0 <= first < last < n:
        raise InvalidInputError(f"a part is a stretch of a passed verdict, waypoints 0 <= first "
                                f"< last < {n}; got {first}, {last} of {validation!r}")
    margins = validation.segment_margins[first:last]
    steps = validation.segment_steps[first:last]
    return Validation(ok=True, reason="ok", min_margin=float(margins.min()),
                      aspect=validation.aspect, steps=int(steps.sum()),
                      poses=validation.poses[first:last + 1], segment_margins=margins,
                      segment_steps=steps)


def validate_path(mechanism, path, start_pose, goal_pose=None,
                  min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP, known=None):
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
    known : (Validation, int), optional
        An earlier verdict, from the same start pose and step, on a path
        whose first ``k + 1`` waypoints are this path's, and ``k``: the
        platform followed that path at least to waypoint ``k``, so following
        resumes there: the verdict is the one of following from the start
        (where the earlier verdict kept a lower ``min_margin`` and dips
        below this one before ``k``, it fails there, its steps counted to
        the end of that segment).

    Returns
    -------
    Validation

    Raises
    ------
    InvalidInputError
        If the path or the poses are not finite arrays of the mechanism's
        sizes, ``max_step`` is not positive, or ``known`` does not reach its
        waypoint.
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
    n = path.shape[0]
    poses = np.full((n, mechanism.pose_size), np.nan)
    trace = np.full((max(n - 1, 0), 2), np.nan)
    trace[:, 1] = 0.0

    def result(ok, reason, smallest, sign, steps=0, segment=-1):
        return Validation(ok=ok, reason=reason, min_margin=smallest, aspect=sign, steps=steps,
                          poses=poses, failed_segment=segment, segment_margins=trace[:, 0],
                          segment_steps=trace[:, 1].astype(np.int64))

    if known is not None:
        earlier, k = known
        if not 0 <= k < n or k >= earlier.reached():
            raise InvalidInputError(f"the earlier verdict {earlier!r} does not reach waypoint "
                                    f"{k} of a path of {n}")
        return _resumed(mechanism, path, earlier, k, goal_pose, min_margin, max_step, poses,
                        trace, result)
    residual = _largest(mechanism.residual(pose, path[0]))
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
                                             poses, trace)
    return _verdict(mechanism, status, k, steps, smallest, sign, followed, goal_pose, min_margin,
                    result)


def _resumed(mechanism, path, earlier, k, goal_pose, min_margin, max_step, poses, trace,
             result):
    """:func:`validate_path` going on from waypoint ``k`` of an earlier verdict."""
    poses[:k + 1] = earlier.poses[:k + 1]
    trace[:k, 0] = earlier.segment_margins[:k]
    trace[:k, 1] = earlier.segment_steps[:k]
    sign, steps = earlier.aspect, int(earlier.segment_steps[:k].sum())
    low = np.flatnonzero(trace[:k, 0] < min_margin)
    if low.size:
        first = int(low[0])
        trace[first + 1:k] = (np.nan, 0.0)
        poses[first + 1:] = np.nan
        return _verdict(mechanism, TOO_CLOSE, first + 1, int(trace[:first + 1, 1].sum()),
                        float(trace[first, 0]), sign, None, goal_pose, min_margin, result)
    followed = poses[k].copy()
    status, stopped, more, smallest = follow_path(mechanism, path[k:], followed, min_margin,
                                                  max_step, poses[k:], trace[k:])
    if k:
        smallest = min(smallest, float(trace[:k, 0].min()))
    return _verdict(mechanism, status, stopped + k if stopped >= 1 else stopped, steps + more,
                    smallest, sign, followed, goal_pose, min_margin, result)


def _verdict(mechanism, status, k, steps, smallest, sign, pose, goal_pose, min_margin, result):
    """The verdict on a path followed (``follow_path``'s outcome) to ``pose``."""
    if status == CANNOT_FOLLOW:
        return result(False, f"platform cannot follow the joints before waypoint {k}",
                      smallest, sign, steps, k)
    if status == CROSSED:
        return result(False, f"the margin changes sign before waypoint {k}: "
                      "a parallel singularity is crossed", 0.0, sign, steps, k)
    if status == TOO_CLOSE:
        return result(False, f"margin {smallest:.2e} below {min_margin:g} before "
                      f"waypoint {k}", smallest, sign, steps, k)
    if goal_pose is not None:
        miss = _largest(mechanism.pose_difference(pose, goal_pose))
        if miss > _GOAL_TOL * mechanism.scale:
            return result(False, f"platform ends {miss:.3g} away from the goal pose: "
                          "another assembly mode", smallest, sign, steps)
    return result(True, "ok", smallest, sign, steps)


def _largest(values):
    """The largest magnitude of a few values: on so few, a numpy reduction's
    call costs several times the comparisons."""
    return max(map(abs, np.ravel(values).tolist()))
