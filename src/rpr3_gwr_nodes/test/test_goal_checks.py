"""The driver's goal checks on hand-built goals, in process: each reason a
goal is rejected for, the first failed check deciding, and acceptance."""

import math

import numpy as np
import pytest

from rpr3_gwr_nodes.goal_checks import (CONTROLLER_CODES, GoalCode, GoalVerdict,
                                        check_follow_trajectory, check_trajectory,
                                        duration_seconds, start_problem, trajectory_fields,
                                        whole_turns)

NAMES = ["rho1", "rho2", "rho3"]
START = [17.0, 12.0, 18.0]
RANGES = [(0.0, 50.0)] * 3
LIMITS = {"ranges": RANGES, "max_velocity": 50.0, "current_joints": START,
          "start_tolerance": 1e-3}


def _goal(positions=(START, [17.0, 12.5, 18.0]), times=((0, 0), (1, 0)), **fields):
    """A step of rho2 in 1 s from START, as check_trajectory's arguments,
    ``fields`` replacing any of them."""
    goal = {"joint_names": list(NAMES), "positions": [list(p) for p in positions],
            "velocities": [[] for _ in positions], "accelerations": [[] for _ in positions],
            "efforts": [[] for _ in positions], "times": list(times)}
    goal.update(fields)
    return goal


def _check(goal, **limits):
    return check_trajectory(**goal, mechanism_joints=NAMES, **{**LIMITS, **limits})


def test_a_step_from_the_current_joints_is_accepted():
    verdict = _check(_goal())
    assert verdict == GoalVerdict(GoalCode.ACCEPTED)
    assert verdict.accepted and verdict.reason == ""


def test_velocities_and_accelerations_may_be_given_one_per_joint():
    goal = _goal(velocities=[[0.0, 0.5, 0.0], [0.0, 0.0, 0.0]],
                 accelerations=[[0.0, 0.0, 0.0], []])
    assert _check(goal).accepted


def test_a_single_point_at_the_current_joints_is_accepted():
    assert _check(_goal(positions=[START], times=[(0, 0)])).accepted


@pytest.mark.parametrize("goal, limits, code, words", [
    (_goal(joint_names=["rho2", "rho1", "rho3"]), {}, GoalCode.JOINT_NAMES,
     "joint names must be ['rho1', 'rho2', 'rho3'], got ['rho2', 'rho1', 'rho3']"),
    (_goal(joint_names=["rho1", "rho2"]), {}, GoalCode.JOINT_NAMES, "joint names must be"),
    (_goal(positions=[], times=[]), {}, GoalCode.NO_POINTS, "the trajectory has no points"),
    (_goal(positions=[START, [17.0, 12.5]]), {}, GoalCode.POSITION_COUNT,
     "every point needs 3 positions"),
    (_goal(velocities=[[], [0.0, 0.5]]), {}, GoalCode.DERIVATIVE_COUNT,
     "velocities must be empty or 3 per point"),
    (_goal(accelerations=[[0.0] * 4, []]), {}, GoalCode.DERIVATIVE_COUNT,
     "accelerations must be empty or 3 per point"),
    (_goal(velocities=[[], [0.0, math.nan, 0.0]]), {}, GoalCode.NOT_FINITE,
     "velocities must be finite"),
    (_goal(accelerations=[[0.0, 0.0, -math.inf], []]), {}, GoalCode.NOT_FINITE,
     "accelerations must be finite"),
    (_goal(efforts=[[], [0.0, 0.0, 0.0]]), {}, GoalCode.EFFORT,
     "the joints are position controlled: effort must be empty"),
    (_goal(positions=[START, [17.0, math.inf, 18.0]]), {}, GoalCode.NOT_FINITE,
     "positions must be finite"),
    (_goal(positions=[START, [17.0, 12.0, 50.5]], times=[(0, 0), (10, 0)]), {},
     GoalCode.OUT_OF_RANGE, "rho3 must lie within its range [0, 50]"),
    (_goal(positions=[START, [17.0, -0.5, 18.0]], times=[(0, 0), (10, 0)]), {},
     GoalCode.OUT_OF_RANGE, "rho2 must lie within its range [0, 50]"),
    (_goal(times=[(0, 0), (0, 2_000_000_000)]), {}, GoalCode.STAMP_NOT_NORMALISED,
     "time_from_start.nanosec must be below 10^9 (a second)"),
    # Read as 0.5 s and 1 s, were nanosec not checked.
    (_goal(times=[(-1, 1_500_000_000), (-1, 2_000_000_000)]), {},
     GoalCode.STAMP_NOT_NORMALISED, "nanosec must be below"),
    (_goal(times=[(-2, 0), (-1, 0)]), {}, GoalCode.NEGATIVE_TIME,
     "time_from_start must not be negative"),
    (_goal(times=[(0, 0), (0, 0)]), {}, GoalCode.TIME_NOT_INCREASING,
     "time_from_start must increase strictly"),
    (_goal(times=[(1, 0), (0, 500_000_000)]), {}, GoalCode.TIME_NOT_INCREASING,
     "must increase strictly"),
    (_goal(times=[(0, 0), (0, 1)]), {}, GoalCode.TOO_FAST,
     "a joint would move at 5e+08 joint unit/s, above max_velocity 50"),
    (_goal(), {"max_velocity": 0.25}, GoalCode.TOO_FAST,
     "a joint would move at 0.5 joint unit/s, above max_velocity 0.25"),
    (_goal(positions=[[17.0, 30.0, 30.0]], times=[(0, 0)]), {}, GoalCode.START_AWAY,
     "the trajectory starts 18 away from the current joints [17.0, 12.0, 18.0]"),
    (_goal(), {"current_joints": [17.0, 12.0, 18.002]}, GoalCode.START_AWAY,
     "the trajectory starts 0.002 away"),
])
def test_each_reason_to_reject_has_its_code_and_says_why(goal, limits, code, words):
    verdict = _check(goal, **limits)
    assert verdict.code is code and not verdict.accepted
    assert words in verdict.reason


def test_the_first_failed_check_decides():
    # Too fast, out of range and away from the start: the range comes first.
    goal = _goal(positions=[[17.0, 30.0, 30.0], [17.0, 30.0, 51.0]], times=[(0, 0), (0, 1)])
    assert _check(goal).code is GoalCode.OUT_OF_RANGE


def test_a_start_within_the_tolerance_is_accepted_and_beyond_it_not():
    near = [17.0, 12.0, 18.0 + 0.9e-3]
    assert _check(_goal(positions=[near], times=[(0, 0)])).accepted
    assert start_problem(near, START, RANGES, 1e-3) is None
    assert start_problem(near, START, RANGES, 0.5e-3).startswith("the trajectory starts")


def test_a_joint_that_turns_fully_has_no_range_and_starts_by_whole_turns():
    ranges = [(0.0, 50.0), None, (0.0, 50.0)]
    turned = [17.0, 12.0 - 4 * np.pi, 18.0]
    goal = _goal(positions=[turned, [17.0, turned[1] - 100.0, 18.0]], times=[(0, 0), (10, 0)])
    assert _check(goal, ranges=ranges).accepted
    np.testing.assert_allclose(whole_turns(turned, START, ranges), [0.0, 4 * np.pi, 0.0])
    # A joint with a range is never turned.
    assert _check(_goal(positions=[turned], times=[(0, 0)])).code is GoalCode.OUT_OF_RANGE
    assert start_problem([17.0 - 2 * np.pi, 12.0, 18.0], START, ranges, 1e-3) is not None


def test_durations_read_as_seconds():
    assert duration_seconds(2, 500_000_000) == 2.5
    assert duration_seconds(-1, 0) == -1.0


class _Point:
    def __init__(self, positions, seconds):
        self.positions, self.velocities, self.accelerations, self.effort = positions, [], [], []
        self.time_from_start = _Duration(*seconds)


class _Duration:
    def __init__(self, sec, nanosec):
        self.sec, self.nanosec = sec, nanosec


class _Trajectory:
    def __init__(self, names, points):
        self.joint_names, self.points = names, points


def test_a_trajectorys_fields_are_read_as_plain_values():
    trajectory = _Trajectory(("rho1", "rho2", "rho3"),
                             [_Point((17.0, 12.0, 18.0), (0, 0)), _Point((17.0, 12.5, 18.0),
                                                                         (1, 5))])
    assert trajectory_fields(trajectory) == {
        "joint_names": NAMES, "positions": [START, [17.0, 12.5, 18.0]],
        "velocities": [[], []], "accelerations": [[], []], "efforts": [[], []],
        "times": [(0, 0), (1, 5)]}
    assert _check(trajectory_fields(trajectory)).accepted


# --- FollowJointTrajectory ---------------------------------------------------------------------

def _follow(goal, multi_dof_joints=(), multi_dof_points=0, header_stamp=(0, 0), now=100.0,
            **limits):
    return check_follow_trajectory(**goal, multi_dof_joints=list(multi_dof_joints),
                                   multi_dof_points=multi_dof_points, header_stamp=header_stamp,
                                   now=now, mechanism_joints=NAMES, **{**LIMITS, **limits})


def test_a_follow_goal_may_name_its_joints_in_any_order():
    order = [2, 0, 1]
    goal = _goal(joint_names=[NAMES[k] for k in order],
                 positions=[[p[k] for k in order] for p in (START, [17.0, 12.5, 18.0])],
                 velocities=[[0.5, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert _follow(goal).accepted
    # In the mechanism's order the same values would start away from its joints.
    assert _check(dict(goal, joint_names=NAMES)).code is GoalCode.START_AWAY


def test_a_follow_goal_in_order_is_checked_as_a_trajectory():
    assert _follow(_goal()).accepted
    assert _follow(_goal(efforts=[[1.0, 1.0, 1.0], []])).code is GoalCode.EFFORT
    # A point of the wrong length is kept as it is, and refused.
    goal = _goal(joint_names=["rho3", "rho1", "rho2"], positions=[START, [1.0, 2.0]])
    assert _follow(goal).code is GoalCode.POSITION_COUNT


@pytest.mark.parametrize("goal, options, code, words", [
    (_goal(joint_names=["rho1", "rho2", "rho2"]), {}, GoalCode.JOINT_SET,
     "the joints must be ['rho1', 'rho2', 'rho3'] (each once, in any order), got"),
    (_goal(joint_names=["rho1", "rho2"]), {}, GoalCode.JOINT_SET, "each once"),
    (_goal(), {"multi_dof_joints": ["platform"]}, GoalCode.MULTI_DOF,
     "the mechanism has no multi-DOF joints: multi_dof_trajectory must be empty"),
    (_goal(), {"multi_dof_points": 1}, GoalCode.MULTI_DOF, "multi_dof_trajectory"),
    (_goal(velocities=[[], [0.0, 0.1, 0.0]]), {}, GoalCode.NOT_AT_REST,
     "the last point's velocities must be 0 (the trajectory ends at rest)"),
    (_goal(velocities=[[], [0.0, math.nan, 0.0]]), {}, GoalCode.NOT_AT_REST, "at rest"),
    (_goal(), {"header_stamp": (10, 0), "now": 12.0}, GoalCode.ENDED,
     "the trajectory starting at 10.000 s ended in the past (11.000 s < now 12.000 s)"),
])
def test_each_controller_check_has_its_code(goal, options, code, words):
    verdict = _follow(goal, **options)
    assert verdict.code is code and code in CONTROLLER_CODES
    assert words in verdict.reason


def test_a_follow_goal_stamped_in_the_future_or_not_yet_ended_is_accepted():
    assert _follow(_goal(), header_stamp=(200, 0), now=100.0).accepted
    assert _follow(_goal(), header_stamp=(99, 500_000_000), now=100.0).accepted


def test_the_controllers_checks_come_before_the_trajectorys():
    bad = _goal(positions=[[17.0, 30.0, 30.0], [17.0, 30.0, 51.0]],
                velocities=[[], [1.0, 0.0, 0.0]])
    assert _follow(bad).code is GoalCode.NOT_AT_REST
    assert _follow(dict(bad, velocities=[[], []])).code is GoalCode.OUT_OF_RANGE
    assert not CONTROLLER_CODES & {GoalCode.OUT_OF_RANGE, GoalCode.JOINT_NAMES}
