"""Scenes, body models and the bodies of every mechanism."""

import math
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.scene_file import load_scene
from rpr3_gwr_core.mechanisms import (DEFAULT_FIVE_BAR, DEFAULT_THREE_PRR, DEFAULT_THREE_RRR,
                                      PAPER_GEOMETRY)
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.workspace import build_roadmap
from rpr3_gwr_core.world import (BodyModel, WorldIndex, body_model_from_dict,
                                 configuration_collision, mechanism_bodies,
                                 path_collisions,
                                 scene_from_dict)
from rpr3_gwr_core.world.collision import (INTERFERENCE, OBSTACLE, PASSIVE, STROKE,
                                           check_bodies, compile_scene)

SCENES = pathlib.Path(__file__).resolve().parents[3] / "config" / "scenes"


def test_scene_files_load_and_round_trip():
    files = sorted(SCENES.glob("*.yaml"))
    assert files
    for path in files:
        scene = load_scene(path)
        again = scene_from_dict(scene.to_dict())
        assert again.obstacle_ids == scene.obstacle_ids
        assert again.limits == scene.limits


@pytest.mark.parametrize("data, words", [
    ({"obstacle": []}, "unknown keys"),
    ({"obstacles": {}}, "must be a list"),
    ({"obstacles": [{"disc": {"center": [0, 0], "radius": 1}}]}, "needs an id"),
    ({"obstacles": [{"id": "a", "disc": {"center": [0, 0], "radius": 1}},
                    {"id": "a", "disc": {"center": [0, 0], "radius": 1}}]}, "used twice"),
    ({"obstacles": [{"id": "a", "disc": {"center": [0, 0], "radius": 0}}]}, "positive"),
    ({"obstacles": [{"id": "a", "disc": {"center": [0], "radius": 1}}]}, "two numbers"),
    ({"obstacles": [{"id": "a", "disc": {"center": [0, "x"], "radius": 1}}]}, "list of numbers"),
    ({"obstacles": [{"id": "a", "polygon": [[0, 0], [1, 0]]}]}, "at least 3"),
    ({"obstacles": [{"id": "a", "polygon": [[0, 0], [1, 0], [2, 0]]}]}, "no area"),
    ({"obstacles": [{"id": "a", "polygon": [[0, 0], [2, 2], [2, 0], [0, 1]]}]}, "crossing"),
    ({"obstacles": [{"id": "a", "polygon": [[0, 0], [1, 0], [0, 1]],
                     "disc": {"center": [0, 0], "radius": 1}}]}, "exactly one"),
    ({"limits": {"obstacle_clearance": -1}}, "non-negative"),
    ({"limits": {"strokes": {"rho2": [5, 1]}}}, "above max"),
    ({"limits": {"passive": {"base1": [0, 7]}}}, "full turn"),
    ({"limits": {"strokes": {"rho2": [1]}}}, "[min, max]"),
    ({"limits": {"speed": 1}}, "unknown keys"),
    ([], "mapping"),
])
def test_malformed_scenes_are_refused(data, words):
    with pytest.raises(InvalidInputError) as error:
        scene_from_dict(data)
    assert words in str(error.value)


def test_passive_ranges_in_degrees_carry_their_unit_in_the_key():
    in_degrees = scene_from_dict({"limits": {"passive_deg": {"base1": [-30, 150]}}})
    in_radians = scene_from_dict({"limits": {"passive": {"base1": [-math.pi / 6,
                                                                   5 * math.pi / 6]}}})
    assert in_degrees.limits.passive["base1"] == pytest.approx(
        in_radians.limits.passive["base1"], abs=1e-15)


@pytest.mark.parametrize("limits, words", [
    ({"passive": {"base1": [-30, 150]}},
     "passive 'base1' [-30.0, 150.0] rad lies beyond a full turn: a scene's passive ranges "
     "are in radians; give degrees under passive_deg"),
    ({"passive": {"base1": [-3.5, 3.5]}}, "spans more than a full turn (7 rad)"),
    ({"passive_deg": {"base1": [0, 400]}}, "spans more than a full turn (400 deg)"),
    ({"passive": {"base1": [0, 1]}, "passive_deg": {"base1": [0, 50]}},
     "give the passive ranges once"),
])
def test_a_passive_range_that_could_be_misread_is_refused_with_its_unit(limits, words):
    with pytest.raises(InvalidInputError) as error:
        scene_from_dict({"limits": limits})
    assert words in str(error.value)


def test_load_scene_reports_unreadable_files(tmp_path):
    with pytest.raises(InvalidInputError, match="cannot read"):
        load_scene(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("obstacles: [")
    with pytest.raises(InvalidInputError, match="not YAML"):
        load_scene(bad)
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    assert load_scene(empty).obstacle_ids == ()


def test_unknown_limit_names_are_refused():
    pose = PAPER_GEOMETRY.direct_kinematics([17, 12, 18])[0]
    for limits in ({"strokes": {"rho9": [0, 1]}}, {"passive": {"knee": [0, 1]}}):
        with pytest.raises(InvalidInputError, match="name no"):
            configuration_collision(PAPER_GEOMETRY, scene_from_dict({"limits": limits}),
                                    [17, 12, 18], pose)


def test_body_model_round_trip_and_validation():
    model = BodyModel(leg_width=0.5, leg_layers=(1, 1, 2), housing_length=10.0)
    assert body_model_from_dict(model.to_dict()) == model
    assert body_model_from_dict(None) == BodyModel()
    for data in ({"leg_width": -1}, {"leg_layers": [1.5]}, {"colour": 1}, {"leg_layers": 3},
                 "wide"):
        with pytest.raises(InvalidInputError):
            body_model_from_dict(data)
    pose = PAPER_GEOMETRY.direct_kinematics([17, 12, 18])[0]
    with pytest.raises(InvalidInputError, match="3 layers"):
        mechanism_bodies(PAPER_GEOMETRY, pose, [17, 12, 18], BodyModel(leg_layers=(1, 1)))


def test_three_rpr_bodies():
    rho = np.array([17.0, 12.0, 18.0])
    poses = PAPER_GEOMETRY.direct_kinematics(rho)
    bodies = mechanism_bodies(PAPER_GEOMETRY, poses, rho)
    assert bodies.names == ("leg1", "leg2", "leg3", "platform")
    assert bodies.capsules.shape == (len(poses), 3, 2, 2)
    assert np.allclose(bodies.capsules[:, :, 0], PAPER_GEOMETRY.base)
    lengths = np.linalg.norm(bodies.capsules[:, :, 1] - bodies.capsules[:, :, 0], axis=-1)
    assert np.allclose(lengths, rho)
    assert np.allclose(bodies.polygons[:, 0], bodies.capsules[:, :, 1])
    assert bodies.pairs.size == 0
    assert np.allclose(bodies.passive[..., :3], PAPER_GEOMETRY.passive_angles(poses))
    # One layer: legs meet each other, never the platform they hold.
    coplanar = mechanism_bodies(PAPER_GEOMETRY, poses, rho, BodyModel(leg_layers=(0, 0, 0)))
    assert coplanar.pairs.tolist() == [[0, 1], [0, 2], [1, 2]]
    housed = mechanism_bodies(PAPER_GEOMETRY, poses, rho, BodyModel(housing_length=15.0))
    assert housed.names[:2] == ("leg1_housing", "leg1_rod")
    housing = housed.capsules[:, 0]
    assert np.allclose(np.linalg.norm(housing[:, 1] - housing[:, 0], axis=-1), 15.0)
    assert np.allclose(housed.capsules[:, 1, 1], bodies.capsules[:, 0, 1])


@pytest.mark.parametrize("mechanism", [DEFAULT_THREE_RRR, DEFAULT_THREE_PRR])
def test_moving_base_bodies(mechanism):
    joints = np.array([0.3, -0.2, 0.5]) if mechanism is DEFAULT_THREE_RRR else \
        np.array([3.0, 4.0, 2.0])
    count, poses = mechanism.solve(joints[None])
    poses = poses[0, :count[0]]
    assert count[0] > 0
    bodies = mechanism_bodies(mechanism, poses, joints)
    assert bodies.names == ("proximal1", "distal1", "proximal2", "distal2", "proximal3",
                            "distal3", "platform")
    caps = bodies.capsules
    assert np.allclose(caps[:, 0::2, 0], mechanism.platform.base)
    assert np.allclose(caps[:, 0::2, 1], mechanism.base_points(joints))
    assert np.allclose(caps[:, 1::2, 0], caps[:, 0::2, 1])
    assert np.allclose(np.linalg.norm(caps[:, 1::2, 1] - caps[:, 1::2, 0], axis=-1),
                       mechanism.distal)
    assert np.allclose(bodies.polygons[:, 0], caps[:, 1::2, 1])
    coplanar = mechanism_bodies(mechanism, poses, joints, BodyModel(leg_layers=(1, 1, 1)))
    # Links of one leg share a joint; the distal links hold the platform.
    assert [0, 1] not in coplanar.pairs.tolist() and [1, 6] not in coplanar.pairs.tolist()
    assert [0, 2] in coplanar.pairs.tolist()


def test_five_bar_bodies_and_limits():
    joints = np.array([2.0, 1.0])
    count, poses = DEFAULT_FIVE_BAR.solve(joints[None])
    poses = poses[0, :count[0]]
    bodies = mechanism_bodies(DEFAULT_FIVE_BAR, poses, joints)
    assert bodies.names == ("proximal1", "distal1", "proximal2", "distal2")
    caps = bodies.capsules
    assert np.allclose(np.linalg.norm(caps[:, 0::2, 1] - caps[:, 0::2, 0], axis=-1), 0.09)
    assert np.allclose(np.linalg.norm(caps[:, 1::2, 1] - caps[:, 1::2, 0], axis=-1), 0.118)
    assert np.allclose(caps[:, 1, 1], poses) and np.allclose(caps[:, 3, 1], poses)
    assert bodies.passive_names == ("elbow1", "elbow2", "end")
    # The elbow's angle: the distal link's direction less th1.
    direction = np.arctan2(*(poses - caps[:, 0, 1])[:, ::-1].T)
    assert np.allclose(np.angle(np.exp(1j * (direction - 2.0))), bodies.passive[:, 0])
    scene = scene_from_dict({"limits": {"strokes": {"th1": [-1.0, 1.0]}}})
    found = configuration_collision(DEFAULT_FIVE_BAR, scene, joints, poses[0])
    assert found.kind == STROKE and found.body == "th1" and "outside its stroke" in found.message
    low = float(bodies.passive[0, 0])
    scene = scene_from_dict({"limits": {"passive": {"elbow1": [low + 0.1, low + 1.0]}}})
    found = configuration_collision(DEFAULT_FIVE_BAR, scene, joints, poses[0])
    assert found.kind == PASSIVE and found.body == "elbow1"
    scene = scene_from_dict({"limits": {"passive": {"elbow1": [low - 0.1, low + 0.1]}}})
    assert configuration_collision(DEFAULT_FIVE_BAR, scene, joints, poses[0]) is None


def test_kernel_kinds_and_reasons():
    rho = np.array([17.0, 12.0, 18.0])
    pose = PAPER_GEOMETRY.direct_kinematics(rho)[0]
    b = PAPER_GEOMETRY.platform_points(pose)
    middle = (b[0] + b[1] + b[2]) / 3
    scene = scene_from_dict({"obstacles": [
        {"id": "far", "disc": {"center": [90.0, 90.0], "radius": 1.0}},
        {"id": "under", "polygon": (middle + [[-0.1, -0.1], [0.1, -0.1], [0.0, 0.1]]).tolist()}]})
    found = configuration_collision(PAPER_GEOMETRY, scene, rho, pose)
    assert (found.kind, found.body, found.other) == (OBSTACLE, "platform", "under")
    # Clearance: a post just beyond leg 2's width is hit only with clearance.
    a2 = np.array(PAPER_GEOMETRY.a2)
    u = (b[1] - a2) / np.linalg.norm(b[1] - a2)
    normal = np.array([-u[1], u[0]])
    radius = 0.02 * PAPER_GEOMETRY.scale / 2
    centre = a2 + 0.5 * (b[1] - a2) + normal * (radius + 1.0 + 0.2)
    post = {"id": "post", "disc": {"center": centre.tolist(), "radius": 1.0}}
    assert configuration_collision(PAPER_GEOMETRY, scene_from_dict({"obstacles": [post]}),
                                   rho, pose) is None
    near = scene_from_dict({"obstacles": [post], "limits": {"obstacle_clearance": 0.3}})
    found = configuration_collision(PAPER_GEOMETRY, near, rho, pose)
    assert found.body in ("leg2", "platform") and found.other == "post"
    bodies = mechanism_bodies(PAPER_GEOMETRY, np.stack([pose, pose]), np.stack([rho, rho]),
                                   BodyModel(leg_layers=(1, 1, 1)))
    rows = check_bodies(compile_scene(scene_from_dict({}), PAPER_GEOMETRY, bodies), bodies,
                        np.stack([rho, rho]), chosen=np.array([1]))
    assert rows.shape == (1, 3) and rows[0, 0] in (0, INTERFERENCE)


def test_path_collisions_find_the_first_violation():
    rho = np.array([[17.0, 12.0, 18.0], [17.0, 14.0, 18.0]])
    pose = PAPER_GEOMETRY.direct_kinematics(rho[0])[0]
    assert path_collisions(PAPER_GEOMETRY, scene_from_dict({}), rho, pose) is None
    scene = scene_from_dict({"limits": {"strokes": {"rho2": [0.0, 13.0]}}})
    found = path_collisions(PAPER_GEOMETRY, scene, rho, pose)
    assert found.kind == STROKE and 0.45 <= found.index <= 0.55
    with pytest.raises(InvalidInputError):
        path_collisions(PAPER_GEOMETRY, scene, rho[:, :2], pose)


@pytest.fixture(scope="module")
def coarse_world():
    roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.5))
    return roadmap, WorldIndex(roadmap)


def test_strokes_and_free_scenes_on_the_roadmap(coarse_world):
    roadmap, world = coarse_world
    field = roadmap.field
    free = world.apply(scene_from_dict({}))
    assert free.n_parts == len(roadmap.segmentation.patches)
    assert np.array_equal(free.free, roadmap.segmentation.patch > 0)
    assert sorted(free.part_patch.tolist()) == sorted(roadmap.segmentation.patches)
    assert len(free.graph.edges) == len(roadmap.segmentation.gates)
    stroked = world.apply(scene_from_dict({"limits": {"strokes": {"rho2": [5.0, 45.0]}}}))
    rho2 = roadmap.grid.joints()[:, 1]
    inside = (rho2 >= 5.0) & (rho2 <= 45.0)
    assert np.array_equal(stroked.free, (roadmap.segmentation.patch > 0) & inside[:, None])
    assert stroked.free.sum() < free.free.sum() and field.count.size


def test_interference_only_with_shared_layers(coarse_world):
    roadmap, world = coarse_world
    coplanar = WorldIndex(roadmap, BodyModel(leg_layers=(1, 1, 1)))
    assert not world.interfering.any()
    assert coplanar.interfering.any() and not coplanar.interfering.all()
    # A disc of the scene joins the interference.
    scene = coplanar.apply(scene_from_dict({}))
    assert np.array_equal(scene.free.ravel()[coplanar.disks], ~coplanar.interfering)


def test_scene_updates_allocate_nothing_that_stays(coarse_world):
    import tracemalloc
    _, world = coarse_world
    scene = scene_from_dict({"obstacles": [{"id": 1, "disc": {"center": [5.0, 30.0],
                                                              "radius": 2.0}}]})
    world.apply(scene)
    tracemalloc.start()
    world.apply(scene)
    first = tracemalloc.get_traced_memory()[0]
    for _ in range(5):
        world.apply(scene)
    grown = tracemalloc.get_traced_memory()[0] - first
    tracemalloc.stop()
    assert grown < 2**20


def test_feasibility_refuses_foreign_locations(coarse_world):
    roadmap, world = coarse_world
    scene = world.apply(scene_from_dict({}))

    class Where:
        cell, slot, patch = 0, 0, 11

    with pytest.raises(InvalidInputError, match="not a solution"):
        scene.feasibility(Where, Where)


def test_crowded_solutions_lie_within_twice_the_clearance(coarse_world):
    _, world = coarse_world
    post = {"id": "post", "disc": {"center": [6.0, 28.0], "radius": 2.0}}
    near = world.apply(scene_from_dict({"obstacles": [post],
                                        "limits": {"obstacle_clearance": 0.5}}))
    wide = world.apply(scene_from_dict({"obstacles": [post],
                                        "limits": {"obstacle_clearance": 1.0}}))
    assert near.crowded.any()
    assert np.array_equal(near.crowded, near.free & ~wide.free)
    assert not world.apply(scene_from_dict({"obstacles": [post]})).crowded.any()


def test_the_scene_index_moves_to_the_mapped_roadmap_without_the_first(tmp_path):
    import gc
    import weakref

    from rpr3_gwr_core.io.cache import map_planning_files, save_planning_files
    from rpr3_gwr_core.planning import Planner

    roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.5))
    first = Planner(roadmap)
    scene = scene_from_dict({"obstacles": [{"id": 1, "disc": {"center": [5.0, 30.0],
                                                              "radius": 2.0}}]})
    world = first.apply_scene(scene)
    save_planning_files(str(tmp_path), roadmap, first.search_index)
    mapped = Planner(*map_planning_files(str(tmp_path)))
    mapped.adopt_scene_indices(first)
    moved = mapped.apply_scene(scene)
    # Not computed again: the same boxes, on the mapped roadmap's arrays.
    assert moved.index.boxes is world.index.boxes
    assert moved.index.roadmap is mapped.roadmap
    assert moved.n_parts == world.n_parts
    assert np.array_equal(moved.free, world.free)
    assert sorted(moved.graph.edges) == sorted(world.graph.edges)
    coarser = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=1.0))
    with pytest.raises(InvalidInputError, match="equal roadmap"):
        world.index.on_roadmap(coarser)
    received = weakref.ref(roadmap)
    del roadmap, first, world
    gc.collect()
    assert received() is None
