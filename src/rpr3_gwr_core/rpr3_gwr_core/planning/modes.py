"""The assembly modes of given joints on a roadmap: where each lies (its
patch, region and aspect) and which of them a singularity-free path reaches
from one of them.

Every direct-kinematic solution of the joints is an assembly mode.  Each is
located on the roadmap as a plan's start would be
(:func:`~rpr3_gwr_core.planning.locate.locate`); one too near a singularity,
or that no validated step joins to a cell, lies on no patch.  From a start
mode, another mode of the same joints is reachable exactly when the
roadmap joins their patches (:func:`~.global_planning.feasibility`): that is
an assembly-mode change, which :meth:`Planner.plan` then plans.
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import (AssemblyModeError, InvalidInputError, NoSolutionError,
                          SingularityError)
from .global_planning import feasibility
from .locate import check_on_grid

__all__ = ["AssemblyMode", "assembly_modes"]

# Locating a mode by its own mode coordinate picks that solution: another
# lies this close only where two solutions coincide.
_OWN_MODE_TOL = 1e-9


@dataclass(frozen=True, repr=False)
class AssemblyMode:
    """One direct-kinematic solution of the joints, located on a roadmap.

    Attributes
    ----------
    configuration : tuple of float, shape (n_joints + 1,)
        The joints [joint unit], then its mode coordinate: a plan's start or
        goal.
    pose : ndarray, shape (pose_size,)
        Its platform pose.
    aspect : int
        The sign of its margin, +1 or -1.
    margin : float
        Its signed normalised distance from a parallel singularity.
    patch, region, layer : int or None
        Where it lies on the roadmap; None where it lies on no patch.
    unlocated : str
        Why it lies on no patch; empty where it lies on one.
    feasibility : str or None
        From the start mode given to :func:`assembly_modes`: ``"start"``
        for that mode itself, else the roadmap's answer (``"same_patch"``,
        ``"connected"``, ``"other_aspect"``, ``"unreachable"``,
        ``"undecided"``); None without a start mode, or where either lies on
        no patch.
    """

    configuration: tuple
    pose: np.ndarray
    aspect: int
    margin: float
    patch: object = None
    region: object = None
    layer: object = None
    unlocated: str = ""
    feasibility: object = None

    @property
    def reachable(self):
        """Whether a singularity-free path joins it to the start mode."""
        return self.feasibility in ("same_patch", "connected")

    def __repr__(self):
        where = (f"patch {self.patch} (region {self.region})" if self.patch is not None
                 else f"no patch: {self.unlocated}")
        mode = f"{self.configuration[-1]:.6g}"
        answer = "" if self.feasibility is None else f", {self.feasibility}"
        return f"AssemblyMode(mode {mode}, aspect {self.aspect:+d}, {where}{answer})"

    def to_dict(self):
        """Plain data (JSON-ready)."""
        return {"configuration": [float(v) for v in self.configuration],
                "pose": [float(v) for v in self.pose], "aspect": self.aspect,
                "signed_margin": self.margin, "patch": self.patch, "region": self.region,
                "layer": self.layer, "unlocated": self.unlocated,
                "feasibility": self.feasibility}


def assembly_modes(planner, joints, start_mode=None, mode_tol=None):
    """Every assembly mode of some joints, located on a planner's roadmap.

    Parameters
    ----------
    planner : Planner
    joints : sequence of float, shape (n_joints,)
        The joints [joint unit] (those the roadmap's grid fixes within
        :data:`~rpr3_gwr_core.planning.locate.FIXED_JOINT_TOL` of its values).
    start_mode : float, optional
        The mode coordinate of the mode to start from: each mode's
        ``feasibility`` then says whether a singularity-free path reaches it.
    mode_tol : float, optional
        Largest difference between ``start_mode`` and its solution's (the
        planner's default, one degree for an angle).

    Returns
    -------
    list of AssemblyMode
        In the order of their mode coordinate.

    Raises
    ------
    InvalidInputError, FixedJointMismatchError, OutOfGridError
        If the joints are not numbers of the roadmap's grid.
    NoSolutionError
        If the joints have no direct-kinematic solution.
    AssemblyModeError, SingularityError
        If ``start_mode`` selects no mode, or one on no patch.
    """
    mechanism = planner.roadmap.mechanism
    try:
        joints = np.array([float(v) for v in joints])
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"joints are {mechanism.n_joints} numbers: {exc}") from None
    if joints.shape != (mechanism.n_joints,) or not np.all(np.isfinite(joints)):
        raise InvalidInputError(f"joints are {mechanism.n_joints} finite numbers "
                                f"{list(mechanism.joint_names)}, got {joints.tolist()}")
    check_on_grid(planner.roadmap, joints)
    count, solutions = mechanism.solve(joints[None])
    poses = solutions[0, :count[0]]
    if not len(poses):
        raise NoSolutionError(f"no real direct-kinematic solution at {joints.tolist()}")
    k = mechanism.mode_coordinate
    poses = poses[np.argsort(poses[:, k], kind="stable")]
    margins = mechanism.margin(poses, np.repeat(joints[None], len(poses), axis=0))
    start = None
    if start_mode is not None:
        tol = {} if mode_tol is None else {"mode_tol": mode_tol}
        start = planner.locate((*joints, float(start_mode)), **tol)
    patches = planner.roadmap.segmentation.patches
    modes = []
    for pose, margin in zip(poses, margins):
        configuration = (*(float(v) for v in joints), float(pose[k]))
        found = {}
        try:
            located = planner.locate(configuration, mode_tol=_OWN_MODE_TOL)
        except (SingularityError, AssemblyModeError) as exc:
            found["unlocated"] = str(exc)
        else:
            patch = patches[located.patch]
            found.update(patch=int(located.patch), region=int(patch.region),
                         layer=int(patch.layer))
            if start is not None:
                same = located.patch == start.patch and np.allclose(
                    pose, start.pose, rtol=0, atol=1e-9 * mechanism.scale)
                found["feasibility"] = "start" if same else feasibility(
                    planner.patch_graph, start.patch, located.patch).reason
        modes.append(AssemblyMode(configuration, pose.copy(), 1 if margin > 0 else -1,
                                  float(margin), **found))
    return modes
