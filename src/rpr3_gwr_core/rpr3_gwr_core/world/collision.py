"""Collisions and limits of many configurations at once, compiled by numba.

A configuration is *blocked* when an actuated joint leaves its stroke, a
passive angle its range, a body comes closer than ``obstacle_clearance`` to
an obstacle, or two bodies that can touch (:class:`Bodies`' pairs) overlap.
:func:`compile_scene` packs a scene for a mechanism into :class:`SceneArrays`
once; :func:`check_bodies` runs the compiled kernel over a batch and says for
each configuration what blocks it first (a *reason* row ``(kind, a, b)``);
:func:`configuration_collision` explains one configuration in words, and
:func:`path_collisions` checks a path continuously.
"""

from collections import namedtuple
from dataclasses import dataclass
import math

import numba
import numpy as np

from ..exceptions import InvalidInputError
from ..mechanisms.base import finite_vectors
from ..mechanisms.continuation import FOLLOWED as FOLLOWED_PATH, follow_path
from .bodies import mechanism_bodies

__all__ = ["SceneArrays", "Collision", "compile_scene", "check_bodies", "configuration_collision",
           "path_collisions", "FREE", "OBSTACLE", "INTERFERENCE", "STROKE", "PASSIVE"]

# Kinds of reason, the first column of check_bodies' rows.
FREE, OBSTACLE, INTERFERENCE, STROKE, PASSIVE = 0, 1, 2, 3, 4

SceneArrays = namedtuple("SceneArrays", ["vertices", "offsets", "discs", "boxes", "circles",
                                         "clearance",
                                         "stroke_low", "stroke_high", "passive_low",
                                         "passive_span"])
SceneArrays.__doc__ = """A scene packed for one mechanism, what the kernel reads.

Attributes
----------
vertices : ndarray, shape (n_vertices, 2)
    The polygons' vertices, one polygon after the other [length unit].
offsets : ndarray of int64, shape (n_polygons + 1,)
    Polygon ``k`` owns ``vertices[offsets[k]:offsets[k + 1]]``.
discs : ndarray, shape (n_discs, 3)
    Centre and radius [length unit].
boxes : ndarray, shape (n_polygons + n_discs, 4)
    Each obstacle's ``(xmin, ymin, xmax, ymax)`` grown by the clearance.
circles : ndarray, shape (n_polygons + n_discs, 3)
    A circle around each obstacle grown by the clearance, centre and radius:
    a link farther from its centre than its radius misses it.
clearance : float
    ``obstacle_clearance`` [length unit].
stroke_low, stroke_high : ndarray, shape (n_joints,)
    Actuated joint ranges, infinite where the scene sets none.
passive_low, passive_span : ndarray, shape (n_passive,)
    Passive ranges as start and counter-clockwise width [rad]; a negative
    width where the scene sets none.
"""

# Default largest body-point move between samples, as a fraction of the
# mechanism's scale, and how many times a path is subdivided at most.
_DENSITY = 1e-2
_REFINEMENTS = 8
# The continuation stops only on a crossing, not on a small margin: the
# validator judges margins.
_FOLLOW_MARGIN = 1e-12

_BodyArrays = namedtuple("_BodyArrays", ["capsules", "capsule_radius", "polygons",
                                         "polygon_radius", "pairs", "passive"])


def compile_scene(scene, mechanism, bodies):
    """Pack a scene for a mechanism's bodies.

    Parameters
    ----------
    scene : Scene
    mechanism : Mechanism
    bodies : Bodies
        Any batch of the mechanism's bodies (their passive names are read).

    Returns
    -------
    SceneArrays

    Raises
    ------
    InvalidInputError
        If a stroke names no joint of the mechanism or a passive range no
        passive angle of its bodies.
    """
    limits = scene.limits
    for names, ranges, what in ((mechanism.joint_names, limits.strokes, "joint"),
                                (bodies.passive_names, limits.passive, "passive angle")):
        unknown = sorted(set(ranges) - set(names))
        if unknown:
            raise InvalidInputError(f"{unknown} name no {what} of the {mechanism.kind}; "
                                    f"known: {list(names)}")
    polygons = [o.vertices for o in scene.polygons]
    vertices = np.concatenate(polygons) if polygons else np.zeros((0, 2))
    offsets = np.concatenate([[0], np.cumsum([len(v) for v in polygons])]).astype(np.int64)
    discs = np.array([[*o.center, o.radius] for o in scene.discs], dtype=float).reshape(-1, 3)
    c = limits.obstacle_clearance
    boxes = np.array([[*(v.min(axis=0) - c), *(v.max(axis=0) + c)] for v in polygons]
                     + [[x - r - c, y - r - c, x + r + c, y + r + c] for x, y, r in discs],
                     dtype=float).reshape(-1, 4)
    centres = (boxes[:, :2] + boxes[:, 2:]) / 2
    reach = [np.linalg.norm(v - m, axis=1).max() + c for v, m in zip(polygons, centres)]
    reach += [r + c for _, _, r in discs]
    circles = np.column_stack([centres, np.array(reach, dtype=float)]).reshape(-1, 3)
    low = np.array([limits.strokes.get(n, (-np.inf, np.inf))[0] for n in mechanism.joint_names])
    high = np.array([limits.strokes.get(n, (-np.inf, np.inf))[1] for n in mechanism.joint_names])
    passive = [limits.passive.get(n) for n in bodies.passive_names]
    return SceneArrays(vertices=vertices, offsets=offsets, discs=discs, boxes=boxes,
                       circles=circles, clearance=float(c), stroke_low=low, stroke_high=high,
                       passive_low=np.array([p[0] if p else 0.0 for p in passive]),
                       passive_span=np.array([p[1] - p[0] if p else -1.0 for p in passive]))


def check_bodies(arrays, bodies, joints, out=None, chosen=None):
    """What first blocks each configuration of a batch.

    Parameters
    ----------
    arrays : SceneArrays
    bodies : Bodies
        Batch shape ``(n,)``.
    joints : ndarray, shape (n, n_joints)
    out : ndarray of int32, shape (m, 3), optional
        Filled and returned, so that repeated calls allocate nothing.
    chosen : ndarray of int64, shape (m,), optional
        Which configurations to check (default all, ``m = n``).

    Returns
    -------
    ndarray of int32, shape (m, 3)
        ``(kind, a, b)``: :data:`FREE`; :data:`OBSTACLE`, body ``a`` and
        obstacle ``b`` (polygons first, then discs); :data:`INTERFERENCE`,
        bodies ``a`` and ``b``; :data:`STROKE`, joint ``a``; :data:`PASSIVE`,
        passive angle ``a``.
    """
    n = joints.shape[0]
    chosen = np.arange(n) if chosen is None else chosen
    out = np.empty((chosen.size, 3), dtype=np.int32) if out is None else out[:chosen.size]
    packed = _BodyArrays(
        np.ascontiguousarray(bodies.capsules.reshape(n, -1, 2, 2)), bodies.capsule_radius,
        np.ascontiguousarray(bodies.polygons.reshape(n, -1, bodies.polygons.shape[-2], 2)),
        bodies.polygon_radius, bodies.pairs,
        np.ascontiguousarray(bodies.passive.reshape(n, -1)))
    _check(arrays, packed, np.ascontiguousarray(joints, dtype=float),
           np.ascontiguousarray(chosen, dtype=np.int64), out)
    return out


@dataclass(frozen=True)
class Collision:
    """Why a configuration is blocked.

    Attributes
    ----------
    kind : int
        :data:`OBSTACLE`, :data:`INTERFERENCE`, :data:`STROKE` or :data:`PASSIVE`.
    body : str
        The body (or joint, or passive angle) concerned.
    other : str
        The obstacle id, the other body, or the range broken.
    message : str
        One line for an error report.
    index : float
        Where along a path (:func:`path_collisions`): the waypoint index, with
        the fraction of the segment after it; 0 for one configuration.
    """

    kind: int
    body: str
    other: str
    message: str
    index: float = 0.0


def configuration_collision(mechanism, scene, joints, pose, model=None):
    """Why one configuration is blocked, or None when it is free.

    Parameters
    ----------
    mechanism : Mechanism
    scene : Scene
    joints : array_like, shape (n_joints,)
    pose : array_like, shape (pose_size,)
        A direct-kinematic solution of ``joints``.
    model : BodyModel, optional

    Returns
    -------
    Collision or None

    Raises
    ------
    InvalidInputError
        If joints or pose are malformed, or the scene names unknown limits.
    """
    bodies = mechanism_bodies(mechanism, np.asarray(pose, dtype=float)[None],
                              np.asarray(joints, dtype=float)[None], model)
    arrays = compile_scene(scene, mechanism, bodies)
    joints = np.asarray(joints, dtype=float)[None]
    row = check_bodies(arrays, bodies, joints)[0]
    return None if row[0] == FREE else _explain(row, mechanism, scene, bodies, joints[0])


def path_collisions(mechanism, scene, joints_path, start_pose, model=None, min_step=None):
    """The first blocked configuration along a joint path, checked continuously.

    The platform is followed along the path's straight joint segments by the
    mechanism's continuation (:func:`~rpr3_gwr_core.mechanisms.continuation.follow_path`,
    as the validator and the driver follow it), on joint waypoints
    subdivided until no body point moves more than ``obstacle_clearance``
    between two consecutive samples; every sample is checked.

    Parameters
    ----------
    mechanism : Mechanism
    scene : Scene
    joints_path : array_like, shape (m, n_joints)
        Joint waypoints [joint unit].
    start_pose : array_like, shape (pose_size,)
        The pose at the first waypoint.
    model : BodyModel, optional
    min_step : float, optional
        Largest body-point move between samples when the scene's clearance
        is smaller [length unit]; default a hundredth of the mechanism's
        scale.

    Returns
    -------
    Collision or None
        The first violation, its ``index`` where along the path (waypoint
        index plus the fraction of the segment after it).  Only the stretch
        the platform can follow is checked: the validator reports the rest.

    Raises
    ------
    InvalidInputError
        If the path or the pose are malformed.
    """
    path = finite_vectors(joints_path, "joints_path", mechanism.n_joints).reshape(
        -1, mechanism.n_joints)
    pose = finite_vectors(start_pose, "start_pose", mechanism.pose_size).reshape(-1)
    if path.shape[0] < 1:
        raise InvalidInputError("joints_path needs at least one waypoint")
    step = max(scene.limits.obstacle_clearance,
               _DENSITY * mechanism.scale if min_step is None else float(min_step))
    position = np.arange(path.shape[0], dtype=float)
    for _ in range(_REFINEMENTS):
        poses, reached = _followed(mechanism, path, pose)
        bodies = mechanism_bodies(mechanism, poses[:reached], path[:reached], model)
        points = np.concatenate([bodies.capsules.reshape(reached, -1, 2),
                                 bodies.polygons.reshape(reached, -1, 2)], axis=1)
        moves = np.linalg.norm(np.diff(points, axis=0), axis=-1).max(axis=1, initial=0.0)
        counts = np.maximum(1, np.ceil(moves / step)).astype(np.int64)
        if np.all(counts == 1):
            break
        # Each too long segment cut into equal joint steps, and followed again.
        fraction = np.concatenate([np.arange(k) / k for k in counts] + [[0.0]])
        segment = np.append(np.repeat(np.arange(counts.size), counts), reached - 1)
        after = np.minimum(segment + 1, reached - 1)
        path = path[segment] + fraction[:, None] * (path[after] - path[segment])
        position = position[segment] + fraction * (position[after] - position[segment])
    arrays = compile_scene(scene, mechanism, bodies)
    rows = check_bodies(arrays, bodies, path[:reached])
    blocked = np.flatnonzero(rows[:, 0] != FREE)
    if blocked.size == 0:
        return None
    k = int(blocked[0])
    one = mechanism_bodies(mechanism, poses[k:k + 1], path[k:k + 1], model)
    found = _explain(rows[k], mechanism, scene, one, path[k])
    return Collision(found.kind, found.body, found.other,
                     f"at waypoint {position[k]:.3f}: {found.message}", float(position[k]))


def _followed(mechanism, path, pose):
    """Poses at each waypoint the platform reaches, and how many it reaches."""
    poses = np.empty((path.shape[0], pose.size))
    status, stopped, _, _ = follow_path(mechanism, np.ascontiguousarray(path), pose.copy(),
                                        _FOLLOW_MARGIN, np.inf, poses)
    return poses, path.shape[0] if status == FOLLOWED_PATH else max(1, stopped)


def _explain(row, mechanism, scene, bodies, joints):
    kind, a, b = (int(v) for v in row)
    if kind == OBSTACLE:
        name, oid = bodies.names[a], scene.obstacle_ids[b]
        return Collision(kind, name, oid, f"{name} is within obstacle_clearance "
                         f"{scene.limits.obstacle_clearance:g} of obstacle {oid!r}")
    if kind == INTERFERENCE:
        first, second = bodies.names[a], bodies.names[b]
        return Collision(kind, first, second, f"{first} and {second} overlap (one layer)")
    if kind == STROKE:
        name = mechanism.joint_names[a]
        low, high = scene.limits.strokes[name]
        return Collision(kind, name, f"[{low:g}, {high:g}]",
                         f"{name} = {joints[a]:.6g} is outside its stroke [{low:g}, {high:g}]")
    name = bodies.passive_names[a]
    low, high = scene.limits.passive[name]
    value = float(bodies.passive.reshape(-1, len(bodies.passive_names))[0, a])
    return Collision(kind, name, f"[{low:g}, {high:g}]",
                     f"passive joint {name} = {value:.4f} rad is outside [{low:g}, {high:g}]")


# The compiled geometry.  Distances are Euclidean in the base plane.

@numba.njit(cache=True, nogil=True, inline="always")
def _point_segment2(px, py, ax, ay, bx, by):
    """Squared distance from a point to a segment."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0
    if length2 > 0.0:
        t = min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / length2))
    ex, ey = ax + t * dx - px, ay + t * dy - py
    return ex * ex + ey * ey


@numba.njit(cache=True, nogil=True, inline="always")
def _orient(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@numba.njit(cache=True, nogil=True, inline="always")
def _segment_segment2(ax, ay, bx, by, cx, cy, dx, dy):
    """Squared distance between two segments, 0 when they cross."""
    d1 = _orient(ax, ay, bx, by, cx, cy)
    d2 = _orient(ax, ay, bx, by, dx, dy)
    d3 = _orient(cx, cy, dx, dy, ax, ay)
    d4 = _orient(cx, cy, dx, dy, bx, by)
    if ((d1 > 0 > d2) or (d1 < 0 < d2)) and ((d3 > 0 > d4) or (d3 < 0 < d4)):
        return 0.0
    return min(_point_segment2(ax, ay, cx, cy, dx, dy), _point_segment2(bx, by, cx, cy, dx, dy),
               _point_segment2(cx, cy, ax, ay, bx, by), _point_segment2(dx, dy, ax, ay, bx, by))


@numba.njit(cache=True, nogil=True, inline="always")
def _inside(px, py, ring, start, stop):
    """Whether a point lies inside the polygon ``ring[start:stop]`` (even-odd)."""
    inside = False
    j = stop - 1
    for i in range(start, stop):
        xi, yi, xj, yj = ring[i, 0], ring[i, 1], ring[j, 0], ring[j, 1]
        if (yi > py) != (yj > py) and px < xi + (py - yi) * (xj - xi) / (yj - yi):
            inside = not inside
        j = i
    return inside


@numba.njit(cache=True, nogil=True, inline="always")
def _segment_polygon_near(ax, ay, bx, by, ring, start, stop, reach):
    """Whether a segment comes within ``reach`` of a polygon (inside counts)."""
    if _inside(ax, ay, ring, start, stop) or _inside(bx, by, ring, start, stop):
        return True
    reach2 = reach * reach
    j = stop - 1
    for i in range(start, stop):
        if _segment_segment2(ax, ay, bx, by, ring[j, 0], ring[j, 1], ring[i, 0],
                             ring[i, 1]) <= reach2:
            return True
        j = i
    return False


@numba.njit(cache=True, nogil=True, inline="always")
def _polygon_polygon_near(ring, start, stop, other, first, last, reach):
    """Whether two polygons come within ``reach`` of each other (inside counts)."""
    # Either may hold the other whole: no edge then comes near.
    if _inside(other[first, 0], other[first, 1], ring, start, stop) or _inside(
            ring[start, 0], ring[start, 1], other, first, last):
        return True
    j = last - 1
    for i in range(first, last):
        if _segment_polygon_near(other[j, 0], other[j, 1], other[i, 0], other[i, 1], ring, start,
                                 stop, reach):
            return True
        j = i
    return False


@numba.njit(cache=True, nogil=True, inline="always")
def _point_polygon_near(px, py, ring, start, stop, reach):
    if _inside(px, py, ring, start, stop):
        return True
    reach2 = reach * reach
    j = stop - 1
    for i in range(start, stop):
        if _point_segment2(px, py, ring[j, 0], ring[j, 1], ring[i, 0], ring[i, 1]) <= reach2:
            return True
        j = i
    return False


@numba.njit(cache=True, nogil=True, inline="always")
def _body_box(body, n_capsules, capsules, radius, polygons, polygon_radius, c, box):
    """``box`` set to a body's bounding box."""
    if body < n_capsules:
        r = radius[body]
        box[0] = min(capsules[c, body, 0, 0], capsules[c, body, 1, 0]) - r
        box[1] = min(capsules[c, body, 0, 1], capsules[c, body, 1, 1]) - r
        box[2] = max(capsules[c, body, 0, 0], capsules[c, body, 1, 0]) + r
        box[3] = max(capsules[c, body, 0, 1], capsules[c, body, 1, 1]) + r
        return
    k = body - n_capsules
    r = polygon_radius[k]
    box[0], box[1], box[2], box[3] = np.inf, np.inf, -np.inf, -np.inf
    for v in range(polygons.shape[2]):
        box[0] = min(box[0], polygons[c, k, v, 0] - r)
        box[1] = min(box[1], polygons[c, k, v, 1] - r)
        box[2] = max(box[2], polygons[c, k, v, 0] + r)
        box[3] = max(box[3], polygons[c, k, v, 1] + r)


@numba.njit(cache=True, nogil=True, inline="always")
def _body_hits_obstacle(world, bodies, c, body, obstacle):
    """Whether body ``body`` of configuration ``c`` comes within the
    clearance of obstacle ``obstacle``."""
    n_capsules = bodies.capsules.shape[1]
    n_polygons = world.offsets.size - 1
    if body < n_capsules:
        ax, ay = bodies.capsules[c, body, 0, 0], bodies.capsules[c, body, 0, 1]
        bx, by = bodies.capsules[c, body, 1, 0], bodies.capsules[c, body, 1, 1]
        reach = bodies.capsule_radius[body] + world.clearance
        if obstacle < n_polygons:
            return _segment_polygon_near(ax, ay, bx, by, world.vertices,
                                         world.offsets[obstacle], world.offsets[obstacle + 1],
                                         reach)
        d = obstacle - n_polygons
        reach += world.discs[d, 2]
        return _point_segment2(world.discs[d, 0], world.discs[d, 1], ax, ay, bx,
                               by) <= reach * reach
    k = body - n_capsules
    plate = bodies.polygons[c, k]
    reach = bodies.polygon_radius[k] + world.clearance
    if obstacle < n_polygons:
        return _polygon_polygon_near(world.vertices, world.offsets[obstacle],
                                     world.offsets[obstacle + 1], plate, 0, plate.shape[0], reach)
    d = obstacle - n_polygons
    return _point_polygon_near(world.discs[d, 0], world.discs[d, 1], plate, 0, plate.shape[0],
                               reach + world.discs[d, 2])


@numba.njit(cache=True, nogil=True, inline="always")
def _bodies_touch(bodies, c, i, j):
    """Whether bodies ``i < j`` of configuration ``c`` overlap."""
    n_capsules = bodies.capsules.shape[1]
    caps = bodies.capsules
    if j < n_capsules:
        reach = bodies.capsule_radius[i] + bodies.capsule_radius[j]
        return _segment_segment2(caps[c, i, 0, 0], caps[c, i, 0, 1], caps[c, i, 1, 0],
                                 caps[c, i, 1, 1], caps[c, j, 0, 0], caps[c, j, 0, 1],
                                 caps[c, j, 1, 0], caps[c, j, 1, 1]) <= reach * reach
    plate = bodies.polygons[c, j - n_capsules]
    reach = bodies.polygon_radius[j - n_capsules]
    if i < n_capsules:
        return _segment_polygon_near(caps[c, i, 0, 0], caps[c, i, 0, 1], caps[c, i, 1, 0],
                                     caps[c, i, 1, 1], plate, 0, plate.shape[0],
                                     reach + bodies.capsule_radius[i])
    other = bodies.polygons[c, i - n_capsules]
    return _polygon_polygon_near(plate, 0, plate.shape[0], other, 0, other.shape[0],
                                 reach + bodies.polygon_radius[i - n_capsules])


@numba.njit(cache=True, nogil=True)
def _check(world, bodies, joints, chosen, out):
    """:func:`check_bodies`' loop: row ``row`` of ``out`` for configuration
    ``chosen[row]``; strokes, then passive ranges, obstacles, interference."""
    n_capsules = bodies.capsules.shape[1]
    n_bodies = n_capsules + bodies.polygons.shape[1]
    n_obstacles = world.boxes.shape[0]
    box = np.empty(4)
    for row in range(chosen.size):
        c = chosen[row]
        out[row, 0], out[row, 1], out[row, 2] = FREE, 0, 0
        found = False
        for q in range(joints.shape[1]):
            if not (world.stroke_low[q] <= joints[c, q] <= world.stroke_high[q]):
                out[row, 0], out[row, 1] = STROKE, q
                found = True
                break
        if found:
            continue
        for p in range(world.passive_span.size):
            span = world.passive_span[p]
            if span >= 0.0:
                offset = (bodies.passive[c, p] - world.passive_low[p]) % (2.0 * math.pi)
                if offset > span:
                    out[row, 0], out[row, 1] = PASSIVE, p
                    found = True
                    break
        if found:
            continue
        for body in range(n_bodies):
            _body_box(body, n_capsules, bodies.capsules, bodies.capsule_radius, bodies.polygons,
                      bodies.polygon_radius, c, box)
            for o in range(n_obstacles):
                if (box[0] > world.boxes[o, 2] or box[2] < world.boxes[o, 0]
                        or box[1] > world.boxes[o, 3] or box[3] < world.boxes[o, 1]):
                    continue
                if body < n_capsules:
                    reach = world.circles[o, 2] + bodies.capsule_radius[body]
                    if _point_segment2(world.circles[o, 0], world.circles[o, 1],
                                       bodies.capsules[c, body, 0, 0],
                                       bodies.capsules[c, body, 0, 1],
                                       bodies.capsules[c, body, 1, 0],
                                       bodies.capsules[c, body, 1, 1]) > reach * reach:
                        continue
                if _body_hits_obstacle(world, bodies, c, body, o):
                    out[row, 0], out[row, 1], out[row, 2] = OBSTACLE, body, o
                    found = True
                    break
            if found:
                break
        if found:
            continue
        for k in range(bodies.pairs.shape[0]):
            i, j = bodies.pairs[k, 0], bodies.pairs[k, 1]
            if _bodies_touch(bodies, c, i, j):
                out[row, 0], out[row, 1], out[row, 2] = INTERFERENCE, i, j
                break
