"""A mechanism's moving bodies as planar shapes, and how thick and stacked they are.

A mechanism outlines its bodies (:meth:`Mechanism.body_outline`): *links*,
segments between two named joint points, and *plates*, convex polygons over
named joint points, plus its passive joint angles.  A :class:`BodyModel` gives
them their width and their *layer*: bodies in different layers never collide
with each other (planar parallel robots stack their legs), every body counts
against obstacles.  :func:`assemble_bodies` turns an outline into
:class:`Bodies`, the bundle the collision kernel reads: capsules (segments
with a radius) and rounded convex polygons, and the pairs of bodies that can
touch (one layer, no joint point in common).

The default model puts each leg in a layer of its own and the platform in
layer 0, so a mechanism's legs only meet obstacles; one layer for all legs
turns leg interference on.
"""

from collections import namedtuple
from dataclasses import dataclass
import math
import numbers

import numpy as np

from ..exceptions import InvalidInputError
from ..mechanisms.base import finite_vectors

__all__ = ["BodyModel", "Bodies", "assemble_bodies", "body_model_from_dict",
           "mechanism_bodies", "DEFAULT_LEG_WIDTH"]

# Default leg width as a fraction of the mechanism's scale: 0.42 for the
# paper's 3-RPR (scale 20.84), thick enough that its coplanar legs interfere
# where they pass within 0.08 of each other.
DEFAULT_LEG_WIDTH = 0.02


@dataclass(frozen=True)
class BodyModel:
    """Width and layer of a mechanism's bodies.

    Attributes
    ----------
    leg_width : float or None
        Width of every link [length unit]; None: ``DEFAULT_LEG_WIDTH`` times
        the mechanism's scale.
    platform_width : float
        Rounding of the platform plate: its outline grown by half of it
        [length unit].
    leg_layers : tuple of int or None
        Layer of each leg; None: leg ``i`` (from 0) in layer ``i + 1``.
    platform_layer : int
        Layer of the platform plate.
    housing_length : float
        Prismatic legs only: when positive, each is a cylinder housing of
        this length from its base joint and a rod from the housing's end to
        its platform joint, two bodies [length unit].
    housing_width : float or None
        Width of the housing [length unit]; None: twice ``leg_width``.

    Raises
    ------
    InvalidInputError
        If a width or length is negative or not finite, or a layer not an
        integer.
    """

    leg_width: float = None
    platform_width: float = 0.0
    leg_layers: tuple = None
    platform_layer: int = 0
    housing_length: float = 0.0
    housing_width: float = None

    def __post_init__(self):
        for name in ("leg_width", "platform_width", "housing_length", "housing_width"):
            value = getattr(self, name)
            if value is None and name in ("leg_width", "housing_width"):
                continue
            object.__setattr__(self, name, _length(value, name))
        if self.leg_layers is not None:
            if isinstance(self.leg_layers, (str, bytes)) or not hasattr(self.leg_layers,
                                                                         "__iter__"):
                raise InvalidInputError(f"leg_layers must be a list of integers, "
                                        f"got {self.leg_layers!r}")
            object.__setattr__(self, "leg_layers",
                               tuple(_layer(v, "leg_layers") for v in self.leg_layers))
        object.__setattr__(self, "platform_layer", _layer(self.platform_layer, "platform_layer"))

    def to_dict(self):
        """Plain data, the keys :func:`body_model_from_dict` reads."""
        return {"leg_width": self.leg_width, "platform_width": self.platform_width,
                "leg_layers": None if self.leg_layers is None else list(self.leg_layers),
                "platform_layer": self.platform_layer, "housing_length": self.housing_length,
                "housing_width": self.housing_width}


def body_model_from_dict(data):
    """A :class:`BodyModel` from plain data (a mechanism file's ``bodies``).

    Parameters
    ----------
    data : mapping or None
        Any of :class:`BodyModel`'s attributes; None or missing keys take
        the defaults.

    Raises
    ------
    InvalidInputError
        If ``data`` is not a mapping, names an unknown key or a bad value.
    """
    if data is None:
        return BodyModel()
    if not isinstance(data, dict):
        raise InvalidInputError(f"bodies must be a mapping, got {data!r}")
    known = set(BodyModel.__dataclass_fields__)
    unknown = sorted(set(map(str, data)) - known)
    if unknown:
        raise InvalidInputError(f"unknown body keys {unknown}; known: {sorted(known)}")
    return BodyModel(**data)


Bodies = namedtuple("Bodies", ["capsules", "capsule_radius", "polygons", "polygon_radius",
                               "layers", "pairs", "passive", "names", "passive_names",
                               "legs"])
Bodies.__doc__ = """A mechanism's bodies in many configurations.

Attributes
----------
capsules : ndarray, shape (..., n_capsules, 2, 2)
    Each link's two end points [length unit].
capsule_radius : ndarray, shape (n_capsules,)
    Half their width [length unit].
polygons : ndarray, shape (..., n_polygons, n_vertices, 2)
    Each plate's vertices, counter-clockwise or clockwise [length unit].
polygon_radius : ndarray, shape (n_polygons,)
    How far each plate reaches beyond its outline [length unit].
layers : ndarray of int64, shape (n_capsules + n_polygons,)
    Layer of each body, capsules first.
pairs : ndarray of int64, shape (n_pairs, 2)
    Bodies that can touch: one layer, no joint point in common.
passive : ndarray, shape (..., n_passive)
    Passive joint angles [rad].
names : tuple of str
    Each body's name, capsules first (``"leg1"``, ``"platform"``, ...).
passive_names : tuple of str
    Each passive angle's name (``"base1"``, ``"platform1"``, ...).
legs : tuple of int
    The leg (from 0) each body belongs to, -1 for the platform.
"""


def mechanism_bodies(mechanism, poses, joints, model=None):
    """The moving bodies of a mechanism's configurations as capsules and polygons.

    Parameters
    ----------
    mechanism : Mechanism
        Outlines its bodies (:meth:`~rpr3_gwr_core.mechanisms.base.Mechanism.body_outline`).
    poses : array_like, shape (..., pose_size)
    joints : array_like, shape (..., n_joints)
        The joints the poses solve, broadcast against ``poses``.
    model : BodyModel, optional
        Widths and layers; the default puts each leg in a layer of its own.

    Returns
    -------
    Bodies
        Batch shape the broadcast of the two leading shapes.

    Raises
    ------
    InvalidInputError
        If poses or joints are not finite or of the wrong size, or the
        model's layers do not fit the legs.
    NotImplementedError
        For mechanisms that do not describe their bodies.
    """
    poses = finite_vectors(poses, "poses", mechanism.pose_size)
    joints = finite_vectors(joints, "joints", mechanism.n_joints)
    shape = np.broadcast_shapes(poses.shape[:-1], joints.shape[:-1])
    poses = np.broadcast_to(poses, shape + poses.shape[-1:])
    joints = np.broadcast_to(joints, shape + joints.shape[-1:])
    return assemble_bodies(mechanism.body_outline(poses, joints), model, mechanism.scale)


def assemble_bodies(outline, model, scale):
    """The :class:`Bodies` of a mechanism's outline with a body model.

    Parameters
    ----------
    outline : (list, list, list)
        :meth:`Mechanism.body_outline`'s links ``(name, leg, (start_point,
        end_point), start, end, prismatic)``, plates ``(name, points,
        vertices)`` and passive angles ``(name, angles)``; ``start`` and
        ``end`` of shape (..., 2), ``vertices`` (..., k, 2), ``angles`` (...).
    model : BodyModel or None
    scale : float
        The mechanism's scale [length unit], for the default widths.

    Returns
    -------
    Bodies
    """
    model = model or BodyModel()
    links, plates, passive = outline
    leg_width = DEFAULT_LEG_WIDTH * scale if model.leg_width is None else model.leg_width
    housing_width = 2 * leg_width if model.housing_width is None else model.housing_width
    n_legs = 1 + max((leg for _, leg, *_ in links), default=-1)
    leg_layers = model.leg_layers if model.leg_layers is not None else tuple(
        range(1, n_legs + 1))
    if len(leg_layers) != n_legs:
        raise InvalidInputError(f"leg_layers must give {n_legs} layers, got {len(leg_layers)}")
    names, legs, points, starts, ends, radius = [], [], [], [], [], []
    for name, leg, (first, last), start, end, prismatic in links:
        if prismatic and model.housing_length > 0:
            # The housing keeps its length; the rod runs from where the
            # housing ends (or from the platform joint, when the leg is
            # shorter than the housing) to the platform joint.
            vector = end - start
            length = np.linalg.norm(vector, axis=-1, keepdims=True)
            unit = vector / np.where(length > 0, length, 1.0)
            mouth = start + model.housing_length * unit
            rod_start = start + np.minimum(model.housing_length, length) * unit
            middle = f"{name}_mouth"
            for part, a, b, width, tags in (("housing", start, mouth, housing_width,
                                             (first, middle)),
                                            ("rod", rod_start, end, leg_width, (middle, last))):
                names.append(f"{name}_{part}")
                legs.append(leg)
                points.append(tags)
                starts.append(a)
                ends.append(b)
                radius.append(width / 2)
        else:
            names.append(name)
            legs.append(leg)
            points.append((first, last))
            starts.append(start)
            ends.append(end)
            radius.append(leg_width / 2)
    layers = [leg_layers[leg] for leg in legs]
    batch = np.broadcast_shapes(*(np.shape(s)[:-1] for s in starts + ends))
    capsules = np.empty(batch + (len(starts), 2, 2))
    for k, (a, b) in enumerate(zip(starts, ends)):
        capsules[..., k, 0, :] = a
        capsules[..., k, 1, :] = b
    n_vertices = max((np.shape(v)[-2] for _, _, v in plates), default=3)
    polygons = np.empty(batch + (len(plates), n_vertices, 2))
    for k, (name, tags, vertices) in enumerate(plates):
        polygons[..., k, :, :] = vertices
        names.append(name)
        legs.append(-1)
        points.append(tuple(tags))
        layers.append(model.platform_layer)
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))
             if layers[i] == layers[j] and not set(points[i]) & set(points[j])]
    angles = np.empty(batch + (len(passive),))
    for k, (_, value) in enumerate(passive):
        angles[..., k] = value
    return Bodies(capsules=capsules, capsule_radius=np.array(radius, dtype=float),
                  polygons=polygons,
                  polygon_radius=np.full(len(plates), model.platform_width / 2),
                  layers=np.array(layers, dtype=np.int64),
                  pairs=np.array(pairs, dtype=np.int64).reshape(-1, 2),
                  passive=angles, names=tuple(names),
                  passive_names=tuple(name for name, _ in passive), legs=tuple(legs))


def _length(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value) or value < 0:
        raise InvalidInputError(f"{name} must be a finite non-negative number, got {value!r}")
    return float(value)


def _layer(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InvalidInputError(f"{name} must be integers, got {value!r}")
    return int(value)
