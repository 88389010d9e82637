"""Uniform grids over any subset of a mechanism's joints, the others fixed.

A grid is a list of axes, each a joint index with a range and a step; the
other joints keep fixed values.  The paper's grid is two axes (rho2 and rho3
in [0, 50], step 0.125) at fixed rho1 = 17; the full 3-DOF roadmap is three
axes.  An axis over a revolute joint may be periodic: its range is one full
turn, and its last and first cells are neighbours, so faces, distances and
cell lookups wrap around it; joint values along a path stay continuous
(unwrapped) and are brought into the axis range only to find their cells.
Cells are the grid's sample points, numbered row-major over the axes in
their order: cell ``(i, j)`` of a 2-D grid is ``i * n_1 + j``.  A grid has
at most :data:`MAX_GRID_CELLS` cells, and :func:`check_roadmap_grid`
tells before a build whether a grid can give a roadmap at all.
"""

from dataclasses import dataclass
import functools
import itertools
import math
import numbers

import numba
import numpy as np

from ..exceptions import GridSizeError, InvalidInputError, OutOfGridError
from .continuity import neighbour_pairs

__all__ = ["Axis", "GridBase", "Grid", "MAX_GRID_CELLS", "check_roadmap_grid", "lattice_box",
           "lattice_cell", "lattice_points", "lattice_point_cell", "box_points", "within_box"]

# Most cells of any grid, about 4 million (2000 x 2000): a roadmap build
# takes about 0.75 kB per cell at its peak (a process building a 1001 x 1001
# slice peaks at 0.95 GB resident), so a grid at the limit takes about 3 GB,
# and far past it the machine runs out of memory before the build ends.
# Grids check it when made, before anything is allocated.
MAX_GRID_CELLS = 4_000_000

# Cells :func:`check_roadmap_grid` solves to tell whether a grid has enough
# solvable cells: a spread sample, so the check stays fast on any grid.
_PROBE_CELLS = 4096


def _real(value, name):
    """``float(value)`` for finite real numbers only (no strings)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidInputError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise InvalidInputError(f"{name} must be finite, got {value}")
    return value


@dataclass(frozen=True)
class Axis:
    """One axis of a grid.

    Attributes
    ----------
    joint : int
        Index of the joint it samples.
    low, high : float
        Inclusive range [joint unit].
    step : float
        Spacing of its cells [joint unit].
    periodic : bool
        A full turn of a revolute joint [rad]: ``high + step - low`` is
        ``2 pi``, and the cell after ``high`` is ``low``.

    Raises
    ------
    InvalidInputError
        If a value is not a finite number, ``step <= 0``, ``high < low``, the
        axis has more than :data:`MAX_GRID_CELLS` cells, or a periodic axis
        does not span one turn in whole steps.
    """

    joint: int
    low: float
    high: float
    step: float
    periodic: bool = False

    def __post_init__(self):
        if isinstance(self.joint, bool) or not isinstance(self.joint, numbers.Integral) \
                or self.joint < 0:
            raise InvalidInputError(f"an axis' joint is an index >= 0, got {self.joint!r}")
        low, high = _real(self.low, "an axis' low end"), _real(self.high, "an axis' high end")
        step = _real(self.step, "an axis' step")
        if step <= 0:
            raise InvalidInputError(f"step must be positive, got {step}")
        if high < low:
            raise InvalidInputError(
                f"an axis' range must satisfy low <= high, got ({low}, {high})")
        # Compared as floats: a tiny step or a huge range overflows int().
        if not (high - low) / step < MAX_GRID_CELLS:
            raise InvalidInputError(
                f"an axis from {low:g} to {high:g} by {step:g} has more than "
                f"{MAX_GRID_CELLS} cells, the limit of a grid")
        object.__setattr__(self, "joint", int(self.joint))
        for name, value in (("low", low), ("high", high), ("step", step)):
            object.__setattr__(self, name, value)
        if not isinstance(self.periodic, bool):
            raise InvalidInputError(f"periodic must be True or False, got {self.periodic!r}")
        if self.periodic and abs(self.count * step - 2 * math.pi) > 1e-9 * 2 * math.pi:
            raise InvalidInputError(
                f"a periodic axis spans one turn: {self.count} cells of {step:g} rad from "
                f"{low:g} to {high:g} cover {self.count * step:g} rad, not 2 pi")

    @property
    def period(self):
        """``2 pi`` for a periodic axis, else 0 [joint unit]."""
        return 2 * math.pi if self.periodic else 0.0

    @property
    def count(self):
        """Number of cells along the axis."""
        return int(math.floor((self.high - self.low) / self.step + 1e-9)) + 1

    @property
    def values(self):
        """Joint value of each cell along the axis, shape (count,)."""
        return self.low + self.step * np.arange(self.count)


class GridBase:
    """What every grid derives from its ``axes`` (the lattice its cells lie
    on), its ``fixed`` joints, ``coordinates()`` and ``_lattice_index(cell)``."""

    @property
    def ndim(self):
        """Number of axes d."""
        return len(self.axes)

    @property
    def n_joints(self):
        """Number of joints of the mechanism."""
        return len(self.axes) + len(self.fixed)

    @property
    def steps(self):
        """Step of each axis [joint unit]."""
        return tuple(a.step for a in self.axes)

    @property
    def step(self):
        """The smallest step [joint unit]."""
        return min(self.steps)

    @property
    def axis_joints(self):
        """Joint index of each axis."""
        return tuple(a.joint for a in self.axes)

    @property
    def periods(self):
        """Period of each axis, 0 where it has none, shape (ndim,) [joint unit]."""
        return np.array([a.period for a in self.axes])

    @property
    def periodic(self):
        """Whether any axis is periodic."""
        return any(a.periodic for a in self.axes)

    def nearest_joints(self, reference, joints):
        """``joints`` moved by whole turns along the periodic axes to lie
        nearest ``reference`` (both shape (..., n_joints), broadcast): the
        end of a continuous move from ``reference``."""
        joints = np.array(joints, dtype=float)
        for axis in self.axes:
            if axis.periodic:
                offset = joints[..., axis.joint] - np.asarray(reference)[..., axis.joint]
                joints[..., axis.joint] += _shortest(offset, axis.period) - offset
        return joints

    def unwrap(self, joints):
        """A sequence of joint vectors, shape (n, n_joints), made continuous
        along the periodic axes: each moved by whole turns to lie nearest the
        one before it (the first stays)."""
        joints = np.array(joints, dtype=float)
        for axis in self.axes:
            if axis.periodic:
                step = _shortest(np.diff(joints[:, axis.joint]), axis.period)
                joints[1:, axis.joint] = joints[0, axis.joint] + np.cumsum(step)
        return joints

    def _wrapped(self, values):
        """Axis values (shape (..., ndim)) of periodic axes brought into
        ``[low - step / 2, low - step / 2 + period)``."""
        values = np.array(values, dtype=float)
        for k, axis in enumerate(self.axes):
            if axis.periodic:
                start = axis.low - axis.step / 2
                values[..., k] = start + np.remainder(values[..., k] - start, axis.period)
        return values

    def describe(self, joint_names=None):
        """One line: each axis' joint and range, the step, the cells and the
        fixed joints, e.g. ``rho2 [0, 50] x rho3 [0, 50], step 0.125: 401 x
        401 cells at rho1 = 17``.

        Parameters
        ----------
        joint_names : sequence of str, optional
            One per joint of the mechanism (its ``joint_names``); else
            joints are named by index.

        Returns
        -------
        str
        """
        def name(joint):
            return joint_names[joint] if joint_names else f"joint {joint}"

        axes = " x ".join(f"{name(a.joint)} (a turn)" if a.periodic
                          else f"{name(a.joint)} [{a.low:g}, {a.high:g}]" for a in self.axes)
        steps = sorted(set(self.steps))
        step = ", ".join(f"{s:g}" for s in steps)
        fixed = ", ".join(f"{name(j)} = {v:g}" for j, v in self.fixed)
        return (f"{axes}, step{'s' if len(steps) > 1 else ''} {step}: {self._cells_phrase()}"
                + (f" at {fixed}" if fixed else ""))

    def __repr__(self):
        return f"{type(self).__name__}({self.describe()})"

    def fixed_value(self, joint):
        """Value of a fixed joint."""
        return dict(self.fixed)[joint]

    def _checked_point(self, joints):
        """The axis joints of a joint vector, finite and within half a step of
        the lattice (else ``InvalidInputError``, ``OutOfGridError``)."""
        values = [float(joints[a.joint]) for a in self.axes]
        if not all(math.isfinite(v) for v in values):
            raise InvalidInputError(f"cell_of needs finite joints, got {values}")
        values = self._wrapped(values).tolist()
        for value, axis in zip(values, self.axes):
            # Compared as floats: a huge joint value would overflow int().
            k = (value - axis.low) / axis.step
            if not -0.5 <= k < axis.count - 0.5:
                raise OutOfGridError(f"{tuple(values)} lies outside the grid "
                                     f"{[(a.low, a.high) for a in self.axes]}")
        return values

    def joints(self):
        """Joint vector of every cell, shape (size, n_joints)."""
        return self._with_fixed(self.coordinates())

    def joints_at(self, cells):
        """Joint vectors of some cells, shape (len(cells), n_joints)."""
        return self._with_fixed(self.coordinates_of(cells))

    def _with_fixed(self, coordinates):
        out = np.empty((len(coordinates), self.n_joints))
        out[:, list(self.axis_joints)] = coordinates
        for joint, value in self.fixed:
            out[:, joint] = value
        return out

    def cells_of(self, points):
        """Flat indices of the cells of many points, -1 outside the grid: the
        cell at the lattice point nearest each point, else (a point of an
        adaptive grid's coarse part) the cell at the nearest base point.

        Parameters
        ----------
        points : ndarray, shape (n, ndim)
            Axis coordinates (not whole joint vectors).

        Returns
        -------
        ndarray of int, shape (n,)
        """
        points = np.ascontiguousarray(points, dtype=float).reshape(-1, self.ndim)
        return _lattice_cells(points, *self.lattice)

    def joints_of(self, cell):
        """Joint vector of one cell, shape (n_joints,)."""
        index = self._lattice_index(cell)
        out = np.empty(self.n_joints)
        for axis, k in zip(self.axes, index):
            out[axis.joint] = axis.low + axis.step * k
        for joint, value in self.fixed:
            out[joint] = value
        return out


@dataclass(frozen=True, repr=False)
class Grid(GridBase):
    """A uniform grid over some joints of a mechanism.

    Attributes
    ----------
    axes : tuple of Axis
        The sampled joints, in the order of the cell numbering.
    fixed : tuple of (int, float)
        ``(joint, value)`` of every joint not on an axis.

    Raises
    ------
    InvalidInputError
        If the axes and fixed joints do not name each joint once, the grid
        has more than :data:`MAX_GRID_CELLS` cells, or its cell volume (the
        product of the steps) overflows.
    """

    axes: tuple
    fixed: tuple = ()

    def __post_init__(self):
        try:
            axes = tuple(self.axes)
            fixed = tuple((int(j), _real(v, f"fixed joint {j}")) for j, v in self.fixed)
        except (TypeError, ValueError):
            raise InvalidInputError(f"a grid needs axes and (joint, value) pairs, got "
                                    f"axes={self.axes!r}, fixed={self.fixed!r}") from None
        if not axes or not all(isinstance(a, Axis) for a in axes):
            raise InvalidInputError("a grid needs at least one Axis")
        joints = sorted([a.joint for a in axes] + [j for j, _ in fixed])
        if joints != list(range(len(joints))):
            raise InvalidInputError(f"the axes and fixed joints must name joints 0..n-1 once "
                                    f"each, got {joints}")
        size = math.prod(a.count for a in axes)
        if size > MAX_GRID_CELLS:
            raise GridSizeError(f"grid of {size} cells exceeds the limit of {MAX_GRID_CELLS}",
                                size, MAX_GRID_CELLS)
        # Cell volumes and face measures are products of steps: no product of
        # some of them may overflow.
        if not math.isfinite(math.prod(max(a.step, 1.0) for a in axes)):
            raise InvalidInputError(f"the steps {[a.step for a in axes]} overflow the volume "
                                    "of a cell")
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "fixed", tuple(sorted(fixed)))

    @classmethod
    def regular(cls, ranges, step, fixed=None):
        """A grid with one step on every axis.

        Parameters
        ----------
        ranges : mapping of int to (float, float)
            Axis joint to its inclusive ``(low, high)``, in axis order.
        step : float
        fixed : mapping of int to float, optional
            The other joints' values.
        """
        try:
            axes = tuple(Axis(joint, *bounds, step) for joint, bounds in ranges.items())
        except TypeError:
            raise InvalidInputError(f"ranges are (low, high) pairs, got {ranges!r}") from None
        return cls(axes=axes, fixed=tuple((fixed or {}).items()))

    @property
    def shape(self):
        """Number of cells along each axis."""
        return tuple(a.count for a in self.axes)

    @property
    def size(self):
        """Total number of cells."""
        return math.prod(self.shape)

    def _cells_phrase(self):
        return f"{' x '.join(map(str, self.shape))} cells"

    def coordinates(self):
        """Axis values of every cell, shape (size, ndim), row-major."""
        mesh = np.meshgrid(*[a.values for a in self.axes], indexing="ij")
        return np.stack([m.ravel() for m in mesh], axis=-1)

    def _lattice_index(self, cell):
        return np.unravel_index(int(cell), self.shape)

    def cell_of(self, joints):
        """Flat index of the cell nearest a joint vector (its axis joints).

        Raises
        ------
        InvalidInputError
            If an axis joint is NaN or infinite.
        OutOfGridError
            If the point lies farther than half a step outside the grid.
        """
        values = self._checked_point(joints)
        index = [min(int(round((v - a.low) / a.step)), a.count - 1)
                 for v, a in zip(values, self.axes)]
        return int(np.ravel_multi_index(index, self.shape))

    @functools.cached_property
    def lattice(self):
        """The cell lookup's description (:func:`lattice_cell`): every
        lattice point is a cell, numbered row-major."""
        steps = np.array(self.steps)
        return (np.array([a.low for a in self.axes]), steps, np.array(self.shape),
                np.zeros(0, dtype=np.int64), steps, 1, self.periods)

    def pairs(self):
        """Face-adjacent cell pairs, one ``(lower, upper)`` pair of flat-index
        arrays per axis, ``upper = lower + stride`` of that axis; along a
        periodic axis followed by the pairs across its seam (``lower`` the
        last cell, ``upper`` the first)."""
        pairs = neighbour_pairs(self.shape)
        index = np.arange(self.size).reshape(self.shape)
        for k, axis in enumerate(self.axes):
            if axis.periodic:
                lower, upper = pairs[k]
                pairs[k] = (np.concatenate([lower, np.take(index, -1, axis=k).ravel()]),
                            np.concatenate([upper, np.take(index, 0, axis=k).ravel()]))
        return pairs

    def pair_lengths(self):
        """Per axis, the length of each pair of :meth:`pairs` [joint unit]."""
        return [np.full(lower.size, step) for (lower, _), step in zip(self.pairs(), self.steps)]

    def face_measures(self):
        """Per axis, the measure of the face each pair crosses: the product of
        the other axes' steps [joint unit**(d - 1)]."""
        steps = np.array(self.steps)
        return [np.full(lower.size, float(np.prod(np.delete(steps, axis))))
                for axis, (lower, _) in enumerate(self.pairs())]

    def cell_volumes(self):
        """Volume each cell stands for, shape (size,) [joint unit**d]."""
        return np.full(self.size, float(np.prod(self.steps)))

    def volume_of(self, cells):
        """Volume a set of cells stands for [joint unit**d]."""
        return float(np.size(cells) * np.prod(self.steps))

    def depth(self, cells):
        """Euclidean distance of each given cell to the nearest cell not given,
        outside the grid included [steps].

        Parameters
        ----------
        cells : ndarray of int, shape (k,)
            Flat indices, ascending.

        Returns
        -------
        ndarray, shape (k,)
        """
        mask = np.zeros(self.shape, dtype=bool)
        mask.flat[cells] = True
        # Copies on both sides of each periodic axis' seam: a distance across
        # it is at most the axis' length.
        tiles = [(n, n) if a.periodic else (0, 0) for n, a in zip(self.shape, self.axes)]
        padded = np.pad(np.pad(mask, tiles, mode="wrap"), 1)
        middle = tuple(slice(1 + t, 1 + t + n) for (t, _), n in zip(tiles, self.shape))
        # Imported here: scipy.ndimage takes a tenth of a second to import,
        # and only building a planning index needs it.
        from scipy.ndimage import distance_transform_edt

        return distance_transform_edt(padded)[middle].ravel()[cells]

    def cells_in_box(self, point, radius):
        """Cells whose axis values lie within ``radius`` steps of a point along
        every axis, ascending; the lattice points of that box are looked up
        (not every cell compared).

        Parameters
        ----------
        point : ndarray, shape (ndim,)
            Values on the grid's axes [joint unit].
        radius : float
            [steps]

        Returns
        -------
        ndarray of int
        """
        point = self._wrapped(point)
        index = box_points(point, radius, np.array([a.low for a in self.axes]),
                            np.array(self.steps), np.array(self.shape), self.periods > 0)
        cells = np.unique(np.ravel_multi_index(tuple(index.T), self.shape))
        return within_box(cells, self.coordinates_of(cells), point, radius, self.steps,
                           self.periods)

    def coordinates_of(self, cells):
        """Axis values of cells, shape (len(cells), ndim)."""
        index = np.stack(np.unravel_index(np.asarray(cells, dtype=np.int64), self.shape), axis=-1)
        return np.array([a.low for a in self.axes]) + index * np.array(self.steps)

    def cells_near(self, joints, radius):
        """Cells within ``radius`` steps of a joint vector, nearest first.

        Returns
        -------
        list of int
        """
        values = self._wrapped([joints[a.joint] for a in self.axes])
        here = np.array([(v - a.low) / a.step for v, a in zip(values, self.axes)])
        reach = int(math.ceil(radius))
        return _nearest_points(here, np.array(self.shape), float(radius),
                               lattice_box(self.ndim, -reach, reach),
                               self.periods > 0).tolist()

    def to_dict(self):
        """Plain-data form, for JSON and cache keys."""
        # "periodic" only where set: the documents (and cache keys) of other
        # grids stay as they were.
        return {"axes": [{"joint": a.joint, "min": a.low, "max": a.high, "step": a.step,
                          **({"periodic": True} if a.periodic else {})}
                         for a in self.axes],
                "fixed": [{"joint": j, "value": v} for j, v in self.fixed]}

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(axes=tuple(Axis(a["joint"], a["min"], a["max"], a["step"],
                                       a.get("periodic", False))
                                  for a in data["axes"]),
                       fixed=tuple((f["joint"], f["value"]) for f in data["fixed"]))
        except (KeyError, TypeError) as exc:
            raise InvalidInputError(f"malformed grid: {exc}") from exc


def check_roadmap_grid(mechanism, grid, min_region_cells=8):
    """Refuse a grid whose roadmap would be empty, before it is built.

    A grid gives a roadmap only with faces along every axis (two cells or
    more along each) and at least ``min_region_cells`` cells that have a
    direct-kinematic solution (fewer make no region).  The solvable cells
    are counted on ``_PROBE_CELLS`` cells spread over the grid (all of them
    on a smaller grid) and scaled to its size.

    Parameters
    ----------
    mechanism : Mechanism
    grid : GridBase
    min_region_cells : int
        Fewest cells of a region, as :func:`~.roadmap.build_roadmap` takes it.

    Raises
    ------
    InvalidInputError
        If the grid has one cell along an axis, or too few solvable cells.
    """
    counts = [a.count for a in grid.axes]
    if min(counts) < 2:
        raise InvalidInputError(f"a grid of {' x '.join(map(str, counts))} cells has no faces "
                                "along one axis: give each axis at least two cells")
    probe = np.unique(np.linspace(0, grid.size - 1, _PROBE_CELLS).astype(np.int64))
    count, _ = mechanism.solve(grid.joints_at(probe))
    solvable = np.count_nonzero(count) * grid.size / probe.size
    if solvable < min_region_cells:
        names = mechanism.joint_names
        at = ", ".join(f"{names[joint]} = {value:g}" for joint, value in grid.fixed)
        raise InvalidInputError(
            f"about {solvable:.0f} cells of the grid have a direct-kinematic solution"
            f"{' at ' + at if at else ''}, fewer than one region needs ({min_region_cells}): "
            "its roadmap would be empty")


def box_points(point, radius, low, steps, shape, periodic=None):
    """The lattice indices around a point, a superset of those within a box.

    One index more than ``radius`` steps on each side, against rounding: the
    caller filters exactly (:func:`within_box`).

    Parameters
    ----------
    point : array_like, shape (ndim,)
        [joint units].
    radius : float
        Half the box's side [steps].
    low, steps : ndarray, shape (ndim,)
        The lattice's first coordinates and steps [joint units].
    shape : ndarray of int, shape (ndim,)
        The lattice's points per axis; indices are clipped to it.
    periodic : ndarray of bool, shape (ndim,), optional
        The axes along which indices wrap instead.

    Returns
    -------
    ndarray of int64, shape (m, ndim)
    """
    periodic = np.zeros(len(shape), bool) if periodic is None else periodic
    here = (np.asarray(point, dtype=float) - low) / steps
    first = np.floor(here - radius).astype(np.int64) - 1
    last = np.ceil(here + radius).astype(np.int64) + 1
    first = np.where(periodic, np.maximum(first, last - shape + 1), np.maximum(first, 0))
    last = np.where(periodic, last, np.minimum(last, shape - 1))
    if np.any(last < first):
        return np.zeros((0, len(shape)), dtype=np.int64)
    axes = [np.arange(a, b + 1) % n for a, b, n in zip(first, last, shape)]
    return np.stack([m.ravel() for m in np.meshgrid(*axes, indexing="ij")], axis=-1)


def within_box(cells, coordinates, point, radius, steps, periods=None):
    """The cells whose coordinates lie within ``radius`` steps of a point on
    every axis, across the seams of axes with a period.

    Parameters
    ----------
    cells : ndarray of int, shape (m,)
        Candidate cells.
    coordinates : ndarray, shape (m, ndim)
        Their coordinates [joint units].
    point : array_like, shape (ndim,)
        [joint units].
    radius : float
        Half the box's side [steps].
    steps : sequence of float, length ndim
        The step of each axis [joint units].
    periods : array_like, shape (ndim,), optional
        Each axis' period [joint units], 0 where it has none.

    Returns
    -------
    ndarray of int, shape (k,)
        Ascending.
    """
    offset = coordinates - point
    if periods is not None:
        offset = _shortest(offset, periods)
    inside = np.max(np.abs(offset) / np.array(steps), axis=1) <= radius
    return np.sort(cells[inside])


def _shortest(offset, period):
    """Offsets moved by whole periods into ``[-period / 2, period / 2]``;
    unchanged where the period is 0 (broadcast)."""
    period = np.asarray(period, dtype=float)
    turns = np.round(offset / np.where(period > 0, period, 1.0))
    return offset - np.where(period > 0, period * turns, 0.0)


@functools.lru_cache(maxsize=16)
def lattice_box(ndim, first, last):
    """Integer offsets from ``first`` to ``last`` on each of ``ndim`` axes,
    row-major, shape ((last - first + 1)**ndim, ndim); read-only and shared."""
    box = np.array(list(itertools.product(range(first, last + 1), repeat=ndim)),
                   dtype=np.int64).reshape(-1, ndim)
    box.flags.writeable = False
    return box


@numba.njit(cache=True)
def _nearest_points(here, shape, radius, box, periodic):
    """Row-major flat indices of the lattice points ``round(here) + box`` in
    ``shape`` (wrapped along the ``periodic`` axes) within ``radius`` of
    ``here`` (in steps), nearest first, ties in index order."""
    centre = np.rint(here).astype(np.int64)
    flat = np.empty(box.shape[0], np.int64)
    distance = np.empty(box.shape[0])
    count = 0
    for k in range(box.shape[0]):
        index, squared = 0, 0.0
        for a in range(here.size):
            i = centre[a] + box[k, a]
            squared += (i - here[a]) ** 2
            if periodic[a]:
                i %= shape[a]
            elif i < 0 or i >= shape[a]:
                index = -1
                break
            index = index * shape[a] + i
        if index >= 0 and math.sqrt(squared) <= radius:
            flat[count], distance[count] = index, math.sqrt(squared)
            count += 1
    # The box is row-major, so the points are in index order: a stable sort
    # keeps it among equal distances.
    return flat[:count][np.argsort(distance[:count], kind="mergesort")]


@numba.njit(cache=True)
def lattice_cell(point, low, steps, shape, index, base_steps, refinement, periods):
    """The cell of one point (:meth:`GridBase.cells_of`), -1 outside.

    ``low``, ``steps`` and ``shape`` describe the lattice; ``index`` holds
    the ascending flat lattice index of each cell, or nothing when every
    lattice point is a cell in row-major order; ``base_steps`` and
    ``refinement`` give the base points (every ``refinement``-th lattice
    point), which are always cells; ``periods`` the period of each axis
    (0: none), along which the point is wrapped first.
    """
    flat, base = lattice_points(point, low, steps, shape, base_steps, refinement, periods)
    return -1 if flat < 0 else lattice_point_cell(flat, base, index)


@numba.njit(cache=True, inline="always")
def lattice_points(point, low, steps, shape, base_steps, refinement, periods):
    """The flat lattice indices of a point's nearest lattice point and of its
    nearest base point, on which alone its cell depends
    (:func:`lattice_point_cell`); ``(-1, -1)`` outside.  Arguments as
    :func:`lattice_cell`'s."""
    flat = 0
    coarse = 0
    for k in range(point.size):
        value = point[k]
        if periods[k] > 0:
            start = low[k] - steps[k] / 2
            value = start + (value - start) % periods[k]
        nearest = np.rint((value - low[k]) / steps[k])
        # Compared as floats: NaN and huge values fall outside.
        if not 0.0 <= nearest <= shape[k] - 1:
            return -1, -1
        flat = flat * shape[k] + int(nearest)
        base = np.rint((value - low[k]) / base_steps[k])
        if periods[k] > 0:
            # A periodic axis has shape[k] / refinement base points, the
            # one after its last being its first.
            base = base % (shape[k] // refinement)
        else:
            base = min(max(base, 0.0), float((shape[k] - 1) // refinement))
        coarse = coarse * shape[k] + int(base) * refinement
    return flat, coarse


@numba.njit(cache=True, inline="always")
def lattice_point_cell(flat, base, index):
    """The cell of the lattice points of :func:`lattice_points`: the nearest
    lattice point's where it is a cell, else the base point's."""
    if index.size == 0:
        return flat
    j = np.searchsorted(index, flat)
    if j < index.size and index[j] == flat:
        return j
    return np.searchsorted(index, base)


@numba.njit(cache=True)
def _lattice_cells(points, low, steps, shape, index, base_steps, refinement, periods):
    out = np.empty(points.shape[0], dtype=np.int64)
    for n in range(points.shape[0]):
        out[n] = lattice_cell(points[n], low, steps, shape, index, base_steps, refinement,
                              periods)
    return out
