"""What the workspace's and the files' objects print: one short line that
says what they hold, never their arrays."""

import pathlib

import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.workspace import build_roadmap, refine
from rpr3_gwr_core.workspace.cusps import find_cusps

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"


def _short(obj):
    text = repr(obj)
    assert len(text) < 200 and "\n" not in text and "array(" not in text, text
    return text


def test_the_papers_roadmap_and_its_parts_print_a_summary(paper_roadmap):
    roadmap = paper_roadmap
    seg = roadmap.segmentation
    assert _short(roadmap) == ("Roadmap(3-RPR: 7 regions, 24 patches, 36 gates; rho2 [0, 50] x "
                               "rho3 [0, 50], step 0.125: 401 x 401 cells at rho1 = 17)")
    assert _short(seg).startswith("Segmentation(7 regions, 24 patches, 36 gates; 3-RPR, rho2")
    field = _short(roadmap.field)
    assert field.startswith("NSolutionField(3-RPR, rho2 [0, 50]") and "2 to 6 solutions" in field
    assert _short(roadmap.grid) == ("Grid(joint 1 [0, 50] x joint 2 [0, 50], step 0.125: "
                                    "401 x 401 cells at joint 0 = 17)")
    patch = seg.patches[11]
    assert _short(patch).startswith(f"Patch(11: region 1, layer 1, aspect {patch.aspect:+d}, "
                                    f"2 solutions, {patch.cells.size} cells")
    (a, b), gate = next(iter(seg.gates.items()))
    assert _short(gate).startswith(f"Gate({a} - {b}: {len(gate.faces)} faces, width")
    cusp = _short(find_cusps(roadmap)[0])
    assert cusp.startswith("Cusp(joints (17, ") and "regions" in cusp


def test_an_adaptive_grid_prints_its_base_and_refinement():
    grid = refine(PAPER_GEOMETRY, rho1_slice(17.0, (10.0, 20.0), (10.0, 20.0), 1.0))
    text = _short(grid)
    assert text.startswith("AdaptiveGrid(joint 1 [10, 20] x joint 2 [10, 20], step 0.25: ")
    assert f"(base 11 x 11, {grid.blocks.size} blocks refined 4 times) at joint 0 = 17)" in text
    roadmap = build_roadmap(PAPER_GEOMETRY, grid)
    assert "rho2 [10, 20] x rho3 [10, 20]" in _short(roadmap)


def test_the_full_roadmap_prints_a_summary(full_roadmap):
    text = _short(full_roadmap)
    seg = full_roadmap.segmentation
    assert text.startswith(f"Roadmap(3-RPR: {seg.n_regions} regions, {len(seg.patches)} "
                           f"patches, {len(seg.gates)} gates; rho1 [1, 50] x rho2 [0, 50] x "
                           "rho3 [0, 50], step 0.25: ")
    assert f"{full_roadmap.grid.size:,} cells (base " in text
    _short(full_roadmap.field)
    _short(seg)


@pytest.mark.parametrize("name, expected", [
    ("five_bar.yaml", "MechanismFile(5R: th1 (120 cells a turn) x th2 (120 cells a turn); "
                      "default bodies)"),
    ("paper_3rpr.yaml", "MechanismFile(3-RPR: rho1 [0, 50] step 0.125 x rho2"),
])
def test_a_mechanism_file_prints_its_box(name, expected):
    assert _short(load_mechanism_file(CONFIG / name)).startswith(expected)


def test_a_periodic_grid_names_its_turns():
    described = load_mechanism_file(CONFIG / "three_rrr.yaml")
    grid = described.grid({"th1": 0.0})
    roadmap = build_roadmap(described.mechanism, grid)
    assert "th2 (a turn) x th3 (a turn), step 0.0523599: 120 x 120 cells at th1 = 0" in _short(
        roadmap)
