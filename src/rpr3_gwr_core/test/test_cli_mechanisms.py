"""``dk`` and ``cusps`` on a mechanism file: the paper's file answers as the
defaults do, another mechanism through its own interface, and what does not
fit is refused with code 2 and one line."""

import json
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
PAPER, FIVE_BAR, THREE_RRR = (str(CONFIG / name) for name in
                              ("paper_3rpr.yaml", "five_bar.yaml", "three_rrr.yaml"))


def _run(argv, capsys):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("legs", [["17", "20", "25"], ["17", "12", "18"], ["3", "40", "2"]])
def test_dk_on_the_paper_file_is_the_default_dk(legs, capsys):
    assert _run(["dk", "--mechanism", PAPER, *legs], capsys) == _run(["dk", *legs], capsys)


@pytest.mark.parametrize("path, joints_deg", [(FIVE_BAR, [28.6, 114.6]),
                                              (THREE_RRR, [0.0, 69.0, 129.0])])
def test_dk_on_a_file_takes_and_gives_angles_in_degrees(path, joints_deg, capsys):
    mechanism = load_mechanism_file(path).mechanism
    joints = np.radians(joints_deg)
    code, solutions = _run(["dk", "--mechanism", path, *map(str, joints_deg)], capsys)
    assert code == 0 and solutions
    labels = [f"{n}_deg" if a else n for n, a in zip(mechanism.pose_names, mechanism.angular)]
    for solution in solutions:
        assert set(solution) == {*labels, "aspect", "signed_margin"}
        pose = np.array([solution[label] for label in labels])
        pose[list(mechanism.angular)] = np.radians(pose[list(mechanism.angular)])
        assert np.max(np.abs(mechanism.residual(pose, joints))) < 1e-6
        assert solution["aspect"] == mechanism.aspect(pose, joints)
        assert solution["signed_margin"] == pytest.approx(mechanism.margin(pose, joints))
    assert len(solutions) == mechanism.solve(np.array([joints]))[0][0]


def test_cusps_on_the_paper_file_are_the_default_cusps(tmp_path, capsys):
    cache = ["--cache-dir", str(tmp_path)]
    code, cusps = _run(["cusps", "--mechanism", PAPER, "--fix", "rho1=17", *cache], capsys)
    assert code == 0 and len(cusps) == 6
    assert _run(["cusps", *cache], capsys) == (code, cusps)


@pytest.mark.parametrize("argv, reason", [
    (["dk", "--mechanism", FIVE_BAR, "1", "2", "3"], "dk takes the 2 joints TH1_DEG TH2_DEG"),
    (["dk", "17", "20"], "dk takes the 3 joints RHO1 RHO2 RHO3"),
    (["dk", "--mechanism", "/nonexistent.yaml", "1", "2"], "/nonexistent.yaml"),
    (["cusps", "--mechanism", FIVE_BAR], "the 5R has no cusp equations"),
    (["cusps", "--mechanism", THREE_RRR, "--fix", "th1=0"], "the 3-RRR has no cusp equations"),
    (["cusps", "--mechanism", PAPER, "--fix", "rho1=17", "--rho1", "17"],
     "--rho1: the paper's 3-RPR"),
    (["cusps", "--mechanism", PAPER, "--fix", "rho1=17", "--trace", "12", "18", "1"],
     "--trace: the paper's 3-RPR"),
    (["cusps", "--mechanism", PAPER, "--fix", "rho1=17", "--step", "1"],
     "--step: the paper's 3-RPR"),
    (["cusps", "--mechanism", PAPER, "--fix", "rho1=17", "--fix", "rho2=20"],
     "cusps are points of 2-D slices"),
    (["cusps", "--fix", "rho1=17"], "--fix needs --mechanism"),
    (["plan", "--full", "--step", "0.1", "--start", "17", "12", "18", "0", "--goal", "17", "10",
      "25", "0"], "--step: the full 3-DOF roadmap's grid is its own"),
    (["plan", "--mechanism", PAPER, "--step", "0.1", "--start", "17", "12", "18", "0",
      "--goal", "17", "10", "25", "0"], "--step: the paper's 3-RPR"),
])
def test_what_does_not_fit_exits_with_code_2_and_one_line(argv, reason, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and reason in err
