"""Whether straight joint segments stay on a patch, or cross given patches in
order, keeping a margin: the test behind the planner's shortcuts and corner
cuts, and the greedy shortcutting that asks it, compiled because a plan
asks it for hundreds of segments."""

from typing import NamedTuple

import numba
import numpy as np

from ..workspace.grid import lattice_point_cell, lattice_points

__all__ = ["Sheets", "segments_clear", "shortcut_path"]


class Sheets(NamedTuple):
    """The roadmap's solution sheets as the segment tests read them.

    Attributes
    ----------
    lattice : tuple
        The grid's :attr:`~rpr3_gwr_core.workspace.grid.GridBase.lattice`.
    step : float
        The grid's smallest step [joint unit].
    samples_per_step : int
        Samples per grid step of a segment's longest axis change (2 at least).
    patch_of : ndarray of int, shape (n_cells, max_solutions)
        Patch of each solution (the segmentation's ``patch``).
    margin : ndarray, shape (n_cells, max_solutions)
        Signed margin of each solution (the field's).
    poses : ndarray, shape (n_cells, max_solutions, pose_size)
        Pose of each solution (the field's).
    angle_scale : ndarray, shape (pose_size,)
        For each pose coordinate, 0 when it is a length, else the
        mechanism's scale: angles are compared modulo 2 pi, as arc lengths.
    """

    lattice: tuple
    step: float
    samples_per_step: int
    patch_of: np.ndarray
    margin: np.ndarray
    poses: np.ndarray
    angle_scale: np.ndarray


@numba.njit(cache=True, nogil=True)
def segments_clear(starts, ends, patches, floors, sheets):
    """Sample each segment and check its points' cells.

    Parameters
    ----------
    starts, ends : ndarray, shape (m, ndim)
        Segment ends in the grid's axis coordinates [joint unit].
    patches : ndarray of int, shape (m,)
        The patch each segment must stay on.
    floors : ndarray, shape (m,)
        The margin magnitude each segment must keep.
    sheets : Sheets

    Returns
    -------
    ndarray of bool, shape (m,)
        Whether every sample lies in a cell where the segment's patch has a
        solution with a margin magnitude of at least its floor.
    """
    out = np.empty(starts.shape[0], dtype=np.bool_)
    point = np.empty(starts.shape[1])
    route = np.empty(1, np.int64)
    for s in range(starts.shape[0]):
        route[0] = patches[s]
        out[s] = _clear_through(starts[s], ends[s], route, floors[s], sheets, point)
    return out


@numba.njit(cache=True, nogil=True)
def shortcut_path(points, patches, margins, clearance, split, sheets, max_passes=3):
    """Greedy shortcutting of a waypoint path by straight segments that pass
    :func:`segments_clear`.

    From each kept waypoint, the longest jump is tried first, then halved
    ones (O(log n) tests per waypoint), for up to ``max_passes`` passes
    over the kept waypoints.  A jump must cross the patches of the
    waypoints it replaces in their order, each where it likes (it may cut
    across a gate elsewhere than the cell path did, since the sheet goes on
    across the whole gate), and keep ``min(clearance, the least positive
    margin of the waypoints it replaces)``: no less than the cell path kept
    there.

    Parameters
    ----------
    points : ndarray, shape (n, ndim)
        Waypoints in the grid's axis coordinates [joint unit].
    patches : ndarray of int, shape (n,)
        Patch of each waypoint.
    margins : ndarray, shape (n,)
        Margin magnitude of each waypoint's solution, 0 where unknown.
    clearance : float
    split : bool
        Whether the jump from the first waypoint straight to the last is
        refused (a repair of that very jump).
    sheets : Sheets

    Returns
    -------
    ndarray of int64
        Indices of the kept waypoints, first and last included.
    """
    n = points.shape[0]
    lowest = np.empty(n)
    point = np.empty(points.shape[1])
    keep = np.arange(n)
    kept = n
    for _ in range(max_passes):
        changed = False
        out = np.empty(kept, np.int64)
        out[0] = keep[0]
        count = 1
        i = 0
        while i < kept - 1:
            a = keep[i]
            reach = 1
            jump = kept - 1 - i
            # Least positive margin from waypoint a up to each later one.
            least = np.inf
            for j in range(a, keep[i + jump] + 1):
                if margins[j] > 0:
                    least = min(least, margins[j])
                lowest[j] = least
            while jump > 1:
                b = keep[i + jump]
                if (not (split and a == 0 and b == n - 1)
                        and _clear_through(points[a], points[b], patches[a:b + 1],
                                           min(clearance, lowest[b]), sheets, point)):
                    reach = jump
                    changed = True
                    break
                jump //= 2
            i += reach
            out[count] = keep[i]
            count += 1
        keep = out[:count]
        kept = count
        if not changed:
            break
    return keep


@numba.njit(cache=True)
def _clear_through(a, b, route, floor, sheets, point):
    """Whether the segment from ``a`` to ``b`` keeps to the patches of
    ``route`` (the waypoints' patches, repeats allowed), entering them in
    order, each sample on the current one or on the next, with a margin
    magnitude of at least ``floor``; ``point`` is work space.

    A patch may border the next across several gates, and a cell of the
    next patch's region may hold the next patch's solution and others: a
    step onto the next patch counts only where its solution is the one
    nearest the current patch's solution at the previous sample, the sheet
    the platform goes on along."""
    low, steps, shape, index, base_steps, refinement, periods = sheets.lattice
    span = np.max(np.abs(b - a)) / sheets.step
    count = max(2, int(span * sheets.samples_per_step) + 1)
    at = 0
    previous, previous_slot = -1, -1
    # Samples run several to a cell: a cell's lookup, a search of the
    # lattice's index, is made once per run of them.
    cell, flat, base = -1, -1, -1
    for n in range(count):
        t = n / (count - 1)
        point[:] = a * (1 - t) + b * t
        here, here_base = lattice_points(point, low, steps, shape, base_steps, refinement,
                                         periods)
        if here < 0:
            return False
        if here != flat or here_base != base:
            flat, base = here, here_base
            cell = lattice_point_cell(flat, base, index)
        slot = _slot(sheets, cell, route[at], floor)
        if slot < 0:
            following = at
            while following < route.size and route[following] == route[at]:
                following += 1
            if following == route.size or previous < 0:
                return False
            slot = _slot(sheets, cell, route[following], floor)
            if slot < 0 or _nearest(sheets, cell, sheets.poses[previous, previous_slot]) != slot:
                return False
            at = following
        previous, previous_slot = cell, slot
    for k in range(at, route.size):
        if route[k] != route[at]:
            return False
    return True


@numba.njit(cache=True)
def _slot(sheets, cell, patch, floor):
    """Slot of the patch's solution in a cell if its margin magnitude is at
    least ``floor``, else -1."""
    cell_patches = sheets.patch_of[cell]
    for slot in range(cell_patches.size):
        if cell_patches[slot] == patch:
            return slot if abs(sheets.margin[cell, slot]) >= floor else -1
    return -1


@numba.njit(cache=True)
def _nearest(sheets, cell, pose):
    """Slot of the cell's solution nearest to a pose (angles as arcs)."""
    best, nearest = np.inf, -1
    for slot in range(sheets.patch_of.shape[1]):
        if np.isnan(sheets.poses[cell, slot, 0]):
            continue  # past the cell's solutions
        distance = 0.0
        for k in range(pose.size):
            d = sheets.poses[cell, slot, k] - pose[k]
            if sheets.angle_scale[k] > 0:
                d = (np.pi - np.remainder(np.pi - d, 2 * np.pi)) * sheets.angle_scale[k]
            distance += d * d
        if distance < best:
            best, nearest = distance, slot
    return nearest
