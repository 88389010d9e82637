"""The planar 3-RRR behind the Mechanism interface, against references
written here: the platform points and elbows from their definitions, the
residuals ``|B_i - C_i|**2 - l2**2``, the normalised ``det Jx``, and an
independent direct kinematics through the torus of poses at fixed th1.

At fixed th1, B1 lies on the circle of radius l2 around the elbow C1
(angle phi) and alpha is free: the poses form the torus (phi, alpha).  Each
torus point fixes B2 and B3, and then th2 and th3 in closed form by circle
intersection (the elbow C_i is at l1 from A_i and at l2 from B_i: 0, 1 or 2
elbows, the two sides of the line A_i B_i).  The solutions of joints
(th1, th2, th3) are the torus points mapped onto (th2, th3): found here by a
dense scan of the torus and Newton on the map.  What every mechanism, and
every mechanism whose base points move with its joints, owes this reference
and the interface is checked in ``test_mechanism_contract.py``.
"""

from collections import deque
import math

import networkx as nx
import numpy as np
import pytest

from rpr3_gwr_core.mechanisms import DEFAULT_THREE_RRR, PAPER_GEOMETRY, ThreeRPR
from rpr3_gwr_core.mechanisms.three_leg_solver import solve_with_bases
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.workspace.grid import Axis, Grid
from rpr3_gwr_core.workspace.roadmap import build_roadmap

from moving_base_reference import MovingBaseReference, wrap

# The default geometry, written again rather than read from the mechanism:
# the paper's base points and platform (sides 17.04, 16.54, 20.84), l1 = 8
# and l2 = 12 on every leg.
A = np.array([[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]])
D1, D2, D3 = 17.04, 16.54, 20.84
BETA = math.acos((D1**2 + D3**2 - D2**2) / (2 * D1 * D3))
L1, L2 = 8.0, 12.0
SCALE = max(D1, D2, D3)
# Joints with six direct-kinematic solutions.
Q6 = (0.0, 0.13499, 0.55223)


def elbows(th):
    th = np.asarray(th, dtype=float)
    return A + L1 * np.stack([np.cos(th), np.sin(th)], -1)


def leg_angle(b, i, side):
    """th_i of the elbow at L1 from A_i and L2 from ``b`` (..., 2), on one
    side (+1 or -1) of the line A_i b; NaN where the circles do not meet."""
    g = b - A[i]
    d = np.hypot(g[..., 0], g[..., 1])
    along = (L1**2 - L2**2 + d**2) / (2 * d)
    across2 = L1**2 - along**2
    across = np.sqrt(np.where(across2 >= 0, across2, np.nan))
    ex, ey = g[..., 0] / d, g[..., 1] / d
    return np.arctan2(along * ey + side * across * ex, along * ex - side * across * ey)


REFERENCE = MovingBaseReference(elbows, leg_angle, L2, D1, D3, BETA, angular=True)
reference_residual, reference_margin = REFERENCE.residual, REFERENCE.margin
torus_map, follow = REFERENCE.torus_map, REFERENCE.follow


def torus_preimages(th, n=720):
    return REFERENCE.torus_preimages(th, window=0.5, n=n)


# --- the mechanism as a value ---------------------------------------------------

def test_elbows_are_the_reference():
    assert np.allclose(DEFAULT_THREE_RRR.elbows(Q6), elbows(Q6))


def test_per_row_base_points_solve_as_separate_3rprs():
    """The 3-RPR's batch solver with base points per row, which the 3-RRR
    uses, answers each row as the 3-RPR of that row's base points does."""
    rng = np.random.default_rng(3)
    rho = rng.uniform(2.0, 28.0, (300, 3))
    bases = A + rng.uniform(-8.0, 8.0, (300, 3, 2))
    count, poses = solve_with_bases(rho, bases, PAPER_GEOMETRY)
    for k in range(0, 300, 7):
        one = ThreeRPR(a1=tuple(bases[k, 0]), a2=tuple(bases[k, 1]), a3=tuple(bases[k, 2]))
        expected = one.direct_kinematics(rho[k])
        assert count[k] == len(expected)
        assert np.allclose(poses[k, : count[k]], expected, rtol=0, atol=1e-6)
    fixed = np.broadcast_to(PAPER_GEOMETRY.base, bases.shape)
    count, poses = solve_with_bases(rho, fixed, PAPER_GEOMETRY)
    expected_count, expected = PAPER_GEOMETRY.solve(rho)
    assert np.array_equal(count, expected_count)
    assert np.allclose(poses, expected, rtol=0, atol=1e-6, equal_nan=True)


# --- continuation -----------------------------------------------------------------

def test_batch_predict_and_correct():
    m = DEFAULT_THREE_RRR
    count, poses = m.solve(np.array([Q6]))
    poses = poses[0, : count[0]]
    start = np.broadcast_to(Q6, poses.shape)
    direction = np.array([0.01, -0.01, 0.005])
    target = start + direction
    # The predictor is first order: its residual is of second order in the
    # step, a quarter of it for half the step.
    misfit = [np.max(np.abs(reference_residual(m.predict(poses, start, start + h * direction),
                                               start + h * direction)), -1)
              for h in (1.0, 0.5)]
    assert np.all((misfit[1] > 0.2 * misfit[0]) & (misfit[1] < 0.3 * misfit[0]))
    assert np.all(misfit[0] < 0.1 * np.max(np.abs(reference_residual(poses, target)), -1))
    predicted = m.predict(poses, start, target)
    corrected = m.correct(predicted, target, 4)
    assert np.max(np.abs(reference_residual(corrected, target))) < 1e-10 * SCALE**2
    assert np.max(np.abs(m.residual(corrected, target))) < 1e-10 * SCALE**2
    for pose, expected in zip(corrected, poses):
        step = m.step(expected, Q6, target[0])
        assert step is not None and np.allclose(pose, step[0], atol=1e-9)


def test_step_takes_the_short_way_across_a_turn():
    """Joints are angles: from just below +pi to just above -pi is a small move."""
    m = DEFAULT_THREE_RRR
    q0 = np.array([math.pi - 0.001, 0.5, 1.0])
    q1 = np.array([-math.pi + 0.001, 0.5, 1.0])
    count, poses = m.solve(q0[None])
    assert count[0] > 0
    for pose in poses[0, : count[0]]:
        result = m.step(pose, q0, q1)
        assert result is not None
        assert np.max(np.abs(np.array(result[0]) - pose)) < 0.05
        assert np.max(np.abs(reference_residual(np.array(result[0]), q1))) < 1e-9 * SCALE**2
        predicted = m.predict(pose, q0, q1)
        assert np.max(np.abs(predicted - pose)) < 0.05


def test_a_stretched_leg_is_no_obstacle():
    """At th1 = 0 with B1 = (l1 + l2, 0) leg 1 is stretched (a serial
    singularity): walking th1 across it, the pose follows with its margin
    far from 0, whatever the step."""
    m = DEFAULT_THREE_RRR
    pose, q = None, None
    for alpha in np.linspace(-math.pi, math.pi, 361):
        for side2, side3 in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            th2, th3, candidate = torus_map(0.0, 0.0, alpha, side2, side3)
            if np.isfinite(th2) and np.isfinite(th3):
                joints = np.array([0.0, th2, th3])
                if q is None or abs(reference_margin(candidate, joints)) \
                        > abs(reference_margin(pose, q)):
                    pose, q = candidate, joints
    assert np.allclose(pose[:2], (L1 + L2, 0.0))
    margin = reference_margin(pose, q)
    assert abs(margin) > 0.5
    for h in (0.05, 0.01, 0.003, 0.001):
        current, at = pose, q
        for th1 in (h, 2 * h, h, 0.0, -h, -2 * h, -h, 0.0):
            target = np.array([th1, q[1], q[2]])
            result = m.step(current, at, target)
            assert result is not None
            current, at = np.array(result[0]), target
            assert np.max(np.abs(reference_residual(current, at))) < 1e-9 * SCALE**2
            assert np.sign(result[1]) == np.sign(margin) and abs(result[1]) > 0.5
        assert np.max(np.abs(current - pose)) < 1e-8


def test_step_fails_where_there_is_no_solution():
    m = DEFAULT_THREE_RRR
    rng = np.random.default_rng(7)
    joints = rng.uniform(-math.pi, math.pi, (2000, 3))
    count, _ = m.solve(joints)
    empty = joints[count == 0][0]
    _, poses = m.solve(np.array([Q6]))
    for pose in poses[0]:
        assert m.step(pose, Q6, empty) is None


# --- the slice th1 = 0 on the joint torus --------------------------------------------

N_SLICE = 120


@pytest.fixture(scope="module")
def slice_roadmap():
    step = 2 * math.pi / N_SLICE
    axes = tuple(Axis(j, -math.pi, math.pi - step, step, periodic=True) for j in (1, 2))
    return build_roadmap(DEFAULT_THREE_RRR, Grid(axes=axes, fixed=((0, 0.0),)))


def wraps_around(mask):
    """Whether a set of cells of the torus holds a loop that goes around it:
    a breadth-first search that lifts cells to the plane meets a cell again
    at another lift."""
    n0, n1 = mask.shape
    lift = {}
    for seed in zip(*np.nonzero(mask)):
        if seed in lift:
            continue
        lift[seed] = (0, 0)
        queue = deque([seed])
        while queue:
            i, j = queue.popleft()
            wi, wj = lift[(i, j)]
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                ni, nj = i + di, j + dj
                here = (wi + ni // n0, wj + nj // n1)
                cell = (ni % n0, nj % n1)
                if not mask[cell]:
                    continue
                if cell not in lift:
                    lift[cell] = here
                    queue.append(cell)
                elif lift[cell] != here:
                    return True
    return False


def test_slice_has_two_four_and_six_solutions(slice_roadmap):
    field, seg = slice_roadmap.field, slice_roadmap.segmentation
    assert set(np.unique(field.count).tolist()) == {2, 4, 6}
    # The field's counts are the torus preimages where the torus says so.
    for th2, th3 in ((Q6[1], Q6[2]), (1.0, 2.0), (-1.0, 0.5)):
        cell = np.argmin(np.sum(wrap(field.grid.coordinates() - (th2, th3)) ** 2, -1))
        q = (0.0, *field.grid.coordinates()[cell])
        assert field.count[cell] == len(torus_preimages(q, n=360))
    # At this resolution (measured): 5 regions, 22 patches, 30 gates.
    assert seg.n_regions == 5 and len(seg.patches) == 22 and len(seg.gates) == 30
    shape = field.grid.shape
    region = seg.region.reshape(shape)
    count = field.count.reshape(shape)
    wrapping = [k for k in np.unique(region[region > 0]) if wraps_around(region == k)]
    assert wrapping and all(set(np.unique(count[region == k])) == {4} for k in wrapping)


def test_non_singular_assembly_mode_change(slice_roadmap):
    """Two solutions of one joint vector, in patches of one connected
    component of the roadmap with one aspect: the planner joins them, and
    the path, followed independently, stays a solution of one aspect."""
    roadmap = slice_roadmap
    seg, field = roadmap.segmentation, roadmap.field
    component = {p: k for k, group in enumerate(nx.connected_components(roadmap.graph))
                 for p in group}
    best = None
    for cell in range(field.count.size):
        ids = seg.patch[cell]
        for i in range(field.count[cell]):
            for j in range(i + 1, field.count[cell]):
                a, b = int(ids[i]), int(ids[j])
                if a not in seg.patches or b not in seg.patches or a == b:
                    continue
                if seg.patches[a].aspect == seg.patches[b].aspect \
                        and component[a] == component[b]:
                    clearance = min(abs(field.margin[cell, i]), abs(field.margin[cell, j]))
                    if best is None or clearance > best[0]:
                        best = (clearance, cell, i, j)
    assert best is not None
    _, cell, i, j = best
    q = np.array([0.0, *field.grid.coordinates()[cell]])
    start, goal = field.poses[cell, i], field.poses[cell, j]
    assert np.max(np.abs(reference_residual(start, q))) < 1e-8
    assert np.max(np.abs(reference_residual(goal, q))) < 1e-8
    sign = np.sign(reference_margin(start, q))
    assert sign == np.sign(reference_margin(goal, q))
    plan = Planner(roadmap).plan((*q, start[2]), (*q, goal[2]))
    assert plan.feasible and plan.validation.ok
    assert np.allclose(plan.joints[0], q) and np.allclose(wrap(plan.joints[-1] - q), 0)
    followed, vertices = follow(start, plan.joints)
    for (joints, pose, move) in followed:
        assert np.max(np.abs(reference_residual(pose, joints))) < 1e-9 * SCALE**2
        assert np.sign(reference_margin(pose, joints)) == sign
        assert abs(reference_margin(pose, joints)) > 1e-3
        assert move < 0.5  # no jump to another solution between dense samples
    for vertex, planned in zip(vertices, plan.poses):
        assert np.max(np.abs(np.r_[vertex[:2] - planned[:2], wrap(vertex[2] - planned[2])])) \
            < 1e-6
    end = vertices[-1]
    assert np.max(np.abs(np.r_[end[:2] - goal[:2], wrap(end[2] - goal[2])])) < 1e-6
    assert np.max(np.abs(goal - start)) > 1.0  # a different assembly mode
