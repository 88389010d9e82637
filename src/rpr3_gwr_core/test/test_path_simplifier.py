"""The path simplifier, the motion checker and the planning problem, checked
directly: a simplified path keeps both ends, is never longer than its input,
and the independent reference follower (:mod:`pose_reference`) drives the
platform along it from the start pose to the goal pose."""

import math

import numpy as np
import pytest

from pose_reference import follow
from rpr3_gwr_core.exceptions import InvalidInputError, PlanningTimeoutError
from rpr3_gwr_core.planning import (MotionChecker, PathSimplifier, PlanningProblem, PlanOptions,
                                    Planner, PlanStatus, Termination)
from rpr3_gwr_core.planning.global_planning import global_paths
from rpr3_gwr_core.planning.simplifier import polyline_turns, segment_floor

D = math.radians
# The paper's first example, and a pair across the slice (as in test_planning).
PAIRS = [((17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))),
         ((17, 20, 25, D(29.47)), (17, 20, 25, D(96.13)))]
CLEARANCE = 0.02


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


def _length(joints):
    return float(np.linalg.norm(np.diff(joints, axis=0), axis=1).sum())


def _cell_path(planner, pair):
    """A problem and the waypoints of its first global path's cell path."""
    problem = PlanningProblem(planner.locate(pair[0]), planner.locate(pair[1]), CLEARANCE)
    s, g = problem.start, problem.goal
    route = global_paths(planner.patch_graph, s.patch, g.patch)[0].patches
    cells = planner.cell_search.search(route, s.cell, g.cell, clearance=CLEARANCE)
    joints, patches, _ = planner.repairer.waypoints(problem, cells.cells, cells.patches)
    return problem, joints, patches


def _assert_followed(joints, problem, min_margin):
    """The reference follower drives the platform along ``joints`` from the
    start pose, keeping ``min_margin``, to the goal pose."""
    followed = follow(joints, problem.start.pose, min_margin * (1 - 1e-3))
    assert followed["ok"], followed["why"]
    end, goal = np.array(followed["pose"]), problem.goal.pose
    assert np.allclose(end[:2], goal[:2], atol=1e-6)
    assert abs(math.remainder(end[2] - goal[2], 2 * math.pi)) < 1e-6


def _assert_simplifies(simplified, joints, problem):
    assert np.array_equal(simplified[0], joints[0])
    assert np.array_equal(simplified[-1], joints[-1])
    assert _length(simplified) <= _length(joints) * (1 + 1e-12)


@pytest.mark.parametrize("pair", PAIRS)
def test_a_shortcut_path_keeps_its_ends_shortens_and_is_followed(planner, pair):
    problem, joints, patches = _cell_path(planner, pair)
    keep = problem.kept_margin(planner.min_margin)
    result, kept = planner.simplifier.shortcut(joints, patches, problem, keep)
    assert result.ok, result.reason
    assert kept[0] == 0 and kept[-1] == len(joints) - 1 and np.all(np.diff(kept) > 0)
    _assert_simplifies(joints[kept], joints, problem)
    _assert_followed(joints[kept], problem, keep)


@pytest.mark.parametrize("pair", PAIRS)
def test_every_segment_of_a_taut_path_passes_the_motion_checker(planner, pair):
    # The whole cell path: its waypoints run from cell centre to cell centre.
    problem, joints, patches = _cell_path(planner, pair)
    result = planner.checker.check(joints, problem, planner.min_margin)
    assert result.ok, result.reason
    verdict, pulled, pulled_patches = planner.simplifier.pull_taut(joints, patches, result,
                                                                   problem)
    assert verdict.ok and len(pulled) == len(pulled_patches) < len(joints)
    _assert_simplifies(pulled, joints, problem)
    _assert_followed(pulled, problem, planner.min_margin)
    for k in range(len(pulled) - 1):
        segment = planner.checker.check_between(pulled[k:k + 2], verdict.poses[k],
                                                verdict.poses[k + 1], planner.min_margin)
        assert segment.ok, (k, segment.reason)


@pytest.mark.parametrize("pair", PAIRS)
def test_a_rounded_path_keeps_its_ends_shortens_and_is_followed(planner, pair):
    problem, joints, patches = _cell_path(planner, pair)
    keep = problem.kept_margin(planner.min_margin)
    result, kept = planner.simplifier.shortcut(joints, patches, problem, keep)
    rounded = planner.simplifier.round(joints[kept], patches[kept], problem,
                                       min(result.min_margin, keep))
    if rounded is None:
        pytest.skip("no corner of this pair can be cut")
    verdict, smooth, smooth_patches = rounded
    assert verdict.ok and len(smooth) == len(smooth_patches)
    _assert_simplifies(smooth, joints[kept], problem)
    _assert_followed(smooth, problem, min(result.min_margin, keep))


def test_pulling_taut_stops_at_a_passed_deadline(planner):
    problem, joints, patches = _cell_path(planner, PAIRS[0])
    result, kept = planner.simplifier.shortcut(joints, patches, problem, planner.min_margin)
    late = PlanningProblem(problem.start, problem.goal, CLEARANCE, Termination(0.0))
    with pytest.raises(PlanningTimeoutError):
        planner.simplifier.pull_taut(joints[kept], patches[kept], result, late)


def test_the_motion_checker_names_the_segment_where_a_path_fails(planner):
    """The straight segment between the two ends of the paper's first
    example crosses the singular locus (the ends lie in different patches
    of one aspect, joined only around it)."""
    problem, joints, patches = _cell_path(planner, PAIRS[0])
    straight = joints[[0, len(joints) // 2, -1]]
    result = planner.checker.check(straight, problem, planner.min_margin)
    if result.ok:
        pytest.skip("the straight path happens to pass")
    k = planner.checker.failed_segment(result, straight, patches[[0, len(joints) // 2, -1]])
    assert 1 <= k <= 2
    assert planner.checker.failed_segment(
        planner.checker.check(joints, problem, 0.0), joints, patches) == -1


class _AfterChecks(Termination):
    """Stops once asked ``checks`` times; its deadline never passes."""

    def __init__(self, checks):
        super().__init__()
        self.checks = checks

    def __call__(self):
        self.checks -= 1
        return self.checks < 0


def test_a_plan_cut_short_before_smoothing_is_approximate_and_says_so(planner):
    # Two checks (before the global path, before its cell path), then the deadline.
    plan = planner.plan(*PAIRS[0], PlanOptions(smooth=True), termination=_AfterChecks(2))
    assert plan.status is PlanStatus.APPROXIMATE_SOLUTION and plan.skipped == ("rounding",)
    assert plan.validation.ok and not plan.smoothed
    assert plan.to_dict()["status"] == "approximate_solution"
    done = planner.plan(*PAIRS[0], PlanOptions(smooth=True))
    assert done.status is PlanStatus.EXACT_SOLUTION and done.skipped == () and done.smoothed
    assert done.to_dict()["skipped"] == []


def test_turns_are_all_a_polyline_needs():
    # Random corners (never three in a line), each segment split at its middle.
    corners = np.random.default_rng(7).normal(size=(6, 3))
    middles = 0.5 * (corners[:-1] + corners[1:])
    points = np.vstack([corners[:1], np.stack([middles, corners[1:]], axis=1).reshape(-1, 3)])
    turns = polyline_turns(points)
    assert turns.tolist() == list(range(0, len(points), 2))
    assert _length(points[turns]) == pytest.approx(_length(points), rel=1e-12)
    with pytest.raises(InvalidInputError):
        polyline_turns(np.zeros((1, 3)))


def test_a_segment_floor_is_the_clearance_or_what_the_stretch_keeps():
    assert segment_floor(np.array([0.0, 0.5, 0.3]), 0.02) == 0.02
    assert segment_floor(np.array([0.0, 0.01, 0.3]), 0.02) == 0.01
    assert segment_floor(np.zeros(3), 0.02) == 0.02


def test_a_problem_refuses_what_it_cannot_plan(planner):
    s, g = (planner.locate(c) for c in PAIRS[0])
    for bad in ({"clearance": 1.0}, {"clearance": math.nan}, {"termination": 3.0}):
        with pytest.raises(InvalidInputError):
            PlanningProblem(s, g, **{"clearance": CLEARANCE, **bad})
    with pytest.raises(InvalidInputError):
        PlanningProblem(PAIRS[0][0], g, CLEARANCE)
    assert PlanningProblem(s, g, 0.0).kept_margin(planner.min_margin) == planner.min_margin


def test_the_kept_margin_is_a_quarter_of_the_clearance_or_half_the_lower_end_margin(planner):
    """A path may dip below an end's own margin (it leaves that end towards
    lower margins), so near-singular ends ask for half of theirs."""
    s, g = (planner.locate(c) for c in PAIRS[0])
    low = min(abs(s.margin), abs(g.margin))
    assert PlanningProblem(s, g, 1e-6).kept_margin(0.0) == pytest.approx(0.25e-6)
    assert PlanningProblem(s, g, 0.99).kept_margin(0.0) == pytest.approx(
        min(0.25 * 0.99, 0.5 * low))
    assert PlanningProblem(s, g, 0.99).kept_margin(1.0) == 1.0


def test_a_checker_and_a_simplifier_refuse_what_they_cannot_count(planner):
    for bad in ({"min_margin": -1.0}, {"max_step": 0.0}, {"max_step": math.inf}):
        with pytest.raises(InvalidInputError):
            MotionChecker(planner.roadmap, **bad)
    for bad in (-1, 1.5, True):
        with pytest.raises(InvalidInputError):
            PathSimplifier(planner.roadmap, planner.checker, bad)
