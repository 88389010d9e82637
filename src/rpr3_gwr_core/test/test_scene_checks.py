"""A scene's checks, whatever it holds: the polygons' crossing rule against
its pairwise definition and its speed, the bounds of a scene, its ids and
its numbers, and scene files of any content."""

import math
import time

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from rpr3_gwr_core.documents import MAX_DOCUMENT_BYTES
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.scene_file import load_scene
from rpr3_gwr_core.world import scene_from_dict
from rpr3_gwr_core.world.scene import MAX_MAGNITUDE, MAX_OBSTACLES, MAX_VERTICES, _crossing


def _side(a, b, c):
    return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _pairwise_crossings(vertices):
    """The pairs of edges ``(i, j)``, ``i < j``, not neighbours, each of whose
    ends are not strictly on one side of the other's line: the rule as the
    scene first checked it, every pair in turn."""
    n = len(vertices)
    pairs = set()
    for i in range(n):
        for j in range(i + 2, n - (i == 0)):
            p, q, r, s = vertices[i], vertices[(i + 1) % n], vertices[j], vertices[(j + 1) % n]
            if _side(p, q, r) * _side(p, q, s) <= 0 and _side(r, s, p) * _side(r, s, q) <= 0:
                pairs.add((i, j))
    return pairs


# Coordinates in quarters of a unit: their orientations are exact, so that
# touching, collinear and repeated vertices are frequent and unambiguous.
_QUARTERS = st.integers(-12, 12).map(lambda k: k / 4)


@st.composite
def _polygons(draw):
    """Random polygons, and star-shaped ones (mostly simple) with a vertex
    or two moved onto another or anywhere."""
    n = draw(st.integers(4, 24))
    if draw(st.booleans()):
        return draw(st.lists(st.tuples(_QUARTERS, _QUARTERS), min_size=n, max_size=n))
    turns = sorted(draw(st.lists(st.integers(0, 47), min_size=n, max_size=n, unique=True)))
    radii = draw(st.lists(st.integers(4, 12), min_size=n, max_size=n))
    vertices = [(round(r * math.cos(t * math.pi / 24)) / 4, round(r * math.sin(t * math.pi / 24))
                 / 4) for t, r in zip(turns, radii)]
    for k, target in draw(st.lists(st.tuples(st.integers(0, n - 1), st.one_of(
            st.integers(0, n - 1), st.tuples(_QUARTERS, _QUARTERS))), max_size=2)):
        vertices[k] = vertices[target] if isinstance(target, int) else target
    return vertices


@settings(max_examples=600, deadline=None, database=None)
@given(vertices=_polygons())
@example(vertices=[(0, 0), (3, 0), (3, 2), (2, 2), (2, 1), (1, 1), (1, 2), (0, 2)])  # apart
@example(vertices=[(0, 0), (2, 0), (1, 0), (1, 1)])  # a spike back along its edge
@example(vertices=[(0, 0), (2, 0), (2, 2), (1, 0), (0, 2)])  # a vertex on an edge
@example(vertices=[(0, 0), (2, 0), (2, 2), (2, 2), (0, 2)])  # an edge of no length
@example(vertices=[(0, 0), (4, 0), (4, 4), (2, 0), (0, 4)])  # two vertices at one point
def test_the_crossing_check_finds_a_crossing_pair_exactly_when_there_is_one(vertices):
    pairs = _pairwise_crossings(vertices)
    found = _crossing(np.array(vertices, dtype=float))
    assert (found is None) == (not pairs), (pairs, found)
    assert found is None or found in pairs


def test_a_refused_polygon_names_two_edges_that_cross():
    bow = [[0, 0], [2, 2], [2, 0], [0, 1]]
    with pytest.raises(InvalidInputError, match="crossing edges 0 and 2"):
        scene_from_dict({"obstacles": [{"id": "bow", "polygon": bow}]})


def _ten_thousand(shape):
    n = 10_000
    turn = np.linspace(0, 2 * math.pi, n, endpoint=False)
    if shape == "regular":
        return np.c_[10 * np.cos(turn), 10 * np.sin(turn)]
    if shape == "random star":
        rng = np.random.default_rng(0)
        turn, radius = np.sort(rng.uniform(0, 2 * math.pi, n)), rng.uniform(1, 100, n)
        return np.c_[radius * np.cos(turn), radius * np.sin(turn)]
    # Long edges back and forth, all cut by one vertical line.
    k = np.arange(n - 2)
    return np.vstack([np.c_[np.where(k % 2, 100.0, 0.0), k], [[-10, n - 3], [-10, 0]]])


@pytest.mark.parametrize("shape", ["regular", "random star", "zigzag"])
def test_a_polygon_of_ten_thousand_vertices_is_checked_in_well_under_a_tenth_of_a_second(
        shape):
    vertices = _ten_thousand(shape)
    _crossing(vertices[:4])  # compiled (or loaded) before the clock starts
    elapsed = []
    for _ in range(3):
        start = time.perf_counter()
        assert _crossing(vertices) is None
        elapsed.append(time.perf_counter() - start)
    assert min(elapsed) < 0.1


def _discs(count):
    return [{"id": f"d{k}", "disc": {"center": [k, 0], "radius": 0.25}} for k in range(count)]


def _ring(oid, x, vertices):
    turn = np.linspace(0, 2 * math.pi, vertices, endpoint=False)
    return {"id": oid, "polygon": np.c_[x + np.cos(turn), np.sin(turn)].tolist()}


def test_a_scene_holds_at_most_its_bounds():
    scene = scene_from_dict({"obstacles": _discs(MAX_OBSTACLES - 1)
                             + [_ring("big", -10, MAX_VERTICES)]})
    assert len(scene.discs) + len(scene.polygons) == MAX_OBSTACLES
    assert sum(len(p.vertices) for p in scene.polygons) == MAX_VERTICES
    with pytest.raises(InvalidInputError,
                       match=f"{MAX_OBSTACLES + 1:,} obstacles, more than the limit of "
                             f"{MAX_OBSTACLES:,}"):
        scene_from_dict({"obstacles": _discs(MAX_OBSTACLES + 1)})
    with pytest.raises(InvalidInputError, match=f"more than the limit of {MAX_VERTICES:,}"):
        scene_from_dict({"obstacles": [_ring("a", 0, MAX_VERTICES // 2),
                                       _ring("b", 5, MAX_VERTICES // 2), _ring("c", 9, 3)]})


def test_the_vertices_are_counted_before_they_are_read():
    # A million vertices, not one of them a number: refused for their count.
    polygon = ["x"] * 1_000_000
    start = time.perf_counter()
    with pytest.raises(InvalidInputError, match=f"limit of {MAX_VERTICES:,}"):
        scene_from_dict({"obstacles": [{"id": "huge", "polygon": polygon}]})
    assert time.perf_counter() - start < 0.1


@pytest.mark.parametrize("obstacle, words", [
    ({"id": "post", "disc": {"center": [1.0e200, 0], "radius": 1}}, "out of range"),
    ({"id": "post", "disc": {"center": [10 ** 400, 0], "radius": 1}}, "out of range"),
    ({"id": "post", "disc": {"center": [0, 0], "radius": 2 * MAX_MAGNITUDE}}, "out of range"),
    ({"id": "plate", "polygon": [[0, 0], [1e200, 0], [0, 1e200]]}, "out of range"),
    ({"id": "plate", "polygon": [[0, 0], [-10 ** 400, 0], [0, 1]]}, "out of range"),
    ({"id": "post", "disc": {"center": [0, math.inf], "radius": 1}}, "finite number"),
    ({"id": "", "disc": {"center": [0, 0], "radius": 1}}, "empty id"),
    ({"id": 10 ** 5000, "disc": {"center": [0, 0], "radius": 1}}, "too many digits"),
])
def test_numbers_out_of_range_and_empty_ids_are_refused(obstacle, words):
    with pytest.raises(InvalidInputError, match=words):
        scene_from_dict({"obstacles": [obstacle]})


def test_limits_out_of_range_are_refused():
    for limits in ({"obstacle_clearance": 10 ** 400}, {"strokes": {"rho1": [0, 1e300]}},
                   {"passive_deg": {"base1": [-1e200, 0]}}):
        with pytest.raises(InvalidInputError, match="out of range"):
            scene_from_dict({"limits": limits})


def test_a_magnitude_at_the_bound_is_a_scene():
    scene = scene_from_dict({"obstacles": [
        {"id": 7, "polygon": [[-MAX_MAGNITUDE, -MAX_MAGNITUDE], [MAX_MAGNITUDE, -MAX_MAGNITUDE],
                              [0, MAX_MAGNITUDE]]}]})
    assert scene.obstacle_ids == ("7",)


# Ten lines that would be 9 ** 10 items written out.
ALIAS_BOMB = "\n".join(["b0: &b0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"] + [
    f"b{k}: &b{k} [{', '.join([f'*b{k - 1}'] * 9)}]" for k in range(1, 10)]).encode()

_HOSTILE_FILES = {
    "random bytes": bytes(range(256)) * 4,
    "utf-16": "obstacles: []\n".encode("utf-16"),
    "latin-1": "obstacles: [{id: caf\xe9, disc: {center: [0, 0], radius: 1}}]\n".encode(
        "latin-1"),
    "nested": b"[" * 50_000 + b"]" * 50_000,
    "nested blocks": b"- " * 50_000 + b"x\n",
    "400 digits": b"obstacles: [{id: a, disc: {center: [" + b"9" * 400 + b", 0], radius: 1}}]",
    "5000 digits": b"obstacles: [{id: a, disc: {center: [" + b"9" * 5000 + b", 0], radius: 1}}]",
    "huge coordinates": b"obstacles: [{id: a, polygon: [[0, 0], [1.0e+200, 0], [0, 1.0e+200]]}]",
    "no month 13": b"obstacles: [{id: 2001-13-01, disc: {center: [0, 0], radius: 1}}]",
    "tab": b"obstacles:\n\t- 1\n",
    "itself": b"obstacles: &o [*o]\n",
    "aliases": b"bomb:\n  " + ALIAS_BOMB.replace(b"\n", b"\n  ")
    + b"\nobstacles: [{id: a, polygon: *b9}]\n",
    "too large": b"# " + b"x" * MAX_DOCUMENT_BYTES + b"\n",
}


@pytest.mark.parametrize("name", sorted(_HOSTILE_FILES))
def test_a_scene_file_of_any_content_fails_with_one_line(name, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_bytes(_HOSTILE_FILES[name])
    with pytest.raises(InvalidInputError) as error:
        load_scene(path)
    assert "\n" not in str(error.value) and len(str(error.value)) < 300


def test_a_list_repeated_by_an_alias_is_refused(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_bytes(b"obstacles: &o [*o]\n")
    with pytest.raises(InvalidInputError, match="repeats a list or mapping by an alias"):
        load_scene(path)


def test_a_file_over_the_size_bound_is_refused_without_being_read(tmp_path):
    path = tmp_path / "scene.yaml"
    with open(path, "wb") as stream:
        stream.truncate(1 << 30)  # a sparse gibibyte
    start = time.perf_counter()
    with pytest.raises(InvalidInputError, match=f"limit of {MAX_DOCUMENT_BYTES:,} bytes"):
        load_scene(path)
    assert time.perf_counter() - start < 0.5


def test_a_scene_file_reads_numbers_with_an_exponent_as_numbers(tmp_path):
    path = tmp_path / "scene.yaml"
    # YAML 1.1 (PyYAML) reads 2e-1 and 1.5e1 as strings; they are numbers.
    path.write_text("\ufeffobstacles: [{id: post, disc: {center: [1.5e1, 3E0], radius: 2e-1}}]\n"
                    "limits: {obstacle_clearance: 1e-2}\n", encoding="utf-8")
    scene = load_scene(path)
    assert scene.discs[0].radius == 0.2 and scene.discs[0].center.tolist() == [15.0, 3.0]
    assert scene.limits.obstacle_clearance == 0.01
    path.write_text("obstacles: [{id: post, disc: {center: [1e300, 0], radius: 1}}]\n")
    with pytest.raises(InvalidInputError, match="out of range: 1e[+]300"):
        load_scene(path)


def test_a_scene_file_with_an_empty_id_is_refused(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text("obstacles: [{id: '', disc: {center: [0, 0], radius: 1}}]\n")
    with pytest.raises(InvalidInputError, match="obstacle 0 has an empty id"):
        load_scene(path)


@pytest.mark.parametrize("content", [None, b"\xff\xfe", b"obstacles: [{id: a, type: disc}]\n"])
def test_a_scene_files_error_names_the_file_once(content, tmp_path):
    path = tmp_path / "scene.yaml"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(InvalidInputError) as error:
        load_scene(path)
    assert str(error.value).count(str(path)) == 1, str(error.value)
