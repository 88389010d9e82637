"""``ik`` and ``plan --start-pose/--goal-pose`` on the command line: the
working modes' joints (degrees for angles) place the pose through the legs
written in the test, the box is the file's, a pose-goal plan's waypoints are
reproduced by those legs and end on the goal pose, and what does not fit is
refused with code 2 and one line."""

import json
import math
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.io.cli import main

from test_inverse_kinematics import POSES, branch_signs, leg_lengths

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
FILES = {"3-RPR": "paper_3rpr.yaml", "3-RRR": "three_rrr.yaml", "3-PRR": "three_prr.yaml",
         "5R": "five_bar.yaml"}
JOINTS = {"3-RPR": ("rho1", "rho2", "rho3"), "3-RRR": ("th1_deg", "th2_deg", "th3_deg"),
          "3-PRR": ("s1", "s2", "s3"), "5R": ("th1_deg", "th2_deg")}
# The files' boxes of the joints that are not angles (angles turn freely).
BOXES = {"3-RPR": (0.0, 50.0), "3-PRR": (0.0, 30.0)}
# The paper's first and second examples as poses: B1 and alpha [deg] of the
# legs (17, 12, 18) and (17, 10, 25), on the slice rho1 = 17.
PAPER_START_POSE = ["14.2844098014", "-9.21713820156", "122.818069928"]
PAPER_GOAL_POSE = ["0.329281929849", "16.9968106835", "-24.2435688728"]


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


def _shown_pose(kind):
    """The test pose as the command line takes it: alpha in degrees."""
    pose = POSES[kind]
    return [str(v) for v in pose[:2]] + ([str(math.degrees(pose[2]))] if len(pose) == 3 else [])


@pytest.mark.parametrize("kind", sorted(FILES))
def test_ik_gives_every_working_mode_whose_joints_place_the_pose(kind, capsys):
    code, modes = _run(["ik", "--mechanism", str(CONFIG / FILES[kind]), *_shown_pose(kind)],
                       capsys)
    assert code == 0
    assert len(modes) == {"3-RPR": 1, "3-RRR": 8, "3-PRR": 8, "5R": 4}[kind]
    for mode in modes:
        shown = np.array([mode[name] for name in JOINTS[kind]])
        joints = np.radians(shown) if JOINTS[kind][0].endswith("_deg") else shown
        lengths, wanted = leg_lengths(kind, POSES[kind], joints)
        assert np.allclose(lengths, wanted, rtol=0, atol=1e-9 * np.max(wanted))
        if kind != "3-RPR":
            signs = branch_signs(kind, POSES[kind], joints)
            assert mode["working_mode"] == "".join("+" if s > 0 else "-" for s in signs)
        low, high = BOXES.get(kind, (-math.inf, math.inf))
        assert mode["in_box"] == bool(np.all((joints >= low) & (joints <= high)))
        assert mode["aspect"] == np.sign(mode["signed_margin"]) != 0


def test_ik_without_a_file_is_the_paper_file_ik(capsys):
    pose = _shown_pose("3-RPR")
    assert _run(["ik", *pose], capsys)[1][0]["rho1"] == pytest.approx(
        _run(["ik", "--mechanism", str(CONFIG / FILES["3-RPR"]), *pose], capsys)[1][0]["rho1"])


def test_ik_of_a_pose_out_of_reach_is_empty(capsys):
    assert _run(["ik", "--mechanism", str(CONFIG / FILES["5R"]), "0.5", "0.5"], capsys) == (0, [])


def test_a_plan_between_two_poses_is_reproduced_by_the_legs(tmp_path, capsys):
    code, plan = _run(["plan", "--start-pose", *PAPER_START_POSE, "--goal-pose",
                       *PAPER_GOAL_POSE, "--cache-dir", str(tmp_path)], capsys)
    assert code == 0 and plan["feasible"]
    assert plan["request"]["goal"] == dict(zip(("x", "y", "alpha_deg"),
                                               map(float, PAPER_GOAL_POSE)))
    assert plan["start"]["working_mode"] == plan["goal"]["working_mode"] == "+++"
    for waypoint in plan["waypoints"]:
        pose = np.array(waypoint["pose"])
        pose[2] = math.radians(pose[2])
        lengths, wanted = leg_lengths("3-RPR", pose, waypoint["joints"])
        assert np.allclose(lengths, wanted, rtol=0, atol=1e-7)
    goal = np.array(PAPER_GOAL_POSE, dtype=float)
    end = np.array(plan["waypoints"][-1]["pose"])
    assert np.allclose(end[:2], goal[:2], rtol=0, atol=1e-6)
    assert abs(math.remainder(end[2] - goal[2], 360.0)) < 1e-6
    lengths, wanted = leg_lengths("3-RPR", (*goal[:2], math.radians(goal[2])),
                                  plan["waypoints"][-1]["joints"])
    assert np.allclose(lengths, wanted, rtol=0, atol=1e-9)


def test_a_five_bar_plan_to_an_end_point_ends_there(tmp_path, capsys):
    # The file's home (0, 0) with its y, and an end point both elbows reach.
    path = str(CONFIG / FILES["5R"])
    code, plan = _run(["plan", "--mechanism", path, "--start", "0", "0", "0.10219099764656375",
                       "--goal-pose", "0.08", "0.13", "--cache-dir", str(tmp_path)], capsys)
    assert code == 0, plan.get("error")
    for waypoint in plan["waypoints"]:
        lengths, wanted = leg_lengths("5R", waypoint["pose"], np.radians(waypoint["joints"]))
        assert np.allclose(lengths, wanted, rtol=0, atol=1e-9)
    assert np.allclose(plan["waypoints"][-1]["pose"], [0.08, 0.13], rtol=0, atol=1e-8)
    assert len(plan["goal"]["working_mode"]) == 2


def test_an_unreachable_working_mode_answers_an_error_object(tmp_path, capsys):
    # The goal moved off the slice rho1 = 17: its one working mode is out.
    goal = ["1", *PAPER_GOAL_POSE[1:]]
    code, plan = _run(["plan", "--start-pose", *PAPER_START_POSE, "--goal-pose", *goal,
                       "--cache-dir", str(tmp_path)], capsys)
    assert code == 1 and plan["error"]["code"] == "INFEASIBLE"
    assert "+++ (off the slice" in plan["error"]["message"]


@pytest.mark.parametrize("argv, reason", [
    (["ik", "1", "2"], "ik takes the 3-RPR's pose X Y ALPHA_DEG"),
    (["ik", "--mechanism", str(CONFIG / FILES["5R"]), "1", "2", "3"],
     "ik takes the 5R's pose X Y"),
    (["ik", "1", "nan", "2"], "not a finite number"),
    (["plan", "--start", "12", "18", "0", "--start-pose", "1", "2", "3", "--goal", "10", "25",
      "0"], "not allowed with argument"),
    (["plan", "--goal", "10", "25", "0"], "one of the arguments --start --start-pose"),
    (["plan", "--start", "12", "18", "0", "--goal", "10", "25", "0",
      "--goal-working-mode", "+++"], "--goal-working-mode needs --goal-pose"),
    (["plan", "--start", "12", "18", "0", "--goal-pose", "1", "2", "3",
      "--goal-working-mode=+-+"], "--goal-working-mode is one of +++"),
    (["plan", "--start-pose", "1", "2", "--goal", "10", "25", "0"],
     "--start-pose takes the 3-RPR's pose X Y ALPHA_DEG"),
])
def test_what_does_not_fit_exits_with_code_2_and_one_line(argv, reason, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and reason in err
