"""The assembly modes of given joints on a roadmap, checked against the
independent pose-space reference: every direct-kinematic solution is listed
once with its aspect, and those said reachable from a start mode are
planned to, the plan followed by the reference's continuation."""

import json
import math
import pathlib
import shlex

import numpy as np
import pytest

from rpr3_gwr_core import assembly_modes
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.exceptions import (FixedJointMismatchError, InvalidInputError,
                                      NoSolutionError)
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.planning import Planner
from rpr3_gwr_core.workspace.roadmap import build_roadmap

from pose_reference import BASE, BETA, D1, D3, assert_executable, follow, legs_of, margin_of

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"

D = math.radians
# The paper's assembly-mode change (section 5.3): the same legs, from
# alpha = 29.47 deg to 96.13 deg.
LEGS, START, CHANGED = (17.0, 20.0, 25.0), D(29.47), D(96.13)


@pytest.fixture(scope="module")
def planner():
    return Planner(build_roadmap(PAPER_GEOMETRY, rho1_slice(rho1=17, step=0.25)))


def _reference_poses(legs, turns=72000):
    """The poses of some legs, by the reference: B1 on leg 1's circle and,
    moved back along the platform's first side, on leg 2's; a root of leg
    3's closure between two of ``turns`` platform angles."""
    alpha = np.linspace(-math.pi, math.pi, turns, endpoint=False)
    a1, a2, a3 = (np.array(p) for p in BASE)
    side1 = D1 * np.column_stack([np.cos(alpha), np.sin(alpha)])
    side3 = D3 * np.column_stack([np.cos(alpha + BETA), np.sin(alpha + BETA)])
    c2 = a2 - side1
    gap = np.linalg.norm(c2 - a1, axis=1)
    along = (c2 - a1) / gap[:, None]
    x = (gap**2 + legs[0]**2 - legs[1]**2) / (2 * gap)
    with np.errstate(invalid="ignore"):
        h = np.sqrt(legs[0]**2 - x**2)
    normal = np.column_stack([-along[:, 1], along[:, 0]])
    poses = []
    for sign in (1.0, -1.0):
        b1 = a1 + along * x[:, None] + sign * normal * h[:, None]
        closure = np.linalg.norm(b1 + side3 - a3, axis=1) - legs[2]
        for k in np.flatnonzero(closure * np.roll(closure, -1) < 0):
            poses.append((*b1[k], alpha[k]))
    return poses


def test_every_mode_of_the_joints_is_listed_once_with_its_aspect(planner):
    modes = assembly_modes(planner, LEGS)
    reference = _reference_poses(LEGS)
    assert len(modes) == len(reference) == 4
    for mode in modes:
        np.testing.assert_allclose(legs_of(mode.pose), LEGS, atol=1e-9)
        assert mode.aspect == np.sign(margin_of(mode.pose))
        assert mode.configuration == (*LEGS, mode.pose[2])
    # Each reference pose is one of them, to the reference's angular step.
    for pose in reference:
        assert min(abs(math.remainder(pose[2] - m.pose[2], 2 * math.pi)) for m in modes) < 1e-3


def test_the_modes_a_path_reaches_are_planned_to_and_the_others_are_not(planner):
    modes = assembly_modes(planner, LEGS, start_mode=START)
    start = next(m for m in modes if m.feasibility == "start")
    assert abs(start.pose[2] - START) < D(1)
    reachable = [m for m in modes if m.reachable and m is not start]
    assert any(abs(m.pose[2] - CHANGED) < D(1) for m in reachable)
    for mode in modes:
        if mode is start or mode.patch is None:
            continue
        if mode.reachable:
            plan = planner.plan(start.configuration, mode.configuration)
            assert_executable(plan, mode.pose, planner.min_margin)
        else:
            assert mode.feasibility in ("other_aspect", "unreachable")
            if mode.feasibility == "other_aspect":
                assert np.sign(margin_of(mode.pose)) != np.sign(margin_of(start.pose))


def test_each_mode_names_its_patch_and_region(planner):
    patches = planner.roadmap.segmentation.patches
    for mode in assembly_modes(planner, LEGS):
        assert mode.patch is not None, mode.unlocated
        assert (patches[mode.patch].region, patches[mode.patch].layer) == (mode.region,
                                                                             mode.layer)
        assert planner.locate(mode.configuration).patch == mode.patch


@pytest.mark.parametrize("joints, error", [
    ((17.0, 20.0), InvalidInputError),
    ((17.0, math.nan, 25.0), InvalidInputError),
    ((13.0, 20.0, 25.0), FixedJointMismatchError),
    ((17.0, 2.0, 45.0), NoSolutionError),
])
def test_joints_the_roadmap_cannot_take_are_refused(planner, joints, error):
    with pytest.raises(error):
        assembly_modes(planner, joints)


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


def test_the_command_line_lists_the_modes_and_the_command_that_plans_each_reachable_one(
        tmp_path, capsys):
    code, modes = _run(["dk", *map(str, LEGS), "--from", str(math.degrees(START)),
                        "--cache-dir", str(tmp_path)], capsys)
    assert code == 0
    assert len(modes) == len(_reference_poses(LEGS))
    assert [m["feasibility"] for m in modes].count("start") == 1
    commands = [m["plan"] for m in modes if "plan" in m]
    assert commands and all(m["feasibility"] in ("same_patch", "connected")
                            for m in modes if "plan" in m)
    for command, goal in ((m["plan"], m) for m in modes if "plan" in m):
        code, plan = _run([*shlex.split(command)[1:], "--cache-dir", str(tmp_path)], capsys)
        assert code == 0 and plan["validation"]["ok"]
        # The reference follows the planned legs from the start pose to this mode.
        assert plan["columns"]["joints"] == ["rho1", "rho2", "rho3"]
        legs = np.array([point["joints"] for point in plan["waypoints"]])
        start = next(m for m in modes if m["feasibility"] == "start")
        followed = follow(legs, (start["x"], start["y"], math.radians(start["alpha_deg"])),
                          1e-3 * (1 - 1e-3))
        assert followed["ok"], followed["why"]
        assert np.allclose(followed["pose"], (goal["x"], goal["y"],
                                              math.radians(goal["alpha_deg"])), atol=1e-6)


def test_the_command_line_locates_the_modes_of_a_mechanism_file_on_its_slice(tmp_path,
                                                                             capsys):
    th = [0.0, 69.0013, 129.0014]
    code, modes = _run(["dk", "--mechanism", str(CONFIG / "three_rrr.yaml"), *map(str, th),
                        "--patches", "--cache-dir", str(tmp_path)], capsys)
    assert code == 0 and modes
    assert all(isinstance(m["patch"], int) and isinstance(m["region"], int) for m in modes)
    assert all("feasibility" not in m or m["feasibility"] is None for m in modes)
