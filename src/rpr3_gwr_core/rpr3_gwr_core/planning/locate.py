"""Locating a configuration on a roadmap.

A configuration is the mechanism's joints and one more number, its
``mode_coordinate`` (the 3-RPR's orientation alpha): the assembly mode is the
direct-kinematic solution at the exact joints nearest that number (within
``mode_tol``).  That solution is then carried by continuation to a nearby
grid cell, which tells its patch: the sheet is identified by continuity,
never by comparing poses across cells.

The nearest cell is not always the right one: a fold of the sheet, or a
sliver of the singular locus thinner than a cell, can lie between the
configuration and that cell's centre.  So the cells within
``_SEARCH_RADIUS`` steps are tried nearest first, and a cell is taken only
when the straight joint segment from the configuration to it passes the
trajectory validator both ways (no fold, the margin keeps its sign and stays
above ``min_margin``) and lands on a solution of a patch.  A plan that starts
with that segment and ends with the goal's therefore joins the exact
configurations to the cell path through validated steps.
"""

from dataclasses import dataclass
import math

import numpy as np

from ..exceptions import (AssemblyModeError, FixedJointMismatchError, InvalidInputError,
                          NoSolutionError, SingularityError)
from .validation import DEFAULT_MAX_STEP, DEFAULT_MIN_MARGIN, validate_path

__all__ = ["Location", "locate", "check_on_grid", "DEFAULT_MODE_TOL", "FIXED_JOINT_TOL"]

# One degree, for an angular mode coordinate [rad].
DEFAULT_MODE_TOL = math.radians(1.0)
FIXED_JOINT_TOL = 1e-4
"""Largest difference between a configuration's value of a joint the grid
fixes and the grid's value, relative to the larger of 1 and that value: a
configuration within it lies on the slice (an angle given in degrees to
three decimals, -20.574 for the radians of a slice, does), and its path
starts by moving the joint onto the slice's value."""
# Cells within this many steps of a configuration are candidates for it.
_SEARCH_RADIUS = 4.0
# A continued pose within this distance (relative to the mechanism's scale,
# angles as arc length at that scale) of a cell's solution is that one.
_LAND_TOL = 1e-6


@dataclass(frozen=True, repr=False)
class Location:
    """Where a configuration lies on a roadmap.

    Attributes
    ----------
    joints : ndarray, shape (n_joints,)
        Its joints [joint unit].
    pose : ndarray, shape (pose_size,)
        Its platform pose.
    margin : float
        Its signed normalised distance from a parallel singularity.
    cell : int
        Flat index of the grid cell it is joined to (a validated straight
        joint segment leads there).
    slot : int
        Index of its solution among that cell's solutions.
    patch : int
        Id of its patch.
    """

    joints: np.ndarray
    pose: np.ndarray
    margin: float
    cell: int
    slot: int
    patch: int

    def __repr__(self):
        joints = ", ".join(f"{q:.6g}" for q in self.joints)
        pose = ", ".join(f"{p:.6g}" for p in self.pose)
        return (f"Location(joints ({joints}), pose ({pose}), patch {self.patch}, "
                f"cell {self.cell}, signed margin {self.margin:.3g})")


def check_on_grid(roadmap, joints):
    """Check that joints lie on a roadmap's grid: values the mechanism takes,
    those the grid fixes within :data:`FIXED_JOINT_TOL` of its values, the
    others in its box.

    Parameters
    ----------
    roadmap : Roadmap
    joints : ndarray, shape (n_joints,)
        Finite [joint unit].

    Raises
    ------
    InvalidInputError, FixedJointMismatchError, OutOfGridError
    """
    mechanism, grid = roadmap.mechanism, roadmap.grid
    mechanism.check_joints(joints)
    for joint, value in grid.fixed:
        if abs(joints[joint] - value) > FIXED_JOINT_TOL * max(1.0, abs(value)):
            name = mechanism.joint_names[joint]
            raise FixedJointMismatchError(
                f"{name} = {joints[joint]} but the roadmap is built for {name} = {value} "
                f"(a value within {FIXED_JOINT_TOL:g} x max(1, |{value:g}|) is taken as its)")
    grid.cell_of(joints)  # raises OutOfGridError


def locate(roadmap, configuration, mode_tol=DEFAULT_MODE_TOL, min_margin=DEFAULT_MIN_MARGIN,
           max_step=DEFAULT_MAX_STEP):
    """Find the assembly mode, cell and patch of a configuration.

    Parameters
    ----------
    roadmap : Roadmap
    configuration : sequence of float, shape (n_joints + 1,)
        The joints [joint unit] (those the grid fixes within
        :data:`FIXED_JOINT_TOL` of its values),
        then the approximate ``mode_coordinate`` of the pose that selects
        the assembly mode (the 3-RPR: ``(rho1, rho2, rho3, alpha)``).
    mode_tol : float
        Largest accepted difference between that value and the solution's.
    min_margin : float
        Smallest accepted margin magnitude, at the configuration and on the
        way to its cell.
    max_step : float
        Validator's continuation step [joint unit].

    Returns
    -------
    Location

    Raises
    ------
    InvalidInputError, FixedJointMismatchError, OutOfGridError, NoSolutionError,
    AssemblyModeError, SingularityError
    """
    mechanism, grid = roadmap.mechanism, roadmap.grid
    size = mechanism.n_joints + 1
    try:
        values = tuple(float(v) for v in configuration)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"a configuration is {size} numbers: {exc}") from None
    if len(values) != size:
        raise InvalidInputError(f"a configuration is {size} numbers "
                                f"{(*mechanism.joint_names, 'mode')}, got {len(values)}")
    if not all(math.isfinite(v) for v in values):
        raise InvalidInputError(f"configuration has NaN or infinity: {values}")
    joints, wanted = np.array(values[:-1]), values[-1]
    check_on_grid(roadmap, joints)
    count, solutions = mechanism.solve(joints[None, :])
    poses = solutions[0, :count[0]]
    if len(poses) == 0:
        raise NoSolutionError(f"no real direct-kinematic solution at {values[:-1]}")
    k = mechanism.mode_coordinate
    off = np.abs(poses[:, k] - wanted)
    if mechanism.angular[k]:
        off = np.abs(np.remainder(poses[:, k] - wanted + np.pi, 2 * np.pi) - np.pi)
    best = int(np.argmin(off))
    if off[best] > mode_tol:
        raise AssemblyModeError(_no_mode_message(mechanism, poses, wanted, mode_tol,
                                                 values[:-1]))
    pose = poses[best]
    margin = float(mechanism.margin(pose, joints))
    if abs(margin) < min_margin:
        raise SingularityError(f"configuration is singular: margin {abs(margin):.2e} "
                               f"< {min_margin:g}")
    for cell in grid.cells_near(joints, _SEARCH_RADIUS):
        slot = _joined_slot(roadmap, joints, pose, cell, min_margin, max_step)
        if slot >= 0:
            return Location(joints=joints, pose=pose, margin=margin, cell=cell, slot=slot,
                            patch=int(roadmap.segmentation.patch[cell, slot]))
    raise SingularityError(
        f"configuration lies within a grid cell of the singular locus at {values[:-1]}: "
        f"its solution (margin {abs(margin):.2e}) reaches no patch within "
        f"{_SEARCH_RADIUS:g} cells without a fold or a margin below {min_margin:g}")


def _no_mode_message(mechanism, poses, wanted, mode_tol, joints):
    k = mechanism.mode_coordinate
    name = mechanism.pose_names[k]
    if mechanism.angular[k]:
        shown = ", ".join(f"{math.degrees(v):.2f}" for v in poses[:, k])
        return (f"no assembly mode within {math.degrees(mode_tol):.2f} deg of {name} = "
                f"{math.degrees(math.remainder(wanted, 2 * math.pi)):.2f} deg (wrapped) at "
                f"{joints}; solutions at [{shown}] deg")
    shown = ", ".join(f"{v:.4g}" for v in poses[:, k])
    return (f"no assembly mode within {mode_tol:g} of {name} = {wanted:g} at {joints}; "
            f"solutions at [{shown}]")


def _joined_slot(roadmap, joints, pose, cell, min_margin, max_step):
    """Slot of ``cell`` that the validated straight joint segment from
    ``(joints, pose)`` lands on, in a patch and validated back; -1 if none."""
    field, seg = roadmap.field, roadmap.segmentation
    mechanism = field.mechanism
    # A cell across a periodic axis' seam is reached by the short way round.
    cell_joints = field.grid.nearest_joints(joints, field.grid.joints_of(cell))
    count = int(field.count[cell])
    if count == 0:
        return -1
    there = validate_path(mechanism, np.stack([joints, cell_joints]), pose, None, min_margin,
                          max_step)
    if not there.ok:
        return -1
    distance = mechanism.pose_distance(field.poses[cell, :count], there.poses[-1])
    slot = int(np.argmin(distance))
    if (distance[slot] > _LAND_TOL * mechanism.scale
            or np.sign(field.margin[cell, slot]) != there.aspect
            or seg.patch[cell, slot] <= 0):
        return -1
    # Plans leave the goal's cell towards the goal: check that direction too.
    back = validate_path(mechanism, np.stack([cell_joints, joints]), field.poses[cell, slot],
                         pose, min_margin, max_step)
    return slot if back.ok else -1
