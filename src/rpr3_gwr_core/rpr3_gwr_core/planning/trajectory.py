"""Turning a cell path into a joint trajectory: smoothing and timing.

Chaikin's corner cutting rounds chosen corners of a polyline (shortcutting,
which needs the roadmap, is :func:`~.segments.shortcut_path`).  The caller
validates the result and puts back what the validator refuses.

Timing is a velocity profile along the path's arc length s: the speed
``v(s)`` is capped so that no joint moves faster than ``max_velocity``, and
at each corner so that the change of joint velocity across it stays within
half of ``max_acceleration``; forward and backward passes then bound the
acceleration along the path, ``v dv/ds``, by the other half, starting and
ending at rest.  A segment takes its length over the mean of its end speeds,
and never less than its length at the speed cap (a segment between two rests
would otherwise be timed by the acceleration alone).  Durations are rounded
up to whole nanoseconds, the resolution of a ROS ``Duration``, so that a
consumer's rounding cannot speed a segment up.  Where a joint's velocity
changes between two waypoints faster than the acceleration limit, the speed
there is lowered and the profile redone.  The limits therefore hold between
the points, for a consumer that moves each joint linearly from point to
point: every segment's joint change over its duration is within
``max_velocity``, and the change of the point velocities over it within
``max_acceleration``.
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
    max_velocity : float
        Largest joint speed [joint unit / s].
    max_acceleration : float
        Largest joint acceleration [joint unit / s**2].

    Returns
    -------
    times : ndarray, shape (n,)
        [s], starting at 0.
    velocities : ndarray, shape (n, n_joints)
        Joint velocities at the waypoints [joint unit / s]: differences of
        the positions over the times (central inside, zero at the ends), so
        they integrate back to the path and never exceed ``max_velocity``.
    accelerations : ndarray, shape (n, n_joints)
        Joint accelerations at the waypoints [joint unit / s**2]: central
        differences of the velocities (one-sided at the ends).  Where the
        velocities change faster than ``max_acceleration`` between two
        waypoints, the speed there is lowered and the profile recomputed, so
        these and the accelerations between the points respect it.

    Raises
    ------
    InvalidInputError
        If a limit is not positive and finite, or the limits are so far from
        the path's scale that the times or derivatives are not finite, or
        two waypoints would be at most a nanosecond apart.
    """
    if not (math.isfinite(max_velocity) and max_velocity > 0
            and math.isfinite(max_acceleration) and max_acceleration > 0):
        raise InvalidInputError("velocity and acceleration limits must be positive and finite")
    path = np.asarray(path, dtype=float)
    n = len(path)
    if n == 1:
        return np.zeros(1), np.zeros_like(path), np.zeros_like(path)
    delta = np.diff(path, axis=0)
    length = np.linalg.norm(delta, axis=1)
    if np.any(length == 0):
        raise InvalidInputError("consecutive waypoints must differ")
    direction = delta / length[:, None]
    # Fastest speed along each segment that keeps every joint within the limit.
    segment_cap = max_velocity / np.max(np.abs(direction), axis=1)
    cap = np.full(n, np.inf)
    cap[:-1] = segment_cap
    cap[1:] = np.minimum(cap[1:], segment_cap)
    turn = np.max(np.abs(direction[1:] - direction[:-1]), axis=1)
    span = 0.5 * (length[1:] + length[:-1])
    half = 0.5 * max_acceleration
    # Straight corners divide by 0, and extreme limits overflow or underflow
    # in here; the result is checked below.
    with np.errstate(all="ignore"):
        cap[1:-1] = np.minimum(cap[1:-1], np.sqrt(half * span / turn))
        cap[0] = cap[-1] = 0.0
        for _ in range(_MAX_REFINEMENTS):
            speed = _speed_profile(cap, length, half)
            times = _times(speed, length, segment_cap, half)
            velocities = _velocities(path, times)
            accelerations = _differences(velocities, times)
            # The fastest change of any joint velocity on either side of a waypoint.
            change = np.max(np.abs(np.diff(velocities, axis=0)), axis=1) / np.diff(times)
            excess = np.maximum(np.concatenate([[0.0], change]),
                                np.concatenate([change, [0.0]])) / max_acceleration
            if np.all(excess <= 1.0):
                break
            # Lower the speed around each offending waypoint and try again.
            over = np.flatnonzero(excess > 1.0)
            for k in (over - 1, over, over + 1):
                k = k[(k >= 0) & (k < n)]
                cap[k] = np.minimum(cap[k], speed[k] / np.sqrt(np.maximum(excess[k], 1.0)) * 0.9)
    if np.all(np.isfinite(times)) and np.any(np.diff(np.round(times * _NANOSECONDS)) < 2):
        raise InvalidInputError(
            f"max_velocity = {max_velocity:g} and max_acceleration = {max_acceleration:g} are so "
            "high that two waypoints are at most 1 ns apart: lower them")
    # Limits far from the path's scale (1e-300, 1e300) overflow or underflow
    # the profile: such a request cannot be timed, and must not look timed.
    if not (np.all(np.isfinite(times)) and np.all(np.diff(times) > 0)
            and np.all(np.isfinite(velocities)) and np.all(np.isfinite(accelerations))
            and np.all(excess <= 1.0)):
        raise InvalidInputError(
            f"max_velocity = {max_velocity:g} and max_acceleration = {max_acceleration:g} cannot "
            f"time this path in floating point (duration {times[-1]:g} s)")
    return times, velocities, accelerations


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
