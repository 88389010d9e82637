"""A plan stops at its termination condition, with what it has."""

import math
import time

import pytest

from pose_reference import assert_executable
from rpr3_gwr_core import PlanningTimeoutError, Planner, PlanOptions, Termination
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.planning.termination import monotonic

D = math.radians
Q1, Q2 = (17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


class _AfterChecks(Termination):
    """Stops once it has been asked ``checks`` times (its deadline, which the
    compiled searches read, never passes)."""

    def __init__(self, checks):
        super().__init__()
        self.checks = checks

    def __call__(self):
        self.checks -= 1
        return self.checks < 0


def test_the_compiled_clock_is_the_monotonic_clock():
    before = time.monotonic()
    now = monotonic()
    assert before <= now <= time.monotonic()


def test_a_negative_time_limit_is_refused():
    with pytest.raises(InvalidInputError):
        Termination.after(-1.0)
    with pytest.raises(InvalidInputError):
        Termination.after(math.nan)


def test_a_passed_deadline_times_out_without_a_path(planner):
    with pytest.raises(PlanningTimeoutError) as error:
        planner.plan(Q1, Q2, termination=Termination.after(0.0))
    assert error.value.code == "TIMEOUT"


def test_the_local_search_stops_at_its_deadline(planner):
    """A search settling thousands of nodes looks at the clock on the way."""
    s, g = planner.locate(Q1), planner.locate(Q2)
    path = planner.plan(Q1, Q2, PlanOptions(feasibility_only=True)).global_paths[0]
    planner.cell_search.search(path.patches, s.cell, g.cell)  # completes without a deadline
    with pytest.raises(PlanningTimeoutError):
        planner.cell_search.search(path.patches, s.cell, g.cell, termination=Termination(0.0))


def test_a_deadline_passing_before_smoothing_returns_the_valid_path_unsmoothed(planner):
    """One check before the global path, one before its local path, then
    the deadline: the validated path comes back as it is."""
    plan = planner.plan(Q1, Q2, PlanOptions(smooth=True), termination=_AfterChecks(2))
    assert plan.validation.ok and not plan.smoothed
    assert_executable(plan, plan.poses[-1], planner.min_margin)
    assert planner.plan(Q1, Q2, PlanOptions(smooth=True)).smoothed


def test_the_cli_answers_a_passed_time_limit_with_a_timeout_error(capsys):
    from rpr3_gwr_core.io.cli import main

    assert main(["plan", "--start", "12", "18", "122.82", "--goal", "10", "25", "-24.24",
                 "--time-limit", "0"]) == 1
    assert '"code": "TIMEOUT"' in capsys.readouterr().out


@pytest.mark.parametrize("bad", [{"global_paths": 0}, {"repairs": -1}, {"split_shortcuts": 1.5},
                                 {"detour_weight": math.nan}, {"repairs": True},
                                 {"detour_inflation": 0}, {"detour_inflation": 2.0}])
def test_retries_refuse_what_cannot_be_counted(bad):
    from rpr3_gwr_core.planning import Retries

    with pytest.raises(InvalidInputError):
        Retries(**bad)


def test_a_planner_that_does_not_retry_still_plans_the_papers_examples(paper_roadmap):
    from rpr3_gwr_core.planning import Retries

    planner = Planner(paper_roadmap, retries=Retries(global_paths=1, repairs=0,
                                                    split_shortcuts=0, detour_weight=0.0))
    assert planner.plan(Q1, Q2, PlanOptions(smooth=True)).validation.ok
