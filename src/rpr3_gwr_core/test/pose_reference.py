"""An independent reference for 3-RPR joint paths, in pose space.

It knows nothing of the project's code: inverse kinematics of the 3-RPR is
unique, so the pose (x, y, alpha) is the configuration space, and a joint
path is executable when a pose track that starts at the start pose, moves
continuously, keeps one sign of det(Jx) and a margin above a threshold, and
ends on the goal pose, satisfies the legs all along.  Its own legs,
Jacobian, margin and continuation (Newton on the legs at fixed joints, with
steps that may move the pose only a small fraction of its distance to the
singular locus) are written here from the paper's numbers.  Imported by name
by the tests and the benchmarks.
"""

import math

import numpy as np

# The paper's geometry (section 4), with the platform angle at B1 from its sides.
BASE = ((0.0, 0.0), (15.91, 0.0), (0.0, 10.0))
D1, D2, D3 = 17.04, 16.54, 20.84
BETA = math.acos((D1**2 + D3**2 - D2**2) / (2 * D1 * D3))
SCALE = max(D1, D2, D3)
# The full roadmap's box of legs.
RHO1_RANGE, LEG_RANGE = (1.0, 50.0), (0.0, 50.0)
# Endpoints this far from the singular locus (as the planner's property tests).
ENDPOINT_MARGIN = 3e-3


def _legs_and_jacobian(x, y, alpha):
    """Leg lengths and their derivatives by (x, y, alpha), rows per leg."""
    c, s = math.cos(alpha), math.sin(alpha)
    c3, s3 = math.cos(alpha + BETA), math.sin(alpha + BETA)
    points = ((x, y, 0.0, 0.0), (x + D1 * c, y + D1 * s, -D1 * s, D1 * c),
              (x + D3 * c3, y + D3 * s3, -D3 * s3, D3 * c3))
    legs, rows = [], []
    for (bx, by, dbx, dby), (ax, ay) in zip(points, BASE):
        ux, uy = bx - ax, by - ay
        rho = math.hypot(ux, uy)
        legs.append(rho)
        rows.append((ux / rho, uy / rho, (ux * dbx + uy * dby) / rho))
    return legs, rows


def _det(rows):
    (a, b, c), (d, e, f), (g, h, i) = rows
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def legs_of(pose):
    """Leg lengths of a pose."""
    return np.array(_legs_and_jacobian(*pose)[0])


def margin_of(pose):
    """det of d(legs)/d(x, y, alpha / SCALE) with unit rows: 0 on a parallel
    singularity, its sign the aspect."""
    _, rows = _legs_and_jacobian(*pose)
    unit = []
    for gx, gy, ga in rows:
        row = (gx, gy, ga / SCALE)
        norm = math.sqrt(sum(v * v for v in row))
        unit.append(tuple(v / norm for v in row))
    return _det(unit)


def _newton(pose, legs):
    """The pose near ``pose`` with these legs, or None."""
    x, y, alpha = pose
    for _ in range(12):
        current, rows = _legs_and_jacobian(x, y, alpha)
        residual = [r - t for r, t in zip(current, legs)]
        if max(abs(v) for v in residual) < 1e-11:
            return (x, y, alpha)
        det = _det(rows)
        if det == 0.0:
            return None
        # Cramer's rule for rows . (dx, dy, dalpha) = residual.
        steps = []
        for k in range(3):
            swapped = [tuple(residual[i] if j == k else rows[i][j] for j in range(3))
                       for i in range(3)]
            steps.append(_det(swapped) / det)
        x, y, alpha = x - steps[0], y - steps[1], alpha - steps[2]
    return None


def follow(joints, start_pose, min_margin):
    """Follow the pose along a piecewise straight joint path.

    Returns
    -------
    dict
        ``ok`` and, when not, ``why``; ``smallest`` margin magnitude met and
        the ``pose`` reached.
    """
    pose = tuple(float(v) for v in start_pose)
    sign = math.copysign(1.0, margin_of(pose))
    smallest = abs(margin_of(pose))
    for a, b in zip(joints[:-1], joints[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        span = float(np.max(np.abs(b - a)))
        done, h = 0.0, min(1.0, 0.02 / span) if span > 0 else 1.0
        while done < 1.0:
            h = min(h, 1.0 - done)
            margin = abs(margin_of(pose))
            new = _newton(pose, a + (b - a) * (done + h))
            if new is not None:
                moved = math.sqrt((new[0] - pose[0]) ** 2 + (new[1] - pose[1]) ** 2
                                  + ((new[2] - pose[2]) * SCALE) ** 2)
                if moved > 0.05 * margin * SCALE:
                    new = None
            if new is None:
                h /= 2
                if h * span < 1e-11:
                    return {"ok": False, "why": "the pose cannot follow the legs",
                            "smallest": smallest, "pose": pose}
                continue
            m = margin_of(new)
            if math.copysign(1.0, m) != sign:
                return {"ok": False, "why": "det(Jx) changes sign", "smallest": 0.0,
                        "pose": new}
            smallest = min(smallest, abs(m))
            if smallest < min_margin:
                return {"ok": False, "why": f"margin {smallest:.3g} < {min_margin:g}",
                        "smallest": smallest, "pose": new}
            pose, done, h = new, done + h, min(2 * h, 0.02 / span)
    return {"ok": True, "why": "", "smallest": smallest, "pose": pose}


def assert_executable(plan, goal_pose, min_margin):
    """The plan's joint path, followed independently from its start pose,
    keeps one sign and ``min_margin`` (to rounding) and ends on the goal pose."""
    assert np.allclose(legs_of(plan.poses[0]), plan.joints[0], atol=1e-7)
    followed = follow(plan.joints, plan.poses[0], min_margin * (1 - 1e-3))
    assert followed["ok"], followed["why"]
    end = np.array(followed["pose"])
    assert np.allclose(end[:2], goal_pose[:2], atol=1e-6)
    assert abs(math.remainder(end[2] - goal_pose[2], 2 * math.pi)) < 1e-6


def assert_within_limits(plan, max_velocity, max_acceleration):
    """Between consecutive points no joint moves faster than the limit and no
    point velocity changes faster than the acceleration limit."""
    dt = np.diff(plan.times)
    assert np.all(dt > 0)
    tolerance = 1 + 1e-9
    speed = np.abs(np.diff(plan.joints, axis=0)) / dt[:, None]
    assert speed.max() <= max_velocity * tolerance
    assert np.abs(plan.velocities).max() <= max_velocity * tolerance
    change = np.abs(np.diff(plan.velocities, axis=0)) / dt[:, None]
    assert change.max() <= max_acceleration * tolerance
    assert np.abs(plan.accelerations).max() <= max_acceleration * tolerance


def random_full_configurations(rng, count):
    """Poses drawn uniformly, kept when the legs lie in the full roadmap's box
    and the margin is at least ``ENDPOINT_MARGIN``.

    Returns
    -------
    list of (tuple, ndarray)
        ``((rho1, rho2, rho3, alpha), pose)``.
    """
    found = []
    while len(found) < count:
        pose = (rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-math.pi, math.pi))
        legs = legs_of(pose)
        if (RHO1_RANGE[0] <= legs[0] <= RHO1_RANGE[1]
                and all(LEG_RANGE[0] <= v <= LEG_RANGE[1] for v in legs[1:])
                and abs(margin_of(pose)) >= ENDPOINT_MARGIN):
            found.append(((*legs, pose[2]), np.array(pose)))
    return found


def random_slice_configurations(rng, rho1, count):
    """Points drawn uniformly on the (theta1, alpha) torus at fixed ``rho1``
    (B1 on leg 1's circle), kept as :func:`random_full_configurations` keeps
    its poses."""
    found = []
    while len(found) < count:
        theta1, alpha = rng.uniform(-math.pi, math.pi, 2)
        pose = (BASE[0][0] + rho1 * math.cos(theta1), BASE[0][1] + rho1 * math.sin(theta1), alpha)
        legs = legs_of(pose)
        if all(LEG_RANGE[0] <= v <= LEG_RANGE[1] for v in legs[1:]) \
                and abs(margin_of(pose)) >= ENDPOINT_MARGIN:
            found.append(((*legs, alpha), np.array(pose)))
    return found


def slice_lattice(rho1, n):
    """The configuration space at fixed ``rho1`` on an n x n lattice of the
    (theta1, alpha) torus (B1 on leg 1's circle): each point's legs, shape
    (n, n, 3), pose (n, n, 3) and signed margin (n, n), computed at once as
    :func:`legs_of` and :func:`margin_of` compute one."""
    angles = 2 * math.pi * (np.arange(n) + 0.5) / n - math.pi
    theta1, alpha = np.meshgrid(angles, angles, indexing="ij")
    x, y = BASE[0][0] + rho1 * np.cos(theta1), BASE[0][1] + rho1 * np.sin(theta1)
    points = [(x, y, 0.0 * x, 0.0 * x),
              (x + D1 * np.cos(alpha), y + D1 * np.sin(alpha), -D1 * np.sin(alpha),
               D1 * np.cos(alpha)),
              (x + D3 * np.cos(alpha + BETA), y + D3 * np.sin(alpha + BETA),
               -D3 * np.sin(alpha + BETA), D3 * np.cos(alpha + BETA))]
    legs, rows = [], []
    for (bx, by, dbx, dby), (ax, ay) in zip(points, BASE):
        ux, uy = bx - ax, by - ay
        rho = np.hypot(ux, uy)
        legs.append(rho)
        row = np.stack([ux / rho, uy / rho, (ux * dbx + uy * dby) / rho / SCALE], -1)
        rows.append(row / np.linalg.norm(row, axis=-1, keepdims=True))
    margin = np.linalg.det(np.stack(rows, -2))
    return np.stack(legs, -1), np.stack([x, y, alpha], -1), margin


def same_aspect_pairs(configurations):
    """Consecutive configurations of the same sign of det(Jx), paired."""
    positive = [c for c in configurations if margin_of(c[1]) > 0]
    negative = [c for c in configurations if margin_of(c[1]) < 0]
    return [pair for group in (positive, negative) for pair in zip(group[0::2], group[1::2])]
