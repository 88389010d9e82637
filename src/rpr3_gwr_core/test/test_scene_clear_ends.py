"""A start clear of the scene is not answered as colliding.

The scene is resolved cell by cell: a configuration between lattice points
is located in a grid cell whose solution, at the lattice point, may touch an
obstacle that the configuration itself keeps clear of.  On the paper's
slice (rho1 = 17, step 0.125) the start (rho2, rho3) = (31.935, 24.185),
0.06 off the lattice, keeps its legs and platform 0.02 clear of a disc of
radius 0.5 at (13.1, 31.3) that its cell's solution meets, both by the plain
geometry of test_world_reference.py: the answer is that no way leaves the
start on this grid, not that it collides; a disc on the platform is a
collision.
"""

import math

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import CollisionError, InfeasiblePathError
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY as G
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.world import scene_from_dict
from test_world_reference import reference_blocked

START = (17.0, 31.935, 24.185, math.radians(69.372))
GOAL = (17.0, 9.875, 2.875, math.radians(76.475))
NEAR = {"obstacles": [{"id": "near", "disc": {"center": [13.1, 31.3], "radius": 0.5}}]}


def _platform(pose):
    """B1, B2, B3 (3, 2) of a pose, from the mechanism's dimensions."""
    x, y, alpha = pose
    return np.array([[x, y], [x + G.d1 * math.cos(alpha), y + G.d1 * math.sin(alpha)],
                     [x + G.d3 * math.cos(alpha + G.beta), y + G.d3 * math.sin(alpha + G.beta)]])


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


def test_a_clear_start_in_a_blocked_cell_is_no_way_out_not_a_collision(planner, paper_roadmap):
    start = planner.locate(START)
    cell_pose = paper_roadmap.segmentation.field.poses[start.cell, start.slot]
    assert not reference_blocked(_platform(start.pose), NEAR)
    assert reference_blocked(_platform(cell_pose), NEAR)
    world = planner.apply_scene(scene_from_dict(NEAR))
    with pytest.raises(InfeasiblePathError, match="the start is clear of the scene") as answer:
        planner.plan(START, GOAL, world=world)
    assert answer.value.reason == "blocked"


def test_a_start_that_meets_an_obstacle_collides(planner):
    start = planner.locate(START)
    on_platform = {"obstacles": [{"id": "on", "disc": {
        "center": _platform(start.pose).mean(axis=0).tolist(), "radius": 0.5}}]}
    assert reference_blocked(_platform(start.pose), on_platform)
    world = planner.apply_scene(scene_from_dict(on_platform))
    with pytest.raises(CollisionError, match="the start is blocked"):
        planner.plan(START, GOAL, world=world)
