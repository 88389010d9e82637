"""The 3-RRR's full roadmap over the torus of its three turning joints, on an
adaptive grid whose axes are periodic: its counts against the closed-form
torus preimages, regions joined across the seams, and a plan across a seam
followed by an independent continuation."""

import math
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.workspace.adaptive import AdaptiveGrid, coarse_base, refine
from rpr3_gwr_core.workspace.grid import Axis, Grid
from rpr3_gwr_core.workspace.roadmap import build_roadmap

from test_rrr3 import SCALE, follow, reference_margin, reference_residual, torus_preimages, wrap

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config" / "three_rrr.yaml"
# A coarse torus: 24 fine cells a turn, from base turns of 12.
CELLS, REFINEMENT = 24, 2


@pytest.fixture(scope="module")
def torus_roadmap():
    described = load_mechanism_file(CONFIG)
    step = 2 * math.pi / CELLS
    fine = Grid(axes=tuple(Axis(j, -math.pi, math.pi - step, step, periodic=True)
                           for j in range(3)))
    grid = refine(described.mechanism, coarse_base(fine, REFINEMENT), REFINEMENT)
    return build_roadmap(described.mechanism, grid)


def test_the_torus_grid_is_adaptive_and_periodic(torus_roadmap):
    grid = torus_roadmap.grid
    assert isinstance(grid, AdaptiveGrid) and all(a.periodic for a in grid.axes)
    assert grid.fine_shape == (CELLS,) * 3
    assert 0 < grid.blocks.size < math.prod(grid.block_shape)
    assert grid.cell_volumes().sum() == pytest.approx((2 * math.pi) ** 3)


def test_solutions_are_the_torus_preimages(torus_roadmap):
    """At sampled cells: every pose the torus scan finds is a stored
    solution, and every stored solution fits the independent constraint
    equations with the stored aspect (the scan may miss a pose whose
    elbow sits near a stretched leg, so it bounds the count from below)."""
    field = torus_roadmap.field
    rng = np.random.default_rng(5)
    # Cells whose solutions all keep off the singular locus, where the
    # count is not a matter of rounding.
    clear = np.flatnonzero(np.all(~field.valid | (np.abs(field.margin) > 0.05), axis=1))
    for cell in rng.choice(clear, 6, replace=False):
        q = field.grid.joints_of(cell)
        stored = field.poses[cell, :field.count[cell]]
        assert np.max(np.abs(reference_residual(stored, q))) < 1e-8 * SCALE**2
        assert np.all(np.sign(reference_margin(stored, q)) == np.sign(
            field.margin[cell, :field.count[cell]]))
        gaps = np.max(np.abs(wrap(stored[:, None, :] - stored[None, :, :])), -1)
        assert np.all(gaps[~np.eye(len(stored), dtype=bool)] > 1e-6)
        for pose in torus_preimages(q, n=360):
            assert np.min(np.max(np.abs(wrap(stored - pose)), -1)) < 1e-6


def test_regions_and_patches_join_across_the_seams(torus_roadmap):
    seg, grid = torus_roadmap.segmentation, torus_roadmap.grid
    index = np.rint((grid.coordinates() + math.pi) / grid.step).astype(int)
    for axis, (lower, upper, match) in enumerate(seg.links):
        seam = (index[lower, axis] == CELLS - 1) & (index[upper, axis] == 0)
        assert seam.any()
        same = seam & (seg.region[lower] > 0) & (seg.region[lower] == seg.region[upper])
        # Regions go on across each seam, and so do their patches.
        assert same.any()
        k = np.flatnonzero(same)[0]
        i = int(np.flatnonzero(match[k] >= 0)[0])
        assert seg.patch[lower[k], i] == seg.patch[upper[k], match[k, i]] > 0


def test_a_plan_across_the_seam_follows_one_solution(torus_roadmap):
    """Two solutions of one patch on both sides of the th1 seam: the planner
    joins them the short way, across the seam, and an independent
    continuation along its joints stays on solutions of one aspect."""
    seg, field, grid = torus_roadmap.segmentation, torus_roadmap.field, torus_roadmap.grid
    lower, upper, match = seg.links[0]
    index = np.rint((grid.coordinates() + math.pi) / grid.step).astype(int)
    seam = np.flatnonzero((index[lower, 0] == CELLS - 1) & (index[upper, 0] == 0))
    best = None
    for k in seam:
        for i in np.flatnonzero(match[k] >= 0):
            j = match[k, i]
            clearance = min(abs(field.margin[lower[k], i]), abs(field.margin[upper[k], j]))
            if seg.patch[lower[k], i] > 0 and (best is None or clearance > best[0]):
                best = (clearance, lower[k], i, upper[k], j)
    clearance, a, i, b, j = best
    assert clearance > 0.05
    qa, qb = grid.joints_of(a), grid.joints_of(b)
    start, goal = field.poses[a, i], field.poses[b, j]
    plan = Planner(torus_roadmap).plan((*qa, start[2]), (*qb, goal[2]))
    assert plan.feasible and plan.validation.ok
    joints = grid.unwrap(plan.joints)
    # The short way: th1 moves one fine step across the seam, not a turn back.
    assert abs(joints[-1, 0] - joints[0, 0]) < 2 * grid.step
    followed, vertices = follow(start, joints)
    sign = np.sign(reference_margin(start, qa))
    for q, pose, move in followed:
        assert np.max(np.abs(reference_residual(pose, q))) < 1e-9 * SCALE**2
        assert np.sign(reference_margin(pose, q)) == sign
    assert np.max(np.abs(wrap(vertices[-1] - goal))) < 1e-6
