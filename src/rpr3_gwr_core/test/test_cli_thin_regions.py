"""``--thin-refinement`` of the commands on a slice (a mechanism file's or
the paper's): by default the roadmap's thin regions are refined, so the
3-RRR's way at th1 = 1.5 rad is planned where its grid alone cannot decide
(and says how to ask at a finer cell); the plan file says how its roadmap
was built, ``plot`` builds the same, and the cache keeps the two builds
apart."""

import json
import math
import pathlib

import pytest

from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file, roadmap_grid

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
THREE_RRR = str(CONFIG / "three_rrr.yaml")
TH1 = f"{math.degrees(1.5)!r}"
JOINTS = [TH1, "165", "-87"]
REQUEST = ["plan", "--mechanism", THREE_RRR, "--fix", f"th1={TH1}",
           "--start", *JOINTS, "-122.510593", "--goal", *JOINTS, "-33.654195"]


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


def test_the_way_along_a_thin_region_is_planned_by_default(tmp_path, capsys):
    plan_file = tmp_path / "plan.json"
    code, answer = _run([*REQUEST, "--cache-dir", str(tmp_path), "-o", str(plan_file)], capsys)
    assert code == 0 and answer["reason"] == "connected" and answer["waypoints"]
    assert answer["roadmap"]["thin_refinement"] == 4
    code, answer = _run(["plot", str(plan_file), "-o", str(tmp_path / "plan.png"),
                         "--cache-dir", str(tmp_path)], capsys)
    assert code == 0 and (tmp_path / "plan.png").stat().st_size > 0


def test_without_thin_refinement_the_grid_alone_cannot_decide_and_says_how_to_ask(
        tmp_path, capsys):
    code, answer = _run([*REQUEST, "--cache-dir", str(tmp_path), "--thin-refinement", "0"],
                        capsys)
    assert code == 1 and answer["reason"] == "undecided"
    assert answer["error"]["code"] == "UNDECIDED"
    undecided = answer["undecided"]
    assert undecided["thin_patches"] and undecided["finer"] == "--thin-refinement 4"
    # The file's 3-degree cells, in the command line's degrees.
    assert undecided["finest_steps"] == pytest.approx({"th2_deg": 3.0, "th3_deg": 3.0})
    # Asked as it says, the same command plans.
    code, answer = _run([*REQUEST, "--cache-dir", str(tmp_path),
                         *undecided["finer"].split()], capsys)
    assert code == 0 and answer["reason"] == "connected"


def test_a_refinement_too_coarse_for_the_strip_says_to_refine_further(tmp_path, capsys):
    code, answer = _run([*REQUEST, "--cache-dir", str(tmp_path), "--thin-refinement", "2"],
                        capsys)
    # Half-width cells still leave the strip thin where it narrows.
    assert code == 1 and answer["reason"] == "undecided"
    assert answer["undecided"]["finer"] == "--thin-refinement 4"
    assert answer["undecided"]["finest_steps"] == pytest.approx({"th2_deg": 1.5,
                                                                "th3_deg": 1.5})


# Two assembly modes of one aspect in two components of the paper's slice at
# rho1 = 27.5 (a pocket that rho1 must move to leave, test_full_roadmap).
POCKET = ["--rho1", "27.5", "--start", "31.67154934", "2.14117832", "-101",
          "--goal", "31.67154934", "2.14117832", "158.048263"]


def test_the_paper_s_slices_refine_thin_regions_too(tmp_path, capsys):
    code, answer = _run(["plan", *POCKET, "--cache-dir", str(tmp_path)], capsys)
    assert code == 1 and answer["reason"] == "unreachable"
    assert answer["roadmap"]["thin_refinement"] == 4
    code, answer = _run(["plan", *POCKET, "--cache-dir", str(tmp_path),
                         "--thin-refinement", "0"], capsys)
    assert code == 1 and answer["reason"] == "undecided"
    assert answer["undecided"]["finer"] == "--thin-refinement 4"
    assert answer["undecided"]["finest_steps"] == {"rho2": 0.125, "rho3": 0.125}


def test_a_paper_slice_refined_around_its_thin_region_is_summarised_with_its_cusps(
        tmp_path, capsys):
    code, summary = _run(["roadmap", "--rho1", "27.5", "--cache-dir", str(tmp_path),
                          "--field-figure", str(tmp_path / "field.png")], capsys)
    assert code == 0 and summary["refinement"]["refined_blocks"] > 0
    assert summary["cusps"] and all(cusp["regions"] for cusp in summary["cusps"])
    assert (tmp_path / "field.png").stat().st_size > 10_000


def test_the_cache_keeps_a_thin_refined_build_apart_from_the_grid_alone(tmp_path):
    described = load_mechanism_file(THREE_RRR)
    grid = roadmap_grid(described, {"th1": 1.5})
    refined, _, hit = cached_planning(described.mechanism, grid, tmp_path, thin_refinement=4)
    assert not hit and refined.grid != grid
    plain, _, hit = cached_planning(described.mechanism, grid, tmp_path)
    assert not hit and plain.grid == grid
    again, _, hit = cached_planning(described.mechanism, grid, tmp_path, thin_refinement=4)
    assert hit and again.grid == refined.grid


@pytest.mark.parametrize("argv, reason", [
    ([*REQUEST, "--thin-refinement", "1"], "--thin-refinement is 0 (off) or at least 2"),
    ([*REQUEST, "--thin-refinement", "-2"], "'-2' is negative"),
    ([*REQUEST, "--thin-refinement", "two"], "'two' is not an integer"),
])
def test_a_thin_refinement_that_does_not_fit_exits_with_code_2_and_one_line(argv, reason,
                                                                           capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and reason in err
