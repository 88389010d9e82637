"""``plan --joint-limit NAME=V,A``: each named joint keeps its own limits
between the points (degrees for an angle), the others those of
``--max-velocity`` and ``--max-acceleration``; what does not fit is refused
with code 2 and one line."""

import json
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.io.cli import main

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
PAPER = ["plan", "--rho1", "17", "--start", "12", "18", "122.82", "--goal", "10", "25",
         "-24.24", "--max-velocity", "2", "--max-acceleration", "4"]


def _limits_hold(answer, velocity, acceleration):
    """In the answer's units (degrees for an angle)."""
    waypoints = np.array([w["joints"] for w in answer["waypoints"]])
    interval = np.diff(answer["times"])[:, None]
    assert np.all(np.abs(np.diff(waypoints, axis=0)) / interval <= np.array(velocity) * 1.000001)
    assert np.all(np.abs(np.diff(answer["velocities"], axis=0)) / interval
                  <= np.array(acceleration) * 1.000001)


def test_a_joint_limit_holds_for_its_joint_and_the_others_keep_theirs(capsys):
    assert main([*PAPER, "--joint-limit", "rho3=0.25,0", "--joint-limit", "rho2=0,0.5"]) == 0
    limited = json.loads(capsys.readouterr().out)
    _limits_hold(limited, (2.0, 2.0, 0.25), (4.0, 0.5, 4.0))
    assert main(PAPER) == 0
    free = json.loads(capsys.readouterr().out)
    assert limited["times"][-1] > free["times"][-1]


def test_an_angular_joint_limit_is_in_degrees(capsys):
    argv = ["plan", "--mechanism", str(CONFIG / "five_bar.yaml"), "--start-pose", "0.0",
            "0.1", "--goal-pose", "0.03", "0.12", "--max-velocity", "90",
            "--max-acceleration", "180"]
    assert main([*argv, "--joint-limit", "th2=2,0"]) == 0
    limited = json.loads(capsys.readouterr().out)
    assert limited["columns"]["joints"] == ["th1_deg", "th2_deg"]
    _limits_hold(limited, (90.0, 2.0), (180.0, 180.0))
    th2 = [w["joints"][1] for w in limited["waypoints"]]
    # th2 turns this far at 2 deg/s at most.
    assert limited["times"][-1] >= abs(th2[-1] - th2[0]) / 2.0
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["times"][-1] < limited["times"][-1]


@pytest.mark.parametrize("extra, says", [
    (["--joint-limit", "rho3=0.25,0"], "give --max-velocity and --max-acceleration"),
    (["--max-velocity", "2", "--max-acceleration", "4", "--joint-limit", "th1=1,1"],
     "not a joint of the 3-RPR"),
    (["--max-velocity", "2", "--max-acceleration", "4", "--joint-limit", "rho2=1,1",
      "--joint-limit", "rho2=2,2"], "named twice"),
    (["--max-velocity", "2", "--max-acceleration", "4", "--joint-limit", "rho2=1"],
     "NAME=V,A"),
    (["--max-velocity", "2", "--max-acceleration", "4", "--joint-limit", "rho2=-1,1"],
     "positive"),
    (["--max-velocity", "2", "--max-acceleration", "4", "--joint-limit", "rho2=nan,1"],
     "finite"),
])
def test_a_joint_limit_that_does_not_fit_is_refused_in_one_line(extra, says, capsys):
    argv = ["plan", "--rho1", "17", "--start", "12", "18", "122.82", "--goal", "10", "25",
            "-24.24", *extra]
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    error = capsys.readouterr().err.strip()
    assert "\n" not in error and says in error, error
