"""The command-line tool: its subcommands, the errors they exit with, and the figures."""

import json

import networkx as nx
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.io.export import roadmap_from_json


def test_cli_dk_prints_the_paper_example_solutions(capsys):
    assert main(["dk", "17", "20", "25"]) == 0
    solutions = json.loads(capsys.readouterr().out)
    assert len(solutions) == 4
    alphas = [s["alpha_deg"] for s in solutions]
    assert min(abs(a - 29.47) for a in alphas) < 0.05
    assert min(abs(a - 96.13) for a in alphas) < 0.05
    assert {s["aspect"] for s in solutions} == {-1, 1}


@pytest.mark.parametrize("argv, reason", [
    (["dk", "17", "nan", "25"], "not a finite number"), (["dk", "17", "x", "25"], "not a number"),
    (["dk", "17", "-3", "25"], "non-negative"), (["dk", "17", "20"], "required"),
    (["roadmap", "--step", "0"], "step must be positive"), (["bogus"], "invalid choice"),
    (["dk", "1e308", "1e308", "1e308"], "out of range"),
    (["plan", "--rho1", "1e308", "--start", "12", "18", "122.82", "--goal", "10", "25",
      "-24.24"], "out of range"),
    (["roadmap", "--rho1", "1e308"], "out of range"),
    (["roadmap", "--rho2", "0", "1e308"], "out of range"),
    (["roadmap", "--step", "1e-4"], "exceeds the limit of 4000000"),
    (["roadmap", "--field-figure", "f.xyz"], "unknown figure format 'xyz'"),
    (["roadmap", "--rho2", "12", "12"], "1 x 401 cells has no faces along one axis"),
    (["roadmap", "--step", "100"], "1 x 1 cells has no faces along one axis"),
    (["roadmap", "--rho1", "1000", "--step", "1"], "fewer than one region needs (8)"),
])
def test_cli_bad_arguments_exit_with_code_2_and_one_line(argv, reason, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and err.startswith("rpr3-gwr")
    assert "error" in err and reason in err


def test_cli_names_the_file_it_cannot_write(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["roadmap", "--step", "2", "-o", "/proc/version"])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err == "rpr3-gwr: error: /proc/version: Input/output error\n"


@pytest.mark.parametrize("step, reason", [
    (1e-5, "more than 4000000 cells"),
    (5.0, "goes through patches [3, 5] that the roadmap has not"),
])
def test_cli_plot_refuses_a_plan_whose_grid_is_not_its_roadmaps(step, reason, tmp_path, capsys):
    grid = rho1_slice(17.0, step=step).to_dict() if step > 1e-3 else {
        "axes": [{"joint": j, "min": 0.0, "max": 50.0, "step": step} for j in (1, 2)],
        "fixed": [{"joint": 0, "value": 17.0}]}
    plan = {"roadmap": {"mechanism": PAPER_GEOMETRY.to_dict(), "grid": grid},
            "columns": {"joints": ["rho1", "rho2", "rho3"], "pose": ["x", "y", "alpha_deg"]},
            "global_paths": [[5, 3]], "path_index": 0,
            "waypoints": [{"joints": [17.0, 12.0, 18.0], "pose": [0.0, 0.0, 120.3]}]}
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    with pytest.raises(SystemExit) as exit_info:
        main(["plot", str(path), "--cache-dir", str(tmp_path / "cache")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and reason in err


def test_cli_roadmap_summary_and_output_file(tmp_path, capsys):
    output, gexf = tmp_path / "roadmap.json", tmp_path / "roadmap.gexf"
    assert main(["roadmap", "--step", "0.5", "-o", str(output), "--gexf", str(gexf)]) == 0
    summary = json.loads(capsys.readouterr().out)
    loaded = roadmap_from_json(output.read_text())
    assert len(summary["patches"]) == len(loaded.segmentation.patches) > 0
    assert [axis["step"] for axis in summary["grid"]["axes"]] == [0.5, 0.5]
    graph = nx.read_gexf(str(gexf), node_type=int)
    assert set(graph.nodes) == set(loaded.segmentation.patches)


def test_the_help_loads_neither_numpy_nor_the_compiled_kernels():
    """``rpr3-gwr --help`` answers at once: the commands load the core."""
    import subprocess
    import sys

    code = ("import sys\nfrom rpr3_gwr_core.io.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted({'numpy', 'numba'} & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"
