"""The five-bar (5R) behind the Mechanism interface, against closed-form
references written here: the elbows from the joints, the end effector by the
law of cosines (``P = C1 + l2 (cos(phi +- gamma), sin(phi +- gamma))`` with
``phi`` the direction of C1C2 and ``cos gamma = |C1C2| / (2 l2)``), the
margin as the normalised cross product of the distal links.  What every
mechanism owes the interface is checked in ``test_mechanism_contract.py``."""

import math

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InfeasiblePathError, InvalidInputError, SingularityError
from rpr3_gwr_core.mechanisms import DEFAULT_FIVE_BAR
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.workspace.grid import Axis, Grid
from rpr3_gwr_core.workspace.roadmap import build_roadmap

# The commercial five-bar's proportions [m], written again rather than read
# from the mechanism.
D, L1, L2 = 0.118, 0.09, 0.118
# Where the elbows coincide: C2 - C1 = 0 needs sin th1 = sin th2 and
# 2 l1 cos th1 = d.
TH_COINCIDE = math.acos(D / (2 * L1))
COINCIDENT = (0.855878, 2.285714)  # the same point to six decimals
# A well-conditioned joint vector (both solutions at margin 0.92) and another
# one (margin 0.94) for moves and plans.
Q0 = (2.0, 1.1)
Q1 = (1.4, 0.4)
# Two more (margins 0.98 and 0.86) whose straight joint segment crosses the
# joints without solutions (around th1 = +-pi, th2 = 0): a plan between them
# must go around.
AROUND = ((2.4, 1.6), (2.4, -2.0))


def elbows(th1, th2):
    th1, th2 = np.asarray(th1, dtype=float), np.asarray(th2, dtype=float)
    return (np.stack([L1 * np.cos(th1), L1 * np.sin(th1)], -1),
            np.stack([D + L1 * np.cos(th2), L1 * np.sin(th2)], -1))


def reference_solutions(th1, th2):
    """``(exists, plus, minus)``: whether the distal circles meet, and the
    end effector on each side of C1C2 (plus: to the left going from C1 to C2)."""
    c1, c2 = elbows(th1, th2)
    gap = c2 - c1
    dist = np.hypot(gap[..., 0], gap[..., 1])
    exists = dist <= 2 * L2
    phi = np.arctan2(gap[..., 1], gap[..., 0])
    gamma = np.arccos(np.clip(dist / (2 * L2), -1.0, 1.0))
    plus = c1 + L2 * np.stack([np.cos(phi + gamma), np.sin(phi + gamma)], -1)
    minus = c1 + L2 * np.stack([np.cos(phi - gamma), np.sin(phi - gamma)], -1)
    return exists, plus, minus


def reference_residual(pose, th1, th2):
    c1, c2 = elbows(th1, th2)
    return np.stack([np.sum((pose - c1) ** 2, -1) - L2**2, np.sum((pose - c2) ** 2, -1) - L2**2],
                    -1)


def reference_margin(pose, th1, th2):
    c1, c2 = elbows(th1, th2)
    u1, u2 = pose - c1, pose - c2
    u1 = u1 / np.linalg.norm(u1, axis=-1, keepdims=True)
    u2 = u2 / np.linalg.norm(u2, axis=-1, keepdims=True)
    return u1[..., 0] * u2[..., 1] - u1[..., 1] * u2[..., 0]


def torus_sample(n):
    th = -math.pi + 2 * math.pi * np.arange(n) / n
    return np.stack([m.ravel() for m in np.meshgrid(th, th, indexing="ij")], -1)


# --- direct kinematics ----------------------------------------------------------

def test_two_solutions_on_81_5_percent_of_the_torus():
    joints = torus_sample(1000)
    count, poses = DEFAULT_FIVE_BAR.solve(joints)
    assert count.dtype == np.uint8 and count.shape == (len(joints),)
    assert poses.shape == (len(joints), 2, 2)
    exists, _, _ = reference_solutions(joints[:, 0], joints[:, 1])
    assert abs(exists.mean() - 0.815) < 1e-3
    assert set(np.unique(count).tolist()) <= {0, 2}
    assert np.array_equal(count == 2, exists)
    assert np.all(np.isnan(poses[count == 0]))
    assert np.all(np.isfinite(poses[count == 2]))


def test_solutions_are_the_closed_form_with_opposite_aspects():
    joints = torus_sample(300)
    count, poses = DEFAULT_FIVE_BAR.solve(joints)
    ok = count == 2
    th1, th2 = joints[ok, 0], joints[ok, 1]
    for k in (0, 1):
        assert np.max(np.abs(reference_residual(poses[ok, k], th1, th2))) < 1e-12
    _, plus, minus = reference_solutions(th1, th2)
    assert np.max(np.abs(poses[ok, 0] - plus)) < 1e-12
    assert np.max(np.abs(poses[ok, 1] - minus)) < 1e-12
    margin_plus = reference_margin(poses[ok, 0], th1, th2)
    margin_minus = reference_margin(poses[ok, 1], th1, th2)
    assert np.all(margin_plus > 0) and np.all(margin_minus < 0)
    both = DEFAULT_FIVE_BAR.margin(poses[ok], joints[ok, None, :])
    assert np.allclose(both, np.stack([margin_plus, margin_minus], -1), rtol=0, atol=1e-12)
    assert np.all(np.abs(both) <= 1.0)


def fold_th1():
    """th1 < 0 where, at th2 = 0, the elbows are 2 l2 apart (the fold): with
    C2 = (d + l1, 0), |C2 - C1|**2 = (d + l1)**2 + l1**2 - 2 (d + l1) l1 cos th1;
    just above it they come closer."""
    return -math.acos(((D + L1) ** 2 + L1**2 - 4 * L2**2) / (2 * (D + L1) * L1))


def test_fold_is_the_singularity():
    # The solutions merge there, at margin 0.
    th1 = fold_th1()
    count, poses = DEFAULT_FIVE_BAR.solve(np.array([[th1 + 1e-6, 0.0]]))
    assert count[0] == 2
    margins = DEFAULT_FIVE_BAR.margin(poses[0], np.array([th1 + 1e-6, 0.0]))
    assert np.all(np.abs(margins) < 1e-2) and margins[0] > 0 > margins[1]


@pytest.mark.parametrize("joints", [COINCIDENT, (TH_COINCIDE, math.pi - TH_COINCIDE)])
def test_coinciding_elbows_have_no_isolated_solutions(joints):
    count, poses = DEFAULT_FIVE_BAR.solve(np.array([joints]))
    assert count.tolist() == [0] and np.all(np.isnan(poses))
    with pytest.raises(SingularityError, match="coincide.*circle of singular poses"):
        DEFAULT_FIVE_BAR.check_joints(np.array(joints))
    assert SingularityError.code == "SINGULAR"


def test_joints_near_the_coincidence_are_accepted():
    joints = np.array([COINCIDENT[0] + 1e-3, COINCIDENT[1]])
    DEFAULT_FIVE_BAR.check_joints(joints)
    count, poses = DEFAULT_FIVE_BAR.solve(joints[None, :])
    assert count[0] == 2
    assert np.max(np.abs(reference_residual(poses[0], *joints))) < 1e-12
    with pytest.raises(InvalidInputError):
        DEFAULT_FIVE_BAR.check_joints(np.array([math.nan, 0.0]))
    with pytest.raises(InvalidInputError):
        DEFAULT_FIVE_BAR.solve(np.zeros((4, 3)))


def test_margin_of_one_pose_is_the_reference():
    _, plus, _ = reference_solutions(*Q0)
    one = DEFAULT_FIVE_BAR.margin(plus, np.array(Q0))
    assert np.ndim(one) == 0 and float(one) == pytest.approx(reference_margin(plus, *Q0))


# --- continuation ---------------------------------------------------------------

@pytest.mark.parametrize("branch", [1, 2])
def test_step_follows_its_branch(branch):
    m = DEFAULT_FIVE_BAR
    q = np.array(Q0)
    pose = tuple(reference_solutions(*q)[branch])
    move = np.array([0.004, -0.004])  # the margin falls from 0.92 to 0.53
    for _ in range(50):
        stepped = m.step(pose, q, q + move)
        assert stepped is not None
        q = q + move
        pose, margin = stepped
        exact = reference_solutions(*q)[branch]
        assert np.max(np.abs(reference_residual(np.array(pose), *q))) < 1e-9 * m.scale**2
        assert np.max(np.abs(np.array(pose) - exact)) < 1e-8
        assert margin == pytest.approx(reference_margin(exact, *q), abs=1e-6)
        assert (margin > 0) == (branch == 1)


def test_step_fails_past_the_fold():
    # Past the fold the pose has nowhere to go: the step must neither land on
    # the other branch nor return a pose that misses the joints.
    m = DEFAULT_FIVE_BAR
    th1 = fold_th1()
    q_from, q_to = np.array([th1 + 0.02, 0.0]), np.array([th1 - 0.02, 0.0])
    assert reference_solutions(*q_from)[0] and not reference_solutions(*q_to)[0]
    assert m.step(tuple(reference_solutions(*q_from)[1]), q_from, q_to) is None


def test_batch_predict_and_correct():
    m = DEFAULT_FIVE_BAR
    rng = np.random.default_rng(3)
    q0 = np.array(Q0) + rng.uniform(-0.2, 0.2, (64, 2))
    q1 = q0 + rng.uniform(-0.01, 0.01, (64, 2))
    for branch in (1, 2):
        start = reference_solutions(q0[:, 0], q0[:, 1])[branch]
        exact = reference_solutions(q1[:, 0], q1[:, 1])[branch]
        predicted = m.predict(start, q0, q1)
        assert predicted.shape == (64, 2)
        # First order: the predictor misses by the square of the move.
        assert np.max(np.linalg.norm(predicted - exact, axis=-1)) < 1e-4
        corrected = m.correct(predicted, q1, 4)
        assert np.max(np.abs(corrected - exact)) < 1e-12
        residual = m.residual(corrected, q1)
        assert residual.shape == (64, 2)
        assert np.allclose(residual, reference_residual(corrected, q1[:, 0], q1[:, 1]),
                           atol=1e-15)


# --- roadmap and planner ----------------------------------------------------------

@pytest.fixture(scope="module")
def roadmap():
    """The roadmap over the whole joint square [-pi, pi]**2, 121 x 121 cells."""
    step = 2 * math.pi / 120
    grid = Grid(axes=(Axis(0, -math.pi, math.pi, step), Axis(1, -math.pi, math.pi, step)))
    return build_roadmap(DEFAULT_FIVE_BAR, grid)


def test_roadmap_has_one_patch_per_aspect_and_no_gate_between_them(roadmap):
    seg = roadmap.segmentation
    assert roadmap.grid.shape == (121, 121)
    assert set(np.unique(roadmap.field.count).tolist()) <= {0, 2}
    largest = max(seg.patches.values(), key=lambda p: p.cells.size)
    assert largest.n_solutions == 2
    for gate in seg.gates.values():
        a, b = (seg.patches[p].aspect for p in gate.patches)
        assert a == b


def test_plan_between_the_two_assembly_modes_is_other_aspect(roadmap):
    _, plus, minus = reference_solutions(*Q0)
    with pytest.raises(InfeasiblePathError) as error:
        Planner(roadmap).plan((*Q0, plus[1]), (*Q0, minus[1]))
    assert error.value.reason == "other_aspect"


@pytest.mark.parametrize("branch", [1, 2])
@pytest.mark.parametrize("ends", [(Q0, Q1), AROUND])
def test_plan_inside_one_aspect_stays_on_its_branch(roadmap, ends, branch):
    (q0, q1), sign = ends, (1 if branch == 1 else -1)
    start, goal = reference_solutions(*q0)[branch], reference_solutions(*q1)[branch]
    plan = Planner(roadmap).plan((*q0, start[1]), (*q1, goal[1]))
    assert plan.feasible and plan.validation.ok
    assert np.allclose(plan.joints[0], q0) and np.allclose(plan.joints[-1], q1)
    assert plan.poses.shape == plan.joints.shape
    if ends == AROUND:
        assert len(plan.joints) > 2
    for q, pose in zip(plan.joints, plan.poses):
        exists, plus, minus = reference_solutions(*q)
        assert exists
        assert np.max(np.abs(pose - (plus, minus)[branch - 1])) < 1e-6
        assert np.sign(reference_margin(pose, *q)) == sign
    # Between waypoints too the branch is kept: every joint vector of the
    # segments has its two solutions, away from the fold.
    s = np.linspace(0.0, 1.0, 201)[:, None, None]
    dense = (plan.joints[:-1] + s * np.diff(plan.joints, axis=0)).reshape(-1, 2)
    exists, plus, minus = reference_solutions(dense[:, 0], dense[:, 1])
    assert np.all(exists)
    same = (plus, minus)[branch - 1]
    margins = reference_margin(same, dense[:, 0], dense[:, 1])
    assert np.all(np.sign(margins) == sign) and np.min(np.abs(margins)) > 1e-3


# --- on the torus: both joints periodic ---------------------------------------------

@pytest.fixture(scope="module")
def torus_roadmap():
    """The roadmap over the joint torus, 120 x 120 cells, both axes periodic."""
    step = 2 * math.pi / 120
    grid = Grid(axes=(Axis(0, -math.pi, math.pi - step, step, periodic=True),
                      Axis(1, -math.pi, math.pi - step, step, periodic=True)))
    return build_roadmap(DEFAULT_FIVE_BAR, grid)


def _assert_on_branch(joints, branch):
    """Every joint vector of a polyline, densely sampled, has both solutions
    and keeps the branch's sign, clear of the fold (closed form)."""
    s = np.linspace(0.0, 1.0, 201)[:, None, None]
    dense = (joints[:-1] + s * np.diff(joints, axis=0)).reshape(-1, 2)
    exists, plus, minus = reference_solutions(dense[:, 0], dense[:, 1])
    assert np.all(exists)
    margins = reference_margin((plus, minus)[branch - 1], dense[:, 0], dense[:, 1])
    assert np.all(np.sign(margins) == (1 if branch == 1 else -1))
    assert np.min(np.abs(margins)) > 1e-3


@pytest.mark.parametrize("branch", [1, 2])
def test_a_plan_across_the_seam_goes_the_short_way(torus_roadmap, branch):
    start_q, goal_q = (3.1, 2.5), (-3.1, 2.5)
    start, goal = reference_solutions(*start_q)[branch], reference_solutions(*goal_q)[branch]
    plan = Planner(torus_roadmap).plan((*start_q, start[1]), (*goal_q, goal[1]))
    assert plan.validation.ok
    # 2 pi - 6.2 = 0.083 rad across the seam, not 6.2 rad back round.
    assert np.linalg.norm(np.diff(plan.joints, axis=0), axis=1).sum() < 0.1
    assert np.allclose(plan.joints[0], start_q)
    assert np.allclose(np.remainder(plan.joints[-1] - goal_q + math.pi, 2 * math.pi), math.pi)
    _assert_on_branch(plan.joints, branch)


def test_random_pairs_on_the_torus_stay_on_their_branch(torus_roadmap):
    """Each aspect is one patch on the torus (the two-solution set is one
    band): every same-branch pair is planned, and every path, checked in
    closed form, stays on its branch."""
    planner = Planner(torus_roadmap)
    rng = np.random.default_rng(4)
    planned = 0
    while planned < 24:
        q = rng.uniform(-math.pi, math.pi, (2, 2))
        exists, plus, minus = reference_solutions(q[:, 0], q[:, 1])
        branch = int(rng.integers(1, 3))
        ends = (plus, minus)[branch - 1]
        if not exists.all() or np.min(np.abs(reference_margin(ends, q[:, 0], q[:, 1]))) < 0.05:
            continue
        plan = planner.plan((*q[0], ends[0, 1]), (*q[1], ends[1, 1]))
        assert plan.validation.ok
        _assert_on_branch(plan.joints, branch)
        planned += 1
