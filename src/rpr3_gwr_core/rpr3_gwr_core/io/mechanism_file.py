"""A robot described in one YAML file: its mechanism and the box of joints
its roadmaps cover.

The file has two keys.  ``mechanism`` is the mechanism's document (its
``kind`` and parameters, as :meth:`~rpr3_gwr_core.mechanisms.Mechanism.to_dict`
writes them; lengths in the mechanism's length unit, angles in radians).
``joints`` lists every actuated joint in the mechanism's order, each with its
``name`` (the mechanism's joint name) and either a range sampled by a step
(``min``, ``max``, ``step``) or, for a revolute joint that turns freely,
``periodic: true`` with the number of ``cells`` of its full turn, starting at
``-pi``.  Angles are in radians; an angle parameter or a revolute joint's
``min``, ``max`` and ``step`` may be given in degrees instead, as the same
key ending in ``_deg`` (``beta_deg: 60``).  A bare angle beyond a full turn
is refused as a likely angle in degrees, and an unknown key is named with
the known ones.  An optional ``bodies`` key gives the widths and layers of its
bodies against obstacles and each other (:class:`~rpr3_gwr_core.world.BodyModel`:
``leg_width``, ``leg_layers``, ``platform_width``, ...; by default each leg
in a layer of its own, so legs never meet).  An optional ``home`` is the
configuration the nodes start at: the joints, then the mode coordinate of
its assembly mode (``[rho1, rho2, rho3, alpha]`` for the 3-RPR), in the
box and off the singular locus.  ``config/`` holds one file per mechanism
the suite knows.

A file is UTF-8 YAML of at most
:data:`~rpr3_gwr_core.documents.MAX_DOCUMENT_BYTES`
(:func:`~rpr3_gwr_core.documents.read_document`: ``1e-3`` is a number);
its numbers are at most :data:`MAX_MAGNITUDE` in magnitude, and ``true``
and ``false`` are no numbers (only ``periodic`` takes them).
"""

from dataclasses import dataclass
import math
import numbers
import os
import reprlib

import numpy as np

from ..exceptions import GridSizeError, InvalidInputError
from ..mechanisms import Mechanism, mechanism_class, mechanism_from_dict
from ..planning.locate import DEFAULT_MODE_TOL
from ..workspace.adaptive import DEFAULT_REFINEMENT
from ..workspace.grid import MAX_GRID_CELLS, Axis, Grid

__all__ = ["MechanismFile", "load_mechanism_file", "mechanism_file_from_dict", "roadmap_grid",
           "physical_memory", "UNIFORM_CELLS", "BYTES_PER_CELL", "ROADMAP_MEMORY_SHARE",
           "HOME_SAMPLES", "HOME_MIN_MARGIN", "MAX_MAGNITUDE"]

MAX_MAGNITUDE = 1e6
"""Largest magnitude of a number of a mechanism file: lengths [length unit],
angles [rad or deg], steps, cells and the home.  The direct kinematics
lose their accuracy long before (the command line takes legs up to 1e6
too), and the squares of larger numbers overflow."""

UNIFORM_CELLS = 1_000_000
"""Largest box of all the joints built as a uniform grid [cells]."""

BYTES_PER_CELL = 1_800
"""Peak memory of a roadmap build with its planning index and messages, per
cell [bytes]: the roadmap builder node's, the largest (the README's
benchmark table has the measurement)."""

ROADMAP_MEMORY_SHARE = 0.5
"""Share of :func:`physical_memory` a roadmap of :func:`roadmap_grid` may take
by default."""

# Coarser steps tried before a refusal gives up naming the ones that fit.
_FIT_ATTEMPTS = 6

HOME_SAMPLES = 12
"""Values of each joint on the lattice a home is looked for on, when a file
gives none: the middles of as many equal parts of the joint's range."""

HOME_MIN_MARGIN = 0.01
"""Smallest margin magnitude of a home, given or found."""


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
    home : tuple of float or None
        The file's ``home``, shape (n_joints + 1,): the joints [joint unit],
        then the mode coordinate; None without one.
    """

    mechanism: Mechanism
    axes: tuple
    bodies: object = None
    home: tuple = None

    def __repr__(self):
        box = " x ".join(f"{name} ({a.count} cells a turn)" if a.periodic
                         else f"{name} [{a.low:g}, {a.high:g}] step {a.step:g}"
                         for name, a in zip(self.mechanism.joint_names, self.axes))
        return (f"MechanismFile({self.mechanism.kind}: {box}; "
                f"{'default bodies' if self.bodies is None else 'bodies of its own'})")

    def default_home(self, samples=HOME_SAMPLES):
        """The configuration to start at: the file's ``home``, else the
        assembly mode of largest margin magnitude on the slice of the first
        joint where a lattice of the box has most configurations that can
        be assembled.

        Parameters
        ----------
        samples : int
            Values of each joint on the lattice (:data:`HOME_SAMPLES`).

        Returns
        -------
        tuple of float, shape (n_joints + 1,)
            The joints [joint unit], then the mode coordinate.

        Raises
        ------
        InvalidInputError
            If no configuration of the lattice can be assembled with a margin
            of at least :data:`HOME_MIN_MARGIN`.
        """
        if self.home is not None:
            return self.home
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
            raise InvalidInputError(f"samples is a whole number >= 1, not {samples!r}")
        return _found_home(self.mechanism, self.axes, samples)

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
                                        f"[{axis.low:g}, {axis.high:g}] "
                                        f"{_unit(self.mechanism, name)}")
            values.append((names.index(name), value))
        axes = tuple(a for a, name in zip(self.axes, names) if name not in fixed)
        if not axes:
            raise InvalidInputError("every joint is fixed: leave at least one free")
        return Grid(axes=axes, fixed=tuple(values))


def roadmap_grid(described, fixed=None, *, memory=None, progress=None, workers=map):
    """The grid to build a roadmap of a mechanism file's box on, some joints
    fixed, that fits in memory.

    A grid of the fixed joints' slice, or of a box with at most
    :data:`UNIFORM_CELLS` cells, is the file's lattice itself.  A larger
    box is refined adaptively (:func:`~rpr3_gwr_core.workspace.adaptive.refine`)
    from a base grid ``DEFAULT_REFINEMENT`` times coarser than the file's
    steps (rounded to whole base steps, so the fine lattice is the file's or
    slightly finer): cells only near the singular locus, where features
    live.  Either grid has at most as many cells as ``memory`` holds at
    :data:`BYTES_PER_CELL` each (and :data:`~rpr3_gwr_core.workspace.grid.MAX_GRID_CELLS`).

    Parameters
    ----------
    described : MechanismFile
    fixed : mapping of str to float, optional
        Joint name to value [joint unit] (:meth:`MechanismFile.grid`).
    memory : int, optional
        Memory a build may take [bytes]; by default
        :data:`ROADMAP_MEMORY_SHARE` of :func:`physical_memory`.
    progress : callable, optional
        Called as ``progress(stage, fraction)`` while a large box is refined.
    workers : callable, optional
        A map-like callable the refinement solves the base grid with.

    Returns
    -------
    GridBase
        A :class:`~rpr3_gwr_core.workspace.grid.Grid` or an
        :class:`~rpr3_gwr_core.workspace.adaptive.AdaptiveGrid`, checked by
        :func:`~rpr3_gwr_core.workspace.grid.check_roadmap_grid`.

    Raises
    ------
    InvalidInputError
        If ``fixed`` is malformed (:meth:`MechanismFile.grid`), the grid
        would not fit, naming the steps that fit, or it would be empty.
    """
    from ..workspace.adaptive import refine
    from ..workspace.grid import check_roadmap_grid

    if not isinstance(described, MechanismFile):
        raise InvalidInputError(f"roadmap_grid takes a MechanismFile, got "
                                f"{type(described).__name__}")
    if memory is None:
        memory = int(ROADMAP_MEMORY_SHARE * physical_memory())
    if isinstance(memory, bool) or not isinstance(memory, numbers.Integral) or memory <= 0:
        raise InvalidInputError(f"memory is a positive number of bytes, got {memory!r}")
    max_cells = min(MAX_GRID_CELLS, int(memory) // BYTES_PER_CELL)
    fixed = dict(fixed or {})
    free = [a for a, name in zip(described.axes, described.mechanism.joint_names)
            if name not in fixed]
    if fixed or math.prod(a.count for a in free) <= UNIFORM_CELLS:
        size = math.prod(a.count for a in free)
        if size > max_cells:
            raise InvalidInputError(_too_large(described, f"{size:,} cells", max_cells, memory,
                                               _fitting_factor(free, max_cells), fixed))
        grid = described.grid(fixed)
        check_roadmap_grid(described.mechanism, grid)
        return grid

    def built(axes):
        return refine(described.mechanism, _coarse_grid(axes), DEFAULT_REFINEMENT,
                      max_cells=max_cells, progress=progress, workers=workers)

    try:
        grid = built(described.axes)
    except GridSizeError as exc:
        size = (f"{exc.size:,} cells" if exc.limit == max_cells
                else f"a fine lattice of {exc.size:,} points (at most {exc.limit:,})")
        raise InvalidInputError(_too_large(
            described, size, max_cells, memory,
            _adaptive_fitting_factor(built, described.axes, exc), fixed)) from None
    check_roadmap_grid(described.mechanism, grid)
    return grid


def physical_memory():
    """The machine's physical memory [bytes]; where the system does not tell,
    what :data:`~rpr3_gwr_core.workspace.grid.MAX_GRID_CELLS` cells take."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return MAX_GRID_CELLS * BYTES_PER_CELL


def _coarse_grid(axes):
    """The base grid ``DEFAULT_REFINEMENT`` times coarser than the axes, in
    whole base steps over each range (a periodic axis' turn in whole cells)."""
    r = DEFAULT_REFINEMENT
    base = []
    for a in axes:
        if a.periodic:
            cells = -(-a.count // r)
            step = 2 * math.pi / cells
            base.append(Axis(a.joint, -math.pi, math.pi - step, step, periodic=True))
        else:
            steps = max(1, -(-(a.count - 1) // r))
            base.append(Axis(a.joint, a.low, a.high, (a.high - a.low) / steps))
    return Grid(axes=tuple(base))


def _coarser(axes, factor):
    """The axes with steps ``factor`` times longer: a bounded axis' step
    rounded up to two significant digits, a turn's cells down to a multiple
    of ``DEFAULT_REFINEMENT``."""
    coarser = []
    for a in axes:
        if a.periodic:
            r = DEFAULT_REFINEMENT
            cells = max(2 * r, int(a.count / factor) // r * r)
            step = 2 * math.pi / cells
            coarser.append(Axis(a.joint, -math.pi, math.pi - step, step, periodic=True))
        else:
            step = a.step * factor
            scale = 10.0 ** (math.floor(math.log10(step)) - 1)
            step = math.ceil(step / scale - 1e-9) * scale
            coarser.append(Axis(a.joint, a.low, a.high, min(step, a.high - a.low or step)))
    return tuple(coarser)


def _fitting_factor(axes, max_cells):
    """Smallest factor of the steps, in tenths, that leaves a lattice of at
    most ``max_cells`` cells."""
    factor = max(1.1, (math.prod(a.count for a in axes) / max_cells) ** (1 / len(axes)))
    while math.prod(a.count for a in _coarser(axes, factor)) > max_cells:
        factor *= 1.1
    return factor


def _adaptive_fitting_factor(built, axes, error):
    """A factor of the file's steps whose adaptive grid fits, each guess
    refined: the refined cells near the singular locus grow as the steps'
    power ``1 - d``, the fine lattice's points as their power ``-d``."""
    factor, d = 1.0, len(axes)
    for _ in range(_FIT_ATTEMPTS):
        factor *= max(1.1, (error.size / error.limit) ** (1 / max(d - 1, 1)))
        try:
            built(_coarser(axes, factor))
        except GridSizeError as exc:
            error = exc
        else:
            return factor
    return None


def _too_large(described, size, max_cells, memory, factor, fixed):
    """Why a file's box is refused, with the steps of its free joints that
    would fit."""
    names = described.mechanism.joint_names
    advice = ""
    if factor is not None:
        steps = []
        for name, a in zip(names, _coarser(described.axes, factor)):
            if name in fixed:
                continue
            if a.periodic:
                steps.append(f"{name} cells {a.count}")
            elif described.mechanism.angular_joints[names.index(name)]:
                steps.append(f"{name} step_deg {math.degrees(a.step):.3g}")
            else:
                steps.append(f"{name} step {a.step:g}")
        advice = f"; these steps fit: {', '.join(steps)}"
        if not fixed:
            advice += " (or fix a joint)"
    return (f"the roadmap of the {described.mechanism.kind}'s "
            f"{'slice' if fixed else 'whole box'} would have {size}, more than a build may take:"
            f" {max_cells:,} cells, the fewer of {memory / 2 ** 30:.1f} GiB of memory at "
            f"{BYTES_PER_CELL} bytes a cell and the limit of a grid, {MAX_GRID_CELLS:,}"
            f"{advice}")


def load_mechanism_file(path):
    """:class:`MechanismFile` of a YAML file (module doc).

    Raises
    ------
    InvalidInputError
        If the file is larger than
        :data:`~rpr3_gwr_core.documents.MAX_DOCUMENT_BYTES`, is not UTF-8
        YAML or does not describe a mechanism and its box: one line, naming
        the file.
    OSError
        If it cannot be opened or read.
    """
    from ..documents import read_document

    document = read_document(path, "mechanism file")
    try:
        return mechanism_file_from_dict(document)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{path}: {exc}") from None


def mechanism_file_from_dict(document):
    """:class:`MechanismFile` of a parsed document (module doc).

    Raises
    ------
    InvalidInputError
        If it does not describe a mechanism and its box: a key missing or
        unknown, a boolean for a number, a number larger than
        :data:`MAX_MAGNITUDE`, ``leg_layers`` not one per leg, and the
        checks of the mechanism, the grid and the home.
    """
    if not isinstance(document, dict) or not {"mechanism", "joints"} <= set(document) \
            or not set(document) <= {"mechanism", "joints", "bodies", "home"}:
        raise InvalidInputError("a mechanism file has the keys 'mechanism' and 'joints', "
                                "and may have 'bodies' and 'home'")
    _check_numbers(document)
    mechanism = mechanism_from_dict(_in_radians(document["mechanism"]))
    joints = document["joints"]
    names = mechanism.joint_names
    if not isinstance(joints, list) or len(joints) != len(names):
        raise InvalidInputError(f"'joints' lists the {len(names)} joints {list(names)}")
    axes = []
    for k, (joint, name) in enumerate(zip(joints, names)):
        if not isinstance(joint, dict) or joint.get("name") != name:
            raise InvalidInputError(f"joint {k} of 'joints' must be named {name!r}")
        axes.append(_axis(k, joint, mechanism.angular_joints[k]))
    bodies = None
    if "bodies" in document:
        from ..world import body_model_from_dict, mechanism_bodies  # only when a file needs it

        bodies = body_model_from_dict(document["bodies"])
        try:
            # The bodies of any configuration tell whether the layers fit the legs.
            mechanism_bodies(mechanism, np.zeros(mechanism.pose_size),
                             np.zeros(mechanism.n_joints), bodies)
        except InvalidInputError as exc:
            raise InvalidInputError(f"'bodies': {exc}") from None
    home = _home(mechanism, axes, document["home"]) if "home" in document else None
    return MechanismFile(mechanism=mechanism, axes=tuple(axes), bodies=bodies, home=home)


def _check_numbers(document):
    """Refuse a boolean in the mechanism's parameters or a joint's range and
    a number larger than :data:`MAX_MAGNITUDE` anywhere, naming where it is
    (the home's and the bodies' own checks refuse their booleans, and each
    value's NaN and infinity)."""
    pending, seen = [(None, document)], set()
    while pending:  # a loop, not a recursion: a document may nest deeply
        where, value = pending.pop()
        if isinstance(value, (dict, list)):
            if id(value) in seen:  # a list given twice, or one inside itself
                continue
            seen.add(id(value))
        if isinstance(value, dict):
            pending += [(str(key) if where is None else f"{where}.{key}", item)
                        for key, item in value.items()]
        elif isinstance(value, list):
            pending += [(f"{where}[{k}]", item) for k, item in enumerate(value)]
        elif isinstance(value, bool):
            if where.startswith(("mechanism", "joints")) and not where.endswith("periodic"):
                raise InvalidInputError(f"'{where}' is {str(value).lower()}: a number is "
                                        "expected")
        elif isinstance(value, numbers.Real) and value == value \
                and value not in (math.inf, -math.inf) \
                and not -MAX_MAGNITUDE <= value <= MAX_MAGNITUDE:
            raise InvalidInputError(f"'{where}' = {reprlib.repr(value)} is out of range: a "
                                    f"mechanism file's numbers are at most {MAX_MAGNITUDE:g} "
                                    "in magnitude")


def _home(mechanism, axes, values):
    """The ``home`` of a file, checked: in the box, and an assembly mode
    within ``DEFAULT_MODE_TOL`` (or 1e-6 of a length) of its mode
    coordinate, of margin at least :data:`HOME_MIN_MARGIN`."""
    size = mechanism.n_joints + 1
    names = (*mechanism.joint_names, mechanism.pose_names[mechanism.mode_coordinate])
    if (not isinstance(values, list) or len(values) != size
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in values)):
        raise InvalidInputError(f"'home' lists {size} numbers, {list(names)}")
    home = tuple(float(v) for v in values)
    if not all(math.isfinite(v) for v in home):
        raise InvalidInputError(f"'home' has NaN or infinity: {list(home)}")
    angles = (*mechanism.angular_joints, mechanism.angular[mechanism.mode_coordinate])
    for name, value, angle in zip(names, home, angles):
        if angle:
            _radians(f"'home': {name}", value)
    for name, value, axis in zip(names, home, axes):
        if not axis.periodic and not axis.low <= value <= axis.high:
            raise InvalidInputError(f"'home': {name} = {value:g} lies outside its range "
                                    f"[{axis.low:g}, {axis.high:g}] {_unit(mechanism, name)}")
    joints = np.array(home[:-1])
    poses = _solutions(mechanism, joints[None])[0]
    k = mechanism.mode_coordinate
    off = np.abs(poses[:, k] - home[-1])
    if mechanism.angular[k]:
        off = np.abs(np.remainder(poses[:, k] - home[-1] + math.pi, 2 * math.pi) - math.pi)
    if not len(poses) or off.min() > (DEFAULT_MODE_TOL if mechanism.angular[k] else 1e-6):
        modes = ", ".join(f"{v:.6g}" for v in poses[:, k]) or "none"
        raise InvalidInputError(f"'home': the joints {list(home[:-1])} have no assembly mode "
                                f"with {names[-1]} near {home[-1]:g} (theirs: {modes})")
    margin = abs(float(mechanism.margin(poses[np.argmin(off)], joints)))
    if margin < HOME_MIN_MARGIN:
        raise InvalidInputError(f"'home' lies too near a singularity: margin {margin:.3g} "
                                f"< {HOME_MIN_MARGIN:g}")
    return home


def _solutions(mechanism, joints):
    """The direct-kinematic solutions of rows of joints: a list of arrays of
    shape (count, pose_size)."""
    count, poses = mechanism.solve(joints)
    return [row[:n] for row, n in zip(poses, count)]


def _found_home(mechanism, axes, samples):
    """The lattice configuration of :meth:`MechanismFile.default_home`."""
    values = [(-math.pi + (np.arange(samples) + 0.5) * 2 * math.pi / samples) if a.periodic
              else a.low + (np.arange(samples) + 0.5) * (a.high - a.low) / samples
              for a in axes]
    lattice = np.stack(np.meshgrid(*values, indexing="ij"), axis=-1).reshape(-1, len(axes))
    solutions = _solutions(mechanism, lattice)
    margins = [np.abs(mechanism.margin(poses, joints)) if len(poses) else np.zeros(0)
               for poses, joints in zip(solutions, lattice)]
    kept = np.array([bool((m >= HOME_MIN_MARGIN).any()) for m in margins])
    per_slice = kept.reshape(samples, -1).sum(axis=1)
    if per_slice.max() == 0:
        raise InvalidInputError(
            f"no configuration of a lattice of {samples} values a joint over the box can be "
            f"assembled with a margin of {HOME_MIN_MARGIN:g} or more: give the file a 'home'")
    # Of the slices with most, the one nearest the middle of the first joint.
    best = max(range(samples), key=lambda k: (per_slice[k], -abs(k - (samples - 1) / 2)))
    per_value = len(lattice) // samples
    rows = [r for r in range(best * per_value, (best + 1) * per_value) if kept[r]]
    row = max(rows, key=lambda r: margins[r].max())
    pose = solutions[row][int(np.argmax(margins[row]))]
    return (*(float(v) for v in lattice[row]), float(pose[mechanism.mode_coordinate]))


def _unit(mechanism, joint_name):
    """The unit of a joint's values, as errors name it."""
    angular = mechanism.angular_joints[mechanism.joint_names.index(joint_name)]
    return "rad" if angular else "[length unit]"


def _radians(what, value, degrees=False):
    """An angle of a file in radians: ``value`` in degrees when ``degrees``,
    else in radians and at most a full turn."""
    unit = "degrees" if degrees else "radians"
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value):
        raise InvalidInputError(f"{what} must be a number of {unit}, finite, got {value!r}")
    if degrees:
        return math.radians(value)
    if abs(value) > 2 * math.pi:
        raise InvalidInputError(
            f"{what} = {value:g} rad is more than a full turn: a mechanism file's angles are "
            f"in radians; for degrees, name the key with _deg ({value:g} deg = "
            f"{math.radians(value):.6g} rad)")
    return float(value)


def _converted(what, mapping, names, angles):
    """A mapping's values by name with its angles in radians: a key
    ``NAME_deg`` of an angle gives NAME in degrees.  Unknown keys are
    refused, named with the known ones; missing ones are not checked."""
    converted, unknown = {}, []
    for key, value in mapping.items():
        degrees = isinstance(key, str) and key.endswith("_deg") and key[:-4] in angles
        name = key[:-4] if degrees else key
        if name not in names:
            unknown.append(key)
        elif name in converted:
            raise InvalidInputError(f"{what}: {name} is given twice, as {name} [rad] and "
                                    f"{name}_deg [deg]")
        else:
            converted[name] = _radians(f"{what}: {key}", value, degrees) if name in angles \
                else value
    if unknown:
        known = ", ".join(f"{n} [rad] or {n}_deg [deg]" if n in angles else n for n in names)
        raise InvalidInputError(f"{what}: unknown key{'s' if len(unknown) > 1 else ''} "
                                f"{', '.join(map(repr, unknown))}; the known: {known}")
    return converted


def _in_radians(document):
    """The ``mechanism`` mapping of a file as :func:`mechanism_from_dict`
    takes it: its angle parameters in radians."""
    if not isinstance(document, dict):
        raise InvalidInputError("'mechanism' is a mapping: the mechanism's 'kind' and "
                                "parameters")
    cls = mechanism_class(document.get("kind"))
    what = f"the {cls.kind}'s parameters"
    parameters = _converted(what, {k: v for k, v in document.items() if k != "kind"},
                            cls.parameter_names(), cls.angle_parameters)
    missing = [name for name in cls.parameter_names() if name not in parameters]
    if missing:
        raise InvalidInputError(f"{what}: {', '.join(map(repr, missing))} missing")
    return {"kind": cls.kind, **parameters}


def _axis(k, joint, angular):
    name = joint["name"]
    keys = {key: value for key, value in joint.items() if key != "name"}
    periodic = keys.get("periodic") is True and set(keys) == {"periodic", "cells"}
    if not periodic:
        keys = _converted(name, keys, ("min", "max", "step", "periodic", "cells"),
                          ("min", "max", "step") if angular else ())
    try:
        if periodic:
            cells = keys["cells"]
            if isinstance(cells, bool) or not isinstance(cells, int) or cells < 2:
                raise InvalidInputError(f"{name}: 'cells' is a whole number >= 2")
            step = 2 * math.pi / cells
            return Axis(k, -math.pi, math.pi - step, step, periodic=True)
        if set(keys) == {"min", "max", "step"}:
            return Axis(k, keys["min"], keys["max"], keys["step"])
    except TypeError as exc:
        raise InvalidInputError(f"{name}: {exc}") from None
    unit = "rad (or min_deg, max_deg and step_deg)" if angular else "[length unit]"
    raise InvalidInputError(f"{name}: give 'min', 'max' and 'step' {unit}, or "
                            "'periodic: true' and 'cells'")
