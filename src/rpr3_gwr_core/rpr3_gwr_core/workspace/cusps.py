"""Cusp points of the singular curve of a 2-D roadmap (paper section 1: the
3-RPR changes assembly mode around them, figure 13).

At a cusp three direct-kinematic solutions merge.  Seeds come from the
field: in cells near a cusp, three solutions of mixed aspect lie close
together (two fold pairs meeting), and the closer they are, the nearer the
cusp.  The seeds are thinned so that one cluster of
cells gives one seed, and each is refined by the mechanism's Newton on its
pose equations (:meth:`~rpr3_gwr_core.mechanisms.Mechanism.refine_cusp`).

Across a family of slices (rho1 varying, for the 3-RPR) the cusps trace
curves: :func:`cusp_curves` follows each from slice to slice by Newton from
its last pose, in substeps, and matches it to the next slice's own cusps.
"""

from dataclasses import dataclass
import itertools

import numba
import numpy as np

from ..exceptions import InvalidInputError, OutOfGridError
from .adaptive import AdaptiveGrid
from .progress import part

__all__ = ["Cusp", "find_cusps", "known_cusps", "cusp_curves"]

# One seed per ball of this many grid steps, the closest triples first.
_SEED_SPACING = 8.0
_MAX_SEEDS = 48
# Two refined cusps closer than this (relative to the scale) are one.
_SAME_CUSP = 1e-6
# Regions whose cells lie within this many steps of a cusp meet there.
_REGION_REACH = 8


@dataclass(frozen=True, repr=False)
class Cusp:
    """A cusp point of a slice's singular curve.

    Attributes
    ----------
    joints : ndarray, shape (n_joints,)
    pose : ndarray, shape (pose_size,)
        The pose where the three solutions merge.
    regions : tuple of int
        The regions of the cells around it.
    """

    joints: np.ndarray
    pose: np.ndarray
    regions: tuple

    def __repr__(self):
        def values(array):
            return ", ".join(f"{v:.6g}" for v in np.asarray(array).tolist())

        return (f"Cusp(joints ({values(self.joints)}), pose ({values(self.pose)}), "
                f"regions {', '.join(map(str, self.regions)) or 'none'})")

    def to_dict(self, mechanism):
        """Plain data: joints and pose by name, and the regions."""
        return {**{n: float(v) for n, v in zip(mechanism.joint_names, self.joints)},
                **{n: float(v) for n, v in zip(mechanism.pose_names, self.pose)},
                "regions": list(self.regions)}


def find_cusps(roadmap):
    """The cusp points of a 2-D roadmap's singular curve inside its grid.

    Parameters
    ----------
    roadmap : Roadmap
        On a grid of two axes.

    Returns
    -------
    list of Cusp
        Sorted by their joints.

    Raises
    ------
    InvalidInputError
        If the grid does not have two axes.
    """
    grid, field = roadmap.grid, roadmap.field
    mechanism = field.mechanism
    if grid.ndim != 2:
        raise InvalidInputError(f"cusps are points of 2-D slices, the grid has {grid.ndim} axes")
    fixed = dict(grid.fixed)
    found = []
    coordinates = None
    for seed in _seeds(field):
        refined = mechanism.refine_cusp(seed, fixed)
        if refined is None:
            continue
        pose, joints = refined
        try:
            cell = grid.cell_of(joints)
        except OutOfGridError:
            continue
        if any(np.max(np.abs(joints - c.joints)) < _SAME_CUSP * mechanism.scale for c in found):
            continue
        if coordinates is None:
            coordinates = grid.coordinates_of(np.arange(grid.size))
        found.append(Cusp(joints=joints, pose=pose,
                          regions=_regions_around(roadmap, coordinates, cell)))
    return sorted(found, key=lambda c: tuple(c.joints))


def known_cusps(roadmap):
    """:func:`find_cusps`, or ``[]`` where the grid is no 2-D slice or the
    mechanism has no cusp equations for it."""
    try:
        return find_cusps(roadmap)
    except (InvalidInputError, NotImplementedError):
        return []


def cusp_curves(roadmaps, substeps=4, *, progress=None):
    """Cusp curves across slices that differ in the value of one fixed joint.

    Parameters
    ----------
    roadmaps : sequence of Roadmap
        2-D roadmaps of one mechanism on grids with the same axes and fixed
        joints, one fixed joint's value increasing from one to the next.
    substeps : int
        Newton continuations between two slices, at least 1.
    progress : callable, optional
        Called as ``progress(stage, fraction)`` (the stage's name, the
        fraction of the work done) as each slice is done.

    Returns
    -------
    list of list of Cusp
        Each curve is the cusps it passes through, one per slice, from the
        first slice it appears in; a cusp no curve continues into starts a
        new one.  Curves are ordered by their first slice, then joints.

    Raises
    ------
    InvalidInputError
        If the slices do not differ in exactly one fixed joint.
    """
    if not roadmaps:
        return []
    grids = [r.grid for r in roadmaps]
    joints = {j for g in grids for j, _ in g.fixed}
    moving = [j for j in sorted(joints)
              if len({dict(g.fixed).get(j) for g in grids}) == len(grids)]
    if (len(moving) != 1 or any(g.axes != grids[0].axes for g in grids)
            or any(g.fixed_value(moving[0]) <= h.fixed_value(moving[0])
                   for h, g in zip(grids, grids[1:]))):
        raise InvalidInputError("cusp curves need slices with the same axes whose one moving "
                                "fixed joint increases")
    if int(substeps) < 1:
        raise InvalidInputError("substeps must be at least 1")
    joint = moving[0]
    mechanism = roadmaps[0].mechanism
    report = part(progress)
    curves, open_curves = [], []
    for k, roadmap in enumerate(roadmaps):
        report("cusps of each slice", k / len(roadmaps))
        fresh = find_cusps(roadmap)
        taken = set()
        still_open = []
        for curve in open_curves:
            pose = _continue(mechanism, curve[-1], grids[k - 1], grids[k], joint, int(substeps))
            match = None if pose is None else _nearest(fresh, pose, mechanism, taken)
            if match is not None:
                taken.add(match)
                curve.append(fresh[match])
                still_open.append(curve)
        for i, cusp in enumerate(fresh):
            if i not in taken:
                curve = [cusp]
                curves.append(curve)
                still_open.append(curve)
        open_curves = still_open
    report("cusps of each slice", 1.0)
    return curves


def _continue(mechanism, cusp, grid_from, grid_to, joint, substeps):
    """A cusp's pose carried by Newton from one slice's value to the next's."""
    fixed = dict(grid_from.fixed)
    start, end = grid_from.fixed_value(joint), grid_to.fixed_value(joint)
    pose = cusp.pose
    for s in range(1, substeps + 1):
        fixed[joint] = start + (end - start) * s / substeps
        refined = mechanism.refine_cusp(pose, fixed)
        if refined is None:
            return None
        pose = refined[0]
    return pose


def _nearest(cusps, pose, mechanism, taken):
    """Index of the cusp whose pose is ``pose`` (Newton converged onto it)."""
    for i, cusp in enumerate(cusps):
        if i not in taken and mechanism.pose_distance(cusp.pose, pose) < (
                1e-6 * mechanism.scale):
            return i
    return None


def _seeds(field):
    """Poses of close triples of solutions of mixed aspect, one per cluster of
    cells, closest triples first.  A triple is a solution and its two
    nearest in pose (not in the solutions' order: at a degenerate
    orientation of the 3-RPR a fourth solution shares the orientation)."""
    mechanism, grid = field.mechanism, field.grid
    cells = np.flatnonzero(field.count >= 3)
    poses, aspect = field.poses[cells], field.aspect[cells]
    # Slot pair by slot pair: all pairs at once would broadcast the poses
    # into copies a hundred times their size.
    slots = field.max_solutions
    distance = np.full((cells.size, slots, slots), np.inf)
    for i, j in itertools.permutations(range(slots), 2):
        distance[:, i, j] = mechanism.pose_distance(poses[:, i], poses[:, j])
    distance = np.where(np.isnan(distance), np.inf, distance)
    nearest = np.argsort(distance, axis=2)[:, :, :2]
    rows = np.arange(cells.size)[:, None]
    j, k = nearest[..., 0], nearest[..., 1]
    spread = np.maximum(np.take_along_axis(distance, nearest, axis=2).max(axis=2),
                        distance[rows, j, k])
    mixed = np.abs(aspect + np.take_along_axis(aspect, j, axis=1)
                   + np.take_along_axis(aspect, k, axis=1)) == 1
    row, slot = np.nonzero(mixed & np.isfinite(spread))
    order = np.argsort(spread[row, slot], kind="stable")
    row, slot = row[order], slot[order]
    for k in _spaced(grid.coordinates_of(cells[row]), _SEED_SPACING * grid.step, _MAX_SEEDS):
        yield poses[row[k], slot[k]]


@numba.njit(cache=True, nogil=True)
def _spaced(points, spacing, most):
    """Indices of the first ``most`` of ``points`` (n, d), taken in order,
    each farther than ``spacing`` along some axis from every one taken before."""
    taken = np.empty(most, dtype=np.int64)
    n_taken = 0
    for i in range(points.shape[0]):
        if n_taken == most:
            break
        near = False
        for t in range(n_taken):
            j = taken[t]
            near = True
            for axis in range(points.shape[1]):
                if abs(points[i, axis] - points[j, axis]) > spacing:
                    near = False
                    break
            if near:
                break
        if not near:
            taken[n_taken] = i
            n_taken += 1
    return taken[:n_taken]


def _regions_around(roadmap, coordinates, cell):
    """The regions of the cells within ``_REGION_REACH`` steps of ``cell``
    along each axis (steps of the base grid of an adaptive one), from the
    cells' ``coordinates``."""
    grid = roadmap.grid
    steps = np.asarray((grid.base if isinstance(grid, AdaptiveGrid) else grid).steps)
    near = np.all(np.abs(coordinates - coordinates[cell]) <= (_REGION_REACH + 0.5) * steps,
                  axis=1)
    regions = roadmap.segmentation.region[near]
    return tuple(int(r) for r in np.unique(regions[regions > 0]))
