"""The independent trajectory validator.

It knows nothing of grids, regions or patches: it drives the legs along the
rho path in steps of at most ``max_step`` and follows the platform like the
real mechanism would, by continuation (Euler predictor, Newton corrector) of
the constraint equations from the start pose.  It fails a path when

* the corrector does not converge even in steps 256 times smaller (the
  platform would have to jump),
* the sign of det(Jx) changes (a parallel singularity was crossed),
* the normalised |det Jx| (:func:`~rpr3_gwr_core.kinematics.singularity_margin`)
  falls below ``min_margin``, or
* the platform does not arrive at the goal pose (another assembly mode).

The steps are sequential and small, so they use the scalar
:class:`~rpr3_gwr_core.mechanism.Mechanism` rather than numpy.
"""

from dataclasses import dataclass
import math

import numpy as np

from .exceptions import InvalidInputError
from .mechanism import Mechanism

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
        Smallest normalised |det Jx| met.
    aspect : int
        Sign of det(Jx) along the path.
    steps : int
        Continuation steps taken.
    failed_segment : int
        Index k of the segment from waypoint k - 1 to waypoint k where the
        path failed; -1 when it did not fail inside a segment.
    poses : ndarray, shape (n, 3)
        The followed platform pose at each waypoint [length unit, length unit, rad].
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


def validate_path(geometry, rho_path, start_pose, goal_pose=None,
                  min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP):
    """Follow the platform along a leg path and check it stays regular.

    Steps are at most ``max_step``, shrunk in proportion to the margin below
    0.05; where the corrector does not converge the step is halved, up to
    ``2**-8`` of it, before the path fails.

    Parameters
    ----------
    geometry : Geometry
    rho_path : array_like, shape (n, 3)
        Waypoints of the legs [length unit]; consecutive waypoints are joined
        by straight segments.
    start_pose : array_like, shape (3,)
        The platform pose at the first waypoint.
    goal_pose : array_like, shape (3,), optional
        The pose the platform must reach at the last waypoint.
    min_margin : float
        Smallest accepted normalised |det Jx|.
    max_step : float
        Largest leg change of one continuation step [length unit].

    Returns
    -------
    Validation
    """
    rho_path = np.asarray(rho_path, dtype=float)
    if rho_path.ndim != 2 or rho_path.shape[1] != 3 or rho_path.shape[0] < 1:
        raise InvalidInputError(f"rho_path must have shape (n, 3), got {rho_path.shape}")
    if not np.all(np.isfinite(rho_path)) or not np.all(np.isfinite(start_pose)):
        raise InvalidInputError("rho_path and start_pose must be finite")
    if not max_step > 0:
        raise InvalidInputError("max_step must be positive")
    mech = Mechanism(geometry)
    x, y, alpha = (float(v) for v in start_pose)
    poses = np.empty((rho_path.shape[0], 3))
    steps = 0

    def result(ok, reason, smallest, sign, segment=-1):
        return Validation(ok=ok, reason=reason, min_margin=smallest, aspect=sign, steps=steps,
                          poses=poses, failed_segment=segment)

    rows = mech.rows(x, y, alpha)
    residual = _residual(rows, rho_path[0])
    if residual > 1e-6 * mech.scale**2:
        poses[:] = np.nan
        return result(False, f"start pose does not fit the first waypoint (residual {residual:.2e})",
                      0.0, 0)
    margin = mech.margin(rows)
    sign = 1 if margin > 0 else -1
    smallest = abs(margin)
    if smallest < min_margin:
        poses[:] = np.nan
        return result(False, f"start is singular (margin {smallest:.2e})", smallest, sign)
    poses[0] = x, y, alpha
    for k in range(1, rho_path.shape[0]):
        start, end = rho_path[k - 1], rho_path[k]
        full = max(1.0, float(np.max(np.abs(end - start))) / max_step)
        done, h = 0.0, min(1.0, smallest / _FINE_MARGIN) / full
        while done < 1.0:
            h = min(h, 1.0 - done)
            pose = mech.step(x, y, alpha, start + (end - start) * done,
                             start + (end - start) * (done + h))
            if pose is None:
                # Near a singularity the platform turns fast: refine before giving up.
                if h * full < 2.0**-_MAX_HALVINGS:
                    poses[k:] = np.nan
                    return result(False, f"platform cannot follow the legs before waypoint {k}",
                                  smallest, sign, k)
                h /= 2
                continue
            (x, y, alpha), margin = pose
            done += h
            # Sample finer where det(Jx) is small, so that no dip between two
            # steps goes unseen.
            h = min(2 * h, min(1.0, abs(margin) / _FINE_MARGIN) / full)
            steps += 1
            if (margin > 0) != (sign > 0):
                poses[k:] = np.nan
                return result(False, f"det(Jx) changes sign before waypoint {k}: "
                              "a parallel singularity is crossed", 0.0, sign, k)
            smallest = min(smallest, abs(margin))
            if smallest < min_margin:
                poses[k:] = np.nan
                return result(False, f"margin {smallest:.2e} below {min_margin:g} before "
                              f"waypoint {k}", smallest, sign, k)
        poses[k] = x, y, math.atan2(math.sin(alpha), math.cos(alpha))
    if goal_pose is not None:
        gx, gy, galpha = (float(v) for v in goal_pose)
        miss = max(abs(x - gx), abs(y - gy),
                   mech.scale * abs(math.remainder(alpha - galpha, 2 * math.pi)))
        if miss > _GOAL_TOL * mech.scale:
            return result(False, f"platform ends {miss:.3g} away from the goal pose: "
                          "another assembly mode", smallest, sign)
    return result(True, "ok", smallest, sign)


def _residuals(rows, rho):
    u1x, u1y, u2x, u2y, _, u3x, u3y, _ = rows
    return (u1x * u1x + u1y * u1y - rho[0] ** 2, u2x * u2x + u2y * u2y - rho[1] ** 2,
            u3x * u3x + u3y * u3y - rho[2] ** 2)


def _residual(rows, rho):
    return max(abs(v) for v in _residuals(rows, rho))
