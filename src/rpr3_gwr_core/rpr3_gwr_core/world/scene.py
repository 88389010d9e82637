"""A scene: static obstacles in the base plane and the mechanism's limits.

Obstacles are simple polygons and discs, each with an id.  Limits are the
actuated joints' ranges (a 3-RPR's leg strokes, replacing the grid's box as
the physical limit), the passive joints' ranges (by the names of
:meth:`Mechanism.body_outline`'s passive angles, e.g. ``base1`` and
``platform1``) and the least distance every body keeps from every obstacle,
``obstacle_clearance``.

A scene document (YAML or JSON, read by
:func:`~rpr3_gwr_core.io.scene_file.load_scene`)::

    obstacles:
      - {id: post, disc: {center: [6.0, 30.0], radius: 1.5}}
      - {id: fixture, polygon: [[20, 30], [26, 30], [26, 34], [20, 34]]}
    limits:
      obstacle_clearance: 0.25            # [length unit]
      strokes: {rho2: [2.0, 45.0]}        # [joint unit], by joint name
      passive: {base1: [0.0, 3.2]}        # [rad], min to max counter-clockwise

``passive_deg`` gives the passive ranges in degrees instead; a bound of
``passive`` beyond a full turn is refused as likely in degrees.

What a scene may hold is bounded, so that a planner and a driver prepare
any scene they are sent in tenths of a second: at most :data:`MAX_OBSTACLES`
obstacles, :data:`MAX_VERTICES` polygon vertices in all, numbers of at most
:data:`MAX_MAGNITUDE`; a scene file is at most
:data:`~rpr3_gwr_core.documents.MAX_DOCUMENT_BYTES` long.
"""

from dataclasses import dataclass, field
import math
import numbers
import reprlib

import numba
import numpy as np

from ..exceptions import InvalidInputError

__all__ = ["PolygonObstacle", "DiscObstacle", "Limits", "Scene", "scene_from_dict",
           "EMPTY_SCENE", "MAX_OBSTACLES", "MAX_VERTICES", "MAX_MAGNITUDE"]

# A planner prepares a scene in time proportional to its obstacles and,
# for the configurations near a polygon, to the polygon's vertices: on the
# paper's slice a polygon of 256 vertices placed where it costs most took
# 0.45 s to 0.9 s (2 cores, busy), 256 discs 0.05 s.
MAX_OBSTACLES = 256
"""Most obstacles (polygons and discs together) of a scene."""

MAX_VERTICES = 256
"""Most vertices of a scene's polygons, all together."""

MAX_MAGNITUDE = 1e6
"""Largest magnitude of a scene's numbers: coordinates, radii and the
clearance [length unit], joint ranges [joint unit, rad or deg].  A scene's
messages carry coordinates as 32-bit floats, and the squares the checks
take stay far from overflowing."""


@dataclass(frozen=True, eq=False)
class PolygonObstacle:
    """A simple polygon.

    Attributes
    ----------
    id : str
    vertices : ndarray, shape (k, 2)
        In order around it, either way, ``k >= 3`` [length unit].
    """

    id: str
    vertices: np.ndarray

    def __repr__(self):
        return f"PolygonObstacle({self.id!r}, {len(self.vertices)} vertices)"


@dataclass(frozen=True, eq=False)
class DiscObstacle:
    """A disc.

    Attributes
    ----------
    id : str
    center : ndarray, shape (2,)
        [length unit].
    radius : float
        Positive [length unit].
    """

    id: str
    center: np.ndarray
    radius: float

    def __repr__(self):
        x, y = self.center
        return f"DiscObstacle({self.id!r}, center ({x:g}, {y:g}), radius {self.radius:g})"


@dataclass(frozen=True)
class Limits:
    """Joint ranges and the clearance from obstacles.

    Attributes
    ----------
    strokes : dict of str to (float, float)
        Actuated joint name to its ``(min, max)`` [joint unit].
    passive : dict of str to (float, float)
        Passive angle name to ``(min, max)`` [rad]: the arc from ``min``
        counter-clockwise to ``max``, at most a full turn.
    obstacle_clearance : float
        Least distance between any body and any obstacle [length unit].
    """

    strokes: dict = field(default_factory=dict)
    passive: dict = field(default_factory=dict)
    obstacle_clearance: float = 0.0


@dataclass(frozen=True, eq=False)
class Scene:
    """Obstacles and limits.

    Attributes
    ----------
    polygons : tuple of PolygonObstacle
    discs : tuple of DiscObstacle
    limits : Limits
    """

    polygons: tuple = ()
    discs: tuple = ()
    limits: Limits = Limits()

    def __repr__(self):
        limits = self.limits
        parts = [_count(len(self.polygons), "polygon"), _count(len(self.discs), "disc")]
        if limits.strokes:
            parts.append("strokes of " + ", ".join(limits.strokes))
        if limits.passive:
            parts.append("ranges of " + ", ".join(limits.passive))
        if limits.obstacle_clearance:
            parts.append(f"obstacle clearance {limits.obstacle_clearance:g}")
        return f"Scene({', '.join(parts)})"

    @property
    def obstacle_ids(self):
        """Ids of the polygons, then of the discs."""
        return tuple(o.id for o in self.polygons) + tuple(o.id for o in self.discs)

    def to_dict(self):
        """Plain data that :func:`scene_from_dict` reads back."""
        obstacles = [{"id": o.id, "polygon": o.vertices.tolist()} for o in self.polygons]
        obstacles += [{"id": o.id, "disc": {"center": o.center.tolist(), "radius": o.radius}}
                      for o in self.discs]
        return {"obstacles": obstacles, "limits": {
            "obstacle_clearance": self.limits.obstacle_clearance,
            "strokes": {k: list(v) for k, v in self.limits.strokes.items()},
            "passive": {k: list(v) for k, v in self.limits.passive.items()}}}


EMPTY_SCENE = Scene()


def _count(n, noun):
    return f"{n} {noun}{'' if n == 1 else 's'}"


def scene_from_dict(data):
    """A :class:`Scene` from plain data (module doc).

    Parameters
    ----------
    data : mapping
        ``obstacles`` (list, optional) and ``limits`` (mapping, optional).

    Returns
    -------
    Scene

    Raises
    ------
    InvalidInputError
        With the offending entry named: an unknown key, an empty or
        duplicate id, a polygon with fewer than 3 vertices, no area or
        crossing edges, a disc without a positive radius, a range with
        ``min > max`` (or a passive one over a full turn), a negative
        clearance, a value that is not a finite number or is larger than
        :data:`MAX_MAGNITUDE`, more than :data:`MAX_OBSTACLES` obstacles or
        :data:`MAX_VERTICES` vertices.
    """
    _keys(data, "scene", {"obstacles", "limits"})
    polygons, discs, seen = [], [], set()
    obstacles = data.get("obstacles")
    obstacles = [] if obstacles is None else obstacles
    if not isinstance(obstacles, list):
        raise InvalidInputError(f"obstacles must be a list, got {_shown(obstacles)}")
    if len(obstacles) > MAX_OBSTACLES:
        raise InvalidInputError(f"the scene has {len(obstacles):,} obstacles, more than the "
                                f"limit of {MAX_OBSTACLES:,}")
    vertices = 0
    for k, entry in enumerate(obstacles):
        where = f"obstacle {k}"
        _keys(entry, where, {"id", "polygon", "disc"})
        oid = _id(entry.get("id"), where)
        if oid in seen:
            raise InvalidInputError(f"obstacle id {oid!r} is used twice")
        seen.add(oid)
        where = f"obstacle {oid!r}"
        if ("polygon" in entry) == ("disc" in entry):
            raise InvalidInputError(f"{where} must be exactly one of polygon or disc")
        if "polygon" in entry:
            # Counted before the vertices are read, which takes their time.
            if isinstance(entry["polygon"], list):
                vertices += len(entry["polygon"])
            if vertices > MAX_VERTICES:
                raise InvalidInputError(f"the scene's polygons have {vertices:,} vertices by "
                                        f"{where}, more than the limit of {MAX_VERTICES:,}")
            polygons.append(PolygonObstacle(oid, _polygon(entry["polygon"], where)))
        else:
            disc = entry["disc"]
            _keys(disc, f"{where}'s disc", {"center", "radius"})
            center = _numbers(disc.get("center"), f"{where}'s center")
            if center.shape != (2,):
                raise InvalidInputError(f"{where}'s center must be two numbers")
            radius = _number(disc.get("radius"), f"{where}'s radius")
            if radius <= 0:
                raise InvalidInputError(f"{where}'s radius must be positive, got {radius}")
            discs.append(DiscObstacle(oid, center, radius))
    limits = data.get("limits")
    limits = {} if limits is None else limits
    _keys(limits, "limits", {"strokes", "passive", "passive_deg", "obstacle_clearance"})
    clearance = _number(limits.get("obstacle_clearance", 0.0), "obstacle_clearance")
    if clearance < 0:
        raise InvalidInputError(f"obstacle_clearance must be non-negative, got {clearance}")
    strokes = _ranges(limits.get("strokes"), "strokes")
    passive = _passive_ranges(limits)
    return Scene(polygons=tuple(polygons), discs=tuple(discs),
                 limits=Limits(strokes=strokes, passive=passive, obstacle_clearance=clearance))


def _shown(value):
    """A value in a message: short, whatever its size or depth."""
    return reprlib.repr(value)


def _keys(data, where, known):
    if not isinstance(data, dict):
        raise InvalidInputError(f"{where} must be a mapping, got {_shown(data)}")
    unknown = sorted(set(map(str, data)) - known)
    if unknown:
        raise InvalidInputError(f"{where} has unknown keys {_shown(unknown)}; known: "
                                f"{sorted(known)}")


def _id(value, where):
    """An obstacle's id as a string: a non-empty string or an integer."""
    if isinstance(value, bool) or not isinstance(value, (str, int)):
        raise InvalidInputError(f"{where} needs an id (a string or an integer)")
    try:
        text = str(value)
    except ValueError:  # an integer of more digits than Python converts
        raise InvalidInputError(f"{where}'s id is an integer of too many digits") from None
    if not text:
        raise InvalidInputError(f"{where} has an empty id: an id names its obstacle in "
                                "messages and must not be empty")
    return text


def _number(value, where):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or value != value \
            or value in (math.inf, -math.inf):
        raise InvalidInputError(f"{where} must be a finite number, got {_shown(value)}")
    # Compared before any conversion: an integer of hundreds of digits has
    # no float.
    if not -MAX_MAGNITUDE <= value <= MAX_MAGNITUDE:
        raise InvalidInputError(f"{where} is out of range: {_shown(value)} is larger than "
                                f"{MAX_MAGNITUDE:g} in magnitude")
    return float(value)


def _numbers(value, where):
    """A list of numbers as an array (any other value refused)."""
    if not isinstance(value, (list, tuple)) or not all(
            isinstance(v, numbers.Real) and not isinstance(v, bool) for v in value):
        raise InvalidInputError(f"{where} must be a list of numbers, got {_shown(value)}")
    return np.array([_number(v, where) for v in value], dtype=float)


def _polygon(value, where):
    # Each vertex's length before its numbers: a vertex may be a long list.
    if not isinstance(value, (list, tuple)) or len(value) < 3 or not all(
            isinstance(v, (list, tuple)) and len(v) == 2 for v in value):
        raise InvalidInputError(f"{where}'s polygon must be at least 3 points [x, y]")
    vertices = np.array([_numbers(v, f"{where}'s polygon") for v in value])
    x, y = vertices.T
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    if area <= 1e-12 * max(1.0, float(np.ptp(vertices)) ** 2):
        raise InvalidInputError(f"{where}'s polygon has no area")
    crossing = _crossing(vertices)
    if crossing is not None:
        raise InvalidInputError(f"{where}'s polygon has crossing edges {crossing[0]} and "
                                f"{crossing[1]}")
    return vertices


def _crossing(vertices):
    """Two edges ``(i, j)``, ``i < j``, of a polygon that cross, or None.

    Edge ``i`` joins vertex ``i`` to vertex ``i + 1`` (the last one to the
    first).  Two edges that are not neighbours cross when each one's ends
    are not strictly on one side of the other's line (:func:`_cross`): they
    touch or cross, or they lie on one line, even apart.  The polygon's
    special cases first (a repeated vertex, an edge of no length, a spike
    back along its edge, two edges on one line, found by sorting), then
    the Shamos-Hoey sweep finds a pair of the others that meet
    (:func:`_swept_crossing`): O(n log n) tests, 2 ms for a regular
    polygon of 10,000 vertices, 40 ms for 10,000 long edges that one line
    cuts (the sweep's array then moves its entries).  Exact for
    coordinates whose orientations are computed without rounding (small
    multiples of a power of two); otherwise an orientation rounded to zero
    may differ from the exact test and a pair that only rounding makes
    cross may be missed.
    """
    x = np.ascontiguousarray(vertices[:, 0])
    y = np.ascontiguousarray(vertices[:, 1])
    # Each edge's line a X + b Y = c, scaled so that the normal (a, b) has
    # its largest component 1 and points up or right: edges on one line get
    # equal keys (a quotient of exact numbers is rounded once, so
    # proportional ones round alike).  Edges of no length have none.
    a, b = np.roll(y, -1) - y, x - np.roll(x, -1)
    keyed = np.flatnonzero((a != 0) | (b != 0))
    a, b = a[keyed], b[keyed]
    scale = np.maximum(np.abs(a), np.abs(b))
    scale[(a < 0) | ((a == 0) & (b < 0))] *= -1
    keys = np.stack([a / scale, b / scale, (a * x[keyed] + b * y[keyed]) / scale])
    by_line = np.lexsort((keyed, *keys[::-1]))
    edges, keys = keyed[by_line], keys[:, by_line]
    # Of three edges on one line two are not neighbours: the edges of a
    # line's run next to each other and one apart cover them.
    collinear = np.concatenate([
        np.stack([edges[:-k], edges[k:]], axis=1)[(keys[:, :-k] == keys[:, k:]).all(axis=0)]
        for k in (1, 2)]).reshape(-1, 2)
    i, j = _first_crossing(x, y, np.lexsort((y, x)), collinear)
    return None if i < 0 else (min(i, j), max(i, j))


@numba.njit(cache=True, nogil=True)
def _side(x, y, a, b, c):
    """Sign of the orientation of vertices ``a``, ``b``, ``c``: 1 when ``c``
    is left of the line from ``a`` to ``b``, -1 right, 0 on it."""
    value = (x[b] - x[a]) * (y[c] - y[a]) - (y[b] - y[a]) * (x[c] - x[a])
    return (value > 0) - (value < 0)


@numba.njit(cache=True, nogil=True)
def _cross(x, y, i, j):
    """Whether edges ``i`` and ``j`` cross: each one's ends not strictly on
    one side of the other's line."""
    n = x.size
    i1, j1 = (i + 1) % n, (j + 1) % n
    return (_side(x, y, i, i1, j) * _side(x, y, i, i1, j1) <= 0
            and _side(x, y, j, j1, i) * _side(x, y, j, j1, i1) <= 0)


@numba.njit(cache=True, nogil=True)
def _neighbours(i, j, n):
    """Whether edges ``i`` and ``j`` of an ``n``-gon share a vertex."""
    gap = abs(i - j)
    return gap <= 1 or gap == n - 1


@numba.njit(cache=True, nogil=True)
def _first_crossing(x, y, order, collinear):
    """Two edges of the polygon ``(x, y)`` that cross and are not neighbours,
    ``(-1, -1)`` if none (:func:`_crossing`).

    ``order`` sorts the vertices by x then y; ``collinear`` lists pairs of
    edges on one line.
    """
    n = x.size
    if n < 4:
        return -1, -1  # every two edges of a triangle are neighbours
    # A vertex twice: its edges touch.
    for k in range(n - 1):
        a, b = order[k], order[k + 1]
        if x[a] == x[b] and y[a] == y[b] and not _neighbours(a, b, n):
            return a, b
    for v in range(n):
        before, after = (v - 1) % n, (v + 1) % n
        # An edge of no length: the edges either side meet at its vertex.
        if x[v] == x[after] and y[v] == y[after]:
            return before, after
        # A spike: the edges either side of v on one line, the second going
        # back along the first, whose far end touches the edge before or
        # after them.
        dot = ((x[before] - x[v]) * (x[after] - x[v])
               + (y[before] - y[v]) * (y[after] - y[v]))
        if _side(x, y, before, v, after) == 0 and dot > 0:
            back = (x[after] - x[v]) ** 2 + (y[after] - y[v]) ** 2
            ahead = (x[before] - x[v]) ** 2 + (y[before] - y[v]) ** 2
            i, j = (before, after) if back < ahead else ((v - 2) % n, v)
            if not _neighbours(i, j, n) and _cross(x, y, i, j):
                return i, j
    for k in range(collinear.shape[0]):
        i, j = collinear[k, 0], collinear[k, 1]
        if not _neighbours(i, j, n) and _cross(x, y, i, j):
            return i, j
    return _swept_crossing(x, y, order)


@numba.njit(cache=True, nogil=True)
def _swept_crossing(x, y, order):
    """Two edges that meet and are not neighbours, by the Shamos-Hoey sweep
    over the vertices in ``order``, ``(-1, -1)`` if none.

    The edges the sweep line cuts are kept in ``status``, from bottom to
    top; each pair that becomes adjacent there is tested, and the leftmost
    meeting point of two edges is always preceded by such a test of two
    edges that meet there.  The vertices must be distinct, no edge of no
    length, no two edges on one line but neighbours that do not overlap
    (:func:`_first_crossing` has found those cases before).
    """
    n = x.size
    rank = np.empty(n, np.int64)
    rank[order] = np.arange(n)
    # Each edge's end met first (low) and last (high) by the sweep.
    low, high = np.empty(n, np.int64), np.empty(n, np.int64)
    for e in range(n):
        f = (e + 1) % n
        low[e], high[e] = (e, f) if rank[e] < rank[f] else (f, e)
    status = np.empty(n, np.int64)
    size = 0
    for v in order:
        edges = ((v - 1) % n, v)
        for e in edges:
            if high[e] != v:
                continue
            # Edges below v first, then those through it: e among these.
            first, last = 0, size
            while first < last:
                middle = (first + last) // 2
                t = status[middle]
                if _side(x, y, low[t], high[t], v) > 0:
                    first = middle + 1
                else:
                    last = middle
            at = first
            while at < size and status[at] != e:
                at += 1
            if at == size:
                # Orientations rounded out of order: e is elsewhere.
                at = 0
                while status[at] != e:
                    at += 1
            below, above = status[at - 1] if at > 0 else -1, \
                status[at + 1] if at + 1 < size else -1
            for k in range(at, size - 1):
                status[k] = status[k + 1]
            size -= 1
            if below >= 0 and above >= 0 and not _neighbours(below, above, n) \
                    and _cross(x, y, below, above):
                return below, above
        for e in edges:
            if low[e] != v:
                continue
            first, last = 0, size
            while first < last:
                middle = (first + last) // 2
                t = status[middle]
                side = _side(x, y, low[t], high[t], v)
                if side == 0 and low[t] != v:
                    # v lies on t.
                    if not _neighbours(t, e, n) and _cross(x, y, t, e):
                        return t, e
                elif side == 0:
                    # The other edge from v: by their directions.
                    side = _side(x, y, low[t], high[t], high[e])
                if side > 0:
                    first = middle + 1
                else:
                    last = middle
            for k in range(size, first, -1):
                status[k] = status[k - 1]
            status[first] = e
            size += 1
            for t in (status[first - 1] if first > 0 else -1,
                      status[first + 1] if first + 1 < size else -1):
                if t >= 0 and not _neighbours(t, e, n) and _cross(x, y, t, e):
                    return t, e
    return -1, -1


def _passive_ranges(limits):
    """The passive ranges [rad] of a scene's limits, from ``passive`` [rad]
    or ``passive_deg`` [deg]."""
    if "passive" in limits and "passive_deg" in limits:
        raise InvalidInputError("limits give passive and passive_deg: give the passive "
                                "ranges once, in radians or in degrees")
    degrees = "passive_deg" in limits
    where, unit, turn = ("passive_deg", "deg", 360.0) if degrees else ("passive", "rad",
                                                                      2 * math.pi)
    ranges = _ranges(limits.get(where), where)
    for name, (low, high) in ranges.items():
        if not degrees and max(abs(low), abs(high)) > turn:
            raise InvalidInputError(
                f"passive {name!r} {[low, high]} rad lies beyond a full turn: a scene's "
                "passive ranges are in radians; give degrees under passive_deg")
        if high - low > turn:
            raise InvalidInputError(f"{where} {name!r} spans more than a full turn "
                                    f"({high - low:g} {unit})")
    if degrees:
        return {name: (math.radians(low), math.radians(high))
                for name, (low, high) in ranges.items()}
    return ranges


def _ranges(value, where):
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InvalidInputError(f"{where} must map names to [min, max], got {value!r}")
    out = {}
    for name, bounds in value.items():
        if not isinstance(bounds, (list, tuple)) or len(bounds) != 2:
            raise InvalidInputError(f"{where} {name!r} must be [min, max], got {bounds!r}")
        low, high = (_number(b, f"{where} {name!r}") for b in bounds)
        if low > high:
            raise InvalidInputError(f"{where} {name!r} has min {low} above max {high}")
        out[str(name)] = (low, high)
    return out
