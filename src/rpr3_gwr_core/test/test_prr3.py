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
found here by a dense scan of the torus and Newton on the map.  What every
mechanism, and every mechanism whose base points move with its joints, owes
this reference and the interface is checked in ``test_mechanism_contract.py``.
"""

import math
import pathlib

import networkx as nx
import numpy as np
import pytest

from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.mechanisms import DEFAULT_THREE_PRR
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.workspace.grid import Axis, Grid
from rpr3_gwr_core.workspace.roadmap import build_roadmap

from moving_base_reference import MovingBaseReference, wrap

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

def test_slider_joints_are_the_reference():
    assert np.allclose(DEFAULT_THREE_PRR.slider_joints(Q_CHANGE), sliders(Q_CHANGE))


# --- continuation -----------------------------------------------------------------

def test_predict_then_correct_is_the_step():
    m = DEFAULT_THREE_PRR
    target = np.array(Q_CHANGE) + 0.05
    count, poses = m.solve(np.array([Q_CHANGE]))
    for pose in poses[0, : count[0]]:
        expected = m.step(pose, Q_CHANGE, target)
        assert expected is not None
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
