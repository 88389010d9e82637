"""The command-line tool's dk and roadmap subcommands, and the figures."""

import json
import math

import networkx as nx
import pytest

from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.io.export import roadmap_from_json


def test_cli_dk_prints_the_paper_example_solutions(capsys):
    assert main(["dk", "17", "20", "25"]) == 0
    solutions = json.loads(capsys.readouterr().out)
    assert len(solutions) == 4
    alphas = [math.degrees(s["alpha"]) for s in solutions]
    assert min(abs(a - 29.47) for a in alphas) < 0.05
    assert min(abs(a - 96.13) for a in alphas) < 0.05
    assert {s["aspect"] for s in solutions} == {-1, 1}


@pytest.mark.parametrize("argv", [["dk", "17", "nan", "25"], ["dk", "17", "x", "25"],
                                  ["dk", "17", "-3", "25"], ["dk", "17", "20"],
                                  ["roadmap", "--step", "0"], ["bogus"]])
def test_cli_bad_arguments_exit_with_code_2(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert "error" in capsys.readouterr().err


def test_cli_roadmap_summary_and_output_file(tmp_path, capsys):
    output, gexf = tmp_path / "roadmap.json", tmp_path / "roadmap.gexf"
    assert main(["roadmap", "--step", "0.5", "-o", str(output), "--gexf", str(gexf)]) == 0
    summary = json.loads(capsys.readouterr().out)
    loaded = roadmap_from_json(output.read_text())
    assert len(summary["patches"]) == len(loaded.segmentation.patches) > 0
    assert [axis["step"] for axis in summary["grid"]["axes"]] == [0.5, 0.5]
    graph = nx.read_gexf(str(gexf), node_type=int)
    assert set(graph.nodes) == set(loaded.segmentation.patches)


def test_field_figure_labels_every_region(coarse_paper_roadmap):
    figures = pytest.importorskip("rpr3_gwr_core.io.figures")
    figure = figures.field_figure(coarse_paper_roadmap)
    texts = {t.get_text() for t in figure.axes[0].texts}
    expected = {str(r) for r in range(1, coarse_paper_roadmap.segmentation.n_regions + 1)}
    assert expected <= texts


def test_roadmap_figure_draws_one_label_per_patch(coarse_paper_roadmap):
    figures = pytest.importorskip("rpr3_gwr_core.io.figures")
    figure = figures.roadmap_figure(coarse_paper_roadmap)
    texts = {t.get_text() for t in figure.axes[0].texts}
    assert {str(p) for p in coarse_paper_roadmap.segmentation.patches} <= texts
