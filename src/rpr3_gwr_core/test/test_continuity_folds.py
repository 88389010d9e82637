"""A solution whose branch ends in a fold inside a face links nothing: the
3-RRR at th1 = -3 rad, checked against the independent reference of
:mod:`moving_base_reference` (circle intersections and a continuation of its
own), and the plan whose ends only such a link joined answers "no path"."""

import math

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InfeasiblePathError
from rpr3_gwr_core.mechanisms.continuation import follow_path, follow_segments
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file, roadmap_grid
from rpr3_gwr_core.planning import Planner, PlanOptions
from rpr3_gwr_core.workspace.continuity import match_solutions
from rpr3_gwr_core.workspace.roadmap import build_roadmap

from test_rrr3 import follow, torus_preimages

D = math.radians
TH1 = -3.0
# Two cells of the default grid (3 deg a cell), one face apart along th2.
BEFORE = np.array([TH1, D(159.0), D(-117.0)])
AFTER = np.array([TH1, D(162.0), D(-117.0)])
# The negative solution at BEFORE whose branch folds at th2 ~ 161.15 deg, and
# the negative solution at AFTER that a corrector left to itself lands on.
FOLDING = (-19.522, -4.194, 0.149)
BORN = (-17.754, 5.748, -0.490)
CONFIG = __import__("pathlib").Path(__file__).resolve().parents[3] / "config" / "three_rrr.yaml"


@pytest.fixture(scope="module")
def roadmap():
    described = load_mechanism_file(CONFIG)
    return build_roadmap(described.mechanism, roadmap_grid(described, {"th1": TH1}))


def _slot(poses, pose):
    distance = np.max(np.abs(poses - np.array(pose)), axis=1)
    slot = int(np.nanargmin(distance))
    assert distance[slot] < 1e-3
    return slot


def test_the_reference_sees_the_branch_end_in_a_fold_inside_the_face():
    start = torus_preimages(BEFORE)[_slot(torus_preimages(BEFORE), FOLDING)]
    followed, ends = follow(start, np.array([BEFORE, AFTER]), steps=2000)
    moves = np.array([move for _, _, move in followed])
    # The pose jumps by a sizeable part of the platform between two of 2,000
    # samples (Newton left the branch where it ends; where exactly depends
    # on the floating point of the numpy installed), onto the born solution.
    assert moves.max() > 1.0 and np.median(moves) < 1e-2
    assert np.max(np.abs(ends[-1] - np.array(BORN))) < 1e-3


def test_a_branch_that_ends_in_a_fold_links_nothing_across_the_face(roadmap):
    field, grid = roadmap.field, roadmap.grid
    before, after = grid.cell_of(BEFORE), grid.cell_of(AFTER)
    assert np.allclose(grid.joints_of(before), BEFORE) and np.allclose(grid.joints_of(after),
                                                                       AFTER)
    folding = _slot(field.poses[before], FOLDING)
    born = _slot(field.poses[after], BORN)
    assert np.sign(field.margin[before, folding]) == np.sign(field.margin[after, born]) == -1
    lower, upper = (before, after) if before < after else (after, before)
    match = match_solutions(field, np.array([lower]), np.array([upper]))[0]
    if lower == before:
        assert match[folding] != born
    else:
        assert match[born] != folding


def test_the_ends_that_only_the_false_link_joined_have_no_path(roadmap):
    """The issue's repro: the same joints, two assembly modes."""
    joints = (TH1, D(101.25), D(9.84375))
    planner = Planner(roadmap)
    with pytest.raises(InfeasiblePathError) as failure:
        planner.plan((*joints, D(35.727484)), (*joints, D(-46.084932)),
                     PlanOptions(feasibility_only=True))
    assert failure.value.reason == "unreachable"


def test_following_many_segments_is_following_each_one(roadmap):
    field, grid = roadmap.field, roadmap.grid
    rng = np.random.default_rng(3)
    cells = rng.choice(np.flatnonzero(field.count > 0), 200)
    slots = rng.integers(0, field.count[cells])
    starts = grid.joints_at(cells)
    # Up to two cells away along the free axes, in any direction.
    ends = starts + np.column_stack([np.zeros(cells.size),
                                     rng.uniform(-2, 2, (cells.size, 2)) * grid.steps])
    poses = np.array(field.poses[cells, slots])
    mechanism = roadmap.mechanism
    status = follow_segments(mechanism, starts, ends, poses, 1e-6)
    for k in range(cells.size):
        pose = np.array(field.poses[cells[k], slots[k]])
        alone = follow_path(mechanism, np.array([starts[k], ends[k]]), pose, 1e-6, np.inf)
        assert status[k] == alone[0]
        np.testing.assert_array_equal(poses[k], pose)
    assert len(set(status.tolist())) > 1  # some segments meet a fold or the locus
