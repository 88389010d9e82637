"""The scene roadmap against an independent reference: at fixed rho1 = 17 the
3-RPR's configuration space is the torus (theta1, alpha) with its legs in
closed form; its bodies are tested against the scene with the plain
geometry below (not the compiled kernel), its aspect with det Jx, and
feasibility is connectivity of free same-aspect samples on the torus."""

import math

import numpy as np
import pytest
import scipy.sparse as sparse
from scipy.sparse.csgraph import connected_components

from gwr_cases import PAPER_EXAMPLES
from rpr3_gwr_core.exceptions import CollisionError, InfeasiblePathError, ValidationError
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY as G
from rpr3_gwr_core.planning.locate import locate
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.planning.planner import Planner
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_core.world import (BodyModel, WorldIndex, configuration_collision,
                                 mechanism_bodies, path_collisions, scene_from_dict)

RHO1 = 17.0
N_THETA, N_ALPHA = 480, 480
BOX = (0.25, 49.75)  # legs inside the roadmap's box, with a margin of two cells

A = np.array([G.a1, G.a2, G.a3])
LEG_RADIUS = 0.02 * G.scale / 2  # the default body model's

SCENES = {
    # Far from every body of either example: the roadmap's answers stand.
    "free": {"obstacles": [{"id": "far", "disc": {"center": [45.0, 45.0], "radius": 2.0}}]},
    # Leg 1's circle cut: B1 cannot turn past (-16, 0).
    "blocking": {"obstacles": [{"id": "post", "disc": {"center": [-16.0, 0.0], "radius": 1.0}}]},
    # A post and a plate that remove configurations and leave both examples
    # connected.
    "narrowing": {"obstacles": [
        {"id": "post", "disc": {"center": [6.0, 28.0], "radius": 2.0}},
        {"id": "plate", "polygon": [[-20.0, 24.0], [-12.0, 24.0], [-12.0, 30.0], [-20.0, 30.0]]}],
        "limits": {"obstacle_clearance": 0.5}},
}


# The reference geometry: plain numpy, one formula per distance.

def torus_configurations(theta1, alpha):
    """Platform points B (..., 3, 2), legs rho (..., 3) and pose (..., 3)."""
    b1 = RHO1 * np.stack([np.cos(theta1), np.sin(theta1)], -1)
    b2 = b1 + G.d1 * np.stack([np.cos(alpha), np.sin(alpha)], -1)
    b3 = b1 + G.d3 * np.stack([np.cos(alpha + G.beta), np.sin(alpha + G.beta)], -1)
    b = np.stack([b1, b2, b3], -2)
    rho = np.linalg.norm(b - A, axis=-1)
    pose = np.concatenate([b1, alpha[..., None] + 0 * theta1[..., None]], -1)
    return b, rho, pose


def det_jx(b, alpha):
    """det of dF/d(x, y, alpha), F_i = |B_i - A_i|^2 (up to a factor 8)."""
    u = b - A
    r = b - b[..., :1, :]
    turn = -u[..., 0] * r[..., 1] + u[..., 1] * r[..., 0]
    m = np.stack([u[..., 0], u[..., 1], turn], -1)
    return np.linalg.det(m)


def point_segment(p, a, b):
    d = b - a
    t = np.clip(np.sum((p - a) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-300), 0, 1)
    return np.linalg.norm(a + t[..., None] * d - p, axis=-1)


def segments_cross(p, q, r, s):
    def orient(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) \
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
    return (orient(p, q, r) * orient(p, q, s) < 0) & (orient(r, s, p) * orient(r, s, q) < 0)


def segment_segment(p, q, r, s):
    d = np.minimum(np.minimum(point_segment(p, r, s), point_segment(q, r, s)),
                   np.minimum(point_segment(r, p, q), point_segment(s, p, q)))
    return np.where(segments_cross(p, q, r, s), 0.0, d)


def point_in_polygon(p, polygon):
    inside = np.zeros(p.shape[:-1], dtype=bool)
    for i in range(len(polygon)):
        (x1, y1), (x2, y2) = polygon[i - 1], polygon[i]
        crosses = (y1 > p[..., 1]) != (y2 > p[..., 1])
        x_at = x1 + (p[..., 1] - y1) * (x2 - x1) / ((y2 - y1) if y2 != y1 else 1.0)
        inside ^= crosses & (p[..., 0] < x_at)
    return inside


def segment_to_polygon(p, q, polygon):
    distance = np.full(p.shape[:-1], np.inf)
    for i in range(len(polygon)):
        r = np.broadcast_to(polygon[i - 1], p.shape)
        s = np.broadcast_to(polygon[i], p.shape)
        distance = np.minimum(distance, segment_segment(p, q, r, s))
    return np.where(point_in_polygon(p, polygon) | point_in_polygon(q, polygon), 0.0, distance)


def reference_blocked(b, data):
    """Whether legs A_i B_i (radius LEG_RADIUS) or the triangle come within
    the clearance of an obstacle."""
    clearance = data.get("limits", {}).get("obstacle_clearance", 0.0)
    blocked = np.zeros(b.shape[:-2], dtype=bool)
    edges = [(b[..., i, :], b[..., (i + 1) % 3, :]) for i in range(3)]
    for obstacle in data["obstacles"]:
        if "disc" in obstacle:
            c = np.array(obstacle["disc"]["center"])
            reach = obstacle["disc"]["radius"] + clearance
            for i in range(3):
                blocked |= point_segment(c, np.broadcast_to(A[i], b[..., i, :].shape),
                                         b[..., i, :]) <= reach + LEG_RADIUS
            triangle_distance = np.min([point_segment(c, p, q) for p, q in edges], axis=0)
            inside = _point_in_triangles(c, b)
            blocked |= inside | (triangle_distance <= reach)
        else:
            polygon = np.array(obstacle["polygon"], dtype=float)
            for i in range(3):
                blocked |= segment_to_polygon(np.broadcast_to(A[i], b[..., i, :].shape),
                                              b[..., i, :], polygon) <= clearance + LEG_RADIUS
            for p, q in edges:
                blocked |= segment_to_polygon(p, q, polygon) <= clearance
            blocked |= _point_in_triangles(polygon[0], b)
    return blocked


def _point_in_triangles(c, b):
    """Whether the point c lies in each triangle b (..., 3, 2)."""
    signs = []
    for i in range(3):
        p, q = b[..., i, :], b[..., (i + 1) % 3, :]
        signs.append((q[..., 0] - p[..., 0]) * (c[1] - p[..., 1])
                     - (q[..., 1] - p[..., 1]) * (c[0] - p[..., 0]))
    signs = np.stack(signs)
    return np.all(signs > 0, axis=0) | np.all(signs < 0, axis=0)


def torus_components(free, sign):
    """Connected components of free samples of one aspect on the torus grid."""
    n1, n2 = free.shape
    index = np.arange(free.size).reshape(free.shape)
    rows, cols = [], []
    for shifted in (np.roll(index, -1, 0), np.roll(index, -1, 1)):
        ok = free.ravel() & free.ravel()[shifted.ravel()] & (
            sign.ravel() == sign.ravel()[shifted.ravel()])
        rows.append(index.ravel()[ok])
        cols.append(shifted.ravel()[ok])
    graph = sparse.coo_matrix((np.ones(sum(r.size for r in rows)),
                               (np.concatenate(rows), np.concatenate(cols))),
                              shape=(free.size, free.size))
    return connected_components(graph, directed=False)[1].reshape(free.shape)


@pytest.fixture(scope="module")
def torus():
    theta1, alpha = np.meshgrid(np.linspace(-np.pi, np.pi, N_THETA, endpoint=False),
                                np.linspace(-np.pi, np.pi, N_ALPHA, endpoint=False),
                                indexing="ij")
    b, rho, pose = torus_configurations(theta1, alpha)
    inside = np.all((rho[..., 1:] >= BOX[0]) & (rho[..., 1:] <= BOX[1]), axis=-1)
    return theta1, alpha, b, rho, pose, inside, np.sign(det_jx(b, alpha))


@pytest.fixture(scope="module")
def world(paper_roadmap):
    return WorldIndex(paper_roadmap)


def torus_sample_of(configuration, torus):
    """The torus sample nearest a configuration (rho2, rho3, alpha [deg])."""
    theta1, alpha, b, rho, pose, *_ = torus
    solutions = G.direct_kinematics([RHO1, configuration[0], configuration[1]])
    wanted = math.radians(configuration[2])
    x, y, a = solutions[np.argmin(np.abs(np.angle(np.exp(1j * (solutions[:, 2] - wanted)))))]
    gap = np.abs(np.angle(np.exp(1j * (theta1 - math.atan2(y, x))))) \
        + np.abs(np.angle(np.exp(1j * (alpha - a))))
    return np.unravel_index(np.argmin(gap), gap.shape)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_kernel_agrees_with_the_reference_on_the_torus(name, torus):
    theta1, alpha, b, rho, pose, inside, _ = torus
    rng = np.random.default_rng(7)
    picks = rng.choice(np.flatnonzero(inside), 4000, replace=False)
    scene = scene_from_dict(SCENES[name])
    expected = reference_blocked(b.reshape(-1, 3, 2)[picks], SCENES[name])
    from rpr3_gwr_core.world.collision import check_bodies, compile_scene
    bodies = mechanism_bodies(G, pose.reshape(-1, 3)[picks], rho.reshape(-1, 3)[picks])
    got = check_bodies(compile_scene(scene, G, bodies), bodies, rho.reshape(-1, 3)[picks])
    assert np.array_equal(got[:, 0] != 0, expected)
    if name != "free":
        assert expected.any() and not expected.all()


@pytest.mark.parametrize("name", sorted(SCENES))
def test_roadmap_free_solutions_agree_with_the_reference(name, paper_roadmap, world):
    scene = world.apply(scene_from_dict(SCENES[name]))
    field = paper_roadmap.field
    rng = np.random.default_rng(3)
    picks = rng.choice(world.disks, 5000, replace=False)
    cells, slots = picks // field.max_solutions, picks % field.max_solutions
    poses = field.poses[cells, slots]
    b = G.platform_points(poses)
    expected = reference_blocked(b, SCENES[name])
    assert np.array_equal(~scene.free[cells, slots], expected)


@pytest.mark.parametrize("name", sorted(SCENES))
@pytest.mark.parametrize("example", [(0, 1), (2, 3)])
def test_feasibility_agrees_with_torus_connectivity(name, example, paper_roadmap, world, torus):
    theta1, alpha, b, rho, pose, inside, sign = torus
    data = SCENES[name]
    free = inside & ~reference_blocked(b, data) & (sign != 0)
    label = torus_components(free, sign)
    ends = [torus_sample_of(PAPER_EXAMPLES[k], torus) for k in example]
    assert all(free[e] for e in ends)
    connected = label[ends[0]] == label[ends[1]]
    scene = world.apply(scene_from_dict(data))
    start, goal = (locate(paper_roadmap, (RHO1, PAPER_EXAMPLES[k][0], PAPER_EXAMPLES[k][1],
                                          math.radians(PAPER_EXAMPLES[k][2]))) for k in example)
    answer = scene.feasibility(start, goal)
    assert answer.feasible == connected
    # The post on leg 1's circle cuts the first example's way, not the
    # second's (its assembly-mode change stays on one side of theta1).
    blocked = name == "blocking" and example == (0, 1)
    assert answer.reason == ("blocked" if blocked else "connected")
    if name == "narrowing":
        assert scene.n_parts > len(paper_roadmap.segmentation.patches)


def reference_track(joints, start_pose, step=0.01):
    """Poses along a joint path by Newton on the closed-form legs, from small
    joint steps: the platform's own motion, the reference's way."""
    track, pose = [np.asarray(start_pose, float)], np.asarray(start_pose, float)
    for a, c in zip(joints[:-1], joints[1:]):
        n = max(1, int(np.ceil(np.max(np.abs(c - a)) / step)))
        for t in np.arange(1, n + 1) / n:
            legs = a + t * (c - a)
            for _ in range(8):
                b = torus_platform(pose)
                u = b - A
                r = b - b[0]
                jac = np.stack([2 * u[:, 0], 2 * u[:, 1],
                                2 * (-u[:, 0] * r[:, 1] + u[:, 1] * r[:, 0])], -1)
                pose = pose - np.linalg.solve(jac, np.sum(u * u, -1) - legs ** 2)
            track.append(pose)
    return np.array(track)


def torus_platform(pose):
    x, y, a = pose
    b1 = np.array([x, y])
    return np.stack([b1, b1 + G.d1 * np.array([math.cos(a), math.sin(a)]),
                     b1 + G.d3 * np.array([math.cos(a + G.beta), math.sin(a + G.beta)])])


def test_returned_paths_agree_with_the_reference(paper_roadmap):
    """The paper's first plan, checked along its whole length by
    path_collisions and, followed in small steps, by the reference."""
    plan = Planner(paper_roadmap).plan(
        (RHO1, 12, 18, math.radians(122.82)), (RHO1, 10, 25, math.radians(-24.24)))
    assert plan.validation.ok
    track = reference_track(plan.joints, plan.poses[0])
    assert np.allclose(track[-1][:2], plan.poses[-1][:2], atol=1e-6)
    b = np.array([torus_platform(p) for p in track])
    for name, data in SCENES.items():
        hit = reference_blocked(b, data)
        found = path_collisions(G, scene_from_dict(data), plan.joints, plan.poses[0])
        assert (found is not None) == bool(hit.any()), name
    # A post where the platform passes half way: it is found, and first met
    # where the reference meets it.
    middle = b[len(b) // 2].mean(axis=0)
    data = {"obstacles": [{"id": "on_the_way", "disc": {"center": middle.tolist(),
                                                        "radius": 0.5}}]}
    first = np.flatnonzero(reference_blocked(b, data))[0]
    found = path_collisions(G, scene_from_dict(data), plan.joints, plan.poses[0])
    assert found is not None and found.other == "on_the_way"
    reached = np.linalg.norm(G.platform_points(_pose_at(plan, found.index)) - b[first], axis=-1)
    assert reached.max() < 0.5


def _pose_at(plan, index):
    """The pose path_collisions reports, followed again to its waypoint position."""
    from rpr3_gwr_core.mechanisms.continuation import follow_path
    k, fraction = int(index), index - int(index)
    joints = np.array(list(plan.joints[:k + 1]) + [
        plan.joints[k] + fraction * (plan.joints[min(k + 1, len(plan.joints) - 1)]
                                     - plan.joints[k])])
    pose = plan.poses[0].copy()
    poses = np.empty((len(joints), 3))
    follow_path(G, np.ascontiguousarray(joints), pose, 1e-12, np.inf, poses)
    return poses[-1]


def test_coplanar_legs_of_the_paper_examples():
    """One layer for all legs: at the first example's goal legs 1 and 3
    cross, at the second's goal legs 1 and 2 pass within 0.08."""
    one_layer = BodyModel(leg_layers=(1, 1, 1))
    empty = scene_from_dict({})
    for (rho2, rho3, degrees), legs, below in (((10, 25, -24.24), (0, 2), 0.0),
                                                ((20, 25, 96.13), (0, 1), 0.08)):
        solutions = G.direct_kinematics([RHO1, rho2, rho3])
        pose = solutions[np.argmin(np.abs(np.angle(np.exp(
            1j * (solutions[:, 2] - math.radians(degrees))))))]
        b = G.platform_points(pose)
        gap = segment_segment(A[legs[0]], b[legs[0]], A[legs[1]], b[legs[1]])
        assert gap <= below
        if below:
            assert gap > 0
        found = configuration_collision(G, empty, [RHO1, rho2, rho3], pose, one_layer)
        assert (found.body, found.other) == (f"leg{legs[0] + 1}", f"leg{legs[1] + 1}")
        assert configuration_collision(G, empty, [RHO1, rho2, rho3], pose) is None


# --- the planner in a scene, its every path followed by the reference ------------------------

EXAMPLE_1 = ((RHO1, 12, 18, math.radians(122.82)), (RHO1, 10, 25, math.radians(-24.24)))


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


def _assert_clear(plan, data):
    """The plan, followed in small steps by the reference, ends on its goal
    pose and keeps every body off the scene's obstacles."""
    track = reference_track(plan.joints, plan.poses[0])
    assert np.allclose(track[-1][:2], plan.poses[-1][:2], atol=1e-6)
    assert abs(np.angle(np.exp(1j * (track[-1][2] - plan.poses[-1][2])))) < 1e-6
    b = np.array([torus_platform(p) for p in track])
    assert not reference_blocked(b, data).any()


@pytest.mark.parametrize("name", ["free", "narrowing"])
def test_plans_in_a_scene_keep_off_its_obstacles(planner, name):
    plan = planner.plan(*EXAMPLE_1, world=planner.apply_scene(scene_from_dict(SCENES[name])))
    assert plan.validation.ok
    _assert_clear(plan, SCENES[name])


def test_a_post_on_the_way_is_gone_round(planner):
    """A post where the scene-free plan passes half way: the plan in the
    scene goes round it, and the reference agrees."""
    free = planner.plan(*EXAMPLE_1)
    track = reference_track(free.joints, free.poses[0])
    middle = np.array([torus_platform(p) for p in track])[len(track) // 2].mean(axis=0)
    data = {"obstacles": [{"id": "on_the_way", "disc": {"center": middle.tolist(),
                                                        "radius": 0.5}}]}
    assert reference_blocked(np.array([torus_platform(p) for p in track]), data).any()
    plan = planner.plan(*EXAMPLE_1, world=planner.apply_scene(scene_from_dict(data)))
    _assert_clear(plan, data)


def test_a_scene_that_cuts_the_roadmap_answers_blocked(planner):
    with pytest.raises(InfeasiblePathError) as caught:
        planner.plan(*EXAMPLE_1, world=planner.apply_scene(scene_from_dict(SCENES["blocking"])))
    assert caught.value.reason == "blocked"


# Limits that the scene-free plan of the first example breaks on its way and
# that its start and goal keep.  Strokes below the ~32.7 that rho2 and rho3
# reach cut its every way; the passive ranges leave another.
LIMITS = {
    "rho2_stroke": {"strokes": {"rho2": [5.0, 29.93]}},
    "rho3_stroke": {"strokes": {"rho3": [5.0, 29.93]}},
    "base3_range": {"passive": {"base3": [-2.0, 0.9]}},
    "platform3_range": {"passive": {"platform3": [0.0, 2.3]}},
}


def reference_limits_broken(b, alpha, limits):
    """Whether the legs' lengths |B_i - A_i| leave their strokes, or the
    legs' directions (``base``) or those relative to the platform
    (``platform``) leave their counter-clockwise arcs."""
    rho = np.linalg.norm(b - A, axis=-1)
    theta = np.arctan2(b[..., 1] - A[:, 1], b[..., 0] - A[:, 0])
    broken = np.zeros(b.shape[:-2], dtype=bool)
    for name, (low, high) in limits.get("strokes", {}).items():
        leg = rho[..., int(name[-1]) - 1]
        broken |= (leg < low) | (leg > high)
    for name, (low, high) in limits.get("passive", {}).items():
        angle = theta[..., int(name[-1]) - 1]
        if name.startswith("platform"):
            angle = angle - alpha
        broken |= np.mod(angle - low, 2 * np.pi) > np.mod(high - low, 2 * np.pi)
    return broken


@pytest.mark.parametrize("name", sorted(LIMITS))
def test_limits_along_plans_agree_with_the_reference(name, planner, torus):
    """Feasibility under a limit is torus connectivity (margins of at least
    3e-3, as the planner keeps), and a returned plan, followed in small
    steps, keeps the limit all along, where the scene-free plan breaks it."""
    theta1, alpha, b, rho, pose, inside, sign = torus
    limits = LIMITS[name]
    margin = np.abs(G.margin(pose.reshape(-1, 3), rho.reshape(-1, 3))).reshape(sign.shape)
    free = inside & (margin >= 3e-3) & ~reference_limits_broken(b, alpha, limits)
    label = torus_components(free, sign)
    ends = [torus_sample_of(PAPER_EXAMPLES[k], torus) for k in (0, 1)]
    assert all(free[e] for e in ends)
    scene_free = planner.plan(*EXAMPLE_1)
    track = reference_track(scene_free.joints, scene_free.poses[0])
    assert reference_limits_broken(np.array([torus_platform(p) for p in track]),
                                   track[:, 2], limits).any()
    world = planner.apply_scene(scene_from_dict({"limits": limits}))
    if label[ends[0]] != label[ends[1]]:
        with pytest.raises(InfeasiblePathError) as caught:
            planner.plan(*EXAMPLE_1, world=world)
        assert caught.value.reason == "blocked"
        return
    plan = planner.plan(*EXAMPLE_1, world=world)
    track = reference_track(plan.joints, plan.poses[0])
    assert abs(np.angle(np.exp(1j * (track[-1][2] - plan.poses[-1][2])))) < 1e-6
    assert not reference_limits_broken(np.array([torus_platform(p) for p in track]),
                                       track[:, 2], limits).any()


@pytest.mark.slow
def test_a_way_narrower_than_a_cell_is_found_on_a_finer_grid(planner, torus):
    """The torus joins the first example within this range of platform
    joint 2 only by a thin band along a fold, under a cell wide on the
    paper's grid: there the answer is ``blocked``, saying so; on a grid of
    half the step the plan exists, and the reference follows it within the
    range."""
    theta1, alpha, b, rho, pose, inside, sign = torus
    limits = {"passive": {"platform2": [-0.5, 2.1]}}
    margin = np.abs(G.margin(pose.reshape(-1, 3), rho.reshape(-1, 3))).reshape(sign.shape)
    label = torus_components(
        inside & (margin >= 3e-3) & ~reference_limits_broken(b, alpha, limits), sign)
    ends = [torus_sample_of(PAPER_EXAMPLES[k], torus) for k in (0, 1)]
    assert label[ends[0]] == label[ends[1]]
    with pytest.raises(InfeasiblePathError, match="narrower than one of its cells"):
        planner.plan(*EXAMPLE_1, world=planner.apply_scene(scene_from_dict({"limits": limits})))
    finer = Planner(build_roadmap(G, rho1_slice(step=0.0625)))
    plan = finer.plan(*EXAMPLE_1, world=finer.apply_scene(scene_from_dict({"limits": limits})))
    track = reference_track(plan.joints, plan.poses[0])
    assert not reference_limits_broken(np.array([torus_platform(p) for p in track]),
                                       track[:, 2], limits).any()


def test_a_start_in_collision_is_refused_with_its_body(planner):
    start = EXAMPLE_1[0]
    pose = locate(planner.roadmap, start).pose
    on_leg_2 = (0.5 * (A[1] + torus_platform(pose)[1])).tolist()
    data = {"obstacles": [{"id": "on_leg_2", "disc": {"center": on_leg_2, "radius": 0.2}}]}
    with pytest.raises(CollisionError, match="leg2.*on_leg_2|on_leg_2.*leg2"):
        planner.plan(start, EXAMPLE_1[1], world=planner.apply_scene(scene_from_dict(data)))


def test_a_wall_thinner_than_a_cells_sweep_gets_no_path_through_it(planner, torus):
    """A small disc on leg 1's circle, which every way of the first example
    sweeps, blocks it on the torus; on the grid it lies between two
    neighbouring cells' samples, so the parts on either side stay joined,
    but every path is checked continuously: no plan goes through it."""
    theta1, alpha, b, rho, pose, inside, sign = torus
    at = math.radians(120.0)
    data = {"obstacles": [{"id": "thin", "disc": {"center": [16.5 * math.cos(at),
                                                              16.5 * math.sin(at)],
                                                   "radius": 0.5}}]}
    label = torus_components(inside & ~reference_blocked(b, data) & (sign != 0), sign)
    ends = [torus_sample_of(PAPER_EXAMPLES[k], torus) for k in (0, 1)]
    assert label[ends[0]] != label[ends[1]]
    with pytest.raises((ValidationError, InfeasiblePathError)):
        planner.plan(*EXAMPLE_1, world=planner.apply_scene(scene_from_dict(data)))
