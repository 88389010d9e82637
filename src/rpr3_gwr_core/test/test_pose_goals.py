"""Plans whose ends are platform poses, on each shipped mechanism's default
slice (the file's box, the first joint fixed at its home value; the
five-bar's whole torus): the working modes of a pose against the legs and
the slice written in the test, the configurations a request resolves to,
and plans checked by those legs (every waypoint's joints reproduce its pose,
the path ends on the goal pose).
"""

import math
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InfeasiblePathError, InvalidInputError, NoSolutionError
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.planning import PlanOptions, Planner, PoseEnd, resolve_ends, working_modes
from rpr3_gwr_core.workspace.roadmap import build_roadmap

from test_inverse_kinematics import branch_signs, leg_lengths, platform_points

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
FILES = {"3-RPR": "paper_3rpr.yaml", "3-RRR": "three_rrr.yaml", "3-PRR": "three_prr.yaml",
         "5R": "five_bar.yaml"}
# The first joint of each default slice, as the files' home gives it (the
# five-bar's roadmap fixes no joint).
SLICE_VALUES = {"3-RPR": 17.0, "3-RRR": 0.0, "3-PRR": 15.0}
# The legs fit a waypoint's pose to this, relative to the pose's size: the
# validator's continuation converges far below it.
WAYPOINT_FIT = 1e-8


@pytest.fixture(scope="module", params=sorted(FILES))
def slice_planner(request):
    kind = request.param
    described = load_mechanism_file(CONFIG / FILES[kind])
    mechanism = described.mechanism
    fixed = ({} if kind not in SLICE_VALUES
             else {mechanism.joint_names[0]: SLICE_VALUES[kind]})
    planner = Planner(build_roadmap(mechanism, described.grid(fixed)))
    return kind, planner, described.default_home()


def two_poses_of_one_patch(planner, home):
    """The home's pose and the pose of a cell of its patch far from it."""
    start = planner.locate(home)
    seg = planner.roadmap.segmentation
    patch = seg.patches[start.patch]
    cell, slot = patch.cells[len(patch.cells) // 3], patch.slots[len(patch.cells) // 3]
    # The cell's solution as the direct kinematics gives it at the cell's
    # joints, the slice's value exactly: the roadmap stores it rounded.
    mechanism = planner.roadmap.mechanism
    count, poses = mechanism.solve(planner.roadmap.grid.joints_of(cell)[None])
    poses = poses[0, :count[0]]
    nearest = np.argmin(mechanism.pose_distance(poses, seg.field.poses[cell, slot]))
    return start.pose, poses[nearest]


def joined_to(planner, home, mode):
    """Whether the roadmap joins the home to a working mode."""
    try:
        planner.plan(home, mode.configuration, PlanOptions(feasibility_only=True))
    except InfeasiblePathError:
        return False
    return True


def assert_reproduces_poses(kind, joints, poses):
    """Each waypoint's joints place its pose: every leg has its length."""
    for q, pose in zip(joints, poses):
        size = max(1.0, np.max(np.abs(platform_points(pose))))
        lengths, wanted = leg_lengths(kind, pose, q)
        assert np.allclose(lengths, wanted, rtol=0, atol=WAYPOINT_FIT * size), (q, pose)


def assert_same_pose(kind, a, b):
    """Two poses agree to the continuation's precision (the pose a plan
    follows fits its legs to about 1e-8 of the pose's size)."""
    a, b = np.asarray(a), np.asarray(b)
    size = max(1.0, np.max(np.abs(platform_points(b))))
    assert np.allclose(a[:2], b[:2], rtol=0, atol=1e-6 * size)
    if kind != "5R":
        assert abs(math.remainder(a[2] - b[2], 2 * math.pi)) < 1e-6


def test_a_plan_between_two_poses_is_reproduced_by_the_legs(slice_planner):
    kind, planner, home = slice_planner
    start_pose, goal_pose = two_poses_of_one_patch(planner, home)
    ends = resolve_ends(planner, PoseEnd(tuple(start_pose)), PoseEnd(tuple(goal_pose)))
    plan = planner.plan(ends.start, ends.goal)
    assert plan.feasible and plan.validation.ok
    assert_reproduces_poses(kind, plan.joints, plan.poses)
    assert_same_pose(kind, plan.poses[0], start_pose)
    assert_same_pose(kind, plan.poses[-1], goal_pose)
    for pose, q in ((start_pose, plan.joints[0]), (goal_pose, plan.joints[-1])):
        lengths, wanted = leg_lengths(kind, pose, q)
        assert np.allclose(lengths, wanted, rtol=0, atol=1e-9 * max(1.0, np.max(wanted)))


def test_a_plan_from_joints_to_a_pose_ends_on_the_pose(slice_planner):
    kind, planner, home = slice_planner
    _, goal_pose = two_poses_of_one_patch(planner, home)
    ends = resolve_ends(planner, home, PoseEnd(tuple(goal_pose)))
    assert ends.start == tuple(home) and ends.start_mode is None
    plan = planner.plan(ends.start, ends.goal)
    assert_reproduces_poses(kind, plan.joints, plan.poses)
    assert_same_pose(kind, plan.poses[-1], goal_pose)


def test_the_working_mode_taken_is_reachable_and_of_largest_margin(slice_planner):
    kind, planner, home = slice_planner
    _, goal_pose = two_poses_of_one_patch(planner, home)
    ends = resolve_ends(planner, home, PoseEnd(tuple(goal_pose)))
    modes = working_modes(planner, goal_pose)
    joined = [m for m in modes if m.patch is not None and joined_to(planner, home, m)]
    assert ends.goal_mode.label in {m.label for m in joined}
    assert abs(ends.goal_mode.margin) == max(abs(m.margin) for m in joined)


def test_working_modes_lie_on_the_slice_where_their_first_joint_has_its_value(slice_planner):
    kind, planner, home = slice_planner
    _, pose = two_poses_of_one_patch(planner, home)
    modes = working_modes(planner, pose)
    assert modes
    for mode in modes:
        lengths, wanted = leg_lengths(kind, pose, mode.joints)
        assert np.allclose(lengths, wanted, rtol=0, atol=1e-9 * max(1.0, np.max(wanted)))
        if kind != "3-RPR":
            assert np.array_equal(branch_signs(kind, pose, mode.joints), mode.signs)
        if kind in SLICE_VALUES:
            value = SLICE_VALUES[kind]
            assert mode.on_slice == (abs(mode.joints[0] - value) <= 1e-4 * max(1.0, abs(value)))
        else:
            assert mode.on_slice
        assert (mode.patch is None) == bool(mode.unlocated)
        if not mode.on_slice:
            assert mode.patch is None and "off the slice" in mode.unlocated


def test_a_named_working_mode_is_taken_as_given(slice_planner):
    kind, planner, home = slice_planner
    _, pose = two_poses_of_one_patch(planner, home)
    for mode in working_modes(planner, pose):
        ends = resolve_ends(planner, home, PoseEnd(tuple(pose), mode.label))
        assert ends.goal == mode.configuration and ends.goal_mode.signs == mode.signs


def test_a_pose_off_the_slice_names_every_working_mode_and_why(slice_planner):
    kind, planner, home = slice_planner
    if kind not in SLICE_VALUES:
        pytest.skip("the five-bar's roadmap fixes no joint")
    _, pose = two_poses_of_one_patch(planner, home)
    # Moved by (-0.3, -0.2): the first leg's joint leaves the slice on every branch.
    moved = np.array(pose, dtype=float)
    moved[:2] -= (0.3, 0.2)
    modes = working_modes(planner, moved)
    assert modes and not any(m.on_slice for m in modes)
    with pytest.raises(InfeasiblePathError) as raised:
        resolve_ends(planner, home, PoseEnd(tuple(moved)))
    assert raised.value.reason == "unreachable"
    message = str(raised.value)
    for mode in modes:
        assert f"{mode.label} (" in message
    assert "off the slice" in message


def test_an_unreachable_pose_has_no_solution(slice_planner):
    kind, planner, home = slice_planner
    far = (500.0, 500.0) if kind == "5R" else (500.0, 500.0, 0.0)
    if kind == "3-RPR":
        assert working_modes(planner, far)[0].patch is None
        return
    assert working_modes(planner, far) == []
    with pytest.raises(NoSolutionError):
        resolve_ends(planner, home, PoseEnd(far))


@pytest.mark.parametrize("bad", [(math.nan, 1.0, 0.0), (1.0,), ("x", 1.0, 2.0)])
def test_a_malformed_pose_is_invalid_input(slice_planner, bad):
    kind, planner, home = slice_planner
    pose = bad[:2] if kind == "5R" and len(bad) == 3 else bad
    with pytest.raises(InvalidInputError):
        working_modes(planner, pose)
    with pytest.raises(InvalidInputError):
        resolve_ends(planner, home, PoseEnd(pose))


@pytest.mark.parametrize("mode", ["+*+", "++++", (1, 0, 1), 7])
def test_a_malformed_working_mode_is_invalid_input(slice_planner, mode):
    kind, planner, home = slice_planner
    _, pose = two_poses_of_one_patch(planner, home)
    with pytest.raises(InvalidInputError):
        resolve_ends(planner, home, PoseEnd(tuple(pose), mode))
