"""A robot described in one YAML file: its mechanism and the box of joints
its roadmaps cover.

The file has two keys.  ``mechanism`` is the mechanism's document (its
``kind`` and parameters, as :meth:`~rpr3_gwr_core.mechanisms.Mechanism.to_dict`
writes them; lengths in the mechanism's length unit, angles in radians).
``joints`` lists every actuated joint in the mechanism's order, each with its
``name`` (the mechanism's joint name) and either a range sampled by a step
(``min``, ``max``, ``step``) or, for a revolute joint that turns freely,
``periodic: true`` with the number of ``cells`` of its full turn, starting at
``-pi``.  An optional ``bodies`` key gives the widths and layers of its
bodies against obstacles and each other (:class:`~rpr3_gwr_core.world.BodyModel`:
``leg_width``, ``leg_layers``, ``platform_width``, ...; by default each leg
in a layer of its own, so legs never meet).  ``config/`` holds one file per
mechanism the suite knows.
"""

from dataclasses import dataclass
import math

from ..exceptions import InvalidInputError
from ..mechanisms import Mechanism, mechanism_from_dict
from ..workspace.grid import Axis, Grid

__all__ = ["MechanismFile", "load_mechanism_file", "mechanism_file_from_dict", "roadmap_grid",
           "UNIFORM_CELLS"]

UNIFORM_CELLS = 1_000_000
"""Largest box of all the joints built as a uniform grid [cells]."""


@dataclass(frozen=True, repr=False)
class MechanismFile:
    """A mechanism and the box of its joints.

    Attributes
    ----------
    mechanism : Mechanism
    axes : tuple of Axis
        One per joint, in the mechanism's joint order.
    bodies : BodyModel or None
        The file's ``bodies``, None without one (the defaults).
    """

    mechanism: Mechanism
    axes: tuple
    bodies: object = None

    def __repr__(self):
        box = " x ".join(f"{name} ({a.count} cells a turn)" if a.periodic
                         else f"{name} [{a.low:g}, {a.high:g}] step {a.step:g}"
                         for name, a in zip(self.mechanism.joint_names, self.axes))
        return (f"MechanismFile({self.mechanism.kind}: {box}; "
                f"{'default bodies' if self.bodies is None else 'bodies of its own'})")

    def grid(self, fixed=None):
        """The grid over the box with some joints fixed.

        Parameters
        ----------
        fixed : mapping of str to float, optional
            Joint name to value [joint unit]; the other joints are the axes.

        Raises
        ------
        InvalidInputError
            If a name is not a joint of the mechanism, a value is not finite
            or lies outside its joint's range, or no joint is left free.
        """
        fixed = dict(fixed or {})
        names = self.mechanism.joint_names
        unknown = sorted(set(fixed) - set(names))
        if unknown:
            raise InvalidInputError(f"{unknown} name no joint of the {self.mechanism.kind}: "
                                    f"its joints are {list(names)}")
        values = []
        for name, value in fixed.items():
            axis = self.axes[names.index(name)]
            value = float(value)
            if not math.isfinite(value) or (
                    not axis.periodic and not axis.low <= value <= axis.high):
                raise InvalidInputError(f"{name} = {value} lies outside its range "
                                        f"[{axis.low:g}, {axis.high:g}]")
            values.append((names.index(name), value))
        axes = tuple(a for a, name in zip(self.axes, names) if name not in fixed)
        if not axes:
            raise InvalidInputError("every joint is fixed: leave at least one free")
        return Grid(axes=axes, fixed=tuple(values))


def roadmap_grid(grid):
    """``(grid, refinement)`` to build a roadmap of a mechanism file's grid
    on (:func:`~rpr3_gwr_core.io.cache.cached_roadmap`): a box of all the
    joints with more than :data:`UNIFORM_CELLS` cells is refined adaptively
    from a coarse base, only near the singular locus (the 3-RRR's 120-cell
    torus has 1.7 million cells, adaptively 0.9 million); any other grid is
    taken whole (refinement None).

    Raises
    ------
    InvalidInputError
        If a large box's axes do not divide into the refinement's blocks.
    """
    from ..workspace.adaptive import DEFAULT_REFINEMENT, coarse_base

    if grid.fixed or grid.size <= UNIFORM_CELLS:
        return grid, None
    return coarse_base(grid, DEFAULT_REFINEMENT), DEFAULT_REFINEMENT


def load_mechanism_file(path):
    """:class:`MechanismFile` of a YAML file (module doc).

    Raises
    ------
    InvalidInputError
        If the file is not YAML or does not describe a mechanism and its box.
    OSError
        If it cannot be read.
    """
    import yaml

    with open(path, encoding="utf-8") as stream:
        try:
            document = yaml.safe_load(stream)
        except yaml.YAMLError as exc:
            raise InvalidInputError(f"{path} is not YAML: {exc}") from None
    try:
        return mechanism_file_from_dict(document)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{path}: {exc}") from None


def mechanism_file_from_dict(document):
    """:class:`MechanismFile` of a parsed document (module doc).

    Raises
    ------
    InvalidInputError
        If it does not describe a mechanism and its box.
    """
    if not isinstance(document, dict) or not {"mechanism", "joints"} <= set(document) \
            or not set(document) <= {"mechanism", "joints", "bodies"}:
        raise InvalidInputError("a mechanism file has the keys 'mechanism' and 'joints', "
                                "and may have 'bodies'")
    mechanism = mechanism_from_dict(document["mechanism"])
    joints = document["joints"]
    names = mechanism.joint_names
    if not isinstance(joints, list) or len(joints) != len(names):
        raise InvalidInputError(f"'joints' lists the {len(names)} joints {list(names)}")
    axes = []
    for k, (joint, name) in enumerate(zip(joints, names)):
        if not isinstance(joint, dict) or joint.get("name") != name:
            raise InvalidInputError(f"joint {k} of 'joints' must be named {name!r}")
        axes.append(_axis(k, joint))
    bodies = None
    if "bodies" in document:
        from ..world import body_model_from_dict  # the world loads only when a file needs it

        bodies = body_model_from_dict(document["bodies"])
    return MechanismFile(mechanism=mechanism, axes=tuple(axes), bodies=bodies)


def _axis(k, joint):
    keys = set(joint) - {"name"}
    try:
        if joint.get("periodic") is True and keys == {"periodic", "cells"}:
            cells = joint["cells"]
            if isinstance(cells, bool) or not isinstance(cells, int) or cells < 2:
                raise InvalidInputError(f"{joint['name']}: 'cells' is a whole number >= 2")
            step = 2 * math.pi / cells
            return Axis(k, -math.pi, math.pi - step, step, periodic=True)
        if keys == {"min", "max", "step"}:
            return Axis(k, joint["min"], joint["max"], joint["step"])
    except TypeError as exc:
        raise InvalidInputError(f"{joint['name']}: {exc}") from None
    raise InvalidInputError(f"{joint['name']}: give 'min', 'max' and 'step', or "
                            "'periodic: true' and 'cells'")
