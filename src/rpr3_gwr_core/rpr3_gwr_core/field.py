"""The n-solution field: every direct-kinematic solution of every grid cell.

The grid discretises the reduced configuration space (rho2, rho3) at a fixed
rho1 (paper section 5: rho2, rho3 in [0, 50], step 0.125, 401 x 401 cells).
Cells are the grid's sample points; cell ``(i, j)`` is at
``(rho2[i], rho3[j])`` and its flat index is ``i * n3 + j`` (row-major).
"""

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
import math
import numbers
import os

import numpy as np

from .exceptions import InvalidInputError, OutOfGridError
from .geometry import PAPER_GEOMETRY
from .kinematics import MAX_SOLUTIONS, _singularity_margin, _solve

__all__ = ["Grid", "NSolutionField", "compute_field", "PAPER_GRID"]


@dataclass(frozen=True)
class Grid:
    """A uniform grid over (rho2, rho3) at fixed rho1.

    Attributes
    ----------
    rho1 : float
        Fixed first leg [length unit].
    rho2_range, rho3_range : tuple of float
        Inclusive (min, max) of each axis [length unit].
    step : float
        Cell spacing on both axes [length unit].
    """

    rho1: float = 17.0
    rho2_range: tuple = (0.0, 50.0)
    rho3_range: tuple = (0.0, 50.0)
    step: float = 0.125

    def __post_init__(self):
        try:
            ranges = [tuple(_real(v) for v in getattr(self, n)) for n in ("rho2_range", "rho3_range")]
            rho1, step = _real(self.rho1), _real(self.step)
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"grid values must be numbers and (min, max) pairs, got rho1={self.rho1!r}, "
                f"rho2_range={self.rho2_range!r}, rho3_range={self.rho3_range!r}, "
                f"step={self.step!r}") from None
        if any(len(r) != 2 for r in ranges):
            raise InvalidInputError("axis ranges are (min, max) pairs")
        if not all(math.isfinite(v) for v in (rho1, step, *ranges[0], *ranges[1])):
            raise InvalidInputError("grid values must be finite")
        if rho1 <= 0:
            raise InvalidInputError(f"rho1 must be positive, got {rho1}")
        if step <= 0:
            raise InvalidInputError(f"step must be positive, got {step}")
        for name, (lo, hi) in zip(("rho2_range", "rho3_range"), ranges):
            if lo < 0 or hi < lo:
                raise InvalidInputError(f"{name} must satisfy 0 <= min <= max, got {(lo, hi)}")
            object.__setattr__(self, name, (lo, hi))
        object.__setattr__(self, "rho1", rho1)
        object.__setattr__(self, "step", step)

    @property
    def shape(self):
        """Number of cells along (rho2, rho3)."""
        return (_count(self.rho2_range, self.step), _count(self.rho3_range, self.step))

    @property
    def size(self):
        """Total number of cells."""
        n2, n3 = self.shape
        return n2 * n3

    @property
    def rho2(self):
        """rho2 of each row, shape (n2,) [length unit]."""
        return self.rho2_range[0] + self.step * np.arange(self.shape[0])

    @property
    def rho3(self):
        """rho3 of each column, shape (n3,) [length unit]."""
        return self.rho3_range[0] + self.step * np.arange(self.shape[1])

    def rho(self):
        """(rho1, rho2, rho3) of every cell, shape (n2 * n3, 3), row-major."""
        r2, r3 = np.meshgrid(self.rho2, self.rho3, indexing="ij")
        return np.stack([np.full(r2.size, self.rho1), r2.ravel(), r3.ravel()], axis=-1)

    def rho_of(self, cell):
        """(rho1, rho2, rho3) of one flat cell index, shape (3,) [length unit]."""
        i, j = divmod(int(cell), self.shape[1])
        return np.array([self.rho1, self.rho2_range[0] + self.step * i,
                         self.rho3_range[0] + self.step * j])

    def cell_of(self, rho2, rho3):
        """Flat index of the cell nearest to (rho2, rho3).

        Raises
        ------
        InvalidInputError
            If a coordinate is NaN or infinite.
        OutOfGridError
            If the point lies farther than half a step outside the grid.
        """
        if not (math.isfinite(rho2) and math.isfinite(rho3)):
            raise InvalidInputError(f"cell_of needs finite legs, got ({rho2}, {rho3})")
        index = []
        for value, (lo, _), n in ((rho2, self.rho2_range, self.shape[0]),
                                  (rho3, self.rho3_range, self.shape[1])):
            # Compared as floats first: a huge leg would overflow int().
            k = (value - lo) / self.step
            if not -0.5 <= k < n - 0.5:
                raise OutOfGridError(f"({rho2}, {rho3}) lies outside the grid "
                                     f"rho2 {self.rho2_range}, rho3 {self.rho3_range}")
            index.append(min(int(round(k)), n - 1))
        return index[0] * self.shape[1] + index[1]

    def cells_of(self, rho2, rho3):
        """Flat indices of the cells nearest to many points, -1 outside the grid.

        Parameters
        ----------
        rho2, rho3 : ndarray, shape (n,)

        Returns
        -------
        ndarray of int, shape (n,)
        """
        n2, n3 = self.shape
        i = np.rint((np.asarray(rho2) - self.rho2_range[0]) / self.step).astype(np.int64)
        j = np.rint((np.asarray(rho3) - self.rho3_range[0]) / self.step).astype(np.int64)
        inside = (i >= 0) & (i < n2) & (j >= 0) & (j < n3)
        return np.where(inside, i * n3 + j, -1)

    def to_dict(self):
        """Plain-data form, for JSON and cache keys."""
        return {"rho1": self.rho1, "rho2_range": list(self.rho2_range),
                "rho3_range": list(self.rho3_range), "step": self.step}

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(rho1=data["rho1"], rho2_range=tuple(data["rho2_range"]),
                       rho3_range=tuple(data["rho3_range"]), step=data["step"])
        except (KeyError, TypeError) as exc:
            raise InvalidInputError(f"malformed grid: {exc}") from exc


def _real(value):
    """``float(value)`` for real numbers only (no strings)."""
    if not isinstance(value, numbers.Real):
        raise TypeError(f"not a real number: {value!r}")
    return float(value)


def _count(axis_range, step):
    lo, hi = axis_range
    return int(math.floor((hi - lo) / step + 1e-9)) + 1


PAPER_GRID = Grid()
_CHUNK = 8192
_WORKERS = max(1, min(4, os.cpu_count() or 1))


@dataclass(frozen=True, eq=False)
class NSolutionField:
    """Direct-kinematic solutions of every cell of a grid.

    Attributes
    ----------
    geometry : Geometry
    grid : Grid
    count : ndarray of uint8, shape (n2 * n3,)
        Number of real solutions of each cell.
    poses : ndarray, shape (n2 * n3, 6, 3)
        ``(x, y, alpha)`` of each solution [length unit, length unit, rad],
        sorted by alpha; NaN beyond ``count``.
    margin : ndarray, shape (n2 * n3, 6)
        Signed normalised ``det(Jx)`` of each solution
        (:func:`~rpr3_gwr_core.kinematics.singularity_margin`); NaN beyond ``count``.
    """

    geometry: object
    grid: Grid
    count: np.ndarray
    poses: np.ndarray
    margin: np.ndarray

    @property
    def aspect(self):
        """``sign(det Jx)`` of each solution, shape (n2 * n3, 6), 0 where none."""
        return np.nan_to_num(np.sign(self.margin)).astype(np.int8)

    @property
    def valid(self):
        """Mask of existing solutions, shape (n2 * n3, 6)."""
        return np.arange(MAX_SOLUTIONS) < self.count[:, None]


def compute_field(geometry=PAPER_GEOMETRY, grid=PAPER_GRID):
    """Solve the direct kinematics on every cell of a grid.

    Parameters
    ----------
    geometry : Geometry
    grid : Grid

    Returns
    -------
    NSolutionField
    """
    rho = grid.rho()
    count = np.empty(grid.size, dtype=np.uint8)
    poses = np.empty((grid.size, MAX_SOLUTIONS, 3))
    margin = np.full((grid.size, MAX_SOLUTIONS), np.nan)

    # Chunks bound the temporaries of the root finder (they scale with cells)
    # and keep every core busy: numpy and LAPACK release the GIL.
    def solve(start):
        part = slice(start, start + _CHUNK)
        count[part], poses[part] = _solve(rho[part], geometry)
        valid = np.arange(MAX_SOLUTIONS) < count[part, None]
        margin[part][valid] = _singularity_margin(poses[part][valid], geometry)

    with ThreadPoolExecutor(max_workers=_WORKERS) as pool:
        list(pool.map(solve, range(0, grid.size, _CHUNK)))
    return NSolutionField(geometry=geometry, grid=grid, count=count, poses=poses, margin=margin)
