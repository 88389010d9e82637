"""Planning on the paper's roadmap: its two examples, errors, and properties."""

import json
import math
import subprocess
import sys

import networkx as nx
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from scipy.optimize import brentq
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from rpr3_gwr_core.exceptions import (AssemblyModeError, InfeasiblePathError, InvalidInputError,
                                      NoSolutionError, OutOfGridError, FixedJointMismatchError,
                                      SingularityError)
from rpr3_gwr_core.mechanisms.rpr3 import ThreeRPR
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.planning.global_planning import feasibility, global_paths
from rpr3_gwr_core.planning.locate import FIXED_JOINT_TOL
from rpr3_gwr_core.planning.planner import DEFAULT_CLEARANCE, PlanOptions, Planner
from rpr3_gwr_core.workspace.grid import Axis, Grid
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_core.planning.segments import Sheets, shortcut_path
from rpr3_gwr_core.planning.trajectory import cut_corners, time_parameterize
from rpr3_gwr_core.planning.validation import validate_path

from pose_reference import follow, legs_of

D = math.radians
Q1, Q2 = (17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))
MODE_A, MODE_B = (17, 20, 25, D(29.47)), (17, 20, 25, D(96.13))


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


def regions(path):
    return [p // 10 for p in path.patches]


def test_first_example_has_exactly_the_papers_two_shortest_global_paths(planner):
    plan = planner.plan(Q1, Q2)
    assert plan.feasible
    assert sorted(regions(g) for g in plan.global_paths) == [[6, 4, 2, 1], [6, 5, 2, 1]]
    assert plan.start.patch // 10 == 6 and plan.goal.patch // 10 == 1


def test_first_example_trajectory_crosses_exactly_the_planned_gates(planner, paper_roadmap):
    plan = planner.plan(Q1, Q2)
    chosen = plan.global_paths[plan.path_index].patches
    # Follow the platform along the path, 8 samples per cell step, and name
    # the patch of the solution it is on at each sample (where a segment
    # clips the corner of a cell its sheet does not reach, none is near).
    seg, grid = paper_roadmap.segmentation, paper_roadmap.grid
    dense = np.vstack([np.linspace(a, b, max(2, int(8 * np.abs(b - a).max() / 0.125) + 1))[:-1]
                       for a, b in zip(plan.joints[:-1], plan.joints[1:])] + [plan.joints[-1:]])
    followed = validate_path(PAPER_GEOMETRY, dense, plan.poses[0], plan.poses[-1])
    assert followed.ok
    cells = grid.cells_of(dense[:, list(grid.axis_joints)])
    distance = np.nan_to_num(PAPER_GEOMETRY.pose_distance(
        seg.field.poses[cells], followed.poses[:, None, :]), nan=np.inf)
    on_sheet = distance.min(axis=1) < 2.0
    crossed = seg.patch[cells, np.argmin(distance, axis=1)][on_sheet]
    visited = [int(p) for k, p in enumerate(crossed) if k == 0 or p != crossed[k - 1]]
    assert tuple(visited) == chosen
    assert plan.validation.ok and plan.validation.min_margin > 1e-3
    np.testing.assert_allclose(plan.joints[0], Q1[:3])
    np.testing.assert_allclose(plan.joints[-1], Q2[:3])
    assert abs(plan.poses[-1, 2] - Q2[3]) < D(0.05)


def test_assembly_mode_change_goes_through_regions_3_1_3(planner):
    plan = planner.plan(MODE_A, MODE_B)
    assert plan.start.patch != plan.goal.patch
    assert plan.start.patch // 10 == plan.goal.patch // 10 == 3
    assert regions(plan.global_paths[0]) == [3, 1, 3]
    # Same legs at both ends, yet the followed platform ends in the other mode.
    np.testing.assert_allclose(plan.joints[0], plan.joints[-1])
    assert abs(plan.poses[0, 2] - MODE_A[3]) < D(0.05)
    assert abs(plan.poses[-1, 2] - MODE_B[3]) < D(0.05)
    assert plan.validation.ok


def test_returned_trajectory_passes_an_independent_validation(planner, paper_roadmap):
    for start, goal in ((Q1, Q2), (MODE_A, MODE_B)):
        plan = planner.plan(start, goal, PlanOptions(smooth=True))
        again = validate_path(paper_roadmap.mechanism, plan.joints, plan.start.pose,
                              plan.goal.pose,
                              max_step=0.01)
        assert again.ok, again.reason
        np.testing.assert_allclose(PAPER_GEOMETRY.inverse(plan.poses), plan.joints, atol=1e-7)


def _layered_reference_cost(roadmap, patches, start_cell, goal_cell, clearance):
    """Least cost of a cell path through the given patches in order, by
    Dijkstra on a graph built here from the continuation links: a step stays
    in its patch or enters the next one, costs its length times the mean
    cost of its two solutions, and a solution below the clearance costs 100."""
    seg = roadmap.segmentation
    slots = seg.patch.shape[1]
    layer = {pid: k for k, pid in enumerate(patches)}
    coords = roadmap.grid.coordinates()
    cost = np.where(np.abs(seg.field.margin) < clearance, 100.0, 1.0).ravel()
    rows, cols, weights = [], [], []
    for lower, upper, match in seg.links:
        cells, slot = np.nonzero(match >= 0)
        a = lower[cells] * slots + slot
        b = upper[cells] * slots + match[cells, slot]
        length = np.abs(coords[lower[cells]] - coords[upper[cells]]).sum(axis=1)
        weight = 0.5 * length * (cost[a] + cost[b])
        la = np.array([layer.get(p, -9) for p in seg.patch.ravel()[a]])
        lb = np.array([layer.get(p, -9) for p in seg.patch.ravel()[b]])
        for u, v, lu, lv in ((a, b, la, lb), (b, a, lb, la)):
            keep = (lu >= 0) & ((lv == lu) | (lv == lu + 1))
            rows.append(u[keep])
            cols.append(v[keep])
            weights.append(weight[keep])
    n = seg.patch.size
    graph = csr_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(n, n))
    source = start_cell * slots + int(np.flatnonzero(seg.patch[start_cell] == patches[0])[0])
    target = goal_cell * slots + int(np.flatnonzero(seg.patch[goal_cell] == patches[-1])[0])
    return dijkstra(graph, indices=source)[target]


@pytest.mark.parametrize("clearance", [0.0, 0.02])
def test_local_paths_cost_what_dijkstra_finds(planner, paper_roadmap, clearance):
    """The A* with its gate and landmark estimates returns least-cost paths."""
    rng = np.random.default_rng(5)
    seg = paper_roadmap.segmentation
    checked = 0
    for _ in range(12):
        start_patch, goal_patch = rng.choice(sorted(seg.patches), 2)
        answer = feasibility(planner.patch_graph, start_patch, goal_patch)
        if not answer.feasible:
            continue
        path = global_paths(planner.patch_graph, start_patch, goal_patch)[0].patches
        start_cell = int(rng.choice(seg.patches[path[0]].cells))
        goal_cell = int(rng.choice(seg.patches[path[-1]].cells))
        local = planner.cell_search.search(path, start_cell, goal_cell, clearance=clearance)
        reference = _layered_reference_cost(paper_roadmap, path, start_cell, goal_cell,
                                            clearance)
        assert local.cost == pytest.approx(reference, rel=1e-9), path
        checked += 1
    assert checked >= 4


@pytest.mark.parametrize("inflation", [2, 3])
def test_an_inflated_estimate_costs_at_most_its_factor_more(planner, paper_roadmap, inflation):
    """Weighted A*: the path found costs between the least and ``inflation``
    times it, and runs from the start cell to the goal cell."""
    rng = np.random.default_rng(7)
    seg = paper_roadmap.segmentation
    checked = 0
    for _ in range(12):
        start_patch, goal_patch = rng.choice(sorted(seg.patches), 2)
        if not feasibility(planner.patch_graph, start_patch, goal_patch).feasible:
            continue
        path = global_paths(planner.patch_graph, start_patch, goal_patch)[0].patches
        start_cell = int(rng.choice(seg.patches[path[0]].cells))
        goal_cell = int(rng.choice(seg.patches[path[-1]].cells))
        local = planner.cell_search.search(path, start_cell, goal_cell, clearance=0.02,
                                   inflation=inflation)
        least = _layered_reference_cost(paper_roadmap, path, start_cell, goal_cell, 0.02)
        assert least * (1 - 1e-9) <= local.cost <= inflation * least * (1 + 1e-9), path
        assert (local.cells[0], local.cells[-1]) == (start_cell, goal_cell)
        checked += 1
    assert checked >= 4


@pytest.mark.parametrize("inflation", [0, 1.5, True])
def test_an_inflation_that_is_not_a_whole_factor_is_refused(planner, paper_roadmap,
                                                             inflation):
    pid = min(paper_roadmap.segmentation.patches)
    cells = paper_roadmap.segmentation.patches[pid].cells
    with pytest.raises(InvalidInputError, match="inflation"):
        planner.cell_search.search((pid,), int(cells[0]), int(cells[-1]), inflation=inflation)


class _InterpretedThreeRPR(ThreeRPR):
    """The paper's geometry without its compiled step: the validator then
    runs its loop in the interpreter, on :meth:`ThreeRPR.step`."""

    step_kernel = None


@pytest.mark.parametrize("min_margin", [1e-3, 0.02, 0.2])
def test_the_compiled_validator_agrees_with_the_interpreted_one(planner, min_margin):
    interpreted = _InterpretedThreeRPR()
    plans = [planner.plan(start, goal) for start, goal in ((Q1, Q2), (MODE_A, MODE_B))]
    paths = [(p.joints, p.start.pose, p.goal.pose) for p in plans]
    # Straight across, the first example crosses the singular locus, and the
    # second one's platform stays in its mode, so it misses the goal pose.
    paths += [(p.joints[[0, -1]], p.start.pose, p.goal.pose) for p in plans]
    outcomes = set()
    for joints, start, goal in paths:
        compiled = validate_path(PAPER_GEOMETRY, joints, start, goal, min_margin)
        again = validate_path(interpreted, joints, start, goal, min_margin)
        assert (compiled.ok, compiled.reason, compiled.aspect, compiled.steps,
                compiled.failed_segment) == (again.ok, again.reason, again.aspect, again.steps,
                                             again.failed_segment)
        assert compiled.min_margin == pytest.approx(again.min_margin, abs=1e-12)
        np.testing.assert_allclose(compiled.poses, again.poses, atol=1e-12)
        outcomes.add(compiled.reason.split(" ")[0])
    assert len(outcomes) >= 2


def test_smoothing_shortens_the_path_and_keeps_the_margin(planner):
    raw = planner.plan(Q1, Q2)
    smooth = planner.plan(Q1, Q2, PlanOptions(smooth=True))
    assert smooth.smoothed
    def length(p):
        return np.sum(np.linalg.norm(np.diff(p.joints, axis=0), axis=1))

    assert length(smooth) < length(raw)
    assert smooth.validation.min_margin >= planner.min_margin


def test_between_aspects_is_infeasible_from_the_roadmap_alone(planner):
    start = planner.locate(Q1)
    goal = planner.locate(MODE_A)
    answer = feasibility(planner.patch_graph, start.patch, goal.patch)
    assert not answer.feasible and answer.reason == "other_aspect"
    assert global_paths(planner.patch_graph, start.patch, goal.patch) == []
    with pytest.raises(InfeasiblePathError) as info:
        planner.plan(Q1, MODE_A)
    assert info.value.reason == "other_aspect"


def test_feasibility_only_returns_paths_without_trajectory(planner):
    plan = planner.plan(Q1, Q2, PlanOptions(feasibility_only=True))
    assert plan.feasible and plan.joints.shape == (0, 3) and len(plan.global_paths) == 2


def test_weighted_mode_ranks_by_cost(planner):
    plan = planner.plan(Q1, Q2, PlanOptions(weighted=True))
    costs = [g.cost for g in plan.global_paths]
    assert costs == sorted(costs) and len(costs) >= 2
    assert regions(plan.global_paths[0]) in ([6, 4, 2, 1], [6, 5, 2, 1])


def test_start_equal_to_goal_is_a_one_point_trajectory(planner):
    plan = planner.plan(Q1, Q1, PlanOptions(max_velocity=1.0, max_acceleration=1.0))
    assert plan.joints.shape == (1, 3) and plan.times.tolist() == [0.0]


def test_time_parameterisation_respects_the_limits(planner):
    plan = planner.plan(Q1, Q2, PlanOptions(smooth=True, max_velocity=2.0, max_acceleration=4.0))
    assert plan.times[0] == 0 and np.all(np.diff(plan.times) > 0)
    assert np.max(np.abs(plan.velocities)) <= 2.0 + 1e-9
    assert np.max(np.abs(plan.accelerations)) <= 4.0 + 1e-9
    # Between waypoints the legs move at most at the limit too.
    segment_speed = np.abs(np.diff(plan.joints, axis=0)) / np.diff(plan.times)[:, None]
    assert np.max(segment_speed) <= 2.0 + 1e-9
    np.testing.assert_array_equal(plan.velocities[[0, -1]], 0.0)


def test_per_joint_limits_hold_each_for_its_joint(planner):
    velocity, acceleration = (2.0, 0.5, 1.0), (4.0, 1.0, 0.25)
    plan = planner.plan(Q1, Q2, PlanOptions(smooth=True, max_velocity=velocity,
                                            max_acceleration=acceleration))
    interval = np.diff(plan.times)[:, None]
    assert np.all(np.abs(np.diff(plan.joints, axis=0)) / interval <= np.array(velocity) + 1e-9)
    assert np.all(np.abs(plan.velocities) <= np.array(velocity) + 1e-9)
    assert np.all(np.abs(plan.accelerations) <= np.array(acceleration) + 1e-9)


@pytest.mark.parametrize("limits", [dict(max_velocity=(1.0, 1.0), max_acceleration=1.0),
                                    dict(max_velocity=1.0, max_acceleration=(1.0,) * 4)])
def test_per_joint_limits_not_one_per_joint_are_refused(planner, limits):
    with pytest.raises(InvalidInputError, match="limits for the 3 joints"):
        planner.plan(Q1, Q2, PlanOptions(**limits))


@pytest.mark.parametrize("configuration, error", [
    ((17, float("nan"), 18, 0.0), InvalidInputError),
    ((17, 12, float("inf"), 0.0), InvalidInputError),
    ((17, -1, 18, 0.0), InvalidInputError),
    ((17, 60, 18, 0.0), OutOfGridError),
    ((13, 12, 18, D(122.82)), FixedJointMismatchError),
    ((17, 2, 45, 0.0), NoSolutionError),
    ((17, 12, 18, 0.0), AssemblyModeError),
])
def test_bad_configurations_raise_their_own_error(planner, configuration, error):
    with pytest.raises(error):
        planner.plan(configuration, Q2)


def test_a_fixed_joint_within_the_tolerance_is_the_slice_s(planner):
    """A slice's joint given a little off (rho1 = 17 + a relative half
    tolerance, as from rounded digits) plans from where it is onto the slice,
    and the independent continuation follows the plan to the goal; twice the
    tolerance off is refused with the joint and the tolerance named."""
    near = (17 * (1 + FIXED_JOINT_TOL / 2), *Q1[1:])
    plan = planner.plan(near, Q2)
    np.testing.assert_array_equal(plan.joints[0], near[:3])
    assert plan.joints[-1, 0] == 17
    followed = follow(plan.joints, plan.poses[0], planner.min_margin * (1 - 1e-3))
    assert followed["ok"], followed["why"]
    np.testing.assert_allclose(legs_of(plan.poses[0]), near[:3], atol=1e-7)
    np.testing.assert_allclose(legs_of(followed["pose"]), Q2[:3], atol=1e-6)
    assert abs(math.remainder(followed["pose"][2] - Q2[3], 2 * math.pi)) < D(1)
    with pytest.raises(FixedJointMismatchError, match=r"rho1 = .* within 0\.0001"):
        planner.plan((17 * (1 + 2 * FIXED_JOINT_TOL), *Q1[1:]), Q2)


def test_a_configuration_on_the_singular_locus_is_refused(planner):
    # A pose with det(Jx) = 0 and rho1 = 17: turn B1 on leg 1's circle
    # until the leg lines concur.
    alpha = 0.5
    def on_circle(t):
        return [17 * math.cos(t), 17 * math.sin(t), alpha]

    theta = brentq(lambda t: PAPER_GEOMETRY.margin(on_circle(t)), math.pi / 3, math.pi / 2)
    rho = PAPER_GEOMETRY.inverse(on_circle(theta))
    assert rho[0] == pytest.approx(17)
    with pytest.raises(SingularityError):
        planner.locate((*rho, alpha))


def test_invalid_options_are_refused():
    with pytest.raises(InvalidInputError):
        PlanOptions(max_velocity=1.0)
    with pytest.raises(InvalidInputError):
        PlanOptions(max_velocity=-1.0, max_acceleration=1.0)
    for bad in ((1.0, float("nan"), 1.0), (), (1.0, "fast"), True):
        with pytest.raises(InvalidInputError, match="one per joint"):
            PlanOptions(max_velocity=bad, max_acceleration=1.0)


def _random_configuration(roadmap, draw):
    seg = roadmap.segmentation
    pid = draw(st.sampled_from(sorted(seg.patches)))
    patch = seg.patches[pid]
    k = draw(st.integers(0, patch.cells.size - 1))
    cell, slot = patch.cells[k], patch.slots[k]
    return (*roadmap.grid.joints_of(cell), float(seg.field.poses[cell, slot, 2])), pid


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_every_plan_validates_and_infeasible_only_without_roadmap_path(planner, paper_roadmap,
                                                                      data):
    start, ps = _random_configuration(paper_roadmap, data.draw)
    goal, pg = _random_configuration(paper_roadmap, data.draw)
    connected = nx.has_path(paper_roadmap.graph, ps, pg)
    try:
        plan = planner.plan(start, goal)
    except InfeasiblePathError:
        assert not connected
        return
    assert connected
    check = validate_path(paper_roadmap.mechanism, plan.joints, plan.start.pose, plan.goal.pose)
    assert check.ok, check.reason
    assert np.all(np.sign(PAPER_GEOMETRY.margin(plan.poses)) == check.aspect)


def _shortcut_on_square(points, patches, margins, clearance=0.1, split=False,
                        other_patch=(), low_margin=()):
    """shortcut_path on a 5 x 5 grid of step 1 that is patch 1 with margin
    0.5, except ``other_patch`` cells (patch 2) and ``low_margin`` cells
    (margin 0.08); one solution per cell, at the same pose."""
    grid = Grid((Axis(0, 0.0, 4.0, 1.0), Axis(1, 0.0, 4.0, 1.0)))
    patch_of = np.ones((grid.size, 1), dtype=np.int64)
    margin = np.full((grid.size, 1), 0.5)
    for x, y in other_patch:
        patch_of[5 * x + y] = 2
    for x, y in low_margin:
        margin[5 * x + y] = -0.08
    sheets = Sheets(grid.lattice, 1.0, 2, patch_of, margin, np.zeros((grid.size, 1, 1)),
                    np.zeros(1))
    return shortcut_path(np.array(points, dtype=float), np.array(patches, dtype=np.int64),
                         np.array(margins, dtype=float), clearance, split, sheets).tolist()


EDGE = [(0, 0), (1, 0), (2, 0), (3, 0), (4, 0), (4, 1), (4, 2), (4, 3), (4, 4)]


def test_shortcut_takes_the_longest_clear_jump_then_halved_ones():
    assert _shortcut_on_square(EDGE, [1] * 9, [0.5] * 9) == [0, 8]
    # The diagonal crosses cell (2, 2), on another patch: refused, so the
    # jump of half as many waypoints is taken, along the edge.
    assert _shortcut_on_square(EDGE, [1] * 9, [0.5] * 9, other_patch=[(2, 2)]) == [0, 4, 8]
    # Without its straight jump, a run is cut in halves.
    assert _shortcut_on_square(EDGE[:5], [1] * 5, [0.5] * 5, split=True) == [0, 2, 4]


def test_shortcut_crosses_the_path_patches_in_order_and_keeps_the_margin():
    # A gate between patch 1 and patch 2 along x = 4: the diagonal crosses
    # it elsewhere than the edge path did, and may.
    beyond = [(4, 1), (4, 2), (4, 3), (4, 4), (3, 4), (3, 3)]
    assert _shortcut_on_square(EDGE, [1] * 5 + [2] * 4, [0.5] * 9,
                               other_patch=beyond) == [0, 8]
    # Patches are crossed in order only: the diagonal through (2, 2), on
    # patch 2, and back on patch 1 at (3, 3) is refused, so the jumps stop
    # at the gate.
    assert _shortcut_on_square(EDGE, [1] * 5 + [2] * 4, [0.5] * 9,
                               other_patch=EDGE[5:] + [(2, 2)]) == [0, 4, 8]
    # Cell (2, 2) has margin 0.08, below the clearance 0.1: refused, unless
    # a waypoint the jump replaces already passes that low.
    assert _shortcut_on_square(EDGE, [1] * 9, [0.5] * 9, low_margin=[(2, 2)]) == [0, 4, 8]
    lower = [0.5] * 9
    lower[6] = 0.05
    assert _shortcut_on_square(EDGE, [1] * 9, lower, low_margin=[(2, 2)]) == [0, 8]


def test_cutting_corners_keeps_the_endpoints():
    points = np.array([[0, 0], [2, 0], [3, 0], [3, 1]], dtype=float)
    rounded, origin = cut_corners(points, np.ones(len(points), dtype=bool))
    np.testing.assert_allclose(rounded[0], points[0])
    np.testing.assert_allclose(rounded[-1], points[-1])
    assert np.all(np.bincount(origin)[1:-1] == 2)
    np.testing.assert_allclose(rounded[-3:-1], [[2.75, 0], [3, 0.25]])


def test_cut_corners_cuts_only_the_chosen_corners():
    points = np.array([[0, 0], [4, 0], [4, 4], [8, 4]], dtype=float)
    rounded, origin = cut_corners(points, [True, False, True, True])
    np.testing.assert_array_equal(origin, [0, 1, 2, 2, 3])
    np.testing.assert_allclose(rounded, [[0, 0], [4, 0], [4, 3], [5, 4], [8, 4]])


def test_time_parameterize_rejects_bad_limits():
    with pytest.raises(InvalidInputError):
        time_parameterize(np.zeros((2, 3)), 0.0, 1.0)


def test_planner_works_on_another_rho1():
    roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(rho1=13, step=0.25))
    planner = Planner(roadmap)
    seg = roadmap.segmentation
    big = max(seg.patches.values(), key=lambda p: p.cells.size)
    deep = np.flatnonzero(planner.cell_search.clearance(big.id) >= 4)
    ends = [(big.cells[k], big.slots[k]) for k in (deep[0], deep[-1])]
    a, b = ((*roadmap.grid.joints_of(c), float(seg.field.poses[c, s, 2])) for c, s in ends)
    plan = planner.plan(a, b)
    assert plan.validation.ok and set(plan.patches.tolist()) == {big.id}


def test_a_polyline_keeps_its_ends_and_turns():
    from rpr3_gwr_core.planning.simplifier import polyline_turns

    points = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [3, 3], [4, 4], [4, 4.5]],
                      dtype=float)
    assert polyline_turns(points).tolist() == [0, 2, 4, 6, 7]


def test_gate_distances_outside_the_index_are_kept_for_the_last_clearances_first_used(
        paper_roadmap):
    planner = Planner(paper_roadmap)
    for clearance in (0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.01):
        planner.plan(Q1, Q2, PlanOptions(clearance=clearance))
    assert planner.search_index.clearances == (DEFAULT_CLEARANCE,)
    assert list(planner.cell_search._extra_fields) == [0.01, 0.03, 0.04, 0.05]


# --- what a worker process needs (the planner node starts them) ----------------------------------

_WARM_UP_CHECK = """
import importlib, json, math, pkgutil
from numba.core.registry import CPUDispatcher
import rpr3_gwr_core
from rpr3_gwr_core.exceptions import GWRError
from rpr3_gwr_core.paper import PAPER_GEOMETRY, PAPER_GRID
from rpr3_gwr_core.planning import PlanOptions, Planner
from rpr3_gwr_core.workspace.roadmap import build_roadmap

planner = Planner(build_roadmap(PAPER_GEOMETRY, PAPER_GRID))
planner.warm_up()
kernels = {}
for info in pkgutil.walk_packages(rpr3_gwr_core.__path__, "rpr3_gwr_core."):
    for name, value in vars(importlib.import_module(info.name)).items():
        if isinstance(value, CPUDispatcher):
            kernels[value] = len(value.overloads)
D = math.radians
pairs = [((17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))),
         ((17, 20, 25, D(29.47)), (17, 20, 25, D(96.13))),
         ((17, 12, 18, D(122.82)), (17, 20, 25, D(96.13)))]
for options in (PlanOptions(), PlanOptions(smooth=True, max_velocity=1.0, max_acceleration=2.0),
                PlanOptions(feasibility_only=True), PlanOptions(weighted=True, clearance=0.05)):
    for start, goal in pairs:
        try:
            planner.plan(start, goal, options)
        except GWRError:
            pass
print(json.dumps(sorted(k.py_func.__qualname__ for k, n in kernels.items()
                        if len(k.overloads) > n)))
"""


def test_warm_up_loads_every_kernel_a_plan_uses():
    # A fresh interpreter: this one has loaded every kernel long ago.
    run = subprocess.run([sys.executable, "-c", _WARM_UP_CHECK], capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert json.loads(run.stdout.splitlines()[-1]) == []
