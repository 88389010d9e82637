"""Locating a configuration (rho1, rho2, rho3, alpha) on a roadmap.

The assembly mode is the direct-kinematic solution at the exact legs whose
orientation is nearest ``alpha`` (within ``alpha_tol``).  That solution is then
carried by continuation to a nearby grid cell, which tells its patch: the
sheet is identified by continuity, never by comparing alphas across cells.

The nearest cell is not always the right one: a fold of the sheet, or a
sliver of the singular locus thinner than a cell, can lie between the
configuration and that cell's centre.  So the cells within
``_SEARCH_RADIUS`` steps are tried nearest first, and a cell is taken only
when the straight leg segment from the configuration to it passes the
trajectory validator both ways (no fold, det Jx keeps its sign, the margin
stays above ``min_margin``) and lands on a solution of a patch.  A plan that
starts with that segment and ends with the goal's therefore joins the exact
configurations to the cell path through validated steps.
"""

from dataclasses import dataclass
import math

import numpy as np

from .exceptions import (AssemblyModeError, InvalidInputError, NoSolutionError,
                         Rho1MismatchError, SingularityError)
from .kinematics import _singularity_margin, direct_kinematics, wrap_angle
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN, validate_path

__all__ = ["Location", "locate", "DEFAULT_ALPHA_TOL"]

DEFAULT_ALPHA_TOL = math.radians(1.0)
_RHO1_TOL = 1e-9
# Cells within this many steps of a configuration are candidates for it.
_SEARCH_RADIUS = 4.0
# A continued pose within this distance (relative to the geometry's scale,
# orientation as arc length at that scale) of a cell's solution is that one.
_LAND_TOL = 1e-6


@dataclass(frozen=True)
class Location:
    """Where a configuration lies on a roadmap.

    Attributes
    ----------
    rho : ndarray, shape (3,)
        Its legs [length unit].
    pose : ndarray, shape (3,)
        Its platform pose ``(x, y, alpha)`` [length unit, length unit, rad].
    margin : float
        Its signed normalised ``det(Jx)``.
    cell : int
        Flat index of the grid cell it is joined to (a validated straight
        leg segment leads there).
    slot : int
        Index of its solution among that cell's sorted solutions.
    patch : int
        Id of its patch.
    """

    rho: np.ndarray
    pose: np.ndarray
    margin: float
    cell: int
    slot: int
    patch: int


def locate(roadmap, rho1, rho2, rho3, alpha, alpha_tol=DEFAULT_ALPHA_TOL,
           min_margin=DEFAULT_MIN_MARGIN, max_step=DEFAULT_MAX_STEP):
    """Find the assembly mode, cell and patch of a configuration.

    Parameters
    ----------
    roadmap : Roadmap
    rho1, rho2, rho3 : float
        Legs [length unit]; rho1 must be the roadmap's.
    alpha : float
        Approximate platform orientation [rad] selecting the assembly mode.
    alpha_tol : float
        Largest accepted difference between ``alpha`` and the solution [rad].
    min_margin : float
        Smallest accepted normalised ``|det Jx|``, at the configuration and
        on the way to its cell.
    max_step : float
        Validator's continuation step [length unit].

    Returns
    -------
    Location

    Raises
    ------
    InvalidInputError, Rho1MismatchError, OutOfGridError, NoSolutionError,
    AssemblyModeError, SingularityError
    """
    values = (rho1, rho2, rho3, alpha)
    try:
        values = tuple(float(v) for v in values)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"configuration must be four numbers: {exc}") from None
    if not all(math.isfinite(v) for v in values):
        raise InvalidInputError(f"configuration has NaN or infinity: {values}")
    rho1, rho2, rho3, alpha = values
    if min(rho1, rho2, rho3) < 0:
        raise InvalidInputError(f"leg lengths must be non-negative: {values[:3]}")
    grid = roadmap.grid
    if abs(rho1 - grid.rho1) > _RHO1_TOL * max(1.0, grid.rho1):
        raise Rho1MismatchError(f"rho1 = {rho1} but the roadmap is built for rho1 = {grid.rho1}")
    grid.cell_of(rho2, rho3)  # raises OutOfGridError
    rho = np.array([rho1, rho2, rho3])
    poses = direct_kinematics(rho, roadmap.geometry)
    if len(poses) == 0:
        raise NoSolutionError(f"no real direct-kinematic solution at rho = {values[:3]}")
    off = np.abs(wrap_angle(poses[:, 2] - alpha))
    best = int(np.argmin(off))
    if off[best] > alpha_tol:
        nearest = ", ".join(f"{math.degrees(a):.2f}" for a in poses[:, 2])
        raise AssemblyModeError(
            f"no assembly mode within {math.degrees(alpha_tol):.2f} deg of alpha = "
            f"{math.degrees(float(wrap_angle(alpha))):.2f} deg (wrapped) at rho = "
            f"{values[:3]}; solutions at [{nearest}] deg")
    pose = poses[best]
    margin = float(_singularity_margin(pose, roadmap.geometry))
    if abs(margin) < min_margin:
        raise SingularityError(f"configuration is singular: normalised |det Jx| = "
                               f"{abs(margin):.2e} < {min_margin:g}")
    for cell in _nearby_cells(grid, rho2, rho3):
        slot = _joined_slot(roadmap, rho, pose, cell, min_margin, max_step)
        if slot >= 0:
            return Location(rho=rho, pose=pose, margin=margin, cell=cell, slot=slot,
                            patch=int(roadmap.segmentation.patch[cell, slot]))
    raise SingularityError(
        f"configuration lies within a grid cell of the singular locus at rho = {values[:3]}: "
        f"its solution (margin {abs(margin):.2e}) reaches no patch within "
        f"{_SEARCH_RADIUS:g} cells without a fold or a margin below {min_margin:g}")


def _nearby_cells(grid, rho2, rho3):
    """Flat indices of the cells within ``_SEARCH_RADIUS`` steps, nearest first."""
    reach = int(math.ceil(_SEARCH_RADIUS))
    i0 = int(round((rho2 - grid.rho2_range[0]) / grid.step))
    j0 = int(round((rho3 - grid.rho3_range[0]) / grid.step))
    di, dj = np.meshgrid(np.arange(-reach, reach + 1), np.arange(-reach, reach + 1),
                         indexing="ij")
    i, j = (i0 + di).ravel(), (j0 + dj).ravel()
    n2, n3 = grid.shape
    inside = (i >= 0) & (i < n2) & (j >= 0) & (j < n3)
    i, j = i[inside], j[inside]
    distance = np.hypot(grid.rho2_range[0] + i * grid.step - rho2,
                        grid.rho3_range[0] + j * grid.step - rho3) / grid.step
    near = distance <= _SEARCH_RADIUS
    order = np.lexsort((j[near], i[near], distance[near]))
    return (i[near] * n3 + j[near])[order].tolist()


def _joined_slot(roadmap, rho, pose, cell, min_margin, max_step):
    """Slot of ``cell`` that the validated straight leg segment from
    ``(rho, pose)`` lands on, in a patch and validated back; -1 if none."""
    field, seg = roadmap.field, roadmap.segmentation
    geometry = field.geometry
    cell_rho = field.grid.rho_of(cell)
    count = int(field.count[cell])
    if count == 0:
        return -1
    there = validate_path(geometry, np.stack([rho, cell_rho]), pose, None, min_margin, max_step)
    if not there.ok:
        return -1
    diff = field.poses[cell, :count] - there.poses[-1]
    diff[:, 2] = wrap_angle(diff[:, 2]) * geometry.scale
    slot = int(np.argmin(np.linalg.norm(diff, axis=1)))
    if (np.linalg.norm(diff[slot]) > _LAND_TOL * geometry.scale
            or np.sign(field.margin[cell, slot]) != there.aspect
            or seg.patch[cell, slot] <= 0):
        return -1
    # Plans leave the goal's cell towards the goal: check that direction too.
    back = validate_path(geometry, np.stack([cell_rho, rho]), field.poses[cell, slot], pose,
                         min_margin, max_step)
    return slot if back.ok else -1
