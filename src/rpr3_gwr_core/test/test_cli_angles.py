"""One angle unit on the command line: every command takes and prints angles
in degrees (keys ending in ``_deg``, joint and pose lists named by the
answer's ``columns``), as the mechanism marks its angles; the core stays in
radians."""

import json
import math
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY
from rpr3_gwr_core.io.cli import _parser, main
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
FIVE_BAR, THREE_RRR = str(CONFIG / "five_bar.yaml"), str(CONFIG / "three_rrr.yaml")
FIVE_BAR_TEXT = (CONFIG / "five_bar.yaml").read_text()
PAPER_COLUMNS = {"joints": ["rho1", "rho2", "rho3"], "pose": ["x", "y", "alpha_deg"]}


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return ["--cache-dir", str(tmp_path_factory.mktemp("cache"))]


def test_dk_of_the_papers_example_in_degrees_is_plans_input(cache, capsys, tmp_path):
    # The paper's first example: legs (17, 12, 18), alpha = 122.82 deg.
    code, solutions = _run(["dk", "17", "12", "18"], capsys)
    assert code == 0
    alpha = min((s["alpha_deg"] for s in solutions), key=lambda a: abs(a - 122.82))
    assert alpha == pytest.approx(122.82, abs=0.01)
    assert all(set(s) == {"x", "y", "alpha_deg", "aspect", "signed_margin"} for s in solutions)
    assert all(np.sign(s["signed_margin"]) == s["aspect"] for s in solutions)
    output = tmp_path / "plan.json"
    code, plan = _run(["plan", "--start", "12", "18", str(alpha), "--goal", "10", "25",
                       "-24.24", "-o", str(output), *cache], capsys)
    assert code == 0 and plan["feasible"]
    assert plan["columns"] == PAPER_COLUMNS
    assert plan["request"]["start"] == {"rho1": 17.0, "rho2": 12.0, "rho3": 18.0,
                                        "alpha_deg": alpha}
    assert plan["start"]["pose"][2] == pytest.approx(alpha, abs=1e-6)
    assert plan["goal"]["pose"][2] == pytest.approx(-24.24, abs=0.01)
    assert "signed_margin" in plan["start"] and "margin" not in plan["start"]
    assert "min_abs_margin" in plan["validation"]
    # Every waypoint's orientation is in degrees: the path leaves from the
    # start's and its steps, modulo a turn, stay small.
    alphas = np.array([w["pose"][2] for w in plan["waypoints"]])
    assert alphas[0] == pytest.approx(alpha, abs=1e-6)
    assert np.max(np.abs((np.diff(alphas) + 180) % 360 - 180)) < 90
    # plot reads the file back in degrees.
    code, drawn = _run(["plot", str(output), *cache], capsys)
    assert code == 0 and pathlib.Path(drawn["figure"]).stat().st_size > 10_000


def test_plot_refuses_a_plan_without_the_columns_of_its_mechanism(cache, capsys, tmp_path):
    output = tmp_path / "plan.json"
    assert main(["plan", "--start", "12", "18", "122.82", "--goal", "10", "25", "-24.24",
                 "-o", str(output), *cache]) == 0
    capsys.readouterr()
    plan = json.loads(output.read_text())
    del plan["columns"]
    output.write_text(json.dumps(plan))
    with pytest.raises(SystemExit) as exit_info:
        main(["plot", str(output), *cache])
    assert exit_info.value.code == 2 and "columns" in capsys.readouterr().err


def test_cusps_print_their_orientation_in_degrees(cache, capsys):
    code, cusps = _run(["cusps", *cache], capsys)
    assert code == 0 and len(cusps) == 6
    assert all(set(c) == {"rho1", "rho2", "rho3", "x", "y", "alpha_deg", "regions"}
               for c in cusps)
    for c in cusps:
        pose = np.array([c["x"], c["y"], math.radians(c["alpha_deg"])])
        assert abs(PAPER_GEOMETRY.margin(pose)) < 1e-6
    code, summary = _run(["roadmap", "--step", "0.25"], capsys)
    assert code == 0 and summary["cusps"]
    assert all("alpha_deg" in c and "alpha" not in c for c in summary["cusps"])


def test_a_files_angular_joints_are_degrees_in_and_out(cache, capsys):
    code, summary = _run(["roadmap", "--mechanism", THREE_RRR, "--fix", "th1=90", *cache],
                         capsys)
    assert code == 0
    # The grid document keeps the core's radians (this slice has thin
    # regions: its grid is the file's, refined around them).
    grid = summary["grid"]
    assert grid["kind"] == "adaptive"
    assert grid["base"]["fixed"] == [{"joint": 0, "value": pytest.approx(math.pi / 2)}]
    mechanism = load_mechanism_file(FIVE_BAR).mechanism
    th = [math.degrees(v) for v in (3.1, 2.5)]
    code, solutions = _run(["dk", "--mechanism", FIVE_BAR, *map(str, th)], capsys)
    y = max(s["y"] for s in solutions)
    code, plan = _run(["plan", "--mechanism", FIVE_BAR, "--start", *map(str, th), str(y),
                       "--goal", str(th[0] - 20), str(th[1]), str(y), "--mode-tol", "0.05",
                       "--max-velocity", "30", "--max-acceleration", "60", *cache], capsys)
    assert code == 0 and plan["feasible"], plan
    assert plan["columns"] == {"joints": ["th1_deg", "th2_deg"], "pose": ["x", "y"]}
    joints = np.array([w["joints"] for w in plan["waypoints"]])
    np.testing.assert_allclose(joints[0], th, atol=1e-6)
    np.testing.assert_allclose(joints[-1], [th[0] - 20, th[1]], atol=1e-6)
    # The limits are in deg/s and deg/s^2 as the joints are: 20 deg at 30
    # deg/s take more than 2/3 s (in rad/s they would take 0.15 s).
    assert plan["times"][-1] > 20 / 30
    poses = np.array([w["pose"] for w in plan["waypoints"]])
    residual = mechanism.residual(poses, np.radians(joints))
    assert np.max(np.abs(residual)) < 1e-6


def test_the_help_of_every_command_and_angle_names_degrees():
    parser = _parser()
    commands = parser._subparsers._group_actions[0].choices
    assert "degrees" in parser.format_help()
    for name, command in commands.items():
        text = command.format_help()
        assert "Angles are in degrees [deg]" in " ".join(text.split()), name
    for name, option in [("dk", None), ("plan", "--start"), ("plan", "--mode-tol"),
                         ("plan", "--max-velocity"), ("plan", "--alpha-tol-deg"),
                         ("roadmap", "--fix"), ("cusps", "--fix")]:
        actions = commands[name]._actions
        action = next(a for a in actions if (a.option_strings or [None])[0] == option
                      or (option is None and a.dest == "joints"))
        assert "deg" in action.help, (name, option)


def test_a_fixed_angle_outside_its_range_is_refused_in_degrees(cache, capsys, tmp_path):
    # A five-bar whose first joint turns within [-1, 1] rad only.
    document = FIVE_BAR_TEXT.replace("- {name: th1, periodic: true, cells: 120}",
                                     "- {name: th1, min: -1.0, max: 1.0, step: 0.02}")
    path = tmp_path / "limited_five_bar.yaml"
    path.write_text(document)
    with pytest.raises(SystemExit) as stop:
        main(["roadmap", "--mechanism", str(path), "--fix", "th1=90", *cache])
    assert stop.value.code == 2
    error = capsys.readouterr().err
    assert "th1=90 deg lies outside its range [-57.2958, 57.2958] deg" in error
    assert main(["roadmap", "--mechanism", str(path), "--fix", "th1=45", *cache]) == 0
