"""Locating a configuration (rho1, rho2, rho3, alpha) on a roadmap.

The assembly mode is the direct-kinematic solution at the exact legs whose
orientation is nearest ``alpha`` (within ``alpha_tol``).  That solution is then
carried by continuation to the nearest grid cell, which tells its patch: the
sheet is identified by continuity, never by comparing alphas across cells.
"""

from dataclasses import dataclass
import math

import numpy as np

from .exceptions import (AssemblyModeError, InvalidInputError, NoSolutionError,
                         Rho1MismatchError, SingularityError)
from .kinematics import _singularity_margin, direct_kinematics, wrap_angle
from .mechanism import Mechanism

__all__ = ["Location", "locate", "DEFAULT_ALPHA_TOL", "DEFAULT_MIN_MARGIN"]

DEFAULT_ALPHA_TOL = math.radians(1.0)
# Normalised |det Jx| (kinematics.singularity_margin) below which a
# configuration counts as singular: the platform's orientation then moves
# more than about a thousand times faster than at a well-conditioned pose.
DEFAULT_MIN_MARGIN = 1e-3
_RHO1_TOL = 1e-9


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
        Flat index of the nearest grid cell.
    slot : int
        Index of its solution among the cell's sorted solutions.
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
           min_margin=DEFAULT_MIN_MARGIN):
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
        Smallest accepted normalised ``|det Jx|``.

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
    cell = grid.cell_of(rho2, rho3)  # raises OutOfGridError
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
            f"{math.degrees(alpha):.2f} deg at rho = {values[:3]}; solutions at [{nearest}] deg")
    pose = poses[best]
    margin = float(_singularity_margin(pose, roadmap.geometry))
    if abs(margin) < min_margin:
        raise SingularityError(f"configuration is singular: normalised |det Jx| = {abs(margin):.2e} "
                               f"< {min_margin:g}")
    slot = _slot_at_cell(roadmap, rho, pose, cell)
    patch = int(roadmap.segmentation.patch[cell, slot]) if slot >= 0 else 0
    if patch == 0:
        raise SingularityError(
            f"configuration lies within a grid cell of the singular locus at rho = {values[:3]} "
            f"(its solution does not continue to the nearest cell's patch)")
    return Location(rho=rho, pose=pose, margin=margin, cell=cell, slot=slot, patch=patch)


def _slot_at_cell(roadmap, rho, pose, cell, tol=1e-6):
    """Solution slot of ``cell`` reached by continuation from ``pose``, or -1."""
    field = roadmap.field
    geometry = field.geometry
    followed = Mechanism(geometry).follow(pose, rho, field.grid.rho_of(cell), substeps=2)
    if followed is None or field.count[cell] == 0:
        return -1
    current, margin, _ = followed
    diff = field.poses[cell, : field.count[cell]] - np.array(current)
    diff[:, 2] = wrap_angle(diff[:, 2]) * geometry.scale
    dist = np.linalg.norm(diff, axis=1)
    slot = int(np.argmin(dist))
    same_side = np.sign(field.margin[cell, slot]) == np.sign(margin)
    return slot if dist[slot] < tol * geometry.scale and same_side else -1
