"""Progress of long builds: the core reports through a ``progress(stage,
fraction)`` callback and never prints; the command line shows a bar on a
terminal, log lines otherwise, on stderr only."""

import io
import json

import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.io import commands
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.workspace import build_roadmap, compute_field, refine, segment
from rpr3_gwr_core.workspace.cusps import cusp_curves


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def _calls(build):
    calls = []
    build(lambda stage, fraction: calls.append((stage, fraction)))
    return calls


def _non_decreasing_to_one(calls):
    fractions = [f for _, f in calls]
    return fractions == sorted(fractions) and 0 <= fractions[0] and fractions[-1] == 1.0


def test_every_build_step_reports_its_stages_up_to_the_whole(capsys):
    grid = rho1_slice(step=1.0)
    field = compute_field(PAPER_GEOMETRY, grid)
    steps = {
        "field": lambda p: compute_field(PAPER_GEOMETRY, grid, progress=p),
        "segmentation": lambda p: segment(field, progress=p),
        "roadmap": lambda p: build_roadmap(PAPER_GEOMETRY, grid, progress=p),
        "refinement": lambda p: refine(PAPER_GEOMETRY, grid, progress=p),
    }
    for name, build in steps.items():
        calls = _calls(build)
        assert calls and _non_decreasing_to_one(calls), name
    stages = {stage for stage, _ in _calls(steps["roadmap"])}
    assert {"n-solution field", "regions", "patches", "done"} <= stages
    assert all(s.startswith("refinement: ") for s, _ in _calls(steps["refinement"]))
    # The core prints nothing.
    assert capsys.readouterr() == ("", "")


def test_the_cache_reports_a_build_and_not_a_load(tmp_path):
    grid = rho1_slice(step=1.0)
    built = _calls(lambda p: cached_planning(PAPER_GEOMETRY, grid, str(tmp_path), p,
                                             refinement=2))
    assert _non_decreasing_to_one(built) and built[-1] == ("done", 1.0)
    assert {"planning index", "refinement: blocks picked"} <= {s for s, _ in built}
    assert _calls(lambda p: cached_planning(PAPER_GEOMETRY, grid, str(tmp_path), p,
                                            refinement=2)) == []


def test_cusp_curves_report_each_slice():
    slices = [build_roadmap(PAPER_GEOMETRY, rho1_slice(v, step=1.0)) for v in (16.0, 17.0)]
    calls = _calls(lambda p: cusp_curves(slices, progress=p))
    assert _non_decreasing_to_one(calls) and len(calls) == 3


def test_a_terminal_gets_a_bar_redrawn_in_place(monkeypatch):
    monkeypatch.setattr(commands._Progress, "DELAY", 0.0)
    stream = _Terminal()
    progress = commands._Progress(stream)
    progress("n-solution field", 0.25)
    progress("n-solution field", 0.5)
    assert stream.getvalue().count("\r") == 2 and "\n" not in stream.getvalue()
    assert "[##########..........]  50% n-solution field" in stream.getvalue()
    progress("done", 1.0)
    assert stream.getvalue().endswith("\n")
    progress("planning", 0.0)
    progress.close()
    progress.close()
    assert stream.getvalue().endswith("planning (0.0 s)\n")


def test_a_log_gets_a_line_now_and_then_and_at_the_end(monkeypatch):
    monkeypatch.setattr(commands._Progress, "DELAY", 0.0)
    calls = [("n-solution field", 0.1), ("n-solution field", 0.3), ("regions", 0.7),
             ("done", 1.0)]
    lines = {}
    for every in (0.0, 3600.0):
        monkeypatch.setattr(commands._Progress, "LOG_EVERY", every)
        stream = io.StringIO()
        progress = commands._Progress(stream)
        for stage, fraction in calls:
            progress(stage, fraction)
        lines[every] = stream.getvalue().splitlines()
        assert all(line.startswith("rpr3-gwr: [") for line in lines[every])
        assert "\r" not in stream.getvalue()
    assert [line.split("] ")[1].rsplit(" (", 1)[0] for line in lines[0.0]] == [
        stage for stage, _ in calls]
    assert len(lines[3600.0]) == 2
    assert lines[3600.0][0].startswith("rpr3-gwr: [ 10%] n-solution field")
    assert lines[3600.0][1].startswith("rpr3-gwr: [100%] done")


def test_nothing_is_shown_before_the_delay():
    stream = _Terminal()
    progress = commands._Progress(stream)
    progress("n-solution field", 0.5)
    progress("done", 1.0)
    progress.close()
    assert stream.getvalue() == ""


@pytest.mark.parametrize("argv", [["roadmap", "--step", "0.5"],
                                  ["cusps", "--trace", "16", "17", "1", "--step", "1"]])
def test_the_command_line_shows_progress_on_stderr_only(argv, monkeypatch, capsys):
    monkeypatch.setattr(commands._Progress, "DELAY", 0.0)
    assert main(argv) == 0
    out, err = capsys.readouterr()
    json.loads(out)
    lines = err.splitlines()
    assert lines and all(line.startswith("rpr3-gwr: [") for line in lines)
    assert any("n-solution field" in line for line in lines)


def test_drawing_a_roadmaps_figures_is_shown(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(commands._Progress, "DELAY", 0.0)
    field, roadmap = tmp_path / "field.png", tmp_path / "roadmap.png"
    assert main(["roadmap", "--step", "0.5", "--field-figure", str(field),
                 "--roadmap-figure", str(roadmap)]) == 0
    err = capsys.readouterr().err
    assert f"drawing {field}" in err and f"drawing {roadmap}" in err
    assert field.exists() and roadmap.exists()
