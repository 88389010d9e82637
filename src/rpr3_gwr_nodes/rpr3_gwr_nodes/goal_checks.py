"""Whether the simulated driver can execute a joint trajectory from where it is.

The checks :mod:`.rpr3_driver` makes when an ``execute_trajectory`` or
``~/follow_joint_trajectory`` goal arrives, before it accepts it (as
ros2_controllers' joint_trajectory_controller validates a goal in its goal
callback and rejects it there).  They take plain values, not messages, so
that they can be tested and reasoned about without a ROS graph; whether
another goal is executing is the node's to say, not theirs.

Every check returns a :class:`GoalVerdict`: a :class:`GoalCode` and the
reason the driver logs when it rejects the goal.
"""

import dataclasses
import enum
import math

import numpy as np

__all__ = ["GoalCode", "GoalVerdict", "CONTROLLER_CODES", "trajectory_fields",
           "duration_seconds", "whole_turns", "start_problem", "check_trajectory",
           "check_follow_trajectory"]


class GoalCode(enum.Enum):
    """Why a goal is rejected, or that it is accepted."""

    ACCEPTED = "accepted"
    #: The joint names are not the mechanism's, in its order.
    JOINT_NAMES = "joint names"
    #: A FollowJointTrajectory goal does not name every joint once.
    JOINT_SET = "joint set"
    NO_POINTS = "no points"
    #: A point without one position per joint.
    POSITION_COUNT = "position count"
    #: Velocities or accelerations neither empty nor one per joint.
    DERIVATIVE_COUNT = "derivative count"
    #: Positions, velocities or accelerations not finite.
    NOT_FINITE = "not finite"
    #: Efforts given to position-controlled joints.
    EFFORT = "effort"
    OUT_OF_RANGE = "out of range"
    #: A ``time_from_start.nanosec`` of a second or more.
    STAMP_NOT_NORMALISED = "stamp not normalised"
    NEGATIVE_TIME = "negative time"
    TIME_NOT_INCREASING = "time not increasing"
    #: A joint faster than the driver's ``max_velocity``.
    TOO_FAST = "too fast"
    #: The first point farther than ``start_tolerance`` from the current joints.
    START_AWAY = "start away"
    #: A FollowJointTrajectory goal with multi-DOF joints.
    MULTI_DOF = "multi-DOF"
    #: A FollowJointTrajectory goal whose last point is not at rest.
    NOT_AT_REST = "not at rest"
    #: A FollowJointTrajectory goal whose header stamp puts its end in the past.
    ENDED = "ended"


#: The codes of the checks joint_trajectory_controller makes before the
#: trajectory's own (:func:`check_follow_trajectory`'s first ones).
CONTROLLER_CODES = frozenset({GoalCode.JOINT_SET, GoalCode.MULTI_DOF, GoalCode.NOT_AT_REST,
                              GoalCode.ENDED})


@dataclasses.dataclass(frozen=True)
class GoalVerdict:
    """A goal's verdict.

    Attributes
    ----------
    code : GoalCode
        ``GoalCode.ACCEPTED``, or the first check the goal fails.
    reason : str
        Why it is rejected, as the driver logs it; ``""`` when accepted.
    """

    code: GoalCode
    reason: str = ""

    @property
    def accepted(self):
        """Whether the goal passes every check."""
        return self.code is GoalCode.ACCEPTED


_ACCEPTED = GoalVerdict(GoalCode.ACCEPTED)


def trajectory_fields(trajectory):
    """The plain values of a trajectory_msgs/JointTrajectory (or anything
    with its fields) that :func:`check_trajectory` takes.

    Parameters
    ----------
    trajectory : trajectory_msgs.msg.JointTrajectory
        The trajectory of a goal.

    Returns
    -------
    dict
        ``joint_names``, then per point ``positions``, ``velocities``,
        ``accelerations``, ``efforts`` (lists of lists) and ``times``
        (``(sec, nanosec)`` of each ``time_from_start``).
    """
    points = trajectory.points
    return {"joint_names": list(trajectory.joint_names),
            "positions": [list(p.positions) for p in points],
            "velocities": [list(p.velocities) for p in points],
            "accelerations": [list(p.accelerations) for p in points],
            "efforts": [list(p.effort) for p in points],
            "times": [(p.time_from_start.sec, p.time_from_start.nanosec) for p in points]}


def duration_seconds(sec, nanosec):
    """A builtin_interfaces Duration or Time's ``(sec, nanosec)`` in seconds."""
    return sec + nanosec * 1e-9


def whole_turns(first, current_joints, ranges):
    """Whole turns that bring a trajectory's first point nearest the current joints.

    Parameters
    ----------
    first : array_like, shape (n_joints,)
        The trajectory's first point.
    current_joints : array_like, shape (n_joints,)
        The driver's joints.
    ranges : sequence of (float, float) or None
        Each joint's range; None for a joint that turns fully.

    Returns
    -------
    numpy.ndarray, shape (n_joints,)
        What to add to each joint of the trajectory: a multiple of 2 pi for
        a joint that turns fully, else 0.
    """
    periodic = np.array([limit is None for limit in ranges])
    gap = (np.asarray(current_joints, dtype=float) - np.asarray(first, dtype=float)) / (2 * np.pi)
    return np.where(periodic, 2 * np.pi * np.round(gap), 0.0)


def start_problem(first, current_joints, ranges, start_tolerance):
    """Why a trajectory's first point is too far from the current joints to
    start from (by whole turns for a joint that turns fully), or None.

    Parameters
    ----------
    first : array_like, shape (n_joints,)
        The trajectory's first point.
    current_joints : array_like, shape (n_joints,)
        The driver's joints.
    ranges : sequence of (float, float) or None
        Each joint's range; None for a joint that turns fully.
    start_tolerance : float
        The largest distance allowed in any joint [joint unit].

    Returns
    -------
    str or None
    """
    first = np.asarray(first, dtype=float)
    current = np.asarray(current_joints, dtype=float)
    gap = float(np.max(np.abs(first + whole_turns(first, current, ranges) - current)))
    if gap > start_tolerance:
        return f"the trajectory starts {gap:.4g} away from the current joints {current.tolist()}"
    return None


def check_trajectory(joint_names, positions, velocities, accelerations, efforts, times, *,
                     mechanism_joints, ranges, max_velocity, current_joints, start_tolerance):
    """Whether the driver can execute a trajectory from its current joints.

    The checks, in order, the first failed giving the verdict: the joint
    names the mechanism's in its order, points, one position per joint per
    point, velocities and accelerations empty or one per joint and finite,
    no efforts, finite positions within the joints' ranges, normalised,
    non-negative and strictly increasing times, no joint faster than
    ``max_velocity``, a first point within ``start_tolerance`` of the current
    joints.

    Parameters
    ----------
    joint_names : sequence of str
        The trajectory's joint names.
    positions, velocities, accelerations, efforts : sequence of sequence of float
        Per point, the trajectory's values (a point's velocities,
        accelerations or efforts may be empty).
    times : sequence of (int, int)
        Per point, ``(sec, nanosec)`` of its ``time_from_start``.
    mechanism_joints : sequence of str
        The mechanism's joint names, in its order.
    ranges : sequence of (float, float) or None
        Each joint's range; None for a joint that turns fully (no range, and
        the start compared by whole turns).
    max_velocity : float
        The fastest a joint may move between two points [joint unit/s].
    current_joints : array_like, shape (n_joints,)
        The driver's joints.
    start_tolerance : float
        The largest distance of the first point from ``current_joints``
        [joint unit].

    Returns
    -------
    GoalVerdict
    """
    names = list(mechanism_joints)
    if list(joint_names) != names:
        return GoalVerdict(GoalCode.JOINT_NAMES,
                           f"joint names must be {names}, got {list(joint_names)}")
    if not positions:
        return GoalVerdict(GoalCode.NO_POINTS, "the trajectory has no points")
    joints = len(names)
    if any(len(p) != joints for p in positions):
        return GoalVerdict(GoalCode.POSITION_COUNT, f"every point needs {joints} positions")
    for field, values in (("velocities", velocities), ("accelerations", accelerations)):
        # Empty, as joint_trajectory_controller allows: not given.
        if any(len(v) not in (0, joints) for v in values):
            return GoalVerdict(GoalCode.DERIVATIVE_COUNT,
                               f"{field} must be empty or {joints} per point")
        if not all(math.isfinite(x) for v in values for x in v):
            return GoalVerdict(GoalCode.NOT_FINITE, f"{field} must be finite")
    if any(len(e) for e in efforts):
        return GoalVerdict(GoalCode.EFFORT,
                           "the joints are position controlled: effort must be empty")
    table = np.array([list(p) for p in positions], dtype=float)
    if not np.all(np.isfinite(table)):
        return GoalVerdict(GoalCode.NOT_FINITE, "positions must be finite")
    for k, (name, limit) in enumerate(zip(names, ranges)):
        if limit is not None and (np.any(table[:, k] < limit[0])
                                  or np.any(table[:, k] > limit[1])):
            return GoalVerdict(GoalCode.OUT_OF_RANGE,
                               f"{name} must lie within its range [{limit[0]:g}, {limit[1]:g}]")
    # A nanosec field of a second or more would shift the stamp past
    # the checks below (sec -1 and nanosec 2e9 read as +1 s).
    if any(nanosec >= 10**9 for _, nanosec in times):
        return GoalVerdict(GoalCode.STAMP_NOT_NORMALISED,
                           "time_from_start.nanosec must be below 10^9 (a second)")
    seconds = np.array([duration_seconds(sec, nanosec) for sec, nanosec in times])
    if np.any(seconds < 0):
        return GoalVerdict(GoalCode.NEGATIVE_TIME, "time_from_start must not be negative")
    if np.any(np.diff(seconds) <= 0):
        return GoalVerdict(GoalCode.TIME_NOT_INCREASING, "time_from_start must increase strictly")
    if len(table) > 1:
        speed = np.max(np.abs(np.diff(table, axis=0)) / np.diff(seconds)[:, None])
        if speed > max_velocity:
            return GoalVerdict(GoalCode.TOO_FAST,
                               f"a joint would move at {speed:.3g} joint unit/s, above "
                               f"max_velocity {max_velocity:g}")
    away = start_problem(table[0], current_joints, ranges, start_tolerance)
    if away is not None:
        return GoalVerdict(GoalCode.START_AWAY, away)
    return _ACCEPTED


def check_follow_trajectory(joint_names, positions, velocities, accelerations, efforts, times,
                            *, multi_dof_joints, multi_dof_points, header_stamp, now,
                            mechanism_joints, **limits):
    """Whether the driver can execute a FollowJointTrajectory goal's
    trajectory from its current joints.

    joint_trajectory_controller's checks, in order (every joint once, in
    any order; no multi-DOF joints; the last point at rest; a header stamp
    whose trajectory has not ended), then :func:`check_trajectory`'s on the
    trajectory with its joints in the mechanism's order.

    Parameters
    ----------
    joint_names, positions, velocities, accelerations, efforts, times
        The goal's trajectory, as :func:`check_trajectory` takes it, its
        joints in any order.
    multi_dof_joints : sequence of str
        The joint names of the goal's ``multi_dof_trajectory``.
    multi_dof_points : int
        How many points its ``multi_dof_trajectory`` has.
    header_stamp : (int, int)
        ``(sec, nanosec)`` of the trajectory's header stamp; ``(0, 0)``
        starts it at once.
    now : float
        The driver's clock [s].
    mechanism_joints : sequence of str
        The mechanism's joint names, in its order.
    **limits
        ``ranges``, ``max_velocity``, ``current_joints`` and
        ``start_tolerance``, as :func:`check_trajectory` takes them.

    Returns
    -------
    GoalVerdict
        Of a code of :data:`CONTROLLER_CODES` when one of the controller's
        checks fails.
    """
    names = list(mechanism_joints)
    given = list(joint_names)
    if sorted(given) != sorted(names):
        return GoalVerdict(GoalCode.JOINT_SET, f"the joints must be {names} (each once, in any "
                                               f"order), got {given}")
    if multi_dof_joints or multi_dof_points:
        return GoalVerdict(GoalCode.MULTI_DOF, "the mechanism has no multi-DOF joints: "
                                               "multi_dof_trajectory must be empty")
    if positions and any(v != 0.0 for v in velocities[-1]):
        return GoalVerdict(GoalCode.NOT_AT_REST,
                           "the last point's velocities must be 0 (the trajectory ends at rest)")
    if tuple(header_stamp) != (0, 0) and positions:
        begin = duration_seconds(*header_stamp)
        end = begin + duration_seconds(*times[-1])
        if end < now:
            return GoalVerdict(GoalCode.ENDED, f"the trajectory starting at {begin:.3f} s ended "
                                               f"in the past ({end:.3f} s < now {now:.3f} s)")
    order = [given.index(name) for name in names]

    def picked(values):
        # A point whose field has not one value per joint keeps it as it
        # is, for check_trajectory to refuse.
        return [values[k] for k in order] if len(values) == len(order) else list(values)

    return check_trajectory(
        names, [picked(p) for p in positions], [picked(v) for v in velocities],
        [picked(a) for a in accelerations], efforts, times, mechanism_joints=names, **limits)
