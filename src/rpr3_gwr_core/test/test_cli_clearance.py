"""``plan --clearance``: the trade of clearance for length reaches the
planner, and each path is followed by the independent pose-space
continuation; a value outside [0, 1) is refused with code 2 and one line."""

import json
import math

import numpy as np
import pytest

from pose_reference import follow
from rpr3_gwr_core.io.cli import main

PAPER = ["plan", "--rho1", "17", "--start", "12", "18", "122.82", "--goal", "10", "25",
         "-24.24"]


def _legs_travel(capsys, *extra):
    assert main([*PAPER, *extra]) == 0
    answer = json.loads(capsys.readouterr().out)
    assert answer["validation"]["ok"]
    joints = np.array([w["joints"] for w in answer["waypoints"]])
    poses = np.array([w["pose"] for w in answer["waypoints"]])
    poses[:, 2] = np.radians(poses[:, 2])
    followed = follow(joints, poses[0], 1e-3 * (1 - 1e-3))
    assert followed["ok"], followed["why"]
    np.testing.assert_allclose(followed["pose"][:2], poses[-1, :2], rtol=0, atol=1e-6)
    assert abs(math.remainder(followed["pose"][2] - poses[-1, 2], 2 * math.pi)) < 1e-6
    return float(np.abs(np.diff(joints[:, 1:], axis=0)).sum())


def test_a_larger_clearance_keeps_farther_and_goes_longer(capsys):
    travels = [_legs_travel(capsys, "--clearance", str(c)) for c in (0.0, 0.1, 0.3)]
    assert travels[0] < travels[1] < travels[2]
    assert _legs_travel(capsys) == _legs_travel(capsys, "--clearance", "0.02")


def test_a_clearance_outside_its_range_is_refused_in_one_line(capsys):
    for value in ("1", "-0.1", "nan"):
        with pytest.raises(SystemExit) as exit_info:
            main([*PAPER, "--clearance", value])
        assert exit_info.value.code == 2
        error = capsys.readouterr().err.strip()
        assert len(error.splitlines()) == 1 and "clearance" in error, error
