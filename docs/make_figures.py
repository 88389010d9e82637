"""Figures and command-line help of the documentation, made by the project's
own code.

Sphinx calls :func:`main` before it reads the pages (``conf.py``), so the
figures always show what the code computes.  Run by hand::

    python docs/make_figures.py docs/_generated          # every figure and help text
    python docs/make_figures.py --overview docs/images   # the README's figure

Everything is drawn on the paper's slice rho1 = 17 at step 0.125 (401 x 401
cells); building it takes about a second once the compiled kernels are in
their cache.
"""

import argparse
import contextlib
import io
import math
import os
import sys

import numpy as np
from matplotlib.figure import Figure

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CONFIG = os.path.join(ROOT, "config")

# The paper's two examples (section 5): (rho1, rho2, rho3, alpha [deg]).
EXAMPLE_1 = ((17.0, 12.0, 18.0, 122.82), (17.0, 10.0, 25.0, -24.24))
EXAMPLE_2 = ((17.0, 20.0, 25.0, 29.47), (17.0, 20.0, 25.0, 96.13))
DPI = 90


def _radians(q):
    return (*q[:3], math.radians(q[3]))


def _paper_setting():
    from rpr3_gwr_core import PAPER_GEOMETRY, PAPER_GRID, Planner, build_roadmap

    roadmap = build_roadmap(PAPER_GEOMETRY, PAPER_GRID)
    return roadmap, Planner(roadmap)


def _margin_figure(roadmap, plan, clearance):
    """Signed margin along a plan's waypoints, with the clearance band."""
    margins = roadmap.mechanism.margin(plan.poses, plan.joints)
    legs = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(plan.joints, axis=0),
                                                           axis=1))])
    fig = Figure(figsize=(7, 3.2))
    ax = fig.add_subplot()
    ax.axhspan(-clearance, clearance, color="tab:red", alpha=0.15,
               label=f"|margin| < clearance ({clearance:g})")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.plot(legs, margins, "o-", ms=3, label="signed margin of the waypoints")
    ax.set_xlabel("distance travelled by the legs [length unit]")
    ax.set_ylabel("signed margin [1]")
    ax.set_title("paper example 1: the sign (the aspect) never changes")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return fig


def _layers_figure(roadmap, region):
    """The orientation alpha of each patch (layer) of one region."""
    seg = roadmap.segmentation
    grid = seg.field.grid
    patches = sorted((p for p in seg.patches.values() if p.region == region),
                     key=lambda p: p.layer)
    (u, v) = grid.axes
    extent = (u.low - u.step / 2, u.high + u.step / 2, v.low - v.step / 2, v.high + v.step / 2)
    i, j = np.unravel_index(np.concatenate([p.cells for p in patches]), grid.shape)
    window = (u.low + u.step * (i.min() - 4), u.low + u.step * (i.max() + 4),
              v.low + v.step * (j.min() - 4), v.low + v.step * (j.max() + 4))
    fig = Figure(figsize=(3.0 * len(patches), 3.4))
    for k, patch in enumerate(patches, start=1):
        image = np.full(grid.shape, np.nan)
        i, j = np.unravel_index(patch.cells, grid.shape)
        image[i, j] = np.degrees(seg.field.poses[patch.cells, patch.slots, 2])
        ax = fig.add_subplot(1, len(patches), k)
        shown = ax.imshow(image.T, origin="lower", extent=extent, cmap="twilight",
                          vmin=-180.0, vmax=180.0)
        sign = "+" if patch.aspect > 0 else "-"
        ax.axis(window)
        ax.set_title(f"patch {patch.id}: layer {patch.layer}, aspect {sign}", fontsize=9)
        ax.set_xlabel("rho2")
        if k == 1:
            ax.set_ylabel("rho3")
    fig.colorbar(shown, ax=fig.axes, label="alpha [deg]", shrink=0.8)
    fig.suptitle(f"the {len(patches)} patches of region {region}: one solution sheet each")
    return fig


def _save(fig, folder, name):
    fig.savefig(os.path.join(folder, name), dpi=DPI)


def cli_help(folder):
    """Write the ``--help`` text of ``rpr3-gwr`` and of each subcommand to
    ``folder``, as ``cli_<command>.txt``, for the command-line reference."""
    from rpr3_gwr_core.io.cli import main as cli

    os.makedirs(folder, exist_ok=True)
    # argparse wraps to the terminal's width; the page's is fixed.
    columns = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "88"
    try:
        for command in ("", "dk", "roadmap", "plan", "plot", "cusps"):
            text = io.StringIO()
            with contextlib.redirect_stdout(text), contextlib.suppress(SystemExit):
                cli([command, "--help"] if command else ["--help"])
            with open(os.path.join(folder, f"cli_{command or 'rpr3-gwr'}.txt"), "w") as out:
                out.write(text.getvalue())
    finally:
        if columns is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = columns


def main(folder):
    """Write every figure of the pages to ``folder`` (created if needed).

    Parameters
    ----------
    folder : str
        Output folder; existing figures are replaced.
    """
    from rpr3_gwr_core.io.figures import field_figure, plan_figure, roadmap_figure
    from rpr3_gwr_core.planning import DEFAULT_CLEARANCE, PlanOptions
    from rpr3_gwr_core.world import load_scene

    os.makedirs(folder, exist_ok=True)
    roadmap, planner = _paper_setting()
    _save(field_figure(roadmap), folder, "field.png")
    _save(roadmap_figure(roadmap), folder, "roadmap.png")
    _save(_layers_figure(roadmap, 2), folder, "layers.png")
    options = PlanOptions(smooth=True)
    first = planner.plan(_radians(EXAMPLE_1[0]), _radians(EXAMPLE_1[1]), options)
    _save(plan_figure(roadmap, first.to_dict()), folder, "plan_example1.png")
    second = planner.plan(_radians(EXAMPLE_2[0]), _radians(EXAMPLE_2[1]), options)
    _save(plan_figure(roadmap, second.to_dict()), folder, "plan_example2.png")
    _save(_margin_figure(roadmap, first, DEFAULT_CLEARANCE), folder, "margin.png")
    world = planner.apply_scene(load_scene(os.path.join(CONFIG, "scenes",
                                                        "paper_example1_blocked.yaml")))
    _save(field_figure(roadmap, world), folder, "scene.png")
    cli_help(folder)


def overview(folder):
    """Write the README's figure, ``overview.png``: the paper's first example
    over the n-solution field and on its solution sheets."""
    roadmap, planner = _paper_setting()
    from rpr3_gwr_core.io.figures import plan_figure
    from rpr3_gwr_core.planning import PlanOptions

    plan = planner.plan(_radians(EXAMPLE_1[0]), _radians(EXAMPLE_1[1]), PlanOptions(smooth=True))
    os.makedirs(folder, exist_ok=True)
    plan_figure(roadmap, plan.to_dict()).savefig(os.path.join(folder, "overview.png"), dpi=80)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--overview", action="store_true",
                        help="write only the README's figure, overview.png")
    args = parser.parse_args()
    sys.path[:0] = [os.path.join(ROOT, "src", "rpr3_gwr_core")]
    (overview if args.overview else main)(args.folder)
