"""The full 3-DOF roadmap (all legs in the default box): its known facts,
checked against configurations drawn on the torus (theta1, alpha) at
random rho1, with the other legs by inverse kinematics, independent of the
roadmap."""

import json
import math
import pathlib

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.csgraph import connected_components

from rpr3_gwr_core import (PAPER_GEOMETRY, InfeasiblePathError, Planner, PlanOptions,
                           UndecidedError, aspect_groups)
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.paper import FULL_BASE_GRID, rho1_slice
from rpr3_gwr_core.planning.validation import validate_path
from rpr3_gwr_core.workspace import AdaptiveGrid, build_roadmap, refine_thin_regions

# The pocket: at rho1 in (26.79, 28.09) a small singular loop
# encloses part of the det Jx < 0 side.  Found on a 720 x 720 torus lattice
# at rho1 = 27.5 (the det < 0 set in the box has two components there, of
# 177,957 and 8,791 lattice points): the same legs, one solution in the
# pocket, the other outside, both with margins above 0.14.
POCKET_LEGS = (27.5, 31.67154934, 2.14117832)
POCKET_ALPHAS = (-1.7627825445142729, 2.7584625675676517)


def torus_configurations(count, seed, min_margin=3e-3):
    """``(rho1, rho2, rho3, alpha)`` rows in the box with their pose and aspect."""
    rng = np.random.default_rng(seed)
    a1 = np.asarray(PAPER_GEOMETRY.a1)
    rho1 = rng.uniform(2.0, 49.0, 20 * count)
    theta1, alpha = rng.uniform(-math.pi, math.pi, (2, rho1.size))
    pose = np.stack([a1[0] + rho1 * np.cos(theta1), a1[1] + rho1 * np.sin(theta1), alpha], 1)
    legs = PAPER_GEOMETRY.inverse(pose)
    margin = PAPER_GEOMETRY.margin(pose)
    keep = np.all((legs >= 0.5) & (legs <= 49.5), axis=1) & (np.abs(margin) >= min_margin)
    rows = [(*q, a) for q, a in zip(legs[keep], alpha[keep])][:count]
    return rows, pose[keep][:count], np.sign(margin[keep])[:count]


def test_the_full_roadmap_is_adaptive_over_the_three_legs(full_roadmap):
    grid = full_roadmap.grid
    assert isinstance(grid, AdaptiveGrid) and grid.base == FULL_BASE_GRID
    assert grid.fixed == () and grid.steps == (0.25, 0.25, 0.25)
    # Far fewer cells than the uniform 0.25 grid of the box (197 x 201 x 201).
    assert grid.size < 0.25 * 197 * 201 * 201


def test_every_stored_solution_has_its_cells_legs(full_roadmap):
    field = full_roadmap.segmentation.field
    cells, slots = np.nonzero(np.arange(field.poses.shape[1]) < field.count[:, None])
    joints = full_roadmap.grid.joints()[cells]
    residual = PAPER_GEOMETRY.residual(field.poses[cells, slots], joints)
    assert np.abs(residual).max() <= 1e-6 * PAPER_GEOMETRY.scale**2


def test_the_configuration_space_has_two_aspect_connected_components(full_roadmap, full_planner):
    seg = full_roadmap.segmentation
    groups = aspect_groups(full_roadmap.graph)
    assert len(groups) == 2
    assert sorted({seg.patches[p].aspect for p in group}.pop() for group in groups) == [-1, 1]
    assert all(len({seg.patches[p].aspect for p in group}) == 1 for group in groups)
    rows, _, signs = torus_configurations(60, seed=3)
    for row, sign in zip(rows, signs):
        location = full_planner.locate(row)
        assert seg.patches[location.patch].aspect == sign


def test_the_rho1_17_slice_of_the_3d_field_has_the_papers_seven_regions(full_roadmap):
    grid, seg, field = full_roadmap.grid, full_roadmap.segmentation, full_roadmap.field
    on_plane = np.isclose(grid.coordinates()[:, 0], 17.0)
    count = field.count.astype(int)
    rows, cols = [], []
    for axis in (1, 2):  # rho2 and rho3: the plane's own faces
        (lower, upper), (_, _, match) = grid.pairs()[axis], seg.links[axis]
        full = (on_plane[lower] & on_plane[upper] & (count[lower] == count[upper])
                & (count[lower] > 0) & ((match >= 0).sum(axis=1) == count[lower]))
        rows.append(lower[full])
        cols.append(upper[full])
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    graph = sparse.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(grid.size,) * 2)
    _, label = connected_components(graph, directed=False)
    pieces = [k for k in np.unique(label[on_plane & (count > 0)])
              if np.count_nonzero(label == k) >= 8]
    counts = sorted(int(count[np.argmax(label == k)]) for k in pieces)
    assert counts == sorted([2, 4, 4, 2, 6, 4, 2])  # the paper's regions 1..7


def test_the_pocket_needs_rho1_to_move(full_roadmap, full_planner):
    start, goal = (*POCKET_LEGS, POCKET_ALPHAS[0]), (*POCKET_LEGS, POCKET_ALPHAS[1])
    # The slice's grid alone has a thin region in their aspect, and cannot
    # tell; refined there, it separates them.
    with pytest.raises(UndecidedError):
        Planner(build_roadmap(PAPER_GEOMETRY, rho1_slice(POCKET_LEGS[0]))).plan(start, goal)
    refined, _ = refine_thin_regions(PAPER_GEOMETRY, rho1_slice(POCKET_LEGS[0]))
    with pytest.raises(InfeasiblePathError) as refused:
        Planner(refined).plan(start, goal)
    assert refused.value.reason == "unreachable"
    plan = full_planner.plan(start, goal)
    assert plan.validation.ok and plan.validation.aspect == -1
    assert np.ptp(plan.joints[:, 0]) > 1.0
    check = validate_path(PAPER_GEOMETRY, plan.joints, plan.poses[0], plan.poses[-1])
    assert check.ok


def test_the_chosen_global_path_is_the_patches_the_smoothed_pocket_path_crosses(full_planner):
    start, goal = (*POCKET_LEGS, POCKET_ALPHAS[0]), (*POCKET_LEGS, POCKET_ALPHAS[1])
    plan = full_planner.plan(start, goal, PlanOptions(smooth=True))
    assert plan.smoothed
    crossed = [int(p) for k, p in enumerate(plan.patches) if k == 0 or p != plan.patches[k - 1]]
    chosen = list(plan.global_paths[plan.path_index].patches)
    assert chosen == crossed
    # Not the weave of the unsmoothed cells along a gate.
    assert all(len(p.patches) <= 4 for p in plan.global_paths)


def test_configurations_of_one_aspect_plan_with_all_legs_moving(full_planner):
    rows, poses, signs = torus_configurations(40, seed=7)
    planned = 0
    for k in range(0, len(rows) - 1, 2):
        if signs[k] != signs[k + 1] or abs(rows[k][0] - rows[k + 1][0]) < 5.0:
            continue
        plan = full_planner.plan(rows[k], rows[k + 1])
        assert plan.validation.ok
        # The path starts and ends on the torus' own poses, all legs moving.
        assert np.allclose(plan.poses[0], poses[k], atol=1e-8)
        assert np.allclose(plan.poses[-1], poses[k + 1], atol=1e-8)
        assert np.all(np.ptp(plan.joints, axis=0) > 0)
        planned += 1
    assert planned >= 5


def test_the_cli_summarises_and_plans_on_the_full_roadmap(full_roadmap, capsys, tmp_path):
    figure = tmp_path / "slice.png"
    assert main(["roadmap", "--full", "--slice-figure", str(figure)]) == 0
    assert figure.stat().st_size > 10_000
    summary = json.loads(capsys.readouterr().out)
    assert summary["from_cache"] is True
    assert len(summary["aspect_groups"]) == 2
    assert summary["refinement"]["cells"] == full_roadmap.grid.size
    assert len(summary["patches"]) == len(full_roadmap.segmentation.patches)
    start = [*map(str, POCKET_LEGS), str(math.degrees(POCKET_ALPHAS[0]))]
    goal = [*map(str, POCKET_LEGS), str(math.degrees(POCKET_ALPHAS[1]))]
    written = tmp_path / "plan.json"
    assert main(["plan", "--full", "--start", *start, "--goal", *goal, "-o", str(written)]) == 0
    plan = json.loads(capsys.readouterr().out)
    assert plan["feasible"] and plan["validation"]["ok"]
    assert main(["plot", str(written)]) == 0
    drawn = pathlib.Path(json.loads(capsys.readouterr().out)["figure"])
    assert drawn == tmp_path / "plan.png" and drawn.stat().st_size > 10_000
    assert main(["plan", "--rho1", "27.5", "--start", *start[1:], "--goal", *goal[1:]]) == 1
    assert json.loads(capsys.readouterr().out)["reason"] == "unreachable"
