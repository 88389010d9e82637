"""Adaptive grids: a coarse grid refined where the field is not uniform.

A uniform grid fine enough for the paper's slice (0.125) has 64 million
cells over the three legs.  Most of the configuration space is far from the
singular locus, where a coarse cell tells as much as many fine ones; features
(small regions, narrow gates) live next to it.  An adaptive grid keeps every
point of a coarse *base* grid and adds the points of a lattice ``r`` times
finer (``refinement``) inside the *refined blocks*: the boxes between
``2**d`` adjacent base points that :func:`refine` picks.

Refinement rule
---------------
A block stays coarse when all of these hold, else it is refined:

1. its ``2**d`` corners have the same number of solutions;
2. along each of its edges every solution continues into a solution of the
   other end (:func:`~rpr3_gwr_core.workspace.continuity.match_solutions`);
3. every solution at its corners has ``|margin| >= min_margin``.

A fold of the singular locus changes the count across it (1.); where two
folds cross an edge the count comes back but the continuation breaks (2.);
a piece of the locus that passes between the corners without crossing an
edge still lowers the margins of the solutions near it (3.).  What can still
be missed is a feature that lies wholly inside a block with well-conditioned
corners, such as a region smaller than a block: blocks whose corners have no
solution at all are not refined.

Cells and faces
---------------
The cells are the points of both lattices, numbered by ascending flat index
on the fine lattice.  Two cells are face-adjacent along an axis when they are
consecutive points on a line of the fine lattice parallel to it and at most
one base step apart: fine neighbours inside refined blocks, base neighbours
along the edges of coarse blocks, and hanging points of a refined block's
face joined across a coarse block to the refined block opposite.  Each cell
has at most one neighbour per face, so the rotary disk search applies as on
a uniform grid.

Periodic axes
-------------
A periodic axis of the base (a revolute joint's full turn) has as many
blocks as base points: its last block lies between its last base point and
its first, one turn on.  Its fine lattice has ``r`` points per base point,
and blocks, faces, volumes, depths and cell lookups wrap around it as a
uniform grid's do (:mod:`.grid`).
"""

import functools
import itertools
import math
import numbers

import numba
import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import dijkstra

from ..exceptions import GridSizeError, InvalidInputError
from .continuity import match_solutions
from .field import compute_field
from .grid import (MAX_GRID_CELLS, Axis, Grid, GridBase, box_points, lattice_box,
                   within_box)
from .progress import part

__all__ = ["AdaptiveGrid", "refine", "grid_from_dict", "coarse_base", "block_shape",
           "DEFAULT_REFINEMENT", "DEFAULT_REFINE_MARGIN"]

DEFAULT_REFINEMENT = 4
DEFAULT_REFINE_MARGIN = 0.02

# Most points of the fine lattice, which is tabulated whole (the points
# taken, their cells, the cell volumes): about 50 bytes per point at the
# peak, so 64 million points stay near the 3 GB of a build of MAX_GRID_CELLS
# cells.  The full 3-DOF grid's lattice has 8 million.
_MAX_LATTICE_POINTS = 16 * MAX_GRID_CELLS


class AdaptiveGrid(GridBase):
    """A base grid with some of its blocks refined (module doc).

    Parameters
    ----------
    base : Grid
        The coarse grid; every one of its points is a cell.
    refinement : int
        Fine points per base step along every axis, at least 2.
    blocks : array_like of int
        Flat indices of the refined blocks, row-major over the block array
        of shape ``base.shape - 1``.
    max_cells : int, optional
        Most cells it may have, at most :data:`~.grid.MAX_GRID_CELLS` (the
        default).

    Attributes
    ----------
    axes : tuple of Axis
        The fine lattice: the base's ranges with steps divided by ``refinement``.

    Raises
    ------
    InvalidInputError
        If an argument is malformed.
    GridSizeError
        If the fine lattice has more than ``_MAX_LATTICE_POINTS`` points or
        the grid more than ``max_cells`` cells (both checked before the
        cells are listed).
    """

    def __init__(self, base, refinement, blocks, *, max_cells=MAX_GRID_CELLS):
        if not isinstance(base, Grid):
            raise InvalidInputError(f"an adaptive grid refines a Grid, got {type(base).__name__}")
        if (isinstance(refinement, bool) or not isinstance(refinement, numbers.Integral)
                or refinement < 2):
            raise InvalidInputError(f"refinement is an integer >= 2, got {refinement!r}")
        if min(base.shape) < 2:
            raise InvalidInputError(f"an adaptive grid needs two base points per axis, "
                                    f"got shape {base.shape}")
        self.base = base
        self.refinement = int(refinement)
        self._periodic = np.array([a.periodic for a in base.axes])
        self.block_shape = block_shape(base)
        blocks = np.unique(np.asarray(blocks, dtype=np.int64).ravel())
        if blocks.size and (blocks[0] < 0 or blocks[-1] >= math.prod(self.block_shape)):
            raise InvalidInputError("refined block index outside the base grid")
        self.blocks = blocks
        if (isinstance(max_cells, bool) or not isinstance(max_cells, numbers.Integral)
                or not 0 < max_cells <= MAX_GRID_CELLS):
            raise InvalidInputError(f"max_cells is an integer in [1, {MAX_GRID_CELLS}], "
                                    f"got {max_cells!r}")
        r = self.refinement
        self.fine_shape = tuple(n * r if a.periodic else (n - 1) * r + 1
                                for n, a in zip(base.shape, base.axes))
        if math.prod(self.fine_shape) > _MAX_LATTICE_POINTS:
            raise GridSizeError(
                f"refining {base.shape} base points {r} times gives a fine lattice of "
                f"{math.prod(self.fine_shape)} points, more than the limit of "
                f"{_MAX_LATTICE_POINTS}", math.prod(self.fine_shape), _MAX_LATTICE_POINTS)
        self.axes = tuple(Axis(a.joint, a.low, a.low + a.step * (a.count - 1 / r if a.periodic
                                                                 else a.count - 1),
                               a.step / r, a.periodic)
                          for a in base.axes)
        self._index = self._sample_points(int(max_cells))
        self._pairs = None
        self._volumes = None

    def _sample_points(self, max_cells):
        """Fine flat index of every cell, ascending."""
        r = self.refinement
        refined = np.zeros(self.block_shape, dtype=bool)
        refined.reshape(-1)[self.blocks] = True
        # A block's points but those of its far faces: the blocks repeated r
        # times along every axis (the far end of a bounded axis left empty).
        taken = refined
        for axis in range(self.ndim):
            taken = np.repeat(taken, r, axis=axis)
        taken = np.pad(taken, [(0, f - t) for f, t in zip(self.fine_shape, taken.shape)])
        # Then the far faces, axis by axis: a point on a multiple of r is also
        # of the block before it, as is a periodic axis' first point of its
        # last block.
        for axis, periodic in enumerate(self._periodic):
            along = np.moveaxis(taken, axis, 0)
            if periodic:
                along[::r] |= np.roll(along[r - 1::r], 1, axis=0)
            else:
                along[r::r] |= along[r - 1::r]
        taken[tuple(slice(None, None, r) for _ in self.fine_shape)] = True
        size = int(np.count_nonzero(taken))
        if size > max_cells:
            raise GridSizeError(f"grid of {size} cells exceeds the limit of {max_cells}",
                                size, max_cells)
        return np.flatnonzero(taken)

    def __eq__(self, other):
        return (isinstance(other, AdaptiveGrid) and other.base == self.base
                and other.refinement == self.refinement
                and np.array_equal(other.blocks, self.blocks))

    __hash__ = None

    # -- the Grid interface ---------------------------------------------------

    @property
    def fixed(self):
        """``(joint, value)`` of every joint not on an axis."""
        return self.base.fixed

    @property
    def size(self):
        """Number of cells."""
        return int(self._index.size)

    def _cells_phrase(self):
        return (f"{self.size:,} cells (base {' x '.join(map(str, self.base.shape))}, "
                f"{self.blocks.size:,} blocks refined {self.refinement} times)")

    def _multi(self, cells=None):
        index = self._index if cells is None else self._index[cells]
        return np.stack(np.unravel_index(index, self.fine_shape), axis=-1)

    def coordinates(self):
        """Axis values of every cell, shape (size, ndim)."""
        low = np.array([a.low for a in self.axes])
        return low + self._multi() * np.array(self.steps)

    def _lattice_index(self, cell):
        return np.unravel_index(int(self._index[int(cell)]), self.fine_shape)

    def _lookup(self, fine_flat):
        """Cell of each fine flat index, -1 where it is no cell."""
        k = np.minimum(np.searchsorted(self._index, fine_flat), self.size - 1)
        return np.where(self._index[k] == fine_flat, k, -1)

    @functools.cached_property
    def lattice(self):
        """The cell lookup's description (:func:`~.grid.lattice_cell`): the
        fine lattice, the cells' fine indices and the base points."""
        return (np.array([a.low for a in self.axes]), np.array(self.steps),
                np.array(self.fine_shape), self._index, np.array(self.base.steps),
                self.refinement, self.periods)

    def cell_of(self, joints):
        """The cell of a joint vector (:meth:`cells_of`).

        Raises
        ------
        InvalidInputError
            If an axis joint is NaN or infinite.
        OutOfGridError
            If the point lies farther than half a fine step outside the grid.
        """
        values = np.array(self._checked_point(joints))
        return int(self.cells_of(values[None, :])[0])

    def pairs(self):
        """Face-adjacent cell pairs (module doc), one ``(lower, upper)`` pair of
        cell arrays per axis, ``lower`` before ``upper`` along the axis (across
        a periodic axis' seam, ``lower`` the last)."""
        if self._pairs is None:
            # int32 halves the table: a grid has far fewer than 2**31 cells.
            rank = np.full(math.prod(self.fine_shape), -1, dtype=np.int32)
            rank[self._index] = np.arange(self.size)
            self._pairs = [_axis_pairs(self._index, rank, math.prod(self.fine_shape[axis + 1:]),
                                       self.fine_shape[axis], self.refinement,
                                       bool(self._periodic[axis]))
                           for axis in range(self.ndim)]
        return [(lower, upper) for lower, upper, _ in self._pairs]

    def _gaps(self):
        self.pairs()
        return [gap for _, _, gap in self._pairs]

    def pair_lengths(self):
        """Per axis, the length of each pair of :meth:`pairs` [joint unit]."""
        return [gap * step for gap, step in zip(self._gaps(), self.steps)]

    def face_measures(self):
        """Per axis, the measure of the face each pair crosses: the other axes'
        fine steps for fine pairs, their base steps for base ones
        [joint unit**(d - 1)]."""
        fine, coarse = np.array(self.steps), np.array(self.base.steps)
        out = []
        for axis, gap in enumerate(self._gaps()):
            small = float(np.prod(np.delete(fine, axis)))
            large = float(np.prod(np.delete(coarse, axis)))
            out.append(np.where(gap < self.refinement, small, large))
        return out

    def volume_of(self, cells):
        """Volume a set of cells stands for [joint unit**d] (:meth:`cell_volumes`)."""
        if self._volumes is None:
            self._volumes = self.cell_volumes()
        return float(self._volumes[cells].sum())

    def cell_volumes(self):
        """Volume each cell stands for: every coarse block shares its volume
        among its corners, every refined block among its fine points,
        shape (size,) [joint unit**d]."""
        r, d = self.refinement, self.ndim
        refined = np.zeros(math.prod(self.block_shape), dtype=bool)
        refined[self.blocks] = True
        refined = refined.reshape(self.block_shape)
        # Per fine point, how many of the 2**d boxes around it are fine boxes
        # (of refined blocks) and how many are coarse blocks it is a corner of.
        fine_box = refined
        for axis in range(d):
            fine_box = np.repeat(fine_box, r, axis=axis)
        fine_share = _corner_sums(fine_box, self._periodic)
        coarse_share = np.zeros(self.fine_shape)
        coarse_share[tuple(slice(None, None, r) for _ in range(d))] = _corner_sums(
            ~refined, self._periodic)
        volume = (fine_share * (float(np.prod(self.steps)) / 2 ** d)
                  + coarse_share * (float(np.prod(self.base.steps)) / 2 ** d))
        return volume.ravel()[self._index]

    def depth(self, cells):
        """Distance of each given cell to the nearest cell not given, along
        face-adjacent pairs, or to just beyond the grid's border if nearer
        [fine steps].

        Parameters
        ----------
        cells : ndarray of int, shape (k,)
            Cells, ascending.

        Returns
        -------
        ndarray, shape (k,)
        """
        cells = np.asarray(cells, dtype=np.int64)
        multi = self._multi(cells)
        # A periodic axis has no border.
        border = np.min(np.where(self._periodic, np.inf,
                                 np.minimum(multi, np.array(self.fine_shape) - 1 - multi)),
                        axis=1) + 1.0
        member = np.zeros(self.size, dtype=bool)
        member[cells] = True
        rows, cols, weights = [], [], []
        self.pairs()
        for lower, upper, gap in self._pairs:
            touch = member[lower] | member[upper]
            rows.append(lower[touch])
            cols.append(upper[touch])
            weights.append(gap[touch].astype(float))
        rows, cols, weights = map(np.concatenate, (rows, cols, weights))
        outside = np.unique(np.concatenate([rows[~member[rows]], cols[~member[cols]]]))
        if outside.size == 0:
            return border
        # Renumber the cells involved so the graph stays as small as the patch.
        nodes = np.unique(np.concatenate([cells, outside]))
        graph = sparse.csr_matrix((weights, (np.searchsorted(nodes, rows),
                                             np.searchsorted(nodes, cols))),
                                  shape=(nodes.size, nodes.size))
        distance = dijkstra(graph, directed=False, indices=np.searchsorted(nodes, outside),
                            min_only=True)
        return np.minimum(distance[np.searchsorted(nodes, cells)], border)

    def cells_in_box(self, point, radius):
        """Cells whose axis values lie within ``radius`` fine steps of a point
        along every axis, ascending (:meth:`.Grid.cells_in_box`)."""
        point = self._wrapped(point)
        index = box_points(point, radius, np.array([a.low for a in self.axes]),
                            np.array(self.steps), np.array(self.fine_shape), self._periodic)
        cells = self._lookup(np.ravel_multi_index(tuple(index.T), self.fine_shape))
        cells = cells[cells >= 0]
        return within_box(cells, self.coordinates_of(cells), point, radius, self.steps,
                           self.periods)

    def coordinates_of(self, cells):
        """Axis values of cells, shape (len(cells), ndim)."""
        low = np.array([a.low for a in self.axes])
        return low + self._multi(np.asarray(cells, dtype=np.int64)) * np.array(self.steps)

    def cells_near(self, joints, radius):
        """Cells within ``radius`` fine steps of a joint vector, nearest first,
        and the base points of the blocks around it (a point in a coarse block
        may have no fine cell within ``radius``).

        Returns
        -------
        list of int
        """
        low = np.array([a.low for a in self.axes])
        here = (self._wrapped([joints[a.joint] for a in self.axes]) - low) / np.array(self.steps)
        reach = int(math.ceil(radius))
        return _cells_near(here, float(radius), self.refinement, np.array(self.fine_shape),
                           self._periodic, self._index, lattice_box(self.ndim, -reach, reach),
                           lattice_box(self.ndim, -1, 2)).tolist()

    def to_dict(self):
        """Plain-data form, for JSON."""
        return {"kind": "adaptive", "base": self.base.to_dict(),
                "refinement": self.refinement, "blocks": self.blocks.tolist()}

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(Grid.from_dict(data["base"]), data["refinement"], data["blocks"])
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"malformed adaptive grid: {exc}") from exc


@numba.njit(cache=True, nogil=True)
def _cells_near(here, radius, refinement, shape, periodic, index, fine_box, base_box):
    """:meth:`AdaptiveGrid.cells_near` of a point ``here`` in fine steps from
    the lattice's low corner: the fine lattice points ``round(here) +
    fine_box`` and the base points of the blocks ``floor(here / refinement)
    + base_box`` that are cells (``index``: the cells' fine flat indices,
    ascending), within ``max(radius, refinement * sqrt(ndim))`` fine steps,
    nearest first, ties in cell order, each cell once."""
    d = here.size
    reach = fine_box[-1, 0]
    limit = max(radius, refinement * math.sqrt(d))
    centre = np.rint(here).astype(np.int64)
    block = np.floor(here / refinement).astype(np.int64)
    n_fine = fine_box.shape[0]
    cells = np.empty(n_fine + base_box.shape[0], np.int64)
    distance = np.empty(cells.size)
    point = np.empty(d, np.int64)
    count = 0
    for k in range(cells.size):
        outside = k < n_fine
        for a in range(d):
            point[a] = (centre[a] + fine_box[k, a] if k < n_fine
                        else (block[a] + base_box[k - n_fine, a]) * refinement)
            # A base point inside the fine box is one of its points already.
            outside = outside or abs(point[a] - centre[a]) > reach
        squared, flat, inside = 0.0, 0, outside
        for a in range(d):
            squared += (point[a] - here[a]) ** 2
            i = point[a]
            if periodic[a]:
                i %= shape[a]
            elif i < 0 or i >= shape[a]:
                inside = False
            flat = flat * shape[a] + i
        if not inside or math.sqrt(squared) > limit:
            continue
        at = min(np.searchsorted(index, flat), index.size - 1)
        if index[at] == flat:
            cells[count], distance[count] = at, math.sqrt(squared)
            count += 1
    cells, distance = cells[:count], distance[:count]
    # A cell met on both sides of a seam is listed once, where nearest.
    by_distance = np.argsort(distance, kind="mergesort")
    by_cell = by_distance[np.argsort(cells[by_distance], kind="mergesort")]
    nearest = np.zeros(count, np.bool_)
    for k in range(count):
        nearest[by_cell[k]] = k == 0 or cells[by_cell[k]] != cells[by_cell[k - 1]]
    order = by_cell[np.argsort(distance[by_cell], kind="mergesort")]
    return cells[order[nearest[order]]]


@numba.njit(cache=True, nogil=True)
def _axis_pairs(index, rank, stride, length, refinement, periodic):
    """Each cell and the next cell along an axis within a base step, and their
    distance in fine steps: ``(lower, upper, gap)``.

    ``index`` holds the cells' fine flat indices, ``rank`` maps fine flat
    indices to cells (-1 none), ``stride`` and ``length`` are the axis's on
    the fine lattice; along a ``periodic`` axis the next cell after the
    last lattice point is looked for from the first on."""
    upper = np.full(index.size, -1, dtype=np.int64)
    gap = np.zeros(index.size, dtype=np.int64)
    for cell in range(index.size):
        position = (index[cell] // stride) % length
        start = index[cell] - position * stride
        reach = refinement if periodic else min(refinement, length - 1 - position)
        # Nearest first: the nearest next cell along the line wins.
        for step in range(1, reach + 1):
            other = rank[start + ((position + step) % length) * stride]
            if other >= 0:
                upper[cell], gap[cell] = other, step
                break
    lower = np.flatnonzero(upper >= 0)
    return lower, upper[lower], gap[lower]


def block_shape(base):
    """Blocks along each axis of a base grid: one fewer than its points, as
    many along a periodic axis (module doc)."""
    return tuple(n if a.periodic else n - 1 for n, a in zip(base.shape, base.axes))


def _corner_sums(boxes, periodic):
    """For every corner point of an array of boxes, how many of the boxes
    around it are set; shape ``boxes.shape + 1`` on every axis but the
    ``periodic`` ones, whose boxes wrap."""
    out = np.zeros(tuple(n if p else n + 1 for n, p in zip(boxes.shape, periodic)))
    for corner in itertools.product((0, 1), repeat=boxes.ndim):
        moved = boxes
        for axis in np.flatnonzero(periodic):
            moved = np.roll(moved, corner[axis], axis=axis)
        out[tuple(slice(None) if p else slice(c, c + n)
                  for c, n, p in zip(corner, boxes.shape, periodic))] += moved
    return out


def _corner_view(values, corner, periodic, blocks):
    """``values`` (one per base point or edge) at one corner of every block,
    shape ``blocks``: the next point along the axes where ``corner`` is 1,
    wrapped along the ``periodic`` ones."""
    for axis in np.flatnonzero(periodic):
        values = np.roll(values, -corner[axis], axis=axis)
    return values[tuple(slice(0, n) if p else slice(c, c + n)
                        for c, n, p in zip(corner, blocks, periodic))]


def grid_from_dict(data):
    """A :class:`~rpr3_gwr_core.workspace.grid.Grid` or an :class:`AdaptiveGrid`
    from its ``to_dict`` form."""
    if isinstance(data, dict) and data.get("kind") == "adaptive":
        return AdaptiveGrid.from_dict(data)
    return Grid.from_dict(data)


def coarse_base(grid, refinement=DEFAULT_REFINEMENT):
    """The base grid whose refinement by ``refinement`` has the lattice of
    ``grid``: the base for :func:`refine` (or ``cached_roadmap(...,
    refinement=...)``) of a mechanism file's whole box, periodic axes
    included.

    Parameters
    ----------
    grid : Grid
        The fine lattice: along each periodic axis a multiple of
        ``refinement`` cells, along each other axis one more than a multiple.
    refinement : int
        Fine points per base step, at least 2.

    Returns
    -------
    Grid
        Its steps ``refinement`` times the grid's, same ranges and fixed joints.

    Raises
    ------
    InvalidInputError
        If ``grid`` is not a :class:`~.grid.Grid`, ``refinement`` is not an
        integer >= 2 or an axis' cells do not divide as above.

    Examples
    --------
    The 3-RRR's turns of 120 cells (``config/three_rrr.yaml``) from base
    turns of 40:

    >>> import math
    >>> turn = Axis(0, -math.pi, math.pi - 2 * math.pi / 120, 2 * math.pi / 120, periodic=True)
    >>> coarse_base(Grid(axes=(turn,)), 3).shape
    (40,)
    """
    if not isinstance(grid, Grid):
        raise InvalidInputError(f"coarse_base takes a Grid, got {type(grid).__name__}")
    if (isinstance(refinement, bool) or not isinstance(refinement, numbers.Integral)
            or refinement < 2):
        raise InvalidInputError(f"refinement is an integer >= 2, got {refinement!r}")
    r = int(refinement)
    axes = []
    for a in grid.axes:
        steps = a.count if a.periodic else a.count - 1
        if steps % r:
            raise InvalidInputError(
                f"joint {a.joint}'s {a.count} cells do not refine {r} times from a base grid: "
                f"{'they' if a.periodic else 'their steps'} must be a multiple of {r}")
        axes.append(Axis(a.joint, a.low, a.low + a.step * (steps - r if a.periodic else steps),
                         a.step * r, a.periodic))
    return Grid(axes=tuple(axes), fixed=grid.fixed)


def refine(mechanism, base, refinement=DEFAULT_REFINEMENT, min_margin=DEFAULT_REFINE_MARGIN, *,
           max_cells=MAX_GRID_CELLS, progress=None, workers=map):
    """The adaptive grid of a base grid under the refinement rule (module doc).

    Parameters
    ----------
    mechanism : Mechanism
    base : Grid
        At least two points per axis.
    refinement : int
        Fine points per base step, at least 2.
    min_margin : float
        Rule 3's margin, non-negative.
    max_cells : int, optional
        Most cells of the adaptive grid (:class:`AdaptiveGrid`).
    progress : callable, optional
        Called as ``progress(stage, fraction)`` (the stage's name, the
        fraction of the work done) as the base field is solved and each
        axis' edges are checked.

    workers : callable, optional
        A map-like callable, ``workers(function, iterable)`` yielding the
        results in order, such as ``ThreadPoolExecutor.map``: the base grid's field is solved
        with it (:func:`~.field.compute_field`).  The
        default, the builtin ``map``, works in the calling thread.

    Returns
    -------
    AdaptiveGrid

    Raises
    ------
    InvalidInputError
        If an argument is malformed.
    GridSizeError
        If the grid would have more than ``max_cells`` cells, or its fine
        lattice too many points.

    Examples
    --------
    A coarse slice at rho1 = 17 refined four times near the singular curve:

    >>> from rpr3_gwr_core import PAPER_GEOMETRY, rho1_slice
    >>> grid = refine(PAPER_GEOMETRY, rho1_slice(17.0, (10.0, 20.0), (10.0, 20.0), 1.0))
    >>> grid.steps, grid.blocks.size < 100, grid.size > 121
    ((0.25, 0.25), True, True)
    """
    if not isinstance(base, Grid):
        raise InvalidInputError(f"refine takes a Grid, got {type(base).__name__}")
    if not (math.isfinite(min_margin) and min_margin >= 0):
        raise InvalidInputError(f"min_margin must be finite and >= 0, got {min_margin}")
    # Validates before the field is computed.
    AdaptiveGrid(base, refinement, (), max_cells=max_cells)
    report = part(progress, within="refinement")
    field = compute_field(mechanism, base, progress=part(report, 0.0, 0.6, "base grid"),
                          workers=workers)
    shape = base.shape
    blocks = block_shape(base)
    periodic = np.array([a.periodic for a in base.axes])
    count = field.count.reshape(shape).astype(np.int16)
    weakest = np.min(np.where(field.valid, np.abs(field.margin), np.inf), axis=1).reshape(shape)
    uniform = np.ones(blocks, dtype=bool)
    corners = list(itertools.product((0, 1), repeat=base.ndim))
    first = _corner_view(count, corners[0], periodic, blocks)
    for corner in corners:
        uniform &= ((_corner_view(count, corner, periodic, blocks) == first)
                    & (_corner_view(weakest, corner, periodic, blocks) >= min_margin))
    pairs = base.pairs()
    for axis, (lower, upper) in enumerate(pairs):
        report("continuity along the blocks' edges", 0.6 + 0.4 * axis / len(pairs))
        match = match_solutions(field, lower, upper)
        continues = ((field.count[lower] == field.count[upper])
                     & np.all((match >= 0) == field.valid[lower], axis=1))
        inner = tuple(n - 1 if k == axis else n for k, n in enumerate(shape))
        edges = continues[:math.prod(inner)].reshape(inner)
        if periodic[axis]:
            # The grid's pairs across the seam come last: edge i joins base
            # points i and i + 1 along the axis, the last one the first.
            seam = continues[math.prod(inner):].reshape(
                tuple(1 if k == axis else n for k, n in enumerate(shape)))
            edges = np.concatenate([edges, seam], axis=axis)
        for corner in corners:
            if corner[axis]:
                continue
            uniform &= _corner_view(edges, corner, periodic, blocks)
    grid = AdaptiveGrid(base, refinement, np.flatnonzero(~uniform.ravel()), max_cells=max_cells)
    report("blocks picked", 1.0)
    return grid
