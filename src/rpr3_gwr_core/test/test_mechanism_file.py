"""A robot described in one YAML file (``config/``): its mechanism and box,
the grids it gives, and the command line on it."""

import json
import math
import pathlib

import pytest

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.io.mechanism_file import (UNIFORM_CELLS, load_mechanism_file,
                                              mechanism_file_from_dict, roadmap_grid)
from rpr3_gwr_core.mechanisms import DEFAULT_FIVE_BAR, DEFAULT_THREE_RRR
from rpr3_gwr_core.paper import PAPER_GEOMETRY, PAPER_GRID

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


def test_a_large_box_of_all_the_joints_builds_adaptively():
    torus = load_mechanism_file(THREE_RRR).grid()
    assert torus.size > UNIFORM_CELLS
    base, refinement = roadmap_grid(torus)
    assert refinement == 4 and base.shape == (30, 30, 30)
    assert [a.periodic for a in base.axes] == [True, True, True]
    for grid in (load_mechanism_file(FIVE_BAR).grid(), load_mechanism_file(THREE_RRR).grid(
            {"th1": 0.0})):
        assert roadmap_grid(grid) == (grid, None)


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


def test_a_file_may_put_the_legs_in_one_layer():
    described = mechanism_file_from_dict(_document(bodies={"leg_layers": [1, 1]}))
    assert described.bodies.leg_layers == (1, 1)
    assert mechanism_file_from_dict(_document()).bodies is None


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
