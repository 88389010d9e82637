"""A robot described in one YAML file (``config/``): its mechanism and box,
the grids it gives, and the command line on it."""

import json
import math
import pathlib
import re

import numpy as np
import pytest
from scipy.optimize import brentq
import yaml

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.io.mechanism_file import (BYTES_PER_CELL, HOME_SAMPLES, UNIFORM_CELLS,
                                              load_mechanism_file, mechanism_file_from_dict,
                                              roadmap_grid)
from rpr3_gwr_core.mechanisms import DEFAULT_FIVE_BAR, DEFAULT_THREE_RRR
from rpr3_gwr_core.paper import PAPER_GEOMETRY, PAPER_GRID
from rpr3_gwr_core.workspace.adaptive import AdaptiveGrid
from rpr3_gwr_core.workspace.grid import MAX_GRID_CELLS

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
FIVE_BAR = str(CONFIG / "five_bar.yaml")
PAPER = str(CONFIG / "paper_3rpr.yaml")
THREE_RRR = str(CONFIG / "three_rrr.yaml")
# Both assembly modes of th = (3.1, 2.5) and the positive one at (-3.1, 2.5),
# by the circle intersection (their y is the mode coordinate).
PLUS_A, MINUS_A, PLUS_B = 0.11622901, -0.05862426, 0.10985067


def test_the_paper_file_gives_the_paper_slice():
    described = load_mechanism_file(PAPER)
    assert described.mechanism == PAPER_GEOMETRY
    assert described.grid({"rho1": 17.0}) == PAPER_GRID


def test_the_five_bar_file_is_the_default_five_bar_on_its_torus():
    described = load_mechanism_file(FIVE_BAR)
    assert described.mechanism == DEFAULT_FIVE_BAR
    assert [a.periodic for a in described.axes] == [True, True]
    assert [a.count for a in described.axes] == [120, 120]
    assert described.axes[0].low == -math.pi


def test_the_three_rrr_file_is_the_default_three_rrr_on_its_torus():
    described = load_mechanism_file(THREE_RRR)
    assert described.mechanism == DEFAULT_THREE_RRR
    assert [a.periodic for a in described.axes] == [True, True, True]
    slice_ = described.grid({"th1": 0.0})
    assert slice_.fixed == ((0, 0.0),) and slice_.shape == (120, 120)


def test_a_large_box_of_all_the_joints_builds_adaptively_on_the_files_lattice():
    described = load_mechanism_file(THREE_RRR)
    assert math.prod(a.count for a in described.axes) > UNIFORM_CELLS
    grid = roadmap_grid(described)
    assert isinstance(grid, AdaptiveGrid) and grid.refinement == 4
    assert grid.base.shape == (30, 30, 30)
    assert [a.count for a in grid.axes] == [a.count for a in described.axes]
    assert np.allclose(grid.steps, [a.step for a in described.axes], rtol=1e-12)
    assert grid.size < math.prod(a.count for a in described.axes)
    five_bar = load_mechanism_file(FIVE_BAR)
    assert roadmap_grid(five_bar) == five_bar.grid()
    assert roadmap_grid(described, {"th1": 0.0}) == described.grid({"th1": 0.0})


# A user's 3-RPR whose lattice (legs 5 to 30 by 0.125: 201 ** 3 points) is
# twice the limit of a uniform grid.
USER_RPR = {"mechanism": {"kind": "3-RPR", "a1": [0.0, 0.0], "a2": [20.0, 0.0],
                          "a3": [5.0, 15.0], "d1": 10.0, "d3": 12.0, "beta_deg": 60},
            "joints": [{"name": f"rho{k}", "min": 5.0, "max": 30.0, "step": 0.125}
                       for k in (1, 2, 3)]}


def test_the_full_box_of_a_lattice_beyond_a_grids_limit_fits_adaptively():
    described = mechanism_file_from_dict(USER_RPR)
    assert math.prod(a.count for a in described.axes) > MAX_GRID_CELLS
    grid = roadmap_grid(described, memory=8 * 2 ** 30)
    assert np.allclose(grid.steps, 0.125, rtol=1e-12) and grid.size <= MAX_GRID_CELLS
    assert grid.size * BYTES_PER_CELL <= 8 * 2 ** 30


def _steps_named(message):
    return {name: float(value) for name, value in re.findall(r"(rho\d) step ([\d.]+)", message)}


@pytest.mark.slow
@pytest.mark.parametrize("document, memory", [
    (USER_RPR, 2 ** 30),
    # The paper's file: a fine lattice of 401 ** 3 points, beyond the refinement's.
    (yaml.safe_load(pathlib.Path(PAPER).read_text()), 16 * 2 ** 30),
])
def test_a_box_that_does_not_fit_is_refused_with_steps_that_fit(document, memory):
    with pytest.raises(InvalidInputError, match="more than a build may take") as refused:
        roadmap_grid(mechanism_file_from_dict(document), memory=memory)
    steps = _steps_named(str(refused.value))
    assert sorted(steps) == ["rho1", "rho2", "rho3"]
    coarser = dict(document, joints=[dict(joint, step=steps[joint["name"]])
                                     for joint in document["joints"]])
    grid = roadmap_grid(mechanism_file_from_dict(coarser), memory=memory)
    assert grid.size * BYTES_PER_CELL <= memory


def test_a_slice_that_does_not_fit_is_refused_with_steps_that_fit():
    document = dict(USER_RPR, joints=[dict(j, step=0.001) for j in USER_RPR["joints"]])
    described = mechanism_file_from_dict(document)
    with pytest.raises(InvalidInputError, match="slice would have 625,") as refused:
        roadmap_grid(described, {"rho1": 15.0})
    steps = _steps_named(str(refused.value))
    assert sorted(steps) == ["rho2", "rho3"]
    coarser = dict(document, joints=[dict(joint, step=steps.get(joint["name"], 0.001))
                                     for joint in document["joints"]])
    assert roadmap_grid(mechanism_file_from_dict(coarser), {"rho1": 15.0}).size \
        <= MAX_GRID_CELLS


def _document(**changes):
    document = {"mechanism": DEFAULT_FIVE_BAR.to_dict(),
                "joints": [{"name": "th1", "periodic": True, "cells": 120},
                           {"name": "th2", "min": -1.0, "max": 1.0, "step": 0.1}]}
    document.update(changes)
    return document


@pytest.mark.parametrize("document, reason", [
    ([], "the keys"),
    (_document(extra=1), "the keys"),
    (_document(mechanism={"kind": "7R"}), "unknown mechanism kind"),
    (_document(joints=[{"name": "th1", "periodic": True, "cells": 120}]), "lists the 2 joints"),
    (_document(joints=[{"name": "th2", "periodic": True, "cells": 9},
                       {"name": "th1", "periodic": True, "cells": 9}]), "must be named 'th1'"),
    (_document(joints=[{"name": "th1", "periodic": True},
                       {"name": "th2", "periodic": True, "cells": 9}]), "'cells'"),
    (_document(joints=[{"name": "th1", "periodic": True, "cells": 1.5},
                       {"name": "th2", "periodic": True, "cells": 9}]), "whole number"),
    (_document(joints=[{"name": "th1", "min": 0, "max": 1},
                       {"name": "th2", "periodic": True, "cells": 9}]), "give 'min'"),
    (_document(joints=[{"name": "th1", "min": "a", "max": 1, "step": 0.1},
                       {"name": "th2", "periodic": True, "cells": 9}]), "must be a number"),
    (_document(bodies={"leg_colour": "red"}), "unknown body keys"),
    (_document(bodies=[1]), "must be a mapping"),
])
def test_malformed_documents_are_refused(document, reason):
    with pytest.raises(InvalidInputError, match=reason):
        mechanism_file_from_dict(document)


def _user_rpr(**changes):
    """A user's 3-RPR: A1 (0, 0), A2 (20, 0), A3 (5, 15), d1 10, d3 12, beta
    60 deg, legs in [5, 30]."""
    mechanism = {"kind": "3-RPR", "a1": [0.0, 0.0], "a2": [20.0, 0.0], "a3": [5.0, 15.0],
                 "d1": 10.0, "d3": 12.0, "beta_deg": 60}
    mechanism.update(changes)
    return {"mechanism": {k: v for k, v in mechanism.items() if v is not None},
            "joints": [{"name": n, "min": 5.0, "max": 30.0, "step": 0.125}
                       for n in ("rho1", "rho2", "rho3")]}


def test_an_angle_in_degrees_carries_its_unit_in_its_key():
    in_degrees = mechanism_file_from_dict(_user_rpr()).mechanism
    in_radians = mechanism_file_from_dict(_user_rpr(beta_deg=None, beta=math.pi / 3)).mechanism
    assert in_degrees == in_radians
    assert in_degrees.beta == pytest.approx(math.pi / 3, abs=1e-15)
    prr = {"kind": "3-PRR", "a1": [0.0, 0.0], "a2": [15.91, 0.0], "a3": [0.0, 10.0],
           "gamma1_deg": 0, "gamma2_deg": 90, "gamma3_deg": 45, "l": 15.0, "d1": 17.04,
           "d3": 20.84, "beta": 0.8826031097644318}
    joints = [{"name": n, "min": 0.0, "max": 30.0, "step": 0.25} for n in ("s1", "s2", "s3")]
    described = mechanism_file_from_dict({"mechanism": prr, "joints": joints})
    assert described.mechanism == load_mechanism_file(str(CONFIG / "three_prr.yaml")).mechanism


def test_a_revolute_joint_s_range_may_be_in_degrees():
    in_degrees = mechanism_file_from_dict(_document(joints=[
        {"name": "th1", "periodic": True, "cells": 120},
        {"name": "th2", "min_deg": -45, "max_deg": 45, "step_deg": 0.5}]))
    axis = in_degrees.axes[1]
    assert (axis.low, axis.high, axis.step) == pytest.approx(
        (-math.pi / 4, math.pi / 4, math.pi / 360), abs=1e-15)


@pytest.mark.parametrize("document, reason", [
    (_user_rpr(beta_deg=None, beta=60),
     r"beta = 60 rad is more than a full turn: a mechanism file's angles are in radians; "
     r"for degrees, name the key with _deg"),
    (_user_rpr(d3=None, d_3=12.0),
     r"unknown key 'd_3'; the known: a1, a2, a3, d1, d3, beta \[rad\] or beta_deg \[deg\]"),
    (_user_rpr(beta=1.0), r"beta is given twice, as beta \[rad\] and beta_deg \[deg\]"),
    (_user_rpr(d3=None), r"'d3' missing"),
    (_user_rpr(beta_deg="60"), r"beta_deg must be a number of degrees"),
    (_document(joints=[{"name": "th1", "periodic": True, "cells": 120},
                       {"name": "th2", "min": -60, "max": 60, "step": 1}]),
     r"th2: min = -60 rad is more than a full turn"),
    (_document(joints=[{"name": "th1", "periodic": True, "cells": 120},
                       {"name": "th2", "min": -1, "max": 1, "step_size": 0.1}]),
     r"th2: unknown key 'step_size'; the known: min \[rad\] or min_deg \[deg\]"),
    (_document(home=[0.0, 0.0, 0.1], joints=[{"name": "th1", "periodic": True, "cells": 120},
                                             {"name": "th2", "min": -1, "max": 1, "step": 0.1}])
     | {"home": [90.0, 0.0, 0.1]}, r"'home': th1 = 90 rad is more than a full turn"),
])
def test_a_file_that_could_be_misread_is_refused_with_the_reason(document, reason):
    with pytest.raises(InvalidInputError, match=reason):
        mechanism_file_from_dict(document)


def test_a_range_error_names_the_unit():
    with pytest.raises(InvalidInputError, match=r"th2 = 2.0 lies outside .* \[-1, 1\] rad$"):
        mechanism_file_from_dict(_document()).grid({"th2": 2.0})
    with pytest.raises(InvalidInputError, match=r"\[0, 50\] \[length unit\]$"):
        load_mechanism_file(PAPER).grid({"rho1": 60.0})


def test_a_file_may_put_the_legs_in_one_layer():
    described = mechanism_file_from_dict(_document(bodies={"leg_layers": [1, 1]}))
    assert described.bodies.leg_layers == (1, 1)
    assert mechanism_file_from_dict(_document()).bodies is None


@pytest.mark.parametrize("layers", [[], [1], [1, 1, 1]])
def test_leg_layers_other_than_one_per_leg_are_refused_where_the_file_is_read(layers):
    # The five-bar has two legs.
    with pytest.raises(InvalidInputError, match=f"'bodies': leg_layers must give 2 layers, "
                                                f"got {len(layers)}"):
        mechanism_file_from_dict(_document(bodies={"leg_layers": layers}))


# A user's 3-RRR (base side 30, platform side 8, links 10 and 10): its box
# middle th = (0, 0, 0) puts two elbows 30 apart, beyond the platform's
# reach of 8 + 2 x 10, so it cannot be assembled there.
USER_RRR = {"kind": "3-RRR", "a1": [0.0, 0.0], "a2": [30.0, 0.0],
            "a3": [15.0, 15.0 * math.sqrt(3)], "d1": 8.0, "d3": 8.0, "beta": math.pi / 3,
            "l1": 10.0, "l2": 10.0}
TORUS = [{"name": name, "periodic": True, "cells": 120} for name in ("th1", "th2", "th3")]


def _closure_gaps(mechanism, th, alpha):
    """For 3-RRR joints ``th`` (shape (n, 3)) and platform angles ``alpha``
    (shape (m,)), by circle intersection: B1 lies l2 from elbow 1 and, moved
    by -d1 along the platform's side, l2 from elbow 2; at each of those two
    points, how far B3 lies from l2 of elbow 3.  Shape (2, n, m), NaN where
    the two circles do not meet."""
    base = np.array([mechanism["a1"], mechanism["a2"], mechanism["a3"]], dtype=float)
    angles = np.asarray(th, dtype=float)[..., None]
    elbows = base + mechanism["l1"] * np.concatenate([np.cos(angles), np.sin(angles)], axis=-1)
    alpha = np.asarray(alpha, dtype=float)
    side1 = mechanism["d1"] * np.stack([np.cos(alpha), np.sin(alpha)], axis=-1)
    turned = alpha + mechanism["beta"]
    side3 = mechanism["d3"] * np.stack([np.cos(turned), np.sin(turned)], axis=-1)
    c1 = elbows[:, None, 0]
    c2 = elbows[:, None, 1] - side1[None]
    r = mechanism["l2"]
    gap = np.linalg.norm(c2 - c1, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        along = (c2 - c1) / gap
        half = np.sqrt(r * r - gap * gap / 4)
    normal = np.stack([-along[..., 1], along[..., 0]], axis=-1)
    middle = c1 + along * gap / 2
    return np.stack([np.linalg.norm(middle + sign * half * normal + side3[None]
                                    - elbows[:, None, 2], axis=-1) - r
                     for sign in (1.0, -1.0)])


def _assemblable(mechanism, th, alphas=2880):
    """Whether each row of 3-RRR joints can be assembled: the closure gap
    of either branch changes sign between two platform angles of a fine
    turn (a tangential closure is missed)."""
    gaps = _closure_gaps(mechanism, th, np.linspace(-math.pi, math.pi, alphas))
    crossing = gaps[..., :-1] * gaps[..., 1:] <= 0
    return crossing.any(axis=(0, 2))


def _closes(mechanism, configuration):
    """Whether joints and platform angle close the chains (to 1e-6)."""
    gaps = _closure_gaps(mechanism, [configuration[:3]], [configuration[3]])
    return bool(np.nanmin(np.abs(gaps)) < 1e-6)


def test_a_file_without_a_home_finds_one_that_assembles_where_its_middle_cannot():
    described = mechanism_file_from_dict({"mechanism": USER_RRR, "joints": TORUS})
    assert described.home is None
    assert not _assemblable(USER_RRR, [[0.0, 0.0, 0.0]])[0]
    home = described.default_home()
    assert len(home) == 4 and all(-math.pi <= v <= math.pi for v in home[:3])
    assert _closes(USER_RRR, home)
    # Its first joint's value is that of the lattice's slice with most
    # configurations the reference can assemble.
    values = -math.pi + (np.arange(HOME_SAMPLES) + 0.5) * 2 * math.pi / HOME_SAMPLES
    lattice = np.stack(np.meshgrid(values, values, values, indexing="ij"), -1).reshape(-1, 3)
    counts = _assemblable(USER_RRR, lattice).reshape(HOME_SAMPLES, -1).sum(axis=1)
    assert counts.max() > 0
    assert counts[int(np.argmin(np.abs(values - home[0])))] == counts.max()


def test_a_file_s_home_is_where_its_nodes_start():
    home = [0.0, 1.2043, 2.2515, 0.6526]
    described = mechanism_file_from_dict({"mechanism": DEFAULT_THREE_RRR.to_dict(),
                                          "joints": TORUS, "home": home})
    assert described.default_home() == tuple(home)
    for path in (PAPER, FIVE_BAR, THREE_RRR):
        assert load_mechanism_file(path).home is not None


@pytest.mark.parametrize("home, reason", [
    ([0.0, 0.0], "lists 3 numbers"),
    ([0.0, "a", 0.1], "lists 3 numbers"),
    ([0.0, True, 0.1], "lists 3 numbers"),
    ([0.0, math.nan, 0.1], "NaN"),
    ([0.0, 2.0, 0.1], "outside its range"),
    ([0.0, 0.0, 0.5], "no assembly mode with y near 0.5"),
])
def test_a_home_that_does_not_fit_the_file_is_refused(home, reason):
    with pytest.raises(InvalidInputError, match=reason):
        mechanism_file_from_dict(_document(home=home))


def test_a_home_near_a_singularity_is_refused():
    # B1 turned on leg 1's circle (rho1 = 17) until the leg lines concur.
    alpha = 0.5
    theta = brentq(lambda t: PAPER_GEOMETRY.margin([17 * math.cos(t), 17 * math.sin(t), alpha]),
                   math.pi / 3, math.pi / 2)
    legs = PAPER_GEOMETRY.inverse([17 * math.cos(theta), 17 * math.sin(theta), alpha])
    document = {"mechanism": PAPER_GEOMETRY.to_dict(),
                "joints": [{"name": n, "min": 0.0, "max": 50.0, "step": 0.125}
                           for n in PAPER_GEOMETRY.joint_names],
                "home": [*map(float, legs), alpha]}
    with pytest.raises(InvalidInputError, match="too near a singularity"):
        mechanism_file_from_dict(document)


@pytest.mark.parametrize("fixed, reason", [
    ({"rho1": 1.0}, "name no joint"), ({"th2": 2.0}, "outside its range"),
    ({"th2": math.nan}, "outside its range"), ({"th1": 0.0, "th2": 0.0}, "every joint"),
])
def test_fixed_joints_are_checked(fixed, reason):
    with pytest.raises(InvalidInputError, match=reason):
        mechanism_file_from_dict(_document()).grid(fixed)


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


def test_the_command_line_builds_and_plans_on_a_file(tmp_path, capsys):
    cache = ["--cache-dir", str(tmp_path)]
    code, summary = _run(["roadmap", "--mechanism", FIVE_BAR, *cache], capsys)
    assert code == 0 and summary["mechanism"]["kind"] == "5R"
    assert sorted(p["aspect"] for p in summary["patches"]) == [-1, 1] and not summary["gates"]
    # Across the seam of th1 (angles in degrees): 4.8 deg, not a turn back.
    th = [str(math.degrees(v)) for v in (3.1, 2.5, -3.1)]
    code, plan = _run(["plan", "--mechanism", FIVE_BAR, *cache, "--start", th[0], th[1],
                       str(PLUS_A), "--goal", th[2], th[1], str(PLUS_B)], capsys)
    assert code == 0 and plan["feasible"] and plan["validation"]["ok"]
    assert plan["columns"] == {"joints": ["th1_deg", "th2_deg"], "pose": ["x", "y"]}
    moved = [w["joints"] for w in plan["waypoints"]]
    assert abs(moved[-1][0] - moved[0][0]) < 6
    # The five-bar's two assembly modes have opposite aspects: never a path.
    code, refused = _run(["plan", "--mechanism", FIVE_BAR, *cache, "--start", th[0], th[1],
                          str(PLUS_A), "--goal", th[0], th[1], str(MINUS_A)], capsys)
    assert code == 1 and refused["reason"] == "other_aspect"


def test_the_command_line_plans_the_three_rrr_assembly_mode_change(tmp_path, capsys):
    """Two modes of th = (0, 1.2043, 2.2515) with one aspect, joined through
    the slice's two-solution region (the path itself is re-checked
    independently in test_rrr3)."""
    th, alpha = [math.degrees(v) for v in (0, 1.2043, 2.2515)], (0.6526, 2.1165)
    code, plan = _run(["plan", "--mechanism", THREE_RRR, "--fix", "th1=0", "--cache-dir",
                       str(tmp_path), "--start", *map(str, th), str(math.degrees(alpha[0])),
                       "--goal", *map(str, th), str(math.degrees(alpha[1]))], capsys)
    assert code == 0 and plan["feasible"] and plan["validation"]["ok"]
    assert plan["start"]["patch"] != plan["goal"]["patch"]


@pytest.mark.parametrize("argv, reason", [
    (["roadmap", "--mechanism", FIVE_BAR, "--rho1", "17"], "--rho1: the paper's 3-RPR"),
    (["plan", "--mechanism", FIVE_BAR, "--full", "--start", "1", "--goal", "1"], "--full"),
    (["roadmap", "--fix", "rho1=17"], "--fix needs --mechanism"),
    (["roadmap", "--mechanism", FIVE_BAR, "--fix", "th1"], "is not NAME=VALUE"),
    (["plan", "--mechanism", FIVE_BAR, "--start", "1", "2", "--goal", "1", "2"],
     "TH1_DEG TH2_DEG and the mode coordinate Y"),
    (["plan", "--mode-tol", "0.1", "--start", "1", "2", "3", "--goal", "1", "2", "3"],
     "--mode-tol needs --mechanism"),
    (["roadmap", "--mechanism", "/nonexistent.yaml"], "/nonexistent.yaml"),
])
def test_file_options_refuse_what_does_not_fit(argv, reason, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert reason in capsys.readouterr().err
