"""A scene: static obstacles in the base plane and the mechanism's limits.

Obstacles are simple polygons and discs, each with an id.  Limits are the
actuated joints' ranges (a 3-RPR's leg strokes, replacing the grid's box as
the physical limit), the passive joints' ranges (by the names of
:meth:`Mechanism.body_outline`'s passive angles, e.g. ``base1`` and
``platform1``) and the least distance every body keeps from every obstacle,
``obstacle_clearance``.

A scene document (YAML or JSON)::

    obstacles:
      - {id: post, disc: {center: [6.0, 30.0], radius: 1.5}}
      - {id: fixture, polygon: [[20, 30], [26, 30], [26, 34], [20, 34]]}
    limits:
      obstacle_clearance: 0.25            # [length unit]
      strokes: {rho2: [2.0, 45.0]}        # [joint unit], by joint name
      passive: {base1: [0.0, 3.2]}        # [rad], min to max counter-clockwise

``passive_deg`` gives the passive ranges in degrees instead; a bound of
``passive`` beyond a full turn is refused as likely in degrees.
"""

from dataclasses import dataclass, field
import math
import numbers

import numpy as np

from ..exceptions import InvalidInputError

__all__ = ["PolygonObstacle", "DiscObstacle", "Limits", "Scene", "scene_from_dict",
           "load_scene", "EMPTY_SCENE"]


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
        With the offending entry named: an unknown key, a duplicate id, a
        polygon with fewer than 3 vertices, no area or crossing edges, a
        disc without a positive radius, a range with ``min > max`` (or a
        passive one over a full turn), a negative clearance, a value that is
        not a finite number.
    """
    _keys(data, "scene", {"obstacles", "limits"})
    polygons, discs, seen = [], [], set()
    obstacles = data.get("obstacles")
    obstacles = [] if obstacles is None else obstacles
    if not isinstance(obstacles, list):
        raise InvalidInputError(f"obstacles must be a list, got {obstacles!r}")
    for k, entry in enumerate(obstacles):
        where = f"obstacle {k}"
        _keys(entry, where, {"id", "polygon", "disc"})
        if "id" not in entry or isinstance(entry["id"], (bool, float)) \
                or not isinstance(entry["id"], (str, int)):
            raise InvalidInputError(f"{where} needs an id (a string or an integer)")
        oid = str(entry["id"])
        if oid in seen:
            raise InvalidInputError(f"obstacle id {oid!r} is used twice")
        seen.add(oid)
        where = f"obstacle {oid!r}"
        if ("polygon" in entry) == ("disc" in entry):
            raise InvalidInputError(f"{where} must be exactly one of polygon or disc")
        if "polygon" in entry:
            polygons.append(PolygonObstacle(oid, _polygon(entry["polygon"], where)))
        else:
            disc = entry["disc"]
            _keys(disc, f"{where}'s disc", {"center", "radius"})
            center = _points(disc.get("center"), f"{where}'s center").reshape(-1)
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


def load_scene(path):
    """Read a scene file (YAML, or JSON which is YAML).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Scene

    Raises
    ------
    InvalidInputError
        If the file cannot be read or parsed, or the scene is malformed
        (:func:`scene_from_dict`).
    """
    import yaml

    try:
        with open(path, encoding="utf-8") as stream:
            data = yaml.safe_load(stream)
    except OSError as exc:
        raise InvalidInputError(f"cannot read scene {path}: {exc.strerror}") from None
    except yaml.YAMLError as exc:
        raise InvalidInputError(f"scene {path} is not YAML: {exc}") from None
    return scene_from_dict({} if data is None else data)


def _keys(data, where, known):
    if not isinstance(data, dict):
        raise InvalidInputError(f"{where} must be a mapping, got {data!r}")
    unknown = sorted(set(map(str, data)) - known)
    if unknown:
        raise InvalidInputError(f"{where} has unknown keys {unknown}; known: {sorted(known)}")


def _number(value, where):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value):
        raise InvalidInputError(f"{where} must be a finite number, got {value!r}")
    return float(value)


def _points(value, where):
    if not isinstance(value, (list, tuple)):
        raise InvalidInputError(f"{where} must be a list of numbers, got {value!r}")
    try:
        flat = [_number(v, where) for v in np.ravel(np.array(value, dtype=object))]
        return np.array(flat, dtype=float).reshape(np.shape(np.array(value, dtype=object)))
    except ValueError:
        raise InvalidInputError(f"{where} must be a list of numbers, got {value!r}") from None


def _polygon(value, where):
    vertices = _points(value, f"{where}'s polygon")
    if vertices.ndim != 2 or vertices.shape[1] != 2 or vertices.shape[0] < 3:
        raise InvalidInputError(f"{where}'s polygon must be at least 3 points [x, y]")
    x, y = vertices.T
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    if area <= 1e-12 * max(1.0, float(np.ptp(vertices)) ** 2):
        raise InvalidInputError(f"{where}'s polygon has no area")
    n = len(vertices)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            if _segments_cross(vertices[i], vertices[(i + 1) % n], vertices[j],
                               vertices[(j + 1) % n]):
                raise InvalidInputError(f"{where}'s polygon has crossing edges {i} and {j}")
    return vertices


def _segments_cross(p, q, r, s):
    def side(a, b, c):
        return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    return side(p, q, r) * side(p, q, s) <= 0 and side(r, s, p) * side(r, s, q) <= 0


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
