"""Thin regions refined until the grid settles what they join.

A region of the singularity-free set narrower than a cell shows on a grid as
a strip one to three cells wide that ends where it narrows below a cell; a
way along it, between regions that the grid keeps apart, is missed.  A thin
region is a patch without a gate (a region of one patch) at least half of
whose base blocks (those its cells lie in) are on its border: a face of the
block leads to a block it does not reach.  Measured in base blocks, a strip
is as thin after a round of refinement as before.  Large regions with no
gate (the five-bar's working modes, each a whole torus but a band) are not
thin, and a region that is not thin is left as the grid has it.

:func:`refine_thin_regions` builds the roadmap, refines the base grid's
blocks within ``reach`` blocks of every cell of a thin region, and builds
again, until no thin region asks for a block not yet refined: as a strip is
refined, more of it is found, and the next round follows it further.  The
finest cell is the grid's step over ``refinement``.  A grid without thin
regions is built once and returned as it is, so roadmaps that have none (the
mechanism files' default slices) are the same bit for bit.
"""

import dataclasses
import numbers

import numpy as np

from ..exceptions import GridSizeError, InvalidInputError
from .adaptive import AdaptiveGrid, block_shape
from .grid import MAX_GRID_CELLS, Grid
from .progress import part
from .roadmap import build_roadmap

__all__ = ["ThinRefinement", "thin_patches", "refine_thin_regions", "DEFAULT_THIN_REFINEMENT",
           "DEFAULT_THIN_REACH", "DEFAULT_THIN_ROUNDS"]

# Fine points per base step where a thin region is refined: the finest cell
# is a quarter of the grid's.
DEFAULT_THIN_REFINEMENT = 4
# Base blocks refined around each cell of a thin region, along every axis:
# two reach past the cell that a sub-cell strip leaves from.
DEFAULT_THIN_REACH = 2
# Most rebuilds, each following a strip a few blocks further.
DEFAULT_THIN_ROUNDS = 24
# Share of a patch's base blocks on its border from which it is thin.
_THIN_BORDER_SHARE = 0.5


@dataclasses.dataclass(frozen=True)
class ThinRefinement:
    """What :func:`refine_thin_regions` did.

    Attributes
    ----------
    rounds : int
        Roadmaps built after the first.
    refined_blocks : int
        Base blocks refined.
    thin_left : tuple of int
        Patches of the returned roadmap still thin: where a finer cell than
        the finest allowed may still join them to another region.
    stopped : {"settled", "rounds", "cells"}
        Why it stopped: no thin region asked for a new block, the rounds ran
        out, or the next grid would have had more than ``max_cells`` cells.
    """

    rounds: int
    refined_blocks: int
    thin_left: tuple
    stopped: str


def thin_patches(roadmap):
    """The patches of a roadmap that are thin regions (module doc).

    Parameters
    ----------
    roadmap : Roadmap

    Returns
    -------
    list of int
        Patch ids, ascending.
    """
    seg = roadmap.segmentation
    base = _base_of(roadmap.grid)
    gated = {pid for pair in seg.gates for pid in pair}
    thin = []
    for pid in sorted(seg.patches):
        if pid in gated:
            continue
        at, shape, periodic = _base_blocks(roadmap.grid, base, seg.patches[pid].cells)
        taken = np.unique(np.ravel_multi_index(tuple(at.T), shape))
        inner = np.ones(taken.size, dtype=bool)
        blocks = np.array(np.unravel_index(taken, shape)).T
        for axis in range(base.ndim):
            for side in (-1, 1):
                beside = blocks.copy()
                beside[:, axis] += side
                if periodic[axis]:
                    beside[:, axis] %= shape[axis]
                inside = (beside[:, axis] >= 0) & (beside[:, axis] < shape[axis])
                flat = np.ravel_multi_index(tuple(np.where(inside[:, None], beside, 0).T), shape)
                inner &= inside & np.isin(flat, taken)
        if np.count_nonzero(~inner) >= _THIN_BORDER_SHARE * taken.size:
            thin.append(pid)
    return thin


def refine_thin_regions(mechanism, grid, refinement=DEFAULT_THIN_REFINEMENT,
                        reach=DEFAULT_THIN_REACH, max_rounds=DEFAULT_THIN_ROUNDS, *,
                        max_cells=MAX_GRID_CELLS, progress=None, workers=map, **build_options):
    """Build a roadmap with its thin regions refined (module doc).

    Parameters
    ----------
    mechanism : Mechanism
    grid : Grid or AdaptiveGrid
        A uniform grid, refined ``refinement`` times in the blocks that ask
        for it, or an adaptive one, whose blocks are added to at its own
        refinement (``refinement`` is then not used).
    refinement : int
        Fine points per base step in a refined block, at least 2.
    reach : int
        Blocks refined around each cell of a thin region, along each axis,
        at least 1.
    max_rounds : int
        Most roadmaps built after the first, at least 0.
    max_cells : int, optional
        Most cells of a refined grid.
    progress : callable, optional
        Called as ``progress(stage, fraction)`` through each build.
    workers : callable, optional
        A map-like callable, as :func:`~.roadmap.build_roadmap`'s.
    **build_options
        More arguments of :func:`~.roadmap.build_roadmap`.

    Returns
    -------
    roadmap : Roadmap
    report : ThinRefinement

    Raises
    ------
    InvalidInputError
        If an argument is malformed, or the errors of
        :func:`~.roadmap.build_roadmap`.
    """
    if isinstance(grid, AdaptiveGrid):
        base, refinement, blocks = grid.base, grid.refinement, set(grid.blocks.tolist())
    elif isinstance(grid, Grid):
        base, blocks = grid, set()
    else:
        raise InvalidInputError(f"refine_thin_regions takes a Grid or an AdaptiveGrid, got "
                                f"{type(grid).__name__}")
    for name, value, least in (("refinement", refinement, 2), ("reach", reach, 1),
                               ("max_rounds", max_rounds, 0)):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
            raise InvalidInputError(f"{name} must be an integer >= {least}, got {value!r}")
    if (isinstance(max_cells, bool) or not isinstance(max_cells, numbers.Integral)
            or not 0 < max_cells <= MAX_GRID_CELLS):
        raise InvalidInputError(f"max_cells is an integer in [1, {MAX_GRID_CELLS}], got "
                                f"{max_cells!r}")
    # The first build is most of the work when nothing is thin; round k
    # starts halfway through what the rounds before it left.
    roadmap = build_roadmap(mechanism, grid, progress=part(progress, 0.0, 0.9),
                            workers=workers, **build_options)
    report = part(progress)
    rounds = 0
    while True:
        thin = thin_patches(roadmap)
        wanted = _blocks_around(roadmap, thin, base, reach) if thin else set()
        if wanted <= blocks:
            stopped = "settled"
            break
        if rounds == max_rounds:
            stopped = "rounds"
            break
        try:
            refined = AdaptiveGrid(base, refinement, sorted(blocks | wanted),
                                   max_cells=max_cells)
        except GridSizeError:
            stopped = "cells"
            break
        blocks |= wanted
        rounds += 1
        # One report a round: its build's own stages are the first's again.
        report(f"thin regions, round {rounds}", 1.0 - 0.1 * 0.5 ** (rounds - 1))
        roadmap = build_roadmap(mechanism, refined, workers=workers, **build_options)
    report("done", 1.0)
    return roadmap, ThinRefinement(rounds, len(blocks), tuple(thin), stopped)


def _base_of(grid):
    return grid.base if isinstance(grid, AdaptiveGrid) else grid


def _base_blocks(grid, base, cells):
    """The base block of each cell, shape (n, ndim), with the block array's
    shape and which axes are periodic."""
    periodic = np.array([axis.periodic for axis in base.axes])
    shape = block_shape(base)
    low = np.array([axis.low for axis in base.axes])
    step = np.array([axis.step for axis in base.axes])
    # The small shift keeps a point on a base point in the block it starts;
    # the last point of a bounded axis is in the block it ends.
    at = np.floor((grid.coordinates_of(np.unique(cells)) - low) / step + 1e-9).astype(np.int64)
    return np.minimum(at, np.array(shape) - 1), shape, periodic


def _blocks_around(roadmap, patches, base, reach):
    """Flat indices of the base blocks within ``reach`` blocks of a cell of
    the patches."""
    seg = roadmap.segmentation
    cells = np.concatenate([seg.patches[pid].cells for pid in patches])
    at, shape, periodic = _base_blocks(roadmap.grid, base, cells)
    offsets = np.stack(np.meshgrid(*[np.arange(-reach, reach + 1)] * base.ndim,
                                   indexing="ij"), axis=-1).reshape(-1, base.ndim)
    around = (at[:, None, :] + offsets[None, :, :]).reshape(-1, base.ndim)
    around = np.where(periodic, around % np.array(shape), around)
    kept = np.all((around >= 0) & (around < np.array(shape)), axis=1)
    flat = np.ravel_multi_index(tuple(around[kept].T), shape)
    return set(np.unique(flat).tolist())
