"""Regions, workspace patches, gates and singular boundaries of a field.

Definitions (paper sections 2 to 4):

* A *region* is a maximal set of 4-connected cells with the same number of
  solutions whose solutions all continue from cell to cell
  (:mod:`~rpr3_gwr_core.continuity`).  Regions are numbered 1..R by
  decreasing volume (on a uniform grid: number of cells; ties: lowest first
  cell), which reproduces the numbering of the paper's figure 6.
* Unresolved cells.  Right on the singular locus a straight step between two
  cells can cross a fold and come back, and a sliver of the field thinner
  than a cell (a fold pair that is real over a tongue narrower than the step)
  shows up as isolated cells; either way a few cells form connected sets of
  one or two cells.  Rule: a connected set of fewer than ``min_region_cells``
  cells (default 8, far below the 100-cell smallest region of the paper's
  case) is no region: its cells get region 0.
* A *patch* is one solution sheet over a region: the solutions of the region's
  cells connected by continuation.  Its layers are numbered 1..n in the
  mechanism's order of the solutions at the region's first cell (lowest flat
  index; for the 3-RPR, by orientation alpha) after the sheets are sorted by
  aspect, negative first.  Its id is ``region * 10**k + layer`` with ``k``
  the number of digits of the mechanism's most solutions (``10 * region +
  layer`` for the 3-RPR's six), so ids never clash; the data model does not
  decode them: a :class:`Patch` carries its region and layer.
* Sheets that do not come back to themselves.  Over the full 3-DOF space a
  region's solutions can be exchanged by going around a loop inside it (the
  4-solution region of the 3-RPR's [1, 50] x [0, 50]**2 box does: a single
  connected sheet covers each of its cells twice).  Such a region is cut into
  one patch per solution of its first cell, each solution carried to the
  other cells along a breadth-first tree of the region; the faces where the
  tree's branches meet with exchanged solutions become gates between the
  region's own patches, so no connection is lost.  Uniform slices at fixed
  rho1 have no such region.
* Only the ill-conditioned solutions of unresolved cells are dropped: a set of
  their solutions connected by continuation joins the patch it continues
  into (the one it has most links with; ties: lowest id), since its sheet is
  that patch's sheet, unless the patch already covers one of its cells (then
  the next patch it continues into; sets are taken best-conditioned first);
  a set that continues into no patch (the fold pair of a sliver, which
  vanishes on every side) belongs to no patch, so no path is planned through
  it.  A patch may therefore hold a few cells of region 0.
* A *gate* joins two patches whose solutions continue into each other across
  a face; a patch's *singular boundary* is the set of its faces through which
  its solution does not continue (it vanishes into a fold, or into the
  dropped solutions above).  Faces on the edge of the grid are neither.

Patches are defined by the rotary disk search (``method="rds"``,
:mod:`~rpr3_gwr_core.rotary_disk`).  The default ``method="components"``
labels the same connected sets with a union-find over the links
(:mod:`~rpr3_gwr_core.workspace.components`) and is tested to give identical
patches, gates and boundaries.
"""

from dataclasses import dataclass, field as dataclass_field
import functools

import numba
import numpy as np
import scipy.sparse as sparse
from scipy.sparse.csgraph import breadth_first_order

from ..exceptions import InvalidInputError
from .progress import part
from .components import connected_labels
from .continuity import match_solutions
from .rotary_disk import passage_from_links, rotary_disk_search

__all__ = ["Patch", "Gate", "Segmentation", "segment", "linked_solutions", "TABLE_TYPES"]

METHODS = ("components", "rds")

# The little-endian dtypes of :meth:`Segmentation.tables`, by name.
TABLE_TYPES = {"patch_ids": "<i8", "patch_region": "<i8", "patch_layer": "<i8",
               "patch_aspect": "<i8", "patch_solutions": "<i8", "patch_starts": "<i8",
               "patch_cells": "<i8", "patch_slots": "<i8", "patch_gate": "|b1",
               "patch_singular": "|b1", "gate_patches": "<i8", "gate_width": "<f8",
               "gate_starts": "<i8", "gate_faces": "<i8"}


@dataclass(frozen=True, eq=False, repr=False)
class Patch:
    """One workspace patch.

    Attributes
    ----------
    id : int
        ``region * 10**k + layer`` (module doc).
    region, layer : int
    aspect : int
        ``sign(det Jx)`` shared by all its solutions, +1 or -1.
    n_solutions : int
        Number of solutions of its region's cells.
    cells : ndarray of int, shape (k,)
        Flat indices of its cells, ascending.
    slots : ndarray of int, shape (k,)
        Which solution (index into the field's sorted solutions) of each cell.
    gate_cells : ndarray of int
        Its cells with a face that is a gate.
    singular_cells : ndarray of int
        Its cells with a face on its singular boundary.
    """

    id: int
    region: int
    layer: int
    aspect: int
    n_solutions: int
    cells: np.ndarray
    slots: np.ndarray
    gate_cells: np.ndarray = dataclass_field(default_factory=lambda: np.zeros(0, int))
    singular_cells: np.ndarray = dataclass_field(default_factory=lambda: np.zeros(0, int))

    def __repr__(self):
        return (f"Patch({self.id}: region {self.region}, layer {self.layer}, "
                f"aspect {self.aspect:+d}, {self.n_solutions} solutions, "
                f"{self.cells.size} cells, {self.gate_cells.size} on gates, "
                f"{self.singular_cells.size} on its singular boundary)")


@dataclass(frozen=True, eq=False, repr=False)
class Gate:
    """The faces through which two patches continue into each other.

    Attributes
    ----------
    patches : tuple of int
        The two patch ids, ascending.
    faces : ndarray of int, shape (k, 2)
        Crossing faces as ``(cell of patches[0], cell of patches[1])``.
    width : float
        Total measure of its faces: their number times the step for 2-D
        grids [joint unit**(d - 1)].
    """

    patches: tuple
    faces: np.ndarray
    width: float

    def __repr__(self):
        a, b = self.patches
        return f"Gate({a} - {b}: {len(self.faces)} faces, width {self.width:.4g})"


@dataclass(frozen=True, eq=False, repr=False)
class Segmentation:
    """Regions, patches and gates of an n-solution field.

    Attributes
    ----------
    field : NSolutionField
    region : ndarray of int32, shape (n_cells,)
        Region id of each cell, 0 for none (no solution, or unresolved).
    patch : ndarray of int32, shape (n_cells, max_solutions)
        Patch id of each solution of each cell, 0 for none.
    patches : dict of int to Patch
    gates : dict of (int, int) to Gate
    matches : list of ndarray of int8, shape (n_faces_of_axis, max_solutions)
        Per grid axis, the continuation links of the faces in the order of
        the grid's ``pairs()``
        (:func:`~rpr3_gwr_core.workspace.continuity.match_solutions`).
    """

    field: object
    region: np.ndarray
    patch: np.ndarray
    patches: dict
    gates: dict
    matches: list

    def __repr__(self):
        mechanism = self.field.mechanism
        return (f"Segmentation({self.n_regions} regions, {len(self.patches)} patches, "
                f"{len(self.gates)} gates; {mechanism.kind}, "
                f"{self.field.grid.describe(mechanism.joint_names)})")

    @property
    def n_regions(self):
        """Number of regions R."""
        return int(self.region.max(initial=0))

    @property
    def id_base(self):
        """The factor of the region in a patch id: ``id = id_base * region +
        layer`` (module doc)."""
        return _id_base(self.field)

    @functools.cached_property
    def links(self):
        """Per grid axis, the face-adjacent cells ``(lower, upper)`` and
        :attr:`matches`: list of (ndarray, ndarray, ndarray).

        Raises
        ------
        InvalidInputError
            If the matches do not fit the grid's faces.
        """
        # Paired on first use: a loaded roadmap plans without them, and the
        # pairs of a large adaptive grid take a third of a second.
        pairs = self.field.grid.pairs()
        _check_matches(self.field, pairs, self.matches)
        return [(lo, up, m) for (lo, up), m in zip(pairs, self.matches)]

    @classmethod
    def from_arrays(cls, field, region, patch, links):
        """The segmentation of a field from its region, patch and link arrays.

        :func:`segment` ends here, and so does every decoder (JSON, ROS
        messages): patches, gates and boundaries are derived from the arrays
        alone, so a roadmap travels as those arrays.

        Parameters
        ----------
        field : NSolutionField
        region : ndarray of int, shape (n_cells,)
        patch : ndarray of int, shape (n_cells, max_solutions)
        links : list of ndarray of int8, shape (n_faces_of_axis, max_solutions)
            Per axis, the continuation links of the faces in the order of
            the grid's ``pairs()``.

        Raises
        ------
        InvalidInputError
            If the arrays do not fit the field's grid, a link names no slot
            or a patch id is negative or past the regions'.
        """
        pairs = field.grid.pairs()
        _check_matches(field, pairs, links)
        region, patch, matches = _checked_arrays(field, region, patch, links, copy=True)
        links = [(lo, up, m) for (lo, up), m in zip(pairs, matches)]
        tally = _tally_faces(field, patch, links)
        segmentation = cls(field=field, region=region, patch=patch,
                           patches=_describe_patches(field, region, patch, *tally[:3]),
                           gates=_gates(field, tally[3]), matches=matches)
        # The pairs are at hand: the cached property need not take them again.
        segmentation.__dict__["links"] = links
        return segmentation

    def tables(self):
        """Its patches and gates as flat arrays, by name (dtypes in
        :data:`TABLE_TYPES`), from which :meth:`from_tables` rebuilds them
        without deriving anything: per patch (ascending ids) its id, region,
        layer, aspect and number of solutions, and ``patch_starts`` into the
        concatenated ``patch_cells``, ``patch_slots`` and flags
        ``patch_gate`` and ``patch_singular`` (the cell is one of its gate or
        singular cells); per gate (ascending pairs) its patches, width, and
        ``gate_starts`` into the concatenated ``gate_faces``.

        Returns
        -------
        dict of str to ndarray
        """
        patches = [self.patches[pid] for pid in sorted(self.patches)]
        gates = [self.gates[key] for key in sorted(self.gates)]
        return {
            "patch_ids": np.array([p.id for p in patches], dtype=np.int64),
            "patch_region": np.array([p.region for p in patches], dtype=np.int64),
            "patch_layer": np.array([p.layer for p in patches], dtype=np.int64),
            "patch_aspect": np.array([p.aspect for p in patches], dtype=np.int64),
            "patch_solutions": np.array([p.n_solutions for p in patches], dtype=np.int64),
            "patch_starts": _starts([p.cells.size for p in patches]),
            "patch_cells": _joined([p.cells for p in patches], np.int64),
            "patch_slots": _joined([p.slots for p in patches], np.int64),
            "patch_gate": _joined([np.isin(p.cells, p.gate_cells) for p in patches], np.bool_),
            "patch_singular": _joined([np.isin(p.cells, p.singular_cells) for p in patches],
                                      np.bool_),
            "gate_patches": np.array([g.patches for g in gates], dtype=np.int64).reshape(-1, 2),
            "gate_width": np.array([g.width for g in gates], dtype=np.float64),
            "gate_starts": _starts([len(g.faces) for g in gates]),
            "gate_faces": _joined([np.reshape(g.faces, (-1, 2)) for g in gates], np.int64,
                                  (0, 2)),
        }

    @classmethod
    def from_tables(cls, field, region, patch, matches, tables, check=True):
        """The segmentation :meth:`tables` describes, its patches' and
        gates' arrays views of ``tables``.

        What a stored roadmap loads instead of :meth:`from_arrays`: the
        tables are checked against the arrays (each patch solution is one
        the ``patch`` array gives that patch, every one is listed, faces
        join cells of their gate's patches), not derived again.

        Parameters
        ----------
        field : NSolutionField
        region, patch, matches
            As :meth:`from_arrays` takes them (``matches`` its ``links``);
            ``region`` and ``patch`` are kept, not copied, when they are
            int32 already (a stored roadmap's mapped arrays).
        tables : dict of str to ndarray
            :meth:`tables`.
        check : bool
            Check the values of the arrays and tables; only their shapes
            and dtypes when False, for arrays and tables whose values were
            checked before (a cache entry's, unchanged since its first load).

        Raises
        ------
        InvalidInputError
            If the arrays do not fit the grid or the tables do not describe
            the arrays' patches.
        """
        region, patch, matches = _checked_arrays(field, region, patch, matches, copy=False,
                                                 check_values=check)
        t = _checked_tables(field, region, patch, tables, check_values=check)
        starts, cells, slots = t["patch_starts"], t["patch_cells"], t["patch_slots"]
        patches = {}
        for k, pid in enumerate(t["patch_ids"].tolist()):
            part = slice(starts[k], starts[k + 1])
            own = cells[part]
            patches[pid] = Patch(
                id=pid, region=int(t["patch_region"][k]), layer=int(t["patch_layer"][k]),
                aspect=int(t["patch_aspect"][k]), n_solutions=int(t["patch_solutions"][k]),
                cells=own, slots=slots[part], gate_cells=own[t["patch_gate"][part]],
                singular_cells=own[t["patch_singular"][part]])
        bounds, faces = t["gate_starts"], t["gate_faces"]
        gates = {}
        for k, (a, b) in enumerate(t["gate_patches"].tolist()):
            gates[(a, b)] = Gate(patches=(a, b), faces=faces[bounds[k]:bounds[k + 1]],
                                 width=float(t["gate_width"][k]))
        return cls(field=field, region=region, patch=patch, patches=patches, gates=gates,
                   matches=matches)


def _starts(sizes):
    starts = np.zeros(len(sizes) + 1, dtype=np.int64)
    starts[1:] = np.cumsum(sizes)
    return starts


def _joined(parts, dtype, empty_shape=(0,)):
    return np.concatenate(parts).astype(dtype, copy=False) if parts else np.zeros(empty_shape,
                                                                                 dtype)


def _check_matches(field, pairs, matches):
    """That ``matches`` hold one array per axis of ``pairs``, a row per face."""
    slots = field.max_solutions
    if len(matches) != len(pairs) or any(np.shape(m) != (lo.size, slots)
                                         for m, (lo, _) in zip(matches, pairs)):
        raise InvalidInputError("region, patch and link arrays do not fit the field's grid")


def _checked_arrays(field, region, patch, matches, copy, check_values=True):
    """``region`` and ``patch`` as int32 (copies, or with ``copy=False`` the
    arrays themselves when int32 already) and ``matches`` as int8 arrays,
    checked as :meth:`Segmentation.from_arrays` documents (the matches'
    shapes aside; their shapes only, without ``check_values``)."""
    n, slots = field.grid.size, field.max_solutions
    region = np.asarray(region)
    patch = np.asarray(patch)
    if region.shape != (n,) or patch.shape != (n, slots) or any(
            np.ndim(m) != 2 or np.shape(m)[1] != slots for m in matches):
        raise InvalidInputError("region, patch and link arrays do not fit the field's grid")
    matches = [np.asarray(m, dtype=np.int8) for m in matches]
    region, patch = region.astype(np.int32, copy=copy), patch.astype(np.int32, copy=copy)
    if not check_values:
        return region, patch, matches
    # The compiled passes index by slot and by id unchecked: links must
    # name slots, and ids be what the module doc makes them, below the
    # next region's first id.
    if any(m.size and (m.min() < -1 or m.max() >= slots) for m in matches):
        raise InvalidInputError("links must be -1 or a solution slot")
    if patch.size and (patch.min() < 0 or patch.max() >= _id_base(field) * (
            int(region.max(initial=0)) + 1)):
        raise InvalidInputError("patch ids must be region * 10**k + layer of the regions")
    return region, patch, matches


def _checked_tables(field, region, patch, tables, check_values=True):
    """The tables of :meth:`Segmentation.from_tables`, checked against the
    arrays (their shapes and dtypes only, without ``check_values``); raises
    InvalidInputError naming what fails."""
    try:
        t = {name: np.asarray(tables[name]) for name in TABLE_TYPES}
    except KeyError as exc:
        raise InvalidInputError(f"the segmentation tables lack {exc}") from None
    n, slots = patch.shape
    n_patches, n_gates, n_entries = (t["patch_ids"].size, t["gate_width"].size,
                                     t["patch_cells"].size)
    shapes = dict.fromkeys(("patch_ids", "patch_region", "patch_layer", "patch_aspect",
                            "patch_solutions"), (n_patches,))
    shapes.update(dict.fromkeys(("patch_cells", "patch_slots", "patch_gate",
                                 "patch_singular"), (n_entries,)))
    shapes.update(patch_starts=(n_patches + 1,), gate_patches=(n_gates, 2),
                  gate_width=(n_gates,), gate_starts=(n_gates + 1,),
                  gate_faces=(t["gate_faces"].size // 2, 2))
    if any(t[name].shape != shape or t[name].dtype != np.dtype(TABLE_TYPES[name])
           for name, shape in shapes.items()):
        raise InvalidInputError("the segmentation tables' shapes or dtypes do not fit")
    if not check_values:
        return t
    ids, starts, cells, cell_slots = (t["patch_ids"], t["patch_starts"], t["patch_cells"],
                                      t["patch_slots"])
    if np.any(np.diff(ids) <= 0) or starts[0] != 0 or starts[-1] != n_entries \
            or np.any(np.diff(starts) <= 0) or n_entries != np.count_nonzero(patch):
        raise InvalidInputError("the patch table does not list each patch solution once")
    if n_entries and (cells.min() < 0 or cells.max() >= n or cell_slots.min() < 0
                      or cell_slots.max() >= slots):
        raise InvalidInputError("the patch table names cells or slots outside the grid")
    owner = np.repeat(np.arange(n_patches), np.diff(starts))
    if not np.array_equal(patch[cells, cell_slots], ids[owner]):
        raise InvalidInputError("the patch table differs from the patch array")
    ascending = np.diff(cells) > 0
    ascending[starts[1:-1] - 1] = True
    if not ascending.all():
        raise InvalidInputError("the patch table's cells do not ascend within each patch")
    # The module doc's rules: the id from region and layer, the region the
    # largest of its cells', the solutions' number that of the region's first
    # cell, the aspect that of its first solution.
    own = region[cells]
    in_own = np.flatnonzero(own == t["patch_region"][owner])
    first = np.searchsorted(in_own, starts[:-1])
    if n_patches and (
            np.any(first >= in_own.size)
            or np.any(owner[in_own[np.minimum(first, in_own.size - 1)]] != np.arange(n_patches))):
        raise InvalidInputError("the patch table's regions differ from the arrays'")
    first = in_own[first]
    if n_patches and (
            np.any(ids != _id_base(field) * t["patch_region"] + t["patch_layer"])
            or np.any(t["patch_layer"] < 1) or np.any(t["patch_layer"] >= _id_base(field))
            or not np.array_equal(np.maximum.reduceat(own, starts[:-1]), t["patch_region"])
            or not np.array_equal(field.count[cells[first]], t["patch_solutions"])
            or not np.array_equal(np.sign(field.margin[cells[starts[:-1]],
                                                       cell_slots[starts[:-1]]]),
                                  t["patch_aspect"])):
        raise InvalidInputError("the patch table's regions, layers, solutions or aspects "
                                "differ from the arrays'")
    pairs, bounds, faces = t["gate_patches"], t["gate_starts"], t["gate_faces"]
    if bounds[0] != 0 or bounds[-1] != len(faces) or np.any(np.diff(bounds) <= 0) \
            or np.any(pairs[:, 0] >= pairs[:, 1]) or not np.all(np.isin(pairs, ids)) \
            or not np.all(t["gate_width"] > 0) or not np.all(np.isfinite(t["gate_width"])):
        raise InvalidInputError("the gate table does not list gates between patches")
    if faces.size and (faces.min() < 0 or faces.max() >= n):
        raise InvalidInputError("the gate table names cells outside the grid")
    # A patch's gate cells are its cells on its gates' faces; as its entries
    # are checked above, so is that each face joins cells of its gate's
    # patches.  The entries ascend by patch and cell: the flagged keys come
    # sorted and distinct.
    sides = np.repeat(pairs, np.diff(bounds), axis=0)
    on_faces = np.sort(np.searchsorted(ids, sides.ravel()) * n + faces.ravel())
    on_faces = on_faces[np.diff(on_faces, prepend=-1) != 0]
    flagged = owner[t["patch_gate"]] * n + cells[t["patch_gate"]]
    if not np.array_equal(on_faces, flagged):
        raise InvalidInputError("the gate table's faces and the patch table's gate cells "
                                "differ")
    return t


def segment(field, method="components", min_region_cells=8, *, progress=None, workers=map):
    """Split a field into regions, patches and gates.

    Parameters
    ----------
    field : NSolutionField
    method : {"components", "rds"}
        How connected patches are found; both give the same result.
    min_region_cells : int
        Connected same-count sets smaller than this are singular locus.
    progress : callable, optional
        Called as ``progress(stage, fraction)`` (the stage's name, the
        fraction of the work done) between stages.

    workers : callable, optional
        A map-like callable, ``workers(function, iterable)`` yielding the
        results in order, such as ``ThreadPoolExecutor.map``: the solutions are
        matched across the faces of each axis, and the links inside regions
        picked, with it, the axes in parallel with a thread pool's (numpy and
        the compiled loops release the interpreter's lock).  The default, the
        builtin ``map``, works in the calling thread.

    Returns
    -------
    Segmentation
    """
    if method not in METHODS:
        raise InvalidInputError(f"method must be one of {METHODS}, got {method!r}")
    if int(min_region_cells) < 1:
        raise InvalidInputError("min_region_cells must be at least 1")
    report = part(progress)
    report("continuity across faces", 0.0)

    def match_axis(pair):
        match = match_solutions(field, *pair)
        # What the later stages take of each axis is taken here, the axes in parallel.
        return match, linked_solutions(*pair, match), _full_faces(*pair, match, field.count)

    matches, linked, full_faces = zip(*workers(match_axis, field.grid.pairs()))
    report("regions", 0.7)
    region = _regions(field, full_faces, int(min_region_cells))
    report("patches", 0.75)
    disk_links = _within_region_links(field, region, linked, workers)
    n_disks = field.grid.size * field.max_solutions
    valid = (field.valid & (region[:, None] > 0)).ravel()
    if method == "rds":
        component = _components_by_rds(valid, disk_links, field.grid.ndim)
    else:
        component = np.where(valid, connected_labels(n_disks, disk_links), -1)
    patch = _absorb_unresolved(
        field, region, _number_patches(field, region, component, disk_links, full_faces), linked)
    report("gates and singular boundaries", 0.9)
    segmentation = Segmentation.from_arrays(field, region, patch, list(matches))
    report("gates and singular boundaries", 1.0)
    return segmentation


def _regions(field, full_faces, min_cells):
    """Region of every cell from the faces inside regions (:func:`_full_faces`
    of each axis)."""
    n = field.grid.size
    label = connected_labels(n, full_faces)
    occupied = field.count > 0
    sizes = np.bincount(label[occupied], minlength=label.max() + 1)
    volumes = np.bincount(label[occupied], weights=field.grid.cell_volumes()[occupied],
                          minlength=sizes.size)
    first = np.full(sizes.size, n)
    np.minimum.at(first, label[occupied], np.flatnonzero(occupied))
    kept = np.flatnonzero(sizes >= min_cells)
    kept = kept[np.lexsort((first[kept], -volumes[kept]))]
    renumber = np.zeros(sizes.size, dtype=np.int32)
    renumber[kept] = np.arange(1, kept.size + 1)
    return np.where(occupied, renumber[label], 0).astype(np.int32)


@numba.njit(cache=True, nogil=True)
def _full_faces(lower, upper, match, count):
    """The faces, ``(lower, upper)`` cells, between two cells of as many
    solutions, every one of which continues across: the faces inside regions."""
    keep = np.zeros(lower.size, dtype=np.bool_)
    for k in range(lower.size):
        n = count[lower[k]]
        if n == 0 or count[upper[k]] != n:
            continue
        linked = 0
        for i in range(match.shape[1]):
            linked += match[k, i] >= 0
        keep[k] = linked == n
    return lower[keep], upper[keep]


@numba.njit(cache=True, nogil=True)
def linked_solutions(lower, upper, match):
    """The solutions one axis's links join (:attr:`Segmentation.links`), as
    disks ``cell * max_solutions + slot``.

    Returns
    -------
    lower, upper : ndarray of int64
        The joined disks, face by face, slot by slot.
    """
    width = match.shape[1]
    total = 0
    for k in range(match.shape[0]):
        for i in range(width):
            total += match[k, i] >= 0
    a = np.empty(total, dtype=np.int64)
    b = np.empty(total, dtype=np.int64)
    j = 0
    for k in range(match.shape[0]):
        for i in range(width):
            if match[k, i] >= 0:
                a[j] = lower[k] * width + i
                b[j] = upper[k] * width + match[k, i]
                j += 1
    return a, b


def _within_region_links(field, region, linked, workers=map):
    """Per axis, the (lower, upper) disks linked inside one region."""
    return list(workers(lambda pair: _inside_regions(*pair, region, field.max_solutions),
                        linked))


@numba.njit(cache=True, nogil=True)
def _inside_regions(lower, upper, region, width):
    """The links of disks ``lower[k]`` and ``upper[k]`` (``cell * width +
    slot``) whose cells are of one region."""
    keep = np.empty(lower.size, dtype=np.bool_)
    for k in range(lower.size):
        r = region[lower[k] // width]
        keep[k] = r > 0 and r == region[upper[k] // width]
    return lower[keep], upper[keep]


def _components_by_rds(valid, disk_links, dimension):
    passage = passage_from_links(valid.size, disk_links)
    component = np.full(valid.size, -1, dtype=np.int64)
    n = 0
    for disk in np.flatnonzero(valid):
        if component[disk] >= 0:
            continue
        visited, _ = rotary_disk_search(int(disk), passage, dimension)
        component[visited] = n
        n += 1
    return component


def _number_patches(field, region, component, disk_links, full_faces):
    """Patch id of every disk from its component label (rule in module doc)."""
    component = component.reshape(field.grid.size, field.max_solutions)
    aspect = field.aspect
    base = _id_base(field)
    first, sheets = _region_sheets(region, component)
    # Component labels of the regions' disks are distinct (links stay inside
    # a region), so one table from label to patch id numbers every disk.
    patch_of_label = {}
    for r in range(1, first.size):
        reference = first[r]
        if sheets[r] < field.count[reference]:
            component = _cut_sheets(field, np.flatnonzero(region == r), component, disk_links,
                                    full_faces)
        # Every sheet of a region covers each of its cells, the first one too:
        # a sheet is known there by its first slot.
        slot_of_label = {}
        for slot in range(field.count[reference]):
            slot_of_label.setdefault(int(component[reference, slot]), slot)
        order = sorted(slot_of_label, key=lambda label: (aspect[reference, slot_of_label[label]],
                                                          slot_of_label[label]))
        for layer, label in enumerate(order, start=1):
            patch_of_label[label] = base * r + layer
    table = np.zeros(int(component.max(initial=-1)) + 2, dtype=np.int32)
    table[np.fromiter(patch_of_label, dtype=np.int64) + 1] = list(patch_of_label.values())
    return table[component + 1]


@numba.njit(cache=True, nogil=True)
def _region_sheets(region, component):
    """Each region's first cell and number of distinct component labels
    (sheets) among its disks, indexed by region (entry 0 unused)."""
    first = np.full(region.max() + 1, -1, dtype=np.int64)
    sheets = np.zeros(first.size, dtype=np.int64)
    seen = np.zeros(component.max() + 1, dtype=np.bool_)
    for cell in range(region.size):
        r = region[cell]
        if r == 0:
            continue
        if first[r] < 0:
            first[r] = cell
        for slot in range(component.shape[1]):
            label = component[cell, slot]
            if label >= 0 and not seen[label]:
                seen[label] = True
                sheets[r] += 1
    return first, sheets


def _id_base(field):
    """``10**k`` of the patch ids (module doc)."""
    return 10 ** len(str(field.max_solutions))


def _cut_sheets(field, cells, component, disk_links, full_faces):
    """Relabel the disks of a region whose sheets do not come back to
    themselves around a loop (rule in module doc): one label per disk of its
    first cell, carried along a breadth-first tree of its cells."""
    n = field.max_solutions
    size = field.grid.size
    member = np.zeros(size, dtype=bool)
    member[cells] = True
    # The tree follows faces across which every solution continues (those
    # that make the region), so each of its edges carries every label.
    lower, upper = (np.concatenate(side) for side in zip(*full_faces))
    inside = member[lower]
    lower, upper = lower[inside], upper[inside]
    cell_graph = sparse.coo_matrix((np.ones(lower.size, dtype=np.int8),
                                    (np.minimum(lower, upper), np.maximum(lower, upper))),
                                   shape=(size, size)).tocsr()
    _, parent = breadth_first_order(cell_graph, int(cells[0]), directed=False)
    label = connected_labels(size * n, [_tree_links(a, b, parent, n) for a, b in disk_links])
    out = component.copy()
    disks = (cells[:, None] * n + np.arange(n)).ravel()
    valid = field.valid[cells].ravel()
    # Fresh labels, past every label in use, so no other region's sheet is met.
    out.ravel()[disks[valid]] = component.max() + 1 + label[disks[valid]]
    return out


@numba.njit(cache=True, nogil=True)
def _tree_links(lower, upper, parent, width):
    """The links of disks ``lower[k]`` and ``upper[k]`` (``cell * width +
    slot``) across a face of a tree of cells: one cell is the other's
    ``parent`` (scipy's predecessors, negative at the root and off the tree)."""
    keep = np.empty(lower.size, dtype=np.bool_)
    for k in range(lower.size):
        a, b = lower[k] // width, upper[k] // width
        keep[k] = parent[a] == b or parent[b] == a
    return lower[keep], upper[keep]


def _absorb_unresolved(field, region, patch, linked):
    """Patch ids for the solutions of unresolved cells (rule in module doc)."""
    unresolved = (field.valid & (region[:, None] == 0)).ravel()
    if not unresolved.any():
        return patch
    n = field.max_solutions
    # The few links that touch them, of the millions.
    a, b = (np.concatenate(side) for side in zip(*(_touching(lower, upper, unresolved)
                                                    for lower, upper in linked)))
    inner = unresolved[a] & unresolved[b]
    label = connected_labels(patch.size, [(a[inner], b[inner])])
    edge = unresolved[a] != unresolved[b]
    source = np.where(unresolved[a[edge]], a[edge], b[edge])
    target = patch.ravel()[np.where(unresolved[a[edge]], b[edge], a[edge])]
    known = target > 0
    votes, counts = np.unique(np.stack([label[source[known]], target[known]], axis=1), axis=0,
                              return_counts=True)
    out = patch.copy()
    margin = np.abs(field.margin).ravel()
    disks = np.flatnonzero(unresolved)
    candidates = {}
    for (set_label, pid), links_to in zip(votes.tolist(), counts.tolist()):
        candidates.setdefault(set_label, []).append((-links_to, pid))
    # Where a sheet folds over itself (an S-shaped sliver), two sets continue
    # into one patch over the same cells; a patch covers a cell once, so the
    # better-conditioned set joins it first and the other tries its next patch.
    sets = {k: disks[label[disks] == k] for k in candidates}
    for set_label in sorted(sets, key=lambda k: (-margin[sets[k]].min(), k)):
        cells, slots = np.divmod(sets[set_label], n)
        if np.unique(cells).size != cells.size:
            continue
        for _, pid in sorted(candidates[set_label]):
            if not np.any(out[cells] == pid):
                out[cells, slots] = pid
                break
    return out


@numba.njit(cache=True, nogil=True)
def _touching(lower, upper, disks):
    """The links of disks ``lower[k]`` and ``upper[k]`` of which one is marked in ``disks``."""
    keep = np.empty(lower.size, dtype=np.bool_)
    for k in range(lower.size):
        keep[k] = disks[lower[k]] or disks[upper[k]]
    return lower[keep], upper[keep]


def _tally_faces(field, patch, links):
    """Each cell's number of faces, each patch solution's number of links into
    a patch and whether one of them is a gate, and the gate crossings
    (:func:`_tally_axis`) of all axes, in axis order."""
    n, width = patch.shape
    faces = np.zeros(n, dtype=np.int64)
    continued = np.zeros((n, width), dtype=np.int64)
    on_gate = np.zeros((n, width), dtype=np.bool_)
    crossings = [_tally_axis(lo, up, match, patch, faces, continued, on_gate)
                 for lo, up, match in links]
    return faces, continued, on_gate, crossings


@numba.njit(cache=True, nogil=True)
def _tally_axis(lower, upper, match, patch, faces, continued, on_gate):
    """Add one axis's faces to ``faces``, its links between patch solutions to
    ``continued`` and mark ``on_gate`` those between two patches; returns
    these crossings, face by face, slot by slot, as rows ``(face, lower cell,
    upper cell, lower patch, upper patch)``."""
    crossings = 0
    for k in range(match.shape[0]):
        lo, up = lower[k], upper[k]
        faces[lo] += 1
        faces[up] += 1
        for i in range(match.shape[1]):
            j, a, b = _patch_link(match, patch, lo, up, k, i)
            if j < 0:
                continue
            continued[lo, i] += 1
            continued[up, j] += 1
            if a != b:
                on_gate[lo, i] = True
                on_gate[up, j] = True
                crossings += 1
    # Counted first and then written: an array that grew inside the loop
    # would cost its references at every step.
    out = np.empty((crossings, 5), dtype=np.int64)
    used = 0
    for k in range(match.shape[0]):
        lo, up = lower[k], upper[k]
        for i in range(match.shape[1]):
            j, a, b = _patch_link(match, patch, lo, up, k, i)
            if j >= 0 and a != b:
                out[used, 0], out[used, 1], out[used, 2] = k, lo, up
                out[used, 3], out[used, 4] = a, b
                used += 1
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def _patch_link(match, patch, lo, up, k, i):
    """``(j, a, b)``: the slot j that solution i of cell ``lo`` continues into
    across face k, and the patches a and b of the two; j is -1 unless both
    are patch solutions."""
    j = match[k, i]
    if j < 0 or patch[lo, i] <= 0 or patch[up, j] <= 0:
        return -1, 0, 0
    return j, patch[lo, i], patch[up, j]


@numba.njit(cache=True, nogil=True)
def _group_patches(patch, region, valid, margin, faces, continued, on_gate):
    """The solutions of each patch id present, ascending: ``(ids, starts,
    cells, slots, gate, singular, aspect, mixed, own, first_own)``.

    Patch ``k`` owns entries ``starts[k]:starts[k + 1]`` of ``cells`` (in
    ascending order), ``slots`` and the flags ``gate`` and ``singular``; its
    aspect is the sign of its first solution's margin, ``mixed`` whether
    another has another sign, ``own`` its largest region and ``first_own``
    its first cell of that region."""
    n, width = patch.shape
    count = np.zeros(patch.max() + 1, dtype=np.int64)
    for c in range(n):
        for s in range(width):
            count[patch[c, s]] += 1
    count[0] = 0
    ids = np.flatnonzero(count)
    starts = np.zeros(ids.size + 1, dtype=np.int64)
    starts[1:] = np.cumsum(count[ids])
    cursor = np.zeros(count.size, dtype=np.int64)
    cursor[ids] = starts[:-1]
    total = starts[-1]
    cells = np.empty(total, dtype=np.int64)
    slots = np.empty(total, dtype=np.int64)
    gate = np.empty(total, dtype=np.bool_)
    singular = np.empty(total, dtype=np.bool_)
    # Indexed by id until the end.
    aspect = np.zeros(count.size, dtype=np.int64)
    mixed = np.zeros(count.size, dtype=np.bool_)
    own = np.full(count.size, -1, dtype=np.int64)
    first_own = np.zeros(count.size, dtype=np.int64)
    for c in range(n):
        for s in range(width):
            p = patch[c, s]
            if p == 0:
                continue
            sign = 1 if margin[c, s] > 0 else (-1 if margin[c, s] < 0 else 0)
            if own[p] < 0:
                aspect[p] = sign
            elif sign != aspect[p]:
                mixed[p] = True
            if region[c] > own[p]:
                own[p], first_own[p] = region[c], c
            j = cursor[p]
            cursor[p] += 1
            cells[j], slots[j], gate[j] = c, s, on_gate[c, s]
            # On its singular boundary where one of its cell's faces does not
            # continue it into a patch.
            singular[j] = valid[c, s] and continued[c, s] < faces[c]
    return (ids, starts, cells, slots, gate, singular, aspect[ids], mixed[ids], own[ids],
            first_own[ids])


def _describe_patches(field, region, patch, faces, continued, on_gate):
    ids, starts, cells_all, slots_all, gate, singular, aspect, mixed, own, first_own = (
        _group_patches(patch, region, field.valid, field.margin, faces, continued, on_gate))
    patches = {}
    layers = {}
    for k, pid in enumerate(ids.tolist()):
        part = slice(starts[k], starts[k + 1])
        cells, slots = cells_all[part], slots_all[part]
        if mixed[k]:
            aspects = np.unique(np.sign(field.margin[cells, slots]).astype(int))
            raise InvalidInputError(f"patch {pid} mixes aspects {aspects}")
        # Its own cells share its region; cells it took from unresolved sets have 0.
        layers.setdefault(int(own[k]), []).append(pid)
        patches[pid] = Patch(
            id=pid, region=int(own[k]), layer=len(layers[int(own[k])]), aspect=int(aspect[k]),
            n_solutions=int(field.count[first_own[k]]), cells=cells, slots=slots,
            gate_cells=cells[gate[part]], singular_cells=cells[singular[part]])
    return patches


def _gates(field, crossings):
    """Gates from the crossings of :func:`_tally_faces`."""
    measure = np.concatenate([measures[rows] for measures, rows in
                              zip(field.grid.face_measures(), (c[:, 0] for c in crossings))])
    _, ca, cb, a, b = np.concatenate(crossings).T
    swap = a > b
    first, second = np.where(swap, b, a), np.where(swap, a, b)
    cells_first, cells_second = np.where(swap, cb, ca), np.where(swap, ca, cb)
    top = int(second.max(initial=0)) + 1
    key = first * top + second
    # Grouped by gate, each gate's faces ascending.
    order = np.lexsort((cells_second, cells_first, key))
    head = np.ones(key.size, dtype=bool)
    head[1:] = key[order][1:] != key[order][:-1]
    keys = key[order][head]
    gate = np.empty(key.size, dtype=np.int64)
    gate[order] = np.cumsum(head) - 1
    # Summed in the order the faces were met, as a running sum would.
    widths = np.bincount(gate, weights=measure, minlength=len(keys))
    faces = np.split(np.stack([cells_first, cells_second], axis=1)[order],
                     np.flatnonzero(head)[1:])
    return {(int(k // top), int(k % top)): Gate(patches=(int(k // top), int(k % top)), faces=f,
                                                width=float(w))
            for k, f, w in zip(keys.tolist(), faces, widths)}
