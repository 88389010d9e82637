"""Thin regions refined until the grid settles what they join: the 3-RRR's
way at th1 = 1.5 rad, which the default grid misses, is found, and the path
planned along it is followed by the independent reference of
:mod:`moving_base_reference` (circle intersections, a continuation of its own)
without a singularity; grids without thin regions are built once, unchanged."""

import math
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InvalidInputError, UndecidedError
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file, roadmap_grid
from rpr3_gwr_core.planning import Planner, PoseEnd, resolve_ends
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_core.workspace.thin_regions import refine_thin_regions, thin_patches

from moving_base_reference import wrap
from test_rrr3 import REFERENCE, torus_preimages

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
TH1 = 1.5
# Two solutions of one joint vector (th2 = 165 deg, th3 = -87 deg) in one
# aspect, which the default grid (3 deg a cell) puts in regions of their own:
# the way between them runs along a strip that narrows below a cell.
JOINTS = (TH1, math.radians(165.0), math.radians(-87.0))
START = (*JOINTS, math.radians(-122.510593))
GOAL = (*JOINTS, math.radians(-33.654195))
# The mechanism files' default slices (as bench_mechanisms builds them).
DEFAULT_SLICES = (("paper_3rpr.yaml", {"rho1": 17.0}), ("five_bar.yaml", None),
                  ("three_rrr.yaml", {"th1": 0.0}), ("three_prr.yaml", {"s1": 5.0}))


def _pose_gap(a, b):
    """Largest difference of poses (..., 3): x, y [length unit], alpha [rad]."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    return np.max(np.abs(np.concatenate([d[..., :2], wrap(d[..., 2:])], -1)), -1)


def _slice(name, fixed):
    described = load_mechanism_file(CONFIG / name)
    return described.mechanism, roadmap_grid(described, fixed)


@pytest.fixture(scope="module")
def refined():
    return refine_thin_regions(*_slice("three_rrr.yaml", {"th1": TH1}))


def test_the_grid_alone_misses_the_way_and_says_it_cannot_decide():
    roadmap = build_roadmap(*_slice("three_rrr.yaml", {"th1": TH1}))
    planner = Planner(roadmap)
    start = planner.locate(START)
    thin = thin_patches(roadmap)
    assert start.patch in thin
    with pytest.raises(UndecidedError) as raised:
        planner.plan(START, GOAL)
    aspect = roadmap.graph.nodes[start.patch]["aspect"]
    assert raised.value.thin_patches == tuple(
        p for p in thin if roadmap.graph.nodes[p]["aspect"] == aspect)
    assert raised.value.steps == roadmap.grid.steps


@pytest.mark.parametrize("open_ends", [("goal",), ("start", "goal")])
def test_a_pose_whose_working_modes_the_grid_alone_cannot_decide_is_undecided(open_ends):
    roadmap = build_roadmap(*_slice("three_rrr.yaml", {"th1": TH1}))
    planner = Planner(roadmap)
    ends = {"start": START, "goal": GOAL}
    for name in open_ends:
        ends[name] = PoseEnd(tuple(planner.locate(ends[name]).pose))
    with pytest.raises(UndecidedError) as raised:
        resolve_ends(planner, ends["start"], ends["goal"])
    assert planner.locate(START).patch in raised.value.thin_patches
    assert "working modes" in str(raised.value)


def test_refining_the_thin_region_settles_with_none_left(refined):
    roadmap, report = refined
    assert report.stopped == "settled" and report.rounds >= 1
    assert report.thin_left == () and thin_patches(roadmap) == []
    assert roadmap.grid.blocks.size == report.refined_blocks


def test_the_way_found_is_followed_by_the_reference_without_a_singularity(refined):
    plan = Planner(refined[0]).plan(START, GOAL)
    joints, poses = plan.joints, plan.poses
    # The reference's own solutions at the ends are the plan's.
    for end, pose in ((START, poses[0]), (GOAL, poses[-1])):
        solutions = torus_preimages(np.array(end[:3]))
        assert np.min(_pose_gap(solutions, pose)) < 1e-6
        assert abs(wrap(pose[2] - end[3])) < 1e-6
    followed, vertices = REFERENCE.follow(poses[0], joints, steps=8)
    margins = np.array([REFERENCE.margin(pose, q) for q, pose, _ in followed])
    moves = np.array([move for _, _, move in followed])
    sign = np.sign(REFERENCE.margin(poses[0], joints[0]))
    assert np.all(np.sign(margins) == sign) and np.min(np.abs(margins)) > 1e-4
    # No jump to another branch: every sample moves the platform a little.
    assert moves.max() < 0.1 * REFERENCE.scale
    assert _pose_gap(vertices[-1], poses[-1]) < 1e-6


@pytest.mark.parametrize("name, fixed", DEFAULT_SLICES)
def test_a_grid_without_thin_regions_is_built_once_and_unchanged(name, fixed):
    mechanism, grid = _slice(name, fixed)
    roadmap, report = refine_thin_regions(mechanism, grid)
    plain = build_roadmap(mechanism, grid)
    assert (report.rounds, report.refined_blocks, report.stopped) == (0, 0, "settled")
    assert roadmap.grid == grid
    assert sorted(roadmap.segmentation.gates) == sorted(plain.segmentation.gates)
    for pid, patch in plain.segmentation.patches.items():
        assert np.array_equal(roadmap.segmentation.patches[pid].cells, patch.cells)
        assert np.array_equal(roadmap.segmentation.patches[pid].slots, patch.slots)


def test_large_regions_without_gates_are_not_thin():
    roadmap = build_roadmap(*_slice("five_bar.yaml", None))
    seg = roadmap.segmentation
    assert seg.patches and not seg.gates
    assert thin_patches(roadmap) == []


def test_rounds_and_cells_bound_the_refinement():
    mechanism, grid = _slice("three_rrr.yaml", {"th1": TH1})
    _, report = refine_thin_regions(mechanism, grid, max_rounds=0)
    assert (report.rounds, report.stopped) == (0, "rounds") and report.thin_left
    _, report = refine_thin_regions(mechanism, grid, max_cells=grid.size + 10)
    assert (report.rounds, report.stopped) == (0, "cells") and report.thin_left


@pytest.mark.parametrize("options", [{"refinement": 1}, {"reach": 0}, {"max_rounds": -1},
                                     {"refinement": 2.0}, {"reach": True}, {"max_cells": 0},
                                     {"max_cells": 10**9}])
def test_malformed_options_are_refused(options):
    mechanism, grid = _slice("three_rrr.yaml", {"th1": 0.0})
    with pytest.raises(InvalidInputError):
        refine_thin_regions(mechanism, grid, **options)


def test_only_grids_are_refined():
    mechanism, _ = _slice("three_rrr.yaml", {"th1": 0.0})
    with pytest.raises(InvalidInputError, match="Grid"):
        refine_thin_regions(mechanism, "a grid")
