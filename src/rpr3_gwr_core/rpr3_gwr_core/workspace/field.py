"""The n-solution field: every direct-kinematic solution of every grid cell.

The grid (:mod:`~rpr3_gwr_core.workspace.grid`) discretises the
configuration space, or a slice of it (paper section 5: rho2, rho3 in
[0, 50], step 0.125, 401 x 401 cells at rho1 = 17); the mechanism
(:mod:`~rpr3_gwr_core.mechanisms`) solves each cell.
"""

from dataclasses import dataclass
import functools

import numpy as np

from .progress import part

__all__ = ["NSolutionField", "compute_field"]


_CHUNK = 8192
_REPORTS = 20


@dataclass(frozen=True, eq=False, repr=False)
class NSolutionField:
    """Direct-kinematic solutions of every cell of a grid.

    Attributes
    ----------
    mechanism : Mechanism
    grid : Grid
    count : ndarray of uint8, shape (n_cells,)
        Number of real solutions of each cell.
    poses : ndarray, shape (n_cells, max_solutions, pose_size)
        The solutions in the mechanism's order; NaN beyond ``count``.
    margin : ndarray, shape (n_cells, max_solutions)
        Signed normalised distance of each solution from a parallel
        singularity (:meth:`Mechanism.margin`); NaN beyond ``count``.
    """

    mechanism: object
    grid: object
    count: np.ndarray
    poses: np.ndarray
    margin: np.ndarray

    def __repr__(self):
        counts = np.flatnonzero(np.bincount(self.count, minlength=1)[1:]) + 1
        solved = (f"{int(np.count_nonzero(self.count)):,} cells with {counts[0]} to "
                  f"{counts[-1]} solutions" if counts.size else "no solution")
        return (f"NSolutionField({self.mechanism.kind}, "
                f"{self.grid.describe(self.mechanism.joint_names)}; {solved})")

    @property
    def max_solutions(self):
        """Solution slots per cell."""
        return self.margin.shape[1]

    @property
    def aspect(self):
        """``sign(margin)`` of each solution, shape (n_cells, max_solutions), 0 where none."""
        return np.nan_to_num(np.sign(self.margin)).astype(np.int8)

    @functools.cached_property
    def valid(self):
        """Mask of existing solutions, shape (n_cells, max_solutions), read-only."""
        # Continuity and segmentation ask for it dozens of times per field.
        mask = np.arange(self.max_solutions) < self.count[:, None]
        mask.flags.writeable = False
        return mask

    @functools.cached_property
    def separation(self):
        """:meth:`Mechanism.separation` of the solutions: the distance from
        each to the nearest other solution of its cell, shape (n_cells,
        max_solutions), read-only: inf for a cell's only solution, NaN beyond
        ``count``."""
        # Per cell once, rather than per face and direction by continuity;
        # compute_field fills it chunk by chunk.
        out = self.mechanism.separation(self.poses, self.count)
        out.flags.writeable = False
        return out


def compute_field(mechanism, grid, *, progress=None, workers=map):
    """Solve the direct kinematics on every cell of a grid.

    Parameters
    ----------
    mechanism : Mechanism
    grid : Grid
        Over the mechanism's joints.
    progress : callable, optional
        Called as ``progress(stage, fraction)`` (the stage's name, the
        fraction of the work done) as chunks of cells are solved.
    workers : callable, optional
        A map-like callable, ``workers(function, iterable)`` yielding the
        results in order, such as ``ThreadPoolExecutor.map``: the chunks of cells are solved
        with it, in parallel with a thread pool's (numpy, LAPACK and the
        mechanisms' compiled kernels release the interpreter's lock).  The
        default, the builtin ``map``, works in the calling thread.

    Returns
    -------
    NSolutionField

    Examples
    --------
    The number of solutions over rho2 = 10, 15, ..., 30 (rows) and
    rho3 = 15, 20, 25 (columns) at rho1 = 17, as in the paper's figure 6:

    >>> from rpr3_gwr_core import PAPER_GEOMETRY, Axis, Grid, compute_field
    >>> grid = Grid(axes=(Axis(1, 10.0, 30.0, 5.0), Axis(2, 15.0, 25.0, 5.0)),
    ...             fixed=((0, 17.0),))
    >>> compute_field(PAPER_GEOMETRY, grid).count.reshape(grid.shape).tolist()
    [[2, 2, 2], [6, 6, 2], [4, 4, 4], [4, 2, 4], [2, 2, 2]]
    """
    joints = grid.joints()
    n = mechanism.max_solutions
    count = np.empty(grid.size, dtype=np.uint8)
    poses = np.empty((grid.size, n, mechanism.pose_size))
    margin = np.full((grid.size, n), np.nan)
    separation = np.empty((grid.size, n))

    # Chunks bound the temporaries of the root finder (they scale with cells)
    # and are what ``workers`` runs in parallel.  The separation is taken
    # here, with the chunk's poses at hand, rather than by the first of the
    # segmentation's threads while the others wait for it.
    def solve(start):
        rows = slice(start, start + _CHUNK)
        count[rows], poses[rows] = mechanism.solve(joints[rows])
        valid = np.arange(n) < count[rows, None]
        margin[rows][valid] = mechanism.margin(
            poses[rows][valid], np.broadcast_to(joints[rows, None, :], valid.shape + (
                mechanism.n_joints,))[valid])
        separation[rows] = mechanism.separation(poses[rows], count[rows])

    report = part(progress)
    starts = range(0, grid.size, _CHUNK)
    # The results come in order in this thread: the callback never runs in
    # a worker.  At most _REPORTS calls, which a log can take line by line.
    for done, _ in enumerate(workers(solve, starts), 1):
        if done * _REPORTS // len(starts) > (done - 1) * _REPORTS // len(starts):
            report("n-solution field", done / len(starts))
    field = NSolutionField(mechanism=mechanism, grid=grid, count=count, poses=poses,
                           margin=margin)
    separation.flags.writeable = False
    field.__dict__["separation"] = separation
    return field
