"""Plans to and from platform poses: the working modes of a pose on a
roadmap, and the configurations a plan request given as poses starts and
ends at.

A pose's inverse kinematics (:meth:`Mechanism.inverse_kinematics`) has one
joint vector per working mode, a branch sign per leg; each with the pose's
mode coordinate is a configuration, as a plan's start or goal is given.  A
working mode is usable where its joints lie in the roadmap's box and on its
slice (a joint the grid fixes within
:data:`~rpr3_gwr_core.planning.locate.FIXED_JOINT_TOL` of its value) and it
locates on a patch (:func:`~rpr3_gwr_core.planning.locate.locate`: off the
singular locus, a validated step from a cell).  A request that leaves a
pose's working mode open takes, among the usable ones, those the roadmap
joins to the other end (the same connected component, one aspect:
:func:`~.global_planning.feasibility`), the one of largest margin first.
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import (AssemblyModeError, FixedJointMismatchError, InfeasiblePathError,
                          InvalidInputError, NoSolutionError, OutOfGridError, SingularityError,
                          UndecidedError)
from ..mechanisms.base import finite_vectors, working_mode_label
from .global_planning import feasibility
from .locate import DEFAULT_MODE_TOL, check_on_grid

__all__ = ["WorkingMode", "PoseEnd", "PlanEnds", "working_modes", "resolve_ends"]

# A located configuration whose pose lies farther than this from the pose
# asked for [scale] is another assembly mode of the same joints, one whose
# mode coordinate is (nearly) the same.
_SAME_POSE = 1e-6
# How a working mode's patch lies apart from the other end's, by the
# roadmap's answer (:class:`~.global_planning.Feasibility`).
_APART = {"other_aspect": "another aspect", "unreachable": "another component",
          "undecided": "another component, with thin regions of its aspect left"}


@dataclass(frozen=True, repr=False)
class WorkingMode:
    """One working mode of a pose, located on a roadmap.

    Attributes
    ----------
    signs : tuple of int, shape (n_joints,)
        Its branch sign per leg, +1 or -1 (:attr:`Mechanism.working_modes`).
    configuration : tuple of float, shape (n_joints + 1,)
        Its joints [joint unit], then the pose's mode coordinate: a plan's
        start or goal.
    pose : ndarray, shape (pose_size,)
        The pose.
    margin : float
        Its signed normalised distance from a parallel singularity.
    in_box : bool
        Whether the joints the roadmap's grid spans lie in its box.
    on_slice : bool
        Whether the joints the grid fixes have its values (within
        :data:`~rpr3_gwr_core.planning.locate.FIXED_JOINT_TOL`).
    patch : int or None
        The patch it lies on; None where it lies on none.
    unlocated : str
        Why it lies on no patch; empty where it lies on one.
    """

    signs: tuple
    configuration: tuple
    pose: np.ndarray
    margin: float
    in_box: bool
    on_slice: bool
    patch: object = None
    unlocated: str = ""

    @property
    def label(self):
        """Its branch signs as text, ``"+-+"``."""
        return working_mode_label(self.signs)

    @property
    def aspect(self):
        """The sign of its margin, +1 or -1 (0 exactly on a singularity)."""
        return int(np.sign(self.margin))

    @property
    def joints(self):
        """Its joints [joint unit], shape (n_joints,)."""
        return np.array(self.configuration[:-1])

    def __repr__(self):
        where = f"patch {self.patch}" if self.patch is not None else f"no patch: {self.unlocated}"
        return f"WorkingMode({self.label}, aspect {self.aspect:+d}, {where})"

    def to_dict(self):
        """Plain data (JSON-ready)."""
        return {"working_mode": self.label, "signs": list(self.signs),
                "configuration": [float(v) for v in self.configuration],
                "pose": [float(v) for v in self.pose], "aspect": self.aspect,
                "signed_margin": self.margin, "in_box": self.in_box,
                "on_slice": self.on_slice, "patch": self.patch, "unlocated": self.unlocated}


@dataclass(frozen=True)
class PoseEnd:
    """A plan's start or goal given as a platform pose.

    Attributes
    ----------
    pose : tuple of float, shape (pose_size,)
        The pose (the mechanism's ``pose_names``, angles [rad]).
    working_mode : tuple of int or str, optional
        Its branch sign per leg, as a tuple of +1 and -1 or as text
        (``"+-+"``); None lets :func:`resolve_ends` choose.
    """

    pose: tuple
    working_mode: object = None


@dataclass(frozen=True)
class PlanEnds:
    """The configurations a plan request starts and ends at.

    Attributes
    ----------
    start, goal : tuple of float, shape (n_joints + 1,)
        The joints [joint unit], then the mode coordinate: what
        :meth:`Planner.plan` takes.
    start_mode, goal_mode : WorkingMode or None
        The working mode taken for an end given as a pose; None for one
        given as a configuration.
    """

    start: tuple
    goal: tuple
    start_mode: object = None
    goal_mode: object = None


def working_modes(planner, pose):
    """Every working mode of a pose, located on a planner's roadmap.

    Parameters
    ----------
    planner : Planner
    pose : array_like, shape (pose_size,)
        The mechanism's pose (:attr:`Mechanism.pose_names`), angles [rad].

    Returns
    -------
    list of WorkingMode
        In the order of :attr:`Mechanism.working_modes`, those whose legs
        all reach the pose; empty where none does.

    Raises
    ------
    InvalidInputError
        If the pose is not ``pose_size`` finite numbers.
    """
    mechanism = planner.roadmap.mechanism
    pose = _checked_pose(mechanism, pose)
    return [_located_mode(planner, pose, signs, joints)
            for signs, joints in zip(mechanism.working_modes,
                                     mechanism.inverse_kinematics(pose))
            if not np.isnan(joints).any()]


def resolve_ends(planner, start, goal, mode_tol=DEFAULT_MODE_TOL):
    """The configurations of a plan request whose ends may be poses.

    An end given as a configuration, or as a pose with its working mode, is
    taken as it is.  For a pose without one, the working modes the roadmap
    joins to the other end are candidates, the one of largest margin
    magnitude taken (with both ends such poses, the pair whose smaller
    margin magnitude is largest).

    Parameters
    ----------
    planner : Planner
    start, goal : sequence of float or PoseEnd
        A configuration (the joints [joint unit], then the mode coordinate,
        as :meth:`Planner.plan` takes it) or a pose.
    mode_tol : float
        Tolerance on a configuration's mode coordinate, as the plan's.

    Returns
    -------
    PlanEnds

    Raises
    ------
    InvalidInputError
        If a pose is not finite numbers of the pose's size, or a working
        mode is not one sign per leg.
    NoSolutionError
        If a leg cannot reach a pose (of its working mode, or of every one).
    InfeasiblePathError
        With ``reason`` ``"unreachable"``, when no working mode of a pose
        left open is joined to the other end: its message lists every
        working mode and why it is out (outside the box, off the slice,
        singular, in another component).
    UndecidedError
        Instead, when the roadmap joins none, and thin regions are left in
        the aspect of a working mode in another component.
    FixedJointMismatchError, OutOfGridError, AssemblyModeError, SingularityError
        As :meth:`Planner.locate`, for an end given as a configuration or a
        working mode that a mode left open is compared with.
    """
    ends = [_end(planner, end) for end in (start, goal)]
    open_ends = [k for k, end in enumerate(ends) if isinstance(end, list)]
    if not open_ends:
        return PlanEnds(*(_configuration(end) for end in ends),
                        *(end if isinstance(end, WorkingMode) else None for end in ends))
    if len(open_ends) == 2:
        start_mode, goal_mode = _best_pair(planner, *ends)
        return PlanEnds(start_mode.configuration, goal_mode.configuration, start_mode,
                        goal_mode)
    fixed = ends[1 - open_ends[0]]
    anchor = planner.locate(_configuration(fixed), mode_tol)
    modes = ends[open_ends[0]]
    answers = [_feasibility(planner, anchor.patch, mode) for mode in modes]
    reached = [mode for mode, answer in zip(modes, answers) if answer in ("same_patch",
                                                                           "connected")]
    which = ("start", "goal")[open_ends[0]]
    if not reached:
        other = ("start", "goal")[1 - open_ends[0]]
        raise _unjoined(planner, [anchor.patch] if "undecided" in answers else [],
                        f"no working mode of the {which} pose is joined to the {other} "
                        f"(patch {anchor.patch}); its working modes: " + _listed(modes, answers))
    best = max(reached, key=lambda mode: abs(mode.margin))
    chosen = [_configuration(fixed), best.configuration]
    if open_ends[0] == 0:
        chosen.reverse()
    fixed_mode = fixed if isinstance(fixed, WorkingMode) else None
    modes_of = [best, fixed_mode] if open_ends[0] == 0 else [fixed_mode, best]
    return PlanEnds(*chosen, *modes_of)


def _checked_pose(mechanism, pose):
    """A pose as a float array of shape (pose_size,), else ``InvalidInputError``."""
    pose = finite_vectors(pose, "poses", mechanism.pose_size)
    if pose.shape != (mechanism.pose_size,):
        raise InvalidInputError(f"a pose is {mechanism.pose_size} numbers "
                                f"{list(mechanism.pose_names)}, got shape {pose.shape}")
    return pose


def _located_mode(planner, pose, signs, joints):
    """The :class:`WorkingMode` of one working mode's joints."""
    roadmap = planner.roadmap
    mechanism = roadmap.mechanism
    configuration = (*(float(v) for v in joints), float(pose[mechanism.mode_coordinate]))
    margin = float(mechanism.margin(pose, joints))
    try:
        roadmap.grid.cell_of(joints)
        in_box = True
    except OutOfGridError:
        in_box = False
    on_slice, patch, why = True, None, ""
    try:
        check_on_grid(roadmap, joints)
        located = planner.locate(configuration)
        if mechanism.pose_distance(located.pose, pose) > _SAME_POSE * mechanism.scale:
            why = ("another assembly mode of its joints has the same "
                   f"{mechanism.pose_names[mechanism.mode_coordinate]}")
        else:
            patch = int(located.patch)
    except FixedJointMismatchError as exc:
        on_slice, why = False, f"off the slice: {exc}"
    except OutOfGridError:
        why = "outside the box"
    except (SingularityError, AssemblyModeError, NoSolutionError) as exc:
        why = f"singular: {exc}"
    return WorkingMode(tuple(int(s) for s in signs), configuration, pose.copy(), margin,
                       in_box, on_slice, patch, why)


def _end(planner, end):
    """A configuration (tuple), the :class:`WorkingMode` a pose end names, or
    the list of a pose's working modes where it names none."""
    if not isinstance(end, PoseEnd):
        return end
    mechanism = planner.roadmap.mechanism
    modes = working_modes(planner, end.pose)
    if end.working_mode is None:
        if not modes:
            raise NoSolutionError(_out_of_reach(mechanism, end.pose))
        return modes
    signs = _signs(mechanism, end.working_mode)
    for mode in modes:
        if mode.signs == signs:
            return mode
    raise NoSolutionError(f"working mode {working_mode_label(signs)}: "
                          + _out_of_reach(mechanism, end.pose, signs))


def _signs(mechanism, working_mode):
    """A working mode as a tuple of +1 and -1, one per leg, checked."""
    if isinstance(working_mode, str):
        signs = tuple({"+": 1, "-": -1}.get(c, 0) for c in working_mode)
    else:
        try:
            signs = tuple(int(s) if s in (1, -1) else 0 for s in working_mode)
        except TypeError:
            signs = ()
    known = {tuple(int(s) for s in m) for m in mechanism.working_modes}
    if signs not in known:
        raise InvalidInputError(
            f"a working mode of the {mechanism.kind} is one sign per leg, +1 or -1 "
            f"({', '.join(working_mode_label(m) for m in sorted(known, reverse=True))}), "
            f"got {working_mode!r}")
    return signs


def _out_of_reach(mechanism, pose, signs=None):
    """Which legs cannot reach a pose (on the branches of ``signs``)."""
    legs = mechanism.leg_joints(_checked_pose(mechanism, pose))
    if signs is None:
        missing = np.isnan(legs).all(axis=-1)
    else:
        branch = [(1 - s) // 2 for s in signs]
        missing = np.isnan(legs[np.arange(mechanism.n_joints), branch])
    shown = ", ".join(f"{v:.6g}" for v in pose)
    legs_out = ", ".join(str(k + 1) for k in np.flatnonzero(missing))
    return f"leg {legs_out} cannot reach the pose ({shown})"


def _configuration(end):
    return end.configuration if isinstance(end, WorkingMode) else tuple(end)


def _feasibility(planner, patch, mode):
    """The roadmap's answer from a patch to a working mode, None where the
    mode lies on no patch."""
    if mode.patch is None:
        return None
    return feasibility(planner.patch_graph, patch, mode.patch).reason


def _best_pair(planner, start_modes, goal_modes):
    """The start and goal working modes the roadmap joins whose smaller
    margin magnitude is largest."""
    answers = [(s, g, _feasibility(planner, s.patch, g)) for s in start_modes
               for g in goal_modes if s.patch is not None]
    pairs = [(s, g) for s, g, answer in answers if answer in ("same_patch", "connected")]
    if not pairs:
        raise _unjoined(
            planner, [s.patch for s, _, answer in answers if answer == "undecided"],
            "no working mode of the start pose is joined to one of the goal pose (those on "
            "a patch lie in another component or aspect); the start's working modes: "
            + _listed(start_modes, [None] * len(start_modes)) + "; the goal's: "
            + _listed(goal_modes, [None] * len(goal_modes)))
    return max(pairs, key=lambda pair: min(abs(pair[0].margin), abs(pair[1].margin)))


def _listed(modes, answers):
    """Each working mode and why it is out."""
    parts = []
    for mode, answer in zip(modes, answers):
        if mode.patch is None:
            why = mode.unlocated
        elif answer is None:
            why = f"patch {mode.patch}"
        else:
            why = f"patch {mode.patch}, in {_APART[answer]}"
        parts.append(f"{mode.label} ({why})")
    return "; ".join(parts)


def _unjoined(planner, undecided, message):
    """The error of working modes none of which the roadmap joins to the
    other end: an ``UndecidedError`` when the roadmap could not decide for
    some (``undecided``: their patches), else an ``InfeasiblePathError``."""
    if not undecided:
        return InfeasiblePathError(message, "unreachable")
    graph = planner.patch_graph
    thin = sorted({pid for patch in undecided for pid in graph.thin[graph.aspect[patch]]})
    return UndecidedError(message + f"; thin regions of their aspect are left "
                          f"(patch{'es' if len(thin) > 1 else ''} {', '.join(map(str, thin))}): "
                          "a finer cell may join them", thin, planner.roadmap.grid.steps)

