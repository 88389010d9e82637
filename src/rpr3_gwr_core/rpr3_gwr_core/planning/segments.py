"""Whether straight joint segments stay on a patch, keeping a margin: the
test behind the planner's shortcuts and corner cuts, and the greedy
shortcutting that asks it, compiled because a plan asks it for hundreds of
segments."""

import numba
import numpy as np

from ..workspace.grid import lattice_cell

__all__ = ["segments_clear", "shortcut_path"]


@numba.njit(cache=True, nogil=True)
def segments_clear(starts, ends, patches, floors, samples_per_step, step, lattice, patch_of,
                   margin):
    """Sample each segment and check its points' cells.

    Parameters
    ----------
    starts, ends : ndarray, shape (m, ndim)
        Segment ends in the grid's axis coordinates [joint unit].
    patches : ndarray of int, shape (m,)
        The patch each segment must stay on.
    floors : ndarray, shape (m,)
        The margin magnitude each segment must keep.
    samples_per_step : int
        Samples per grid step of a segment's longest axis change (2 at least).
    step : float
        The grid's smallest step [joint unit].
    lattice : tuple
        The grid's :attr:`~rpr3_gwr_core.workspace.grid.GridBase.lattice`.
    patch_of : ndarray of int, shape (n_cells, max_solutions)
        Patch of each solution (the segmentation's ``patch``).
    margin : ndarray, shape (n_cells, max_solutions)
        Signed margin of each solution (the field's).

    Returns
    -------
    ndarray of bool, shape (m,)
        Whether every sample lies in a cell where the segment's patch has a
        solution with a margin magnitude of at least its floor.
    """
    out = np.empty(starts.shape[0], dtype=np.bool_)
    point = np.empty(starts.shape[1])
    for s in range(starts.shape[0]):
        out[s] = _clear(starts[s], ends[s], patches[s], floors[s], samples_per_step, step,
                        lattice, patch_of, margin, point)
    return out


@numba.njit(cache=True, nogil=True)
def shortcut_path(points, patches, margins, clearance, split, samples_per_step, step, lattice,
                  patch_of, margin, max_passes=3):
    """Greedy shortcutting of a waypoint path by straight segments that pass
    :func:`segments_clear`.

    From each kept waypoint, the longest jump is tried first, then halved
    ones (O(log n) tests per waypoint), for up to ``max_passes`` passes
    over the kept waypoints.  A jump from waypoint i must stay within i's
    run of waypoints on one patch (gate crossings stay in place) and keep
    ``min(clearance, the least positive margin of the waypoints it
    replaces)``: no less than the cell path kept there.

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
    samples_per_step, step, lattice, patch_of, margin :
        As for :func:`segments_clear`.

    Returns
    -------
    ndarray of int64
        Indices of the kept waypoints, first and last included.
    """
    n = points.shape[0]
    run_end = np.empty(n, np.int64)
    run_end[n - 1] = n - 1
    for i in range(n - 2, -1, -1):
        run_end[i] = run_end[i + 1] if patches[i] == patches[i + 1] else i
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
            for j in range(a, min(keep[i + jump], run_end[a]) + 1):
                if margins[j] > 0:
                    least = min(least, margins[j])
                lowest[j] = least
            while jump > 1:
                b = keep[i + jump]
                if (b <= run_end[a] and not (split and a == 0 and b == n - 1)
                        and _clear(points[a], points[b], patches[a],
                                   min(clearance, lowest[b]), samples_per_step, step, lattice,
                                   patch_of, margin, point)):
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
def _clear(a, b, patch, floor, samples_per_step, step, lattice, patch_of, margin, point):
    """Whether the segment from ``a`` to ``b`` passes (:func:`segments_clear`);
    ``point`` is work space."""
    low, steps, shape, index, base_steps, refinement, periods = lattice
    span = np.max(np.abs(b - a)) / step
    count = max(2, int(span * samples_per_step) + 1)
    for n in range(count):
        t = n / (count - 1)
        point[:] = a * (1 - t) + b * t
        cell = lattice_cell(point, low, steps, shape, index, base_steps, refinement, periods)
        if cell < 0 or not _keeps(patch_of[cell], margin[cell], patch, floor):
            return False
    return True


@numba.njit(cache=True)
def _keeps(cell_patches, cell_margins, patch, floor):
    for slot in range(cell_patches.size):
        if cell_patches[slot] == patch:
            return abs(cell_margins[slot]) >= floor
    return False
