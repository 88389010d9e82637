"""Turning a cell path into a joint trajectory: smoothing and timing.

Chaikin's corner cutting rounds chosen corners of a polyline (shortcutting,
which needs the roadmap, is :func:`~.segments.shortcut_path`).  The caller
validates the result and puts back what the validator refuses.

Timing is a velocity profile along the path's arc length s: the speed
``v(s)`` is capped so that no joint moves faster than its ``max_velocity``,
and at each corner so that the change of each joint's velocity across it
stays within half of its ``max_acceleration``; forward and backward passes
then bound the acceleration along the path, ``v dv/ds``, by the other half
of the smallest, starting and ending at rest.  Limits are per joint, as
MoveIt's joint limits give them, or one for all joints.  A segment takes its
length over the mean of its end speeds, and never less than its length at
the speed cap (a segment between two rests would otherwise be timed by the
acceleration alone).  Durations are rounded up to whole nanoseconds, the
resolution of a ROS ``Duration``, so that a consumer's rounding cannot speed
a segment up.  Where a joint's velocity changes between two waypoints faster
than the acceleration limit, the speed there is lowered and the profile
redone.  The limits therefore hold between the points, for a consumer that
moves each joint linearly from point to point: every segment's change of a
joint over its duration is within the joint's ``max_velocity``, and the
change of its point velocities over it within its ``max_acceleration``.
"""

import math

import numpy as np

from ..exceptions import InvalidInputError

__all__ = ["cut_corners", "corner_cuts", "time_parameterize"]


def cut_corners(points, corners):
    """One step of Chaikin's corner cutting, at chosen corners.

    Each chosen corner is replaced by the points a quarter of the way along
    its two segments; the end points stay.

    Parameters
    ----------
    points : ndarray, shape (n, d)
    corners : ndarray of bool, shape (n,)
        Which points to cut (the first and last are never cut).

    Returns
    -------
    points : ndarray, shape (m, d)
    origin : ndarray of int, shape (m,)
        The point of the input each output point stands for.
    """
    points = np.asarray(points, dtype=float)
    cut = np.asarray(corners, dtype=bool).copy()
    cut[[0, -1]] = False
    origin = np.repeat(np.arange(len(points)), np.where(cut, 2, 1))
    out = points[origin]
    first = np.flatnonzero(cut[origin] & (np.diff(origin, prepend=-1) > 0))
    out[first], out[first + 1] = corner_cuts(points, origin[first])
    return out, origin


def corner_cuts(points, at):
    """Chaikin's cut of the corners at indices ``at``: the points a quarter
    of the way from each to its previous and to its next neighbour.

    Returns
    -------
    before, after : ndarray, shape (len(at), d)
    """
    return (0.75 * points[at] + 0.25 * points[at - 1],
            0.75 * points[at] + 0.25 * points[at + 1])


def time_parameterize(path, max_velocity, max_acceleration):
    """Time stamps, joint velocities and accelerations along a leg path.

    Parameters
    ----------
    path : ndarray, shape (n, n_joints)
        Waypoints [joint unit], no two consecutive ones equal.
    max_velocity : float or array_like, shape (n_joints,)
        Largest speed of every joint, or of each [joint unit / s].
    max_acceleration : float or array_like, shape (n_joints,)
        Largest acceleration of every joint, or of each [joint unit / s**2].

    Returns
    -------
    times : ndarray, shape (n,)
        [s], starting at 0.
    velocities : ndarray, shape (n, n_joints)
        Joint velocities at the waypoints [joint unit / s]: differences of
        the positions over the times (central inside, zero at the ends), so
        they integrate back to the path and never exceed a joint's
        ``max_velocity``.
    accelerations : ndarray, shape (n, n_joints)
        Joint accelerations at the waypoints [joint unit / s**2]: central
        differences of the velocities (one-sided at the ends).  Where the
        velocities change faster than a joint's ``max_acceleration`` between two
        waypoints, the speed there is lowered and the profile recomputed, so
        these and the accelerations between the points respect it.

    Raises
    ------
    InvalidInputError
        If a limit is not positive and finite, a list of limits does not
        have one per joint, or the limits are so far from
        the path's scale that the times or derivatives are not finite, or
        two waypoints would be at most a nanosecond apart.
    """
    path = np.asarray(path, dtype=float)
    velocity_limits = _joint_limits(max_velocity, path.shape[1])
    acceleration_limits = _joint_limits(max_acceleration, path.shape[1])
    shown = (f"max_velocity = {_shown_limits(velocity_limits)} and "
             f"max_acceleration = {_shown_limits(acceleration_limits)}")
    n = len(path)
    if n == 1:
        return np.zeros(1), np.zeros_like(path), np.zeros_like(path)
    delta = np.diff(path, axis=0)
    length = np.linalg.norm(delta, axis=1)
    if np.any(length == 0):
        raise InvalidInputError("consecutive waypoints must differ")
    direction = delta / length[:, None]
    # Joints a segment or a corner does not move divide by 0 (no bound from
    # them), straight corners too, and extreme limits overflow or underflow
    # in here; the result is checked below.
    with np.errstate(all="ignore"):
        # Fastest speed along each segment that keeps every joint within its limit.
        segment_cap = np.min(velocity_limits / np.abs(direction), axis=1)
        cap = np.full(n, np.inf)
        cap[:-1] = segment_cap
        cap[1:] = np.minimum(cap[1:], segment_cap)
        turn = np.abs(direction[1:] - direction[:-1])
        span = 0.5 * (length[1:] + length[:-1])
        half = 0.5 * acceleration_limits
        cap[1:-1] = np.minimum(cap[1:-1], np.sqrt(span * np.min(half / turn, axis=1)))
        # Along the path, a joint accelerates at most at v dv/ds.
        half = float(np.min(half))
        cap[0] = cap[-1] = 0.0
        for _ in range(_MAX_REFINEMENTS):
            speed = _speed_profile(cap, length, half)
            times = _times(speed, length, segment_cap, half)
            velocities = _velocities(path, times)
            accelerations = _differences(velocities, times)
            # The fastest change of a joint velocity, over its limit, on
            # either side of a waypoint.
            change = (np.max(np.abs(np.diff(velocities, axis=0)) / acceleration_limits, axis=1)
                      / np.diff(times))
            excess = np.maximum(np.concatenate([[0.0], change]),
                                np.concatenate([change, [0.0]]))
            if np.all(excess <= 1.0):
                break
            # Lower the speed around each offending waypoint and try again.
            over = np.flatnonzero(excess > 1.0)
            for k in (over - 1, over, over + 1):
                k = k[(k >= 0) & (k < n)]
                cap[k] = np.minimum(cap[k], speed[k] / np.sqrt(np.maximum(excess[k], 1.0)) * 0.9)
    if np.all(np.isfinite(times)) and np.any(np.diff(np.round(times * _NANOSECONDS)) < 2):
        raise InvalidInputError(
            f"{shown} are so high that two waypoints are at most 1 ns apart: lower them")
    # Limits far from the path's scale (1e-300, 1e300) overflow or underflow
    # the profile: such a request cannot be timed, and must not look timed.
    if not (np.all(np.isfinite(times)) and np.all(np.diff(times) > 0)
            and np.all(np.isfinite(velocities)) and np.all(np.isfinite(accelerations))
            and np.all(excess <= 1.0)):
        raise InvalidInputError(
            f"{shown} cannot time this path in floating point (duration {times[-1]:g} s)")
    return times, velocities, accelerations


def _joint_limits(limits, n_joints):
    """One positive, finite limit per joint, from one for all or one each."""
    try:
        values = np.asarray(limits, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"a limit must be a number or one per joint, got "
                                f"{limits!r:.80}") from None
    if values.shape not in ((), (n_joints,)):
        raise InvalidInputError(f"give one limit for all joints or one per joint "
                                f"({n_joints}), got {values.size}")
    if not np.all(np.isfinite(values) & (values > 0)):
        raise InvalidInputError("velocity and acceleration limits must be positive and finite")
    return np.broadcast_to(values, (n_joints,))


def _shown_limits(limits):
    """One limit, or the list of them."""
    if np.all(limits == limits[0]):
        return f"{limits[0]:g}"
    return "[" + ", ".join(f"{v:g}" for v in limits) + "]"


_MAX_REFINEMENTS = 60
_NANOSECONDS = 1e9


def _speed_profile(cap, length, acceleration):
    """Largest speeds under the caps with ``v dv/ds <= acceleration`` both ways."""
    speed = cap.copy()
    for k in range(1, len(speed)):
        speed[k] = min(speed[k], math.sqrt(speed[k - 1] ** 2 + 2 * acceleration * length[k - 1]))
    for k in range(len(speed) - 2, -1, -1):
        speed[k] = min(speed[k], math.sqrt(speed[k + 1] ** 2 + 2 * acceleration * length[k]))
    return speed


def _times(speed, length, segment_cap, acceleration):
    """Time stamps [s], whole nanoseconds: each segment at the mean of its end
    speeds, at most its cap; between two rests, the bang-bang time or the
    cap's, whichever is longer."""
    mean = np.minimum(0.5 * (speed[:-1] + speed[1:]), segment_cap)
    duration = np.where(mean > 0, length / np.where(mean > 0, mean, 1.0),
                        np.maximum(2.0 * np.sqrt(length / acceleration), length / segment_cap))
    nanoseconds = np.ceil(duration * _NANOSECONDS)
    return np.concatenate([[0.0], np.cumsum(nanoseconds)]) / _NANOSECONDS


def _velocities(positions, times):
    out = np.zeros_like(positions)
    out[1:-1] = (positions[2:] - positions[:-2]) / (times[2:] - times[:-2])[:, None]
    return out


def _differences(velocities, times):
    out = np.empty_like(velocities)
    out[1:-1] = (velocities[2:] - velocities[:-2]) / (times[2:] - times[:-2])[:, None]
    out[0] = (velocities[1] - velocities[0]) / (times[1] - times[0])
    out[-1] = (velocities[-1] - velocities[-2]) / (times[-1] - times[-2])
    return out
