"""The validator resumed where an earlier verdict's path agrees with the one
checked gives the verdict of following from the start, and passed verdicts
of stretches laid end to end are the whole path's verdict."""

import math

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.planning import Planner, PlanningProblem
from rpr3_gwr_core.planning.global_planning import global_paths
from rpr3_gwr_core.planning.validation import joined_validation, validation_part

D = math.radians
# The paper's first example: its ends lie in patches joined only around the
# singular locus, so the straight way between them fails.
START, GOAL = (17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))
CLEARANCE = 0.02


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


@pytest.fixture(scope="module")
def cell_path(planner):
    """A problem and the waypoints of its first global path's cell path."""
    problem = PlanningProblem(planner.locate(START), planner.locate(GOAL), CLEARANCE)
    s, g = problem.start, problem.goal
    route = global_paths(planner.patch_graph, s.patch, g.patch)[0].patches
    cells = planner.cell_search.search(route, s.cell, g.cell, clearance=CLEARANCE)
    joints, _, _ = planner.repairer.waypoints(problem, cells.cells, cells.patches)
    return problem, joints


def _assert_same(resumed, scratch, steps=True):
    assert (resumed.ok, resumed.reason, resumed.failed_segment, resumed.aspect) \
        == (scratch.ok, scratch.reason, scratch.failed_segment, scratch.aspect)
    assert resumed.min_margin == pytest.approx(scratch.min_margin, rel=1e-9)
    np.testing.assert_allclose(resumed.poses, scratch.poses, rtol=0, atol=1e-9)
    if steps:
        assert resumed.steps == scratch.steps
        np.testing.assert_allclose(resumed.segment_margins, scratch.segment_margins,
                                   rtol=1e-9)
        np.testing.assert_array_equal(resumed.segment_steps, scratch.segment_steps)


def test_a_check_resumed_where_the_paths_part_is_the_check_from_the_start(planner, cell_path):
    problem, joints = cell_path
    checker, keep = planner.checker, planner.min_margin
    earlier = checker.check(joints, problem, keep)
    assert earlier.ok, earlier.reason
    n = len(joints)
    for part in sorted({1, n // 4, n // 2, n - 3}):
        # The cell path to waypoint ``part``, then straight to the goal: it
        # passes or fails, and either way resuming must not change that.
        other = np.vstack([joints[:part + 1], joints[-1:]])
        known = checker.resumable(earlier, joints, other)
        assert known == (earlier, part)
        _assert_same(checker.check(other, problem, keep, known),
                     checker.check(other, problem, keep))


def test_a_failed_check_resumes_only_where_the_platform_was_followed(planner, cell_path):
    problem, joints = cell_path
    checker, keep = planner.checker, planner.min_margin
    straight = joints[[0, len(joints) // 2, -1]]
    failed = checker.check(straight, problem, keep)
    if failed.ok:
        pytest.skip("the straight path happens to pass")
    assert failed.reached() == failed.failed_segment
    assert np.isnan(failed.segment_margins[failed.failed_segment:]).all()
    with pytest.raises(InvalidInputError, match="does not reach"):
        checker.check(straight, problem, keep, (failed, failed.failed_segment))
    if failed.failed_segment > 1:
        known = checker.resumable(failed, straight, straight)
        _assert_same(checker.check(straight, problem, keep, known), failed)


def test_a_resumed_check_at_a_higher_margin_fails_where_the_shared_start_dips(planner,
                                                                              cell_path):
    problem, joints = cell_path
    checker = planner.checker
    earlier = checker.check(joints, problem, 0.0)
    assert earlier.ok, earlier.reason
    part = len(joints) // 2
    lowest = int(np.argmin(earlier.segment_margins[:part]))
    higher = float(earlier.segment_margins[lowest]) * (1 + 1e-6)
    resumed = checker.check(joints, problem, higher, (earlier, part))
    assert not resumed.ok and resumed.failed_segment == lowest + 1
    # From the start, following stops inside that segment; the earlier
    # verdict followed all of it.
    _assert_same(resumed, checker.check(joints, problem, higher), steps=False)


def test_stretches_of_a_passed_verdict_laid_end_to_end_are_the_whole_verdict(planner,
                                                                             cell_path):
    problem, joints = cell_path
    whole = planner.checker.check(joints, problem, planner.min_margin)
    assert whole.ok, whole.reason
    assert whole.min_margin == pytest.approx(whole.segment_margins.min(), rel=1e-12)
    assert whole.steps == whole.segment_steps.sum()
    n = len(joints)
    cuts = [0, n // 3, 2 * n // 3, n - 1]
    joined = joined_validation(validation_part(whole, a, b) for a, b in zip(cuts, cuts[1:]))
    _assert_same(joined, whole)


def test_only_passed_verdicts_are_cut_into_stretches_or_joined(planner, cell_path):
    problem, joints = cell_path
    whole = planner.checker.check(joints, problem, planner.min_margin)
    for first, last in ((0, 0), (2, 1), (-1, 1), (0, len(joints))):
        with pytest.raises(InvalidInputError):
            validation_part(whole, first, last)
    failed = planner.checker.check(joints[[0, -1]], problem, planner.min_margin)
    for parts in ([], [failed]) if not failed.ok else ([],):
        with pytest.raises(InvalidInputError):
            joined_validation(parts)
