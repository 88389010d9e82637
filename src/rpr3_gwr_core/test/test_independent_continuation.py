"""Every returned path is followed again by a second, independent continuation
(:mod:`pose_reference`): in pose space, with its own legs, margin and
continuation, checking sign, margin threshold and goal pose, and the limits
holding between the trajectory's points."""

import math

import numpy as np
import pytest

from pose_reference import (assert_executable, assert_within_limits, follow, legs_of,
                            margin_of, random_full_configurations, random_slice_configurations,
                            same_aspect_pairs)
from rpr3_gwr_core import PAPER_GEOMETRY
from rpr3_gwr_core.exceptions import GWRError, InfeasiblePathError
from rpr3_gwr_core.paper import PAPER_GRID
from rpr3_gwr_core.planning.planner import PlanOptions, Planner
from rpr3_gwr_core.planning.validation import validate_path


# --- the reference itself --------------------------------------------------------------------

def test_reference_agrees_with_the_paper_examples():
    """The paper's example configurations satisfy the reference's legs, and
    the reference's margin is that of the project up to rounding."""
    for rho2, rho3, alpha_deg in ((12.0, 18.0, 122.82), (10.0, 25.0, -24.24)):
        count_poses = [p for p in PAPER_GEOMETRY.solve(np.array([[17.0, rho2, rho3]]))[1][0]
                       if np.isfinite(p[0])]
        pose = min(count_poses, key=lambda p: abs(math.remainder(
            p[2] - math.radians(alpha_deg), 2 * math.pi)))
        assert np.allclose(legs_of(pose), [17.0, rho2, rho3], atol=1e-9)
        assert margin_of(pose) == pytest.approx(float(PAPER_GEOMETRY.margin(pose)), abs=1e-9)


# --- segments that sampling alone misjudges ---------------------------------------------------

# The followed branch ends in a fold (margin ~1e-5) between two steps of
# 0.0625, where a corrector converges 7.7 pose units away on another branch
# of the same sign.
FOLD_SEGMENT = ([[16.0, 14.5, 6.75], [15.5, 14.5, 6.75]],
                [-15.137410089595532, -5.182549158504548, 0.22371427481345596])
# The margin dips to 6.1e-4 between two samples 0.0625 apart.
DIP_SEGMENT = ([[24.25, 23.5, 8.75], [24.0, 23.5, 8.75]],
               [-23.90871949478126, 4.0540883216658266, -0.289170656701961])


@pytest.mark.parametrize("segment", [FOLD_SEGMENT, DIP_SEGMENT], ids=["fold", "dip"])
def test_validator_refuses_what_the_reference_refuses(segment):
    joints, pose = segment
    reference = follow(np.array(joints), pose, 1e-3)
    assert not reference["ok"]
    assert not validate_path(PAPER_GEOMETRY, joints, pose).ok


def test_driver_style_following_stops_short_of_the_fold():
    """The continuation the simulated driver executes refuses the fold too."""
    from rpr3_gwr_core.mechanisms.continuation import FOLLOWED, follow_path

    joints, pose = FOLD_SEGMENT
    status, _, _, smallest = follow_path(PAPER_GEOMETRY, np.array(joints), np.array(pose),
                                         5e-4, 0.0625)
    assert status != FOLLOWED and smallest < 1e-3


# --- random same-aspect pairs, every returned path followed again ---------------------------

def test_full_roadmap_paths_pass_an_independent_continuation(full_planner):
    """Random same-aspect pairs, legs from poses, on the full 3-DOF roadmap:
    each plans (one aspect is one connected component there), and each path
    is executable by the reference, with its limits holding between points."""
    rng = np.random.default_rng(20261201)
    pairs = same_aspect_pairs(random_full_configurations(rng, 48))
    assert len(pairs) >= 20
    options = PlanOptions(max_velocity=2.0, max_acceleration=5.0)
    for (start, start_pose), (goal, goal_pose) in pairs:
        plan = full_planner.plan(start, goal, options)
        assert_executable(plan, goal_pose, full_planner.min_margin)
        assert_within_limits(plan, 2.0, 5.0)


# Hard pairs: their shortest paths run into a fold, dip between samples a
# validator step apart, or stray onto another sheet where a shortcut crosses
# a patch: (rho1, rho2, rho3, alpha [deg]) for start and goal.
HARD_PAIRS = [
    ((15.856800030099839, 13.350389426107647, 5.52274634045044, 17.86138662020088),
     (2.8297520855141283, 29.789979372485924, 28.4096171624187, -155.71380292508331)),
    ((22.35486434408209, 10.604039853166562, 25.21010846317499, 170.63560676503536),
     (13.986737081864305, 25.20743973732461, 41.45525655439277, -86.88719988812036)),
    ((16.586361199860892, 18.813204219486213, 19.440043489827747, 177.47910744966433),
     (31.96392016393267, 28.90869366364332, 25.820331436231207, -12.843549163859713)),
    ((25.14142057431614, 31.670382548061863, 5.58776898641194, -153.29419115746353),
     (26.721995831170915, 22.49574727157337, 14.865687520516225, 16.157301028787153)),
    ((32.95606895124558, 5.640996752178792, 23.007677054084137, 135.0230031967625),
     (26.878642485831683, 27.96142084050075, 41.34224274503682, -2.3914394575724782)),
]


@pytest.mark.parametrize("start, goal", HARD_PAIRS)
def test_hard_full_roadmap_pairs_plan_executable_paths(full_planner, start, goal):
    start = (*start[:3], math.radians(start[3]))
    goal = (*goal[:3], math.radians(goal[3]))
    plan = full_planner.plan(start, goal)
    assert np.allclose(legs_of(plan.poses[-1]), goal[:3], atol=1e-7)
    assert_executable(plan, plan.poses[-1], full_planner.min_margin)
    assert abs(math.remainder(plan.poses[-1][2] - goal[3], 2 * math.pi)) < 0.05


@pytest.fixture(scope="module")
def slice_planner(paper_roadmap):
    return Planner(paper_roadmap)


def test_slice_paths_pass_an_independent_continuation(slice_planner):
    """On the paper's slice: configurations drawn on the (theta1, alpha)
    torus at rho1 = 17; every path the planner returns is executable by the
    reference, and most same-aspect pairs plan (the others are in different
    components of the slice, which the roadmap says)."""
    rng = np.random.default_rng(17)
    configurations = random_slice_configurations(rng, PAPER_GRID.fixed_value(0), 60)
    planned = 0
    for (start, _), (goal, goal_pose) in same_aspect_pairs(configurations):
        try:
            plan = slice_planner.plan(start, goal, PlanOptions(smooth=True, max_velocity=1.0,
                                                                max_acceleration=0.5))
        except GWRError as error:
            assert isinstance(error, InfeasiblePathError), error
            assert error.reason in ("unreachable", "other_aspect"), error
            continue
        planned += 1
        assert_executable(plan, goal_pose, slice_planner.min_margin)
        assert_within_limits(plan, 1.0, 0.5)
    assert planned >= 10
