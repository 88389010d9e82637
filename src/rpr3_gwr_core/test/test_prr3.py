"""The planar 3-PRR behind the Mechanism interface, against references
written here: the platform points and slider joints from their
definitions, the residuals ``|B_i - C_i|**2 - l**2``, the normalised
``det Jx``, and an independent direct kinematics through the torus of poses
at fixed s1.

At fixed s1, B1 lies on the circle of radius l around the slider joint C1
(angle phi) and alpha is free: the poses form the torus (phi, alpha).  Each
torus point fixes B2 and B3, and then s2 and s3 in closed form: the slider
line ``A_i + s (cos gamma_i, sin gamma_i)`` meets the circle of radius l
around B_i in 0, 1 or 2 points (the two roots of a quadratic in s).  The
solutions of joints (s1, s2, s3) are the torus points mapped onto (s2, s3):
found here by a dense scan of the torus and Newton on the map.
"""

import json
import math
import pathlib

import networkx as nx
import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.mechanisms import (DEFAULT_THREE_PRR, Mechanism, ThreePRR,
                                      mechanism_from_dict)
from rpr3_gwr_core.mechanisms.rrr3 import _step_kernel
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.workspace.grid import Axis, Grid
from rpr3_gwr_core.workspace.roadmap import build_roadmap

from moving_base_reference import MovingBaseReference, check_kernel_agrees_with_step, wrap

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"

# The default geometry, written again rather than read from the mechanism:
# the paper's base points and platform (sides 17.04, 16.54, 20.84), sliders
# along 0, pi/2 and pi/4, distal links l = 15.
A = np.array([[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]])
GAMMA = np.array([0.0, math.pi / 2, math.pi / 4])
E = np.stack([np.cos(GAMMA), np.sin(GAMMA)], -1)
D1, D2, D3 = 17.04, 16.54, 20.84
BETA = math.acos((D1**2 + D3**2 - D2**2) / (2 * D1 * D3))
L = 15.0
SCALE = max(D1, D2, D3)
# The slice of the docstring and its assembly-mode change.
S1 = 5.0
Q_CHANGE = (5.0, 26.5, 10.0)


def sliders(s):
    """C_i = A_i + s_i e_i of joints (..., 3), shape (..., 3, 2)."""
    return A + np.asarray(s, dtype=float)[..., None] * E


def slider_value(b, i, side):
    """s of the point of slider line i at distance L from ``b`` (..., 2): the
    root ``-e.g + side sqrt((e.g)**2 - |g|**2 + L**2)`` with ``g = A_i - b``;
    NaN where the line misses the circle."""
    g = A[i] - b
    eg = g[..., 0] * E[i, 0] + g[..., 1] * E[i, 1]
    disc = eg**2 - np.sum(g**2, -1) + L**2
    return -eg + side * np.sqrt(np.where(disc >= 0, disc, np.nan))


REFERENCE = MovingBaseReference(sliders, slider_value, L, D1, D3, BETA, angular=False)
reference_residual, reference_margin = REFERENCE.residual, REFERENCE.margin
torus_map, follow = REFERENCE.torus_map, REFERENCE.follow


def torus_preimages(s, n=720):
    return REFERENCE.torus_preimages(s, window=2.0, n=n)


# --- the mechanism as a value ---------------------------------------------------

def test_default_geometry_and_interface():
    m = DEFAULT_THREE_PRR
    assert isinstance(m, Mechanism) and m.kind == "3-PRR"
    assert m.joint_names == ("s1", "s2", "s3") and m.pose_names == ("x", "y", "alpha")
    assert m.angular == (False, False, True) and m.mode_coordinate == 2
    assert m.max_solutions == 6
    assert np.allclose([m.a1, m.a2, m.a3], A)
    assert np.allclose([m.gamma1, m.gamma2, m.gamma3], GAMMA) and m.l == L
    assert (m.d1, m.d3) == (D1, D3) and m.beta == pytest.approx(BETA, abs=1e-12)
    assert m.scale == pytest.approx(SCALE)
    assert np.allclose(m.slider_joints(Q_CHANGE), sliders(Q_CHANGE))


def test_to_dict_round_trip():
    m = ThreePRR(a2=(16.0, 1.0), gamma1=0.3, gamma3=-2.0, l=13.5)
    data = json.loads(json.dumps(m.to_dict()))
    assert data["kind"] == "3-PRR"
    assert mechanism_from_dict(data) == m
    assert mechanism_from_dict(DEFAULT_THREE_PRR.to_dict()) == DEFAULT_THREE_PRR


@pytest.mark.parametrize("change", [{"l": 0.0}, {"l": -1.0}, {"l": math.nan}, {"l": "12"},
                                    {"l": True}, {"gamma1": math.inf}, {"gamma2": "0"},
                                    {"gamma3": None}, {"a1": (0.0,)}, {"beta": 0.0},
                                    {"d1": math.inf}])
def test_malformed_geometry_is_refused(change):
    data = {**DEFAULT_THREE_PRR.to_dict(), **change}
    with pytest.raises(InvalidInputError):
        mechanism_from_dict(data)


def test_missing_parameter_is_refused():
    data = DEFAULT_THREE_PRR.to_dict()
    del data["gamma2"]
    with pytest.raises(InvalidInputError):
        mechanism_from_dict(data)


@pytest.mark.parametrize("joints", [[0.0, 1.0], [0.0, math.nan, 1.0], "abc"])
def test_malformed_joints_are_refused(joints):
    with pytest.raises(InvalidInputError):
        DEFAULT_THREE_PRR.check_joints(joints)


def test_margin_needs_the_joints():
    count, poses = DEFAULT_THREE_PRR.solve(np.array([Q_CHANGE]))
    with pytest.raises(TypeError, match="joints"):
        DEFAULT_THREE_PRR.margin(poses[0, 0])


def test_margin_and_residual_are_the_reference():
    rng = np.random.default_rng(2)
    poses = rng.uniform([-10, -10, -math.pi], [30, 30, math.pi], (500, 3))
    joints = rng.uniform(-5, 35, (500, 3))
    m = DEFAULT_THREE_PRR
    assert np.allclose(m.residual(poses, joints), reference_residual(poses, joints),
                       rtol=0, atol=1e-9)
    assert np.allclose(m.margin(poses, joints), reference_margin(poses, joints),
                       rtol=0, atol=1e-12)
    assert np.all(m.aspect(poses, joints) == np.sign(reference_margin(poses, joints)))
    one = m.margin(poses[0], joints[0])
    assert np.ndim(one) == 0 and one == pytest.approx(reference_margin(poses[0], joints[0]))


# --- direct kinematics against the torus ------------------------------------------

@pytest.mark.parametrize("s, n_solutions", [(Q_CHANGE, 4), ((5.0, 16.49, 0.83), 6),
                                            ((5.0, 9.89, 23.65), 6), ((5.0, 9.35, 12.7), 2),
                                            ((5.0, 24.83, 12.28), 4), ((5.0, 6.1, 7.87), 2)])
def test_solutions_are_the_torus_preimages(s, n_solutions):
    expected = torus_preimages(s)
    count, poses = DEFAULT_THREE_PRR.solve(np.array([s]))
    assert len(expected) == n_solutions == count[0]
    assert np.max(np.abs(poses[0, :n_solutions] - expected)) < 1e-8
    assert np.all(np.isnan(poses[0, n_solutions:]))
    assert np.max(np.abs(reference_residual(expected, s))) < 1e-8
    assert np.min(np.abs(reference_margin(expected, s))) > 0.1


def test_torus_points_are_found_and_every_solution_fits():
    """Joints made from a dense torus sample at s1 = 5: each has the pose it
    was made from among its solutions, and every solution fits the legs."""
    seen = REFERENCE.check_torus_points(DEFAULT_THREE_PRR, S1)
    assert seen[0] == 0 and seen[2] and seen[4] and seen[6]

def test_never_more_than_six_and_counts_are_even():
    rng = np.random.default_rng(5)
    joints = rng.uniform(-10, 40, (20000, 3))
    count, poses = DEFAULT_THREE_PRR.solve(joints)
    assert count.dtype == np.uint8 and poses.shape == (20000, 6, 3)
    assert set(np.unique(count).tolist()) <= {0, 2, 4, 6}
    finite = np.isfinite(poses[..., 0])
    assert np.array_equal(finite.sum(1), count)
    assert np.nanmax(np.abs(reference_residual(poses, joints[:, None, :]))) < 1e-9 * SCALE**2


# --- continuation -----------------------------------------------------------------

def test_step_follows_each_solution():
    REFERENCE.check_step_follows_each_solution(DEFAULT_THREE_PRR, (5.0, 16.49, 0.83), 0.01)


def test_compiled_step_kernel_agrees_with_step_and_predict_and_correct():
    m = DEFAULT_THREE_PRR
    target = np.array(Q_CHANGE) + 0.05
    for pose in check_kernel_agrees_with_step(m, _step_kernel, Q_CHANGE, target, 19):
        expected = m.step(pose, Q_CHANGE, target)
        corrected = m.correct(m.predict(pose, np.array(Q_CHANGE), target), target, 6)
        assert np.allclose(corrected, expected[0], atol=1e-9)
        assert np.max(np.abs(reference_residual(corrected, target))) < 1e-10 * SCALE**2


@pytest.fixture(scope="module")
def slice_roadmap():
    axes = tuple(Axis(j, 0.0, 30.0, 0.25) for j in (1, 2))
    return build_roadmap(DEFAULT_THREE_PRR, Grid(axes=axes, fixed=((0, S1),)))


def test_slice_counts_regions_patches_and_gates(slice_roadmap):
    field, seg = slice_roadmap.field, slice_roadmap.segmentation
    assert field.grid.shape == (121, 121)
    assert set(np.unique(field.count).tolist()) == {2, 4, 6}
    # The field's counts are the torus preimages where the torus says so.
    coordinates = field.grid.coordinates()
    for s2, s3 in ((26.5, 10.0), (16.5, 0.75), (9.25, 12.75), (10.0, 23.75)):
        cell = np.argmin(np.sum((coordinates - (s2, s3)) ** 2, -1))
        q = (S1, *coordinates[cell])
        assert field.count[cell] == len(torus_preimages(q, n=360))
    # At this resolution (measured): 12 regions, 40 patches, 51 gates.
    assert seg.n_regions == 12 and len(seg.patches) == 40 and len(seg.gates) == 51


def test_non_singular_assembly_mode_change(slice_roadmap):
    """The docstring's example: two solutions of (5, 26.5, 10) of one
    aspect, in two patches of one region joined through another by the
    roadmap; the planner joins them, and the path, followed independently,
    stays a solution of one aspect."""
    roadmap = slice_roadmap
    seg, field = roadmap.segmentation, roadmap.field
    cell = int(np.argmin(np.sum((field.grid.coordinates() - Q_CHANGE[1:]) ** 2, -1)))
    q = np.array([S1, *field.grid.coordinates()[cell]])
    assert np.allclose(q, Q_CHANGE)
    expected = torus_preimages(Q_CHANGE)
    assert field.count[cell] == len(expected) == 4
    alphas = field.poses[cell, : field.count[cell], 2]
    i = int(np.argmin(np.abs(alphas - 0.4778)))
    j = int(np.argmin(np.abs(alphas - 0.7657)))
    start, goal = field.poses[cell, i], field.poses[cell, j]
    assert np.allclose(start, (-8.378, 6.784, 0.4778), atol=1e-3)
    assert np.allclose(goal, (17.317, 8.561, 0.7657), atol=1e-3)
    for pose in (start, goal):
        assert np.min(np.max(np.abs(expected - pose), -1)) < 1e-8
        assert np.max(np.abs(reference_residual(pose, q))) < 1e-8
        assert reference_margin(pose, q) == pytest.approx(0.541, abs=1e-3)
    a, b = int(seg.patch[cell][i]), int(seg.patch[cell][j])
    assert a != b and seg.patches[a].aspect == seg.patches[b].aspect
    assert seg.patches[a].region == seg.patches[b].region
    component = {p: k for k, group in enumerate(nx.connected_components(roadmap.graph))
                 for p in group}
    assert component[a] == component[b]

    plan = Planner(roadmap).plan((*q, start[2]), (*q, goal[2]))
    assert plan.feasible and plan.validation.ok
    assert plan.global_paths and all(p.patches[0] == a and p.patches[-1] == b
                                     for p in plan.global_paths)
    # The two patches are joined through another region.
    assert any(seg.patches[k].region != seg.patches[a].region
               for p in plan.global_paths for k in p.patches)
    assert np.allclose(plan.joints[0], q) and np.allclose(plan.joints[-1], q)
    followed, vertices = follow(start, plan.joints)
    sign = np.sign(reference_margin(start, q))
    for joints, pose, move in followed:
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


# --- the mechanism file -----------------------------------------------------------

def test_the_three_prr_file_is_the_default_three_prr(slice_roadmap):
    robot = load_mechanism_file(str(CONFIG / "three_prr.yaml"))
    assert robot.mechanism == DEFAULT_THREE_PRR
    assert [a.periodic for a in robot.axes] == [False, False, False]
    assert [(a.low, a.high, a.step) for a in robot.axes] == [(0.0, 30.0, 0.25)] * 3
    grid = robot.grid({"s1": S1})
    assert grid.fixed == ((0, S1),) and grid.shape == (121, 121)
    assert np.array_equal(grid.coordinates(), slice_roadmap.field.grid.coordinates())
