"""Turning a cell path into a leg trajectory: smoothing and timing.

Smoothing works in the (rho2, rho3) plane of the path (rho1 is fixed):
shortcutting replaces a stretch of the path by a straight segment when every
cell that segment passes over (sampled at a fifth of a cell) belongs, in
order, to the patches of the stretch, and keeps ``min_clearance`` cells from
the patch boundary except within a few cells of the stretch's gate
crossings; Chaikin corner cutting then rounds the corners.  The caller
validates the result and falls back to the unsmoothed path if it fails.

Timing is a velocity profile along the path's arc length s: the speed
``v(s)`` is capped so that no joint moves faster than ``max_velocity``, and
at each corner so that the change of joint velocity across it stays within
half of ``max_acceleration``; forward and backward passes then bound the
acceleration along the path, ``v dv/ds``, by the other half, starting and
ending at rest.  A joint's acceleration is the sum of the two parts, so it
stays within ``max_acceleration``.
"""

import math

import numpy as np

from .exceptions import InvalidInputError

__all__ = ["shortcut", "chaikin", "time_parameterize"]


def shortcut(points, allowed, max_passes=3):
    """Greedy shortcutting of a polyline.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        Path in the (rho2, rho3) plane [length unit].
    allowed : callable
        ``allowed(i, j)`` is True when the straight segment from point i to
        point j may replace the points between them.
    max_passes : int

    Returns
    -------
    ndarray of int
        Indices of the kept points, first and last included.
    """
    keep = list(range(len(points)))
    for _ in range(max_passes):
        changed = False
        out = [keep[0]]
        i = 0
        while i < len(keep) - 1:
            j = len(keep) - 1
            # Longest jump first, halving the reach so a pass costs O(n log n) tests.
            reach = j - i
            while reach > 1 and not allowed(keep[i], keep[i + reach]):
                reach //= 2
            if reach > 1:
                changed = True
            i += max(reach, 1)
            out.append(keep[i])
        keep = out
        if not changed:
            break
    return np.array(keep)


def chaikin(points, iterations=2):
    """Chaikin corner cutting; the end points stay.

    Parameters
    ----------
    points : ndarray, shape (n, d)
    iterations : int

    Returns
    -------
    ndarray, shape (m, d)
    """
    points = np.asarray(points, dtype=float)
    for _ in range(iterations):
        if len(points) < 3:
            return points
        q = 0.75 * points[:-1] + 0.25 * points[1:]
        r = 0.25 * points[:-1] + 0.75 * points[1:]
        inner = np.empty((2 * (len(points) - 1), points.shape[1]))
        inner[0::2], inner[1::2] = q, r
        points = np.vstack([points[:1], inner[1:-1], points[-1:]])
    return points


def time_parameterize(rho_path, max_velocity, max_acceleration):
    """Time stamps, joint velocities and accelerations along a leg path.

    Parameters
    ----------
    rho_path : ndarray, shape (n, 3)
        Waypoints [length unit].
    max_velocity : float
        Largest joint speed [length unit / s].
    max_acceleration : float
        Largest joint acceleration [length unit / s**2].

    Returns
    -------
    times : ndarray, shape (n,)
        [s], starting at 0.
    velocities : ndarray, shape (n, 3)
        Joint velocities at the waypoints [length unit / s].
    accelerations : ndarray, shape (n, 3)
        Joint accelerations at the waypoints [length unit / s**2], by finite
        differences of the velocities.
    """
    if not (math.isfinite(max_velocity) and max_velocity > 0
            and math.isfinite(max_acceleration) and max_acceleration > 0):
        raise InvalidInputError("velocity and acceleration limits must be positive and finite")
    rho_path = np.asarray(rho_path, dtype=float)
    n = len(rho_path)
    if n == 1:
        return np.zeros(1), np.zeros((1, 3)), np.zeros((1, 3))
    delta = np.diff(rho_path, axis=0)
    length = np.linalg.norm(delta, axis=1)
    direction = delta / np.where(length > 0, length, 1.0)[:, None]
    # Speed cap per waypoint from the joint speed limit along the adjacent segments.
    seg_cap = max_velocity / np.maximum(np.max(np.abs(direction), axis=1), 1e-12)
    cap = np.full(n, np.inf)
    cap[:-1] = np.minimum(cap[:-1], seg_cap)
    cap[1:] = np.minimum(cap[1:], seg_cap)
    turn = np.max(np.abs(direction[1:] - direction[:-1]), axis=1)
    span = 0.5 * (length[1:] + length[:-1])
    with np.errstate(divide="ignore"):
        cap[1:-1] = np.minimum(cap[1:-1], np.sqrt(0.5 * max_acceleration * span / turn))
    cap[0] = cap[-1] = 0.0
    half = 0.5 * max_acceleration
    speed = cap.copy()
    for k in range(1, n):
        speed[k] = min(speed[k], math.sqrt(speed[k - 1] ** 2 + 2 * half * length[k - 1]))
    for k in range(n - 2, -1, -1):
        speed[k] = min(speed[k], math.sqrt(speed[k + 1] ** 2 + 2 * half * length[k]))
    mean = 0.5 * (speed[:-1] + speed[1:])
    # A segment between two rests (speed 0 at both ends) takes the bang-bang time.
    duration = np.where(mean > 0, length / np.where(mean > 0, mean, 1.0),
                        2.0 * np.sqrt(length / half))
    times = np.concatenate([[0.0], np.cumsum(duration)])
    tangent = np.zeros((n, 3))
    tangent[:-1] += direction
    tangent[1:] += direction
    norms = np.linalg.norm(tangent, axis=1)
    tangent /= np.where(norms > 0, norms, 1.0)[:, None]
    velocities = speed[:, None] * tangent
    accelerations = np.gradient(velocities, times, axis=0) if n > 2 else np.zeros((n, 3))
    return times, velocities, accelerations
