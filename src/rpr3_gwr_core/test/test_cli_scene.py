"""``--scene`` on the command line: a plan among obstacles, checked by the
plain-geometry reference of the scene tests, "blocked" and "IN_COLLISION"
answers with exit code 1, the field figure's collision layer, and scene
files that do not parse refused with code 2."""

import json
import pathlib

import numpy as np
import pytest
import yaml

from rpr3_gwr_core.io.cli import main
from test_world_reference import reference_blocked, reference_track, torus_platform

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
SCENES = CONFIG / "scenes"
EXAMPLE_1 = ["--start", "12", "18", "122.82", "--goal", "10", "25", "-24.24"]


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return str(tmp_path_factory.mktemp("cache"))


def test_a_plan_in_a_scene_keeps_off_its_obstacles(cache_dir, capsys):
    path = SCENES / "paper_narrowed.yaml"
    code, plan = _run(["plan", *EXAMPLE_1, "--smooth", "--scene", str(path),
                       "--cache-dir", cache_dir], capsys)
    assert code == 0 and plan["feasible"]
    assert plan["scene"]["obstacles"]
    joints = np.array([w["joints"] for w in plan["waypoints"]])
    poses = np.array([w["pose"] for w in plan["waypoints"]])
    assert plan["columns"]["pose"] == ["x", "y", "alpha_deg"]
    poses[:, 2] = np.radians(poses[:, 2])
    track = reference_track(joints, poses[0])
    assert np.allclose(track[-1][:2], poses[-1][:2], atol=1e-6)
    scene = yaml.safe_load(path.read_text())
    assert not reference_blocked(np.array([torus_platform(p) for p in track]), scene).any()


def test_a_scene_that_cuts_the_roadmap_is_blocked(cache_dir, capsys):
    code, answer = _run(["plan", *EXAMPLE_1, "--scene",
                         str(SCENES / "paper_example1_blocked.yaml"), "--cache-dir", cache_dir],
                        capsys)
    assert code == 1 and answer["reason"] == "blocked"
    assert answer["error"]["code"] == "INFEASIBLE"


def test_a_start_in_collision_names_the_body(cache_dir, tmp_path, capsys):
    # Leg 1 of the start runs from A1 = (0, 0) to B1, 17 away: a post on it.
    code, solutions = _run(["dk", "17", "12", "18"], capsys)
    b1 = next(s for s in solutions if abs(s["alpha_deg"] - 122.82) < 1)
    middle = [b1["x"] / 2, b1["y"] / 2]
    scene = tmp_path / "post.yaml"
    scene.write_text(yaml.safe_dump(
        {"obstacles": [{"id": "post", "disc": {"center": middle, "radius": 0.3}}]}))
    code, answer = _run(["plan", *EXAMPLE_1, "--scene", str(scene), "--cache-dir", cache_dir],
                        capsys)
    assert code == 1 and answer["error"]["code"] == "IN_COLLISION"
    assert "leg1" in answer["error"]["message"] and "post" in answer["error"]["message"]


def test_the_roadmap_counts_the_parts_a_scene_leaves(cache_dir, tmp_path, capsys):
    figure = tmp_path / "field.png"
    code, summary = _run(["roadmap", "--scene", str(SCENES / "paper_narrowed.yaml"),
                          "--field-figure", str(figure), "--cache-dir", cache_dir], capsys)
    assert code == 0
    scene = summary["scene"]
    assert 0 < scene["blocked_solutions"] < scene["solutions"]
    assert scene["parts"] > len(summary["patches"])
    assert figure.stat().st_size > 10_000


@pytest.mark.parametrize("text", ["obstacles: [{id: a, disc: {center: [0, 0], radius: -1}}]",
                                  "obstacles: [{id: a, disc: {center: [0, .nan], radius: 1}}]",
                                  "limits: {strokes: {rho9: [0, 1]}}",
                                  "walls: []", "{"])
def test_scene_files_that_do_not_describe_a_scene_are_refused(text, cache_dir, tmp_path,
                                                               capsys):
    scene = tmp_path / "bad.yaml"
    scene.write_text(text)
    with pytest.raises(SystemExit) as exit_info:
        main(["plan", *EXAMPLE_1, "--scene", str(scene), "--cache-dir", cache_dir])
    assert exit_info.value.code == 2
    assert "bad.yaml" in capsys.readouterr().err
