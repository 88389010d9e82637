"""Whether straight joint segments stay on a patch, keeping a margin: the
test behind the planner's shortcuts and corner cuts, compiled because a
plan asks it for hundreds of segments."""

import numba
import numpy as np

from ..workspace.grid import lattice_cell

__all__ = ["segments_clear"]


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
    low, steps, shape, index, base_steps, refinement = lattice
    out = np.ones(starts.shape[0], dtype=np.bool_)
    point = np.empty(starts.shape[1])
    for s in range(starts.shape[0]):
        a, b = starts[s], ends[s]
        span = np.max(np.abs(b - a)) / step
        count = max(2, int(span * samples_per_step) + 1)
        for n in range(count):
            t = n / (count - 1)
            point[:] = a * (1 - t) + b * t
            cell = lattice_cell(point, low, steps, shape, index, base_steps, refinement)
            if cell < 0 or not _keeps(patch_of[cell], margin[cell], patches[s], floors[s]):
                out[s] = False
                break
    return out


@numba.njit(cache=True)
def _keeps(cell_patches, cell_margins, patch, floor):
    for slot in range(cell_patches.size):
        if cell_patches[slot] == patch:
            return abs(cell_margins[slot]) >= floor
    return False
