"""``--scene`` on the command line: a plan among obstacles, checked by the
plain-geometry reference of the scene tests, "blocked" and "IN_COLLISION"
answers with exit code 1, the field figure's collision layer, the plot of a
plan in a scene (its base plane, with the body model the plan was made
with), and scene files that do not parse refused with code 2."""

import json
import pathlib

import numpy as np
import pytest
import yaml
from matplotlib.patches import Circle, Polygon

from rpr3_gwr_core import figures
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.world import BodyModel
from test_world_reference import reference_blocked, reference_track, torus_platform

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
SCENES = CONFIG / "scenes"
EXAMPLE_1 = ["--start", "12", "18", "122.82", "--goal", "10", "25", "-24.24"]


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


def _plotted(plan_file, cache_dir, monkeypatch, capsys):
    """Runs ``plot`` on a plan file: the arguments ``plan_figure`` was called
    with and the figure it drew."""
    calls, draw = [], figures.plan_figure

    def recorded(*args):
        calls.append((args, draw(*args)))
        return calls[-1][1]

    monkeypatch.setattr(figures, "plan_figure", recorded)
    figure_file = plan_file.with_suffix(".png")
    code, answer = _run(["plot", str(plan_file), "-o", str(figure_file), "--cache-dir",
                         cache_dir], capsys)
    assert code == 0 and answer == {"figure": str(figure_file)}
    assert figure_file.stat().st_size > 10_000
    (call,) = calls
    return call


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


def test_the_plot_of_a_plan_in_a_scene_draws_its_base_plane(cache_dir, tmp_path, monkeypatch,
                                                             capsys):
    plan_file = tmp_path / "plan.json"
    code, plan = _run(["plan", *EXAMPLE_1, "--step", "0.5", "--scene",
                       str(SCENES / "paper_narrowed.yaml"), "-o", str(plan_file),
                       "--cache-dir", cache_dir], capsys)
    assert code == 0 and "bodies" not in plan
    (_, _, world), figure = _plotted(plan_file, cache_dir, monkeypatch, capsys)
    assert world.index.model is None
    plane, _, base = figure.axes
    assert "scene blocks some solutions" in [t.get_text() for t in
                                             plane.get_legend().get_texts()]
    assert base.get_title().startswith("base plane")
    assert [base.get_xlabel(), base.get_ylabel()] == ["x [length]", "y [length]"]
    assert [(tuple(c.center), c.radius) for c in base.patches
            if isinstance(c, Circle)] == [((6.0, 28.0), 2.0)]
    plate = [-20.0, 24.0], [-12.0, 24.0], [-12.0, 30.0], [-20.0, 30.0]
    assert any(np.allclose(p.get_xy()[:4], plate) for p in base.patches
               if isinstance(p, Polygon))
    assert {"post", "plate"} <= {t.get_text() for t in base.texts}
    # The bodies at the start and at the goal, each end's legs in its colour.
    colours = [line.get_color() for line in base.get_lines()]
    assert colours.count("tab:green") >= 3 and colours.count("tab:red") >= 3
    trace = next(line for line in base.get_lines() if line.get_label() == "trace of (x, y)")
    assert np.allclose(trace.get_xydata(), [w["pose"][:2] for w in plan["waypoints"]])


def test_the_plot_of_a_plan_without_a_scene_keeps_its_two_panels(cache_dir, tmp_path,
                                                                  monkeypatch, capsys):
    plan_file = tmp_path / "plan.json"
    code, plan = _run(["plan", *EXAMPLE_1, "--step", "0.5", "-o", str(plan_file),
                       "--cache-dir", cache_dir], capsys)
    assert code == 0 and "scene" not in plan
    (_, _, world), figure = _plotted(plan_file, cache_dir, monkeypatch, capsys)
    assert world is None
    assert len(figure.axes) == 2 and tuple(figure.get_size_inches()) == (14.0, 6.5)
    assert figure.axes[0].get_title().startswith("trajectory via global path")
    assert figure.axes[1].name == "3d"
    assert not any(t.get_text().startswith("scene") for t in
                   figure.axes[0].get_legend().get_texts())


def test_a_plan_records_its_files_bodies_for_the_plot(cache_dir, tmp_path, monkeypatch,
                                                       capsys):
    # The five-bar's legs in one layer, a pin below its base and a block above.
    mechanism = tmp_path / "five_bar.yaml"
    mechanism.write_text((CONFIG / "five_bar.yaml").read_text()
                         + "bodies: {leg_width: 0.008, leg_layers: [1, 1]}\n")
    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump({"obstacles": [
        {"id": "pin", "disc": {"center": [0.06, -0.12], "radius": 0.015}},
        {"id": "block", "polygon": [[-0.15, 0.1], [-0.1, 0.1], [-0.1, 0.15], [-0.15, 0.15]]}]}))
    plan_file = tmp_path / "plan.json"
    code, plan = _run(["plan", "--mechanism", str(mechanism), "--scene", str(scene),
                       "--start", "177.6", "143.2", "0.1", "--goal", "157.6", "143.2", "0.1",
                       "--mode-tol", "0.05", "-o", str(plan_file), "--cache-dir", cache_dir],
                      capsys)
    assert code == 0 and plan["feasible"], plan
    model = BodyModel(leg_width=0.008, leg_layers=(1, 1))
    assert plan["bodies"] == model.to_dict()
    (_, _, world), figure = _plotted(plan_file, cache_dir, monkeypatch, capsys)
    assert world.index.model == model
    base = figure.axes[2]
    assert {"pin", "block"} <= {t.get_text() for t in base.texts}
    assert [line.get_color() for line in base.get_lines()].count("tab:green") == 4


def test_the_plot_names_a_plan_file_whose_scene_it_cannot_read(cache_dir, tmp_path, capsys):
    plan_file = tmp_path / "plan.json"
    code, plan = _run(["plan", *EXAMPLE_1, "--step", "0.5", "--scene",
                       str(SCENES / "paper_narrowed.yaml"), "-o", str(plan_file),
                       "--cache-dir", cache_dir], capsys)
    assert code == 0
    post = next(o for o in plan["scene"]["obstacles"] if o["id"] == "post")
    post["disc"]["radius"] = -1.0
    plan_file.write_text(json.dumps(plan))
    with pytest.raises(SystemExit) as exit_info:
        main(["plot", str(plan_file), "--cache-dir", cache_dir])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert f"the scene of {plan_file}" in err and "radius must be positive" in err


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
