"""``--thin-refinement`` of the commands on a mechanism file: by default the
roadmap's thin regions are refined, so the 3-RRR's way at th1 = 1.5 rad is
planned where its grid alone answers unreachable; the plan file says how its
roadmap was built, ``plot`` builds the same, and the cache keeps the two
builds apart."""

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


def test_without_thin_refinement_the_grid_alone_answers_unreachable(tmp_path, capsys):
    code, answer = _run([*REQUEST, "--cache-dir", str(tmp_path), "--thin-refinement", "0"],
                        capsys)
    assert code != 0 and answer["reason"] == "unreachable"
    assert answer["error"]["code"] == "INFEASIBLE"


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
    (["plan", "--start", "12", "18", "122.82", "--goal", "10", "25", "-24.24",
      "--thin-refinement", "4"], "--thin-refinement needs --mechanism"),
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
