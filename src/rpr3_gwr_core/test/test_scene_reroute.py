"""One post reroutes a plan onto the other listed global path.

On the paper's slice (rho1 = 17, 401 x 401 grid) the start
(rho2, rho3, alpha) = (31.875, 24.125, 69.372 deg) and the goal
(9.875, 2.875, 76.475 deg) are joined by two global paths with the fewest
gates, 11 -> 62 -> 41 and 11 -> 22 -> 41.  Without a scene the plan goes
along the first: leg 1 turns the long way round A1, through theta1 = 180 deg.
A post of radius 1 at (-16, 0), on leg 1's circle (as the "blocking" post of
test_world_reference.py), cuts every way through patches 11, 62 and 41 in
the scene's roadmap, and the plan goes along 11 -> 22 -> 41 instead, turning
leg 1 the short way.

The rerouted path is checked independently of the planner's kernels: at
every waypoint with the plain distances below (legs as capsules of the width
the mechanism's bodies give, the platform as a triangle), and along the
joint path, followed in small steps by the reference continuation of
test_world_reference.py, for collisions, for the sign of det Jx and for the
patches it crosses (11, 22, 41; the scene-free path's: 11, 62, 41).  That
reference also finds the post on the scene-free path.

(The pair and the post were found by a search: random cell solutions with
margins of at least 0.05 whose scene-free plan lists two global paths, posts
on a 4-unit lattice of centres, judged by the scene's roadmap and then the
planner.  Among the paper's four examples and their other assembly modes,
only pairs with patch 64 list two paths (through 56 or 42), and no disc of
radius 0.5 to 6 centred on a 2-unit lattice reroutes any of them.)
"""

import math

import networkx as nx
import numpy as np
import pytest

from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY as G
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.world import mechanism_bodies, scene_from_dict
from test_world_reference import (det_jx, reference_blocked, reference_track,
                                  torus_platform)

RHO1 = 17.0
START = (RHO1, 31.875, 24.125, math.radians(69.372))
GOAL = (RHO1, 9.875, 2.875, math.radians(76.475))
PATH_A = (11, 62, 41)  # the scene-free plan's, listed first
PATH_B = (11, 22, 41)  # listed second; the plan's with the post
CENTER, RADIUS = np.array([-16.0, 0.0]), 1.0
POST = {"obstacles": [{"id": "post", "disc": {"center": CENTER.tolist(), "radius": RADIUS}}]}
BASE = np.array([G.a1, G.a2, G.a3], dtype=float)


def leg_radius():
    """Half the legs' width in the bodies the mechanism gives (default model)."""
    start = G.direct_kinematics(list(START[:3]))
    bodies = mechanism_bodies(G, start[0], START[:3])
    return float(max(r for r, name in zip(bodies.capsule_radius, bodies.names)
                     if name.startswith("leg")))


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


@pytest.fixture(scope="module")
def world(planner):
    return planner.apply_scene(scene_from_dict(POST))


@pytest.fixture(scope="module")
def free_plan(planner):
    return planner.plan(START, GOAL)


@pytest.fixture(scope="module")
def free_track(free_plan):
    """The scene-free plan followed in small steps by the reference."""
    return reference_track(free_plan.joints, free_plan.poses[0])


@pytest.fixture(scope="module")
def rerouted(planner, world):
    return planner.plan(START, GOAL, world=world)


# Plain geometry, written out again here: distances from the post's centre.

def point_to_segment(p, a, b):
    """Distance from point p (2,) to segments a-b (..., 2)."""
    d = b - a
    t = np.clip(np.sum((p - a) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-300), 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * d - p, axis=-1)


def inside_triangle(p, b):
    """Whether point p lies inside triangles b (..., 3, 2)."""
    cross = [(b[..., (i + 1) % 3, 0] - b[..., i, 0]) * (p[1] - b[..., i, 1])
             - (b[..., (i + 1) % 3, 1] - b[..., i, 1]) * (p[0] - b[..., i, 0])
             for i in range(3)]
    return np.all(np.array(cross) > 0, axis=0) | np.all(np.array(cross) < 0, axis=0)


def gaps_to_post(b, capsule_radius):
    """Per configuration (b: (..., 3, 2) platform points), how far the legs
    (capsules A_i-B_i) and the platform triangle keep from the post."""
    legs = np.min([point_to_segment(CENTER, np.broadcast_to(BASE[i], b[..., i, :].shape),
                                     b[..., i, :]) for i in range(3)], axis=0) - capsule_radius
    edges = np.min([point_to_segment(CENTER, b[..., i, :], b[..., (i + 1) % 3, :])
                    for i in range(3)], axis=0)
    platform = np.where(inside_triangle(CENTER, b), -np.inf, edges)
    return np.minimum(legs, platform) - RADIUS


def leg1_angles(poses):
    """Leg 1's direction theta1 [deg] along poses, unwrapped (A1 is the origin)."""
    return np.degrees(np.unwrap(np.arctan2(poses[:, 1], poses[:, 0])))


def patches_crossed(roadmap, track):
    """The patches a followed track crosses, in order: at each step the patch
    of the solution of the track's grid cell nearest its pose."""
    field, grid = roadmap.segmentation.field, roadmap.grid
    b = np.array([torus_platform(p) for p in track])
    cells = grid.cells_of(np.linalg.norm(b - BASE, axis=-1)[:, list(grid.axis_joints)])
    gap = (np.abs(np.angle(np.exp(1j * (field.poses[cells, :, 2] - track[:, None, 2]))))
           + np.linalg.norm(field.poses[cells, :, :2] - track[:, None, :2], axis=-1) / G.scale)
    gap[np.arange(field.max_solutions)[None] >= field.count[cells][:, None]] = np.inf
    patch = roadmap.segmentation.patch[cells, np.argmin(gap, axis=1)].tolist()
    return tuple(p for k, p in enumerate(patch) if k == 0 or p != patch[k - 1])


def test_without_the_post_the_plan_goes_along_11_62_41_turning_leg_1_past_180_deg(
        paper_roadmap, free_plan, free_track):
    assert [p.patches for p in free_plan.global_paths] == [PATH_A, PATH_B]
    assert free_plan.global_paths[free_plan.path_index].patches == PATH_A
    assert free_plan.validation.ok
    assert patches_crossed(paper_roadmap, free_track) == PATH_A
    theta1 = leg1_angles(free_track)
    assert theta1.min() < 180.0 < theta1.max()


def test_the_reference_finds_the_post_on_the_scene_free_path(free_plan, free_track):
    assert np.allclose(free_track[-1][:2], free_plan.poses[-1][:2], atol=1e-6)
    b = np.array([torus_platform(p) for p in free_track])
    assert reference_blocked(b, POST).any()
    assert np.any(gaps_to_post(b, leg_radius()) < 0)


def test_the_post_cuts_every_way_through_the_patches_of_11_62_41(planner, world):
    s, g = planner.locate(START), planner.locate(GOAL)
    start, goal = int(world.part[s.cell, s.slot]), int(world.part[g.cell, g.slot])
    assert start >= 0 and goal >= 0
    assert world.feasibility(s, g).feasible

    def joined_within(patches):
        graph = world.graph.subgraph(p for p, data in world.graph.nodes(data=True)
                                     if data["patch"] in patches)
        return nx.has_path(graph, start, goal)

    assert not joined_within(PATH_A)
    assert joined_within(PATH_B)
    # Without the post, patches 11, 62 and 41 alone join them.
    empty = planner.apply_scene(scene_from_dict({}))
    graph = empty.graph.subgraph(p for p, data in empty.graph.nodes(data=True)
                                 if data["patch"] in PATH_A)
    assert nx.has_path(graph, int(empty.part[s.cell, s.slot]), int(empty.part[g.cell, g.slot]))


def test_with_the_post_the_plan_goes_along_the_second_listed_path_11_22_41(rerouted):
    assert [p.patches for p in rerouted.global_paths] == [PATH_A, PATH_B]
    assert rerouted.path_index == 1
    assert rerouted.global_paths[rerouted.path_index].patches == PATH_B
    assert rerouted.validation.ok
    assert set(rerouted.patches.tolist()) <= set(PATH_B)
    assert np.allclose(rerouted.joints[0], START[:3]) and np.allclose(rerouted.joints[-1],
                                                                      GOAL[:3])


def test_every_rerouted_waypoint_keeps_legs_and_platform_off_the_post(rerouted):
    poses, joints = rerouted.poses, rerouted.joints
    b = np.array([torus_platform(p) for p in poses])
    # The poses solve the joints, and the mechanism's bodies are these legs.
    assert np.allclose(np.linalg.norm(b - BASE, axis=-1), joints, atol=1e-6)
    bodies = mechanism_bodies(G, poses, joints)
    legs = [k for k, name in enumerate(bodies.names) if name.startswith("leg")]
    assert len(legs) == 3
    assert np.allclose(bodies.capsules[:, legs, 0], BASE, atol=1e-9)
    assert np.allclose(bodies.capsules[:, legs, 1], b, atol=1e-9)
    assert np.allclose(bodies.capsule_radius[legs], leg_radius())
    assert leg_radius() == pytest.approx(0.01 * G.scale)  # the default leg width's half
    assert np.all(gaps_to_post(b, leg_radius()) > 1.0)


def test_the_rerouted_path_followed_in_small_steps_stays_clear_and_in_one_aspect(
        paper_roadmap, rerouted):
    track = reference_track(rerouted.joints, rerouted.poses[0])
    assert patches_crossed(paper_roadmap, track) == PATH_B
    assert np.allclose(track[-1][:2], rerouted.poses[-1][:2], atol=1e-6)
    assert abs(np.angle(np.exp(1j * (track[-1][2] - rerouted.poses[-1][2])))) < 1e-6
    assert abs(np.angle(np.exp(1j * (track[-1][2] - GOAL[3])))) < 1e-3
    b = np.array([torus_platform(p) for p in track])
    assert not reference_blocked(b, POST).any()
    assert np.all(gaps_to_post(b, leg_radius()) > 1.0)
    sign = np.sign(det_jx(b, track[:, 2]))
    assert np.all(sign == sign[0]) and sign[0] != 0
    # Leg 1 turns the short way: it never points at the post (180 deg).
    theta1 = leg1_angles(track)
    assert -180.0 < theta1.min() and theta1.max() < 180.0
