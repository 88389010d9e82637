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


# The mechanism files drawn on the page of drawings, each at the joints given
# (the 3-RPR's: the paper's first example; the others': where no two bodies
# cross and the labels keep apart), in its assembly mode nearest the mode
# coordinate given [rad, or length unit for the five-bar's y].
MECHANISM_DRAWINGS = (
    ("paper_3rpr", (17.0, 12.0, 18.0), math.radians(122.82)),
    ("three_rrr", (math.radians(116.0), math.radians(90.0), math.radians(159.0)), 1.153),
    ("three_prr", (9.75, 10.25, 19.75), -0.062),
    ("five_bar", (math.radians(110.0), math.radians(60.0)), 0.1485),
)
_LINK_COLOUR, _PLATFORM_COLOUR, _NOTE_COLOUR = "tab:blue", "tab:orange", "tab:red"


def _solution(mechanism, joints, mode):
    """The pose of ``joints`` whose mode coordinate is nearest ``mode``."""
    count, poses = mechanism.solve(np.array([joints], dtype=float))
    poses = poses[0, :count[0]]
    gap = poses[:, mechanism.mode_coordinate] - mode
    if mechanism.angular[mechanism.mode_coordinate]:
        gap = np.angle(np.exp(1j * gap))
    return poses[np.argmin(np.abs(gap))]


def _cross(u, v):
    """The z component of the cross product of two plane vectors."""
    return u[0] * v[1] - u[1] * v[0]


def _arc(ax, centre, start, end, radius, label, colour=_NOTE_COLOUR):
    """An angle from direction ``start`` to ``end`` [rad] at a point, as an
    arc with an arrow head and its label beyond the middle."""
    from matplotlib.patches import FancyArrowPatch

    angles = np.linspace(start, end, 40)
    arc = np.asarray(centre) + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    ax.plot(*arc[:-1].T, color=colour, lw=1)
    ax.add_patch(FancyArrowPatch(arc[-2], arc[-1], arrowstyle="-|>", mutation_scale=9,
                                 color=colour, lw=1))
    middle = 0.5 * (start + end)
    ax.text(*(np.asarray(centre) + 1.35 * radius * np.array([np.cos(middle), np.sin(middle)])),
            label, color=colour, ha="center", va="center", fontsize=10)


def _along(ax, a, b, label, side=1.0, colour="k", scale=1.0):
    """A label beside the middle of the segment from ``a`` to ``b``."""
    a, b = np.asarray(a), np.asarray(b)
    direction = (b - a) / max(np.linalg.norm(b - a), 1e-12)
    normal = side * np.array([-direction[1], direction[0]])
    ax.text(*(0.5 * (a + b) + 0.06 * scale * normal), label, color=colour, ha="center",
            va="center", fontsize=10,
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8})


def _mechanism_drawing(name, joints, mode):
    """A labelled drawing of the mechanism of ``config/<name>.yaml`` at some
    joints: its bodies (:meth:`Mechanism.body_outline`), its joint points by
    name, its parameters (the file's, ``Mechanism.to_dict``) on the bodies
    they measure, the joints and the pose."""
    from matplotlib.patches import Polygon
    from rpr3_gwr_core.io.mechanism_file import load_mechanism_file

    described = load_mechanism_file(os.path.join(CONFIG, f"{name}.yaml"))
    mechanism = described.mechanism
    parameters = mechanism.to_dict()
    kind = parameters["kind"]
    pose = _solution(mechanism, joints, mode)
    links, plates, _ = mechanism.body_outline(pose[None], np.array([joints], dtype=float))
    points = {}
    for _, _, ends, a, b, _ in links:
        points.update({ends[0]: a[0], ends[1]: b[0]})
    for _, names, vertices in plates:
        points.update(zip(names, vertices[0]))
    everything = np.array(list(points.values()))
    scale = float(np.max(np.ptp(everything, axis=0)))
    fig = Figure(figsize=(7.5, 6.2))
    ax = fig.add_subplot()
    fig.subplots_adjust(left=0.03, right=0.97, bottom=0.03, top=0.85)
    for _, _, vertices in plates:
        ax.add_patch(Polygon(vertices[0], fc=_PLATFORM_COLOUR, ec=_PLATFORM_COLOUR, alpha=0.3,
                             lw=2))
    centre = everything.mean(axis=0)
    angle = {}
    for link, leg, ends, a, b, prismatic in links:
        a, b = a[0], b[0]
        ax.plot(*np.stack([a, b]).T, "-", color=_LINK_COLOUR, lw=6 if prismatic else 3,
                solid_capstyle="round", alpha=0.8 if prismatic else 1.0)
        if prismatic:  # the rod of a prismatic leg, thinner
            ax.plot(*np.stack([a, b]).T, "-", color="white", lw=2)
        angle[ends] = math.atan2(*(b - a)[::-1])
        # Labels on the side away from the drawing's centre.
        side = 1.0 if _cross(b - a, centre - a) < 0 else -1.0
        if kind == "3-RPR":
            label = mechanism.joint_names[leg]
        elif link.startswith("proximal"):
            label = mechanism.joint_names[leg] if kind == "3-PRR" else "l1"
        else:
            label = "l" if kind == "3-PRR" else "l2"
        _along(ax, a, b, label, side, scale=scale)
    # The base: its points, the sliders' rails and the actuated angles.
    bases = sorted(n for n in points if n.startswith("A"))
    reach = 0.12 * scale
    for n in bases:
        i = int(n[1:]) - 1
        a = points[n]
        ax.plot(*a, marker="^", ms=14, color="0.3", ls="none", zorder=3)
        key = f"a{i + 1}"
        text = (f"{n} = {key} ({a[0]:g}, {a[1]:g})" if key in parameters
                else f"{n} ({a[0]:g}, {a[1]:g})")
        ax.annotate(text, a, xytext=(0, -16), textcoords="offset points", ha="center",
                    va="top", fontsize=9)
        if kind == "3-PRR":
            gamma = parameters[f"gamma{i + 1}"]
            direction = np.array([math.cos(gamma), math.sin(gamma)])
            # The rail: the stroke of the slider, the file's range of its joint.
            stroke = described.axes[i]
            rail = np.stack([a + stroke.low * direction, a + stroke.high * direction])
            ax.plot(*rail.T, "--", color="0.4", lw=1.2)
            ax.annotate(f"{mechanism.joint_names[i]} in [{stroke.low:g}, {stroke.high:g}]",
                        rail[1], xytext=(4, 4), textcoords="offset points", fontsize=9,
                        color="0.3")
            ax.plot(*np.stack([a, a + reach * 1.6 * np.array([1.0, 0.0])]).T, ":", color="0.4")
            if abs(gamma) > 1e-9:
                _arc(ax, a, 0.0, gamma, reach, f"gamma{i + 1}")
        elif kind in ("3-RRR", "5R"):
            ax.plot(*np.stack([a, a + reach * 1.6 * np.array([1.0, 0.0])]).T, ":", color="0.4")
            _arc(ax, a, 0.0, joints[i], reach, mechanism.joint_names[i])
    if kind == "5R":
        _along(ax, points["A1"], points["A2"], "d", -1.0, scale=scale)
        ax.plot(*np.stack([points["A1"], points["A2"]]).T, "-", color="0.3", lw=1)
    # The moving joints and the pose point.
    for n, at in points.items():
        if n in bases:
            continue
        ax.plot(*at, "o", ms=7, mfc="white", mec="k", zorder=4)
        ax.annotate(n, at, xytext=(7, 7), textcoords="offset points", fontsize=10,
                    fontweight="bold")
    pose_point = points["B1"] if "B1" in points else points["P"]
    names = mechanism.pose_names
    ax.annotate(f"({names[0]}, {names[1]})", pose_point, xytext=(7, -7),
                textcoords="offset points", va="top", fontsize=9, color=_PLATFORM_COLOUR)
    if plates:
        b1, b2, b3 = (points[f"B{k}"] for k in (1, 2, 3))
        inside = (b1 + b2 + b3) / 3
        for far, key in ((b2, "d1"), (b3, "d3")):
            side = 1.0 if _cross(far - b1, inside - b1) < 0 else -1.0
            _along(ax, b1, far, key, side, colour="tab:brown", scale=scale)
        alpha, beta = pose[2], parameters["beta"]
        _arc(ax, b1, alpha, alpha + beta, 0.1 * scale, "beta", colour="tab:brown")
        ax.plot(*np.stack([b1, b1 + 0.18 * scale * np.array([1.0, 0.0])]).T, ":",
                color=_PLATFORM_COLOUR)
        _arc(ax, b1, 0.0, alpha, 0.16 * scale, "alpha", colour=_PLATFORM_COLOUR)
    values = []
    for key, value in parameters.items():
        if key == "kind":
            continue
        if key in mechanism.angle_parameters:
            values.append(f"{key} = {math.degrees(value):.2f} deg")
        elif isinstance(value, (list, tuple)):
            values.append(f"{key} = ({', '.join(f'{v:g}' for v in value)})")
        else:
            values.append(f"{key} = {value:g}")
    shown = ", ".join(
        f"{n} = {math.degrees(q):.0f} deg" if mechanism.angular_joints[k] else f"{n} = {q:g}"
        for k, (n, q) in enumerate(zip(mechanism.joint_names, joints)))
    lines = [""]
    for value in values:  # wrapped between the parameters, not inside one
        if lines[-1] and len(lines[-1]) + len(value) > 88:
            lines.append("")
        lines[-1] += (", " if lines[-1] else "") + value
    ax.set_title(f"{kind} (config/{name}.yaml)\n" + "\n".join(lines) + f"\ndrawn at {shown}",
                 fontsize=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.12)
    ax.set_axis_off()
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
        for command in ("", "dk", "ik", "roadmap", "plan", "plot", "cusps"):
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
    from rpr3_gwr_core.figures import field_figure, plan_figure, roadmap_figure
    from rpr3_gwr_core.planning import DEFAULT_CLEARANCE, PlanOptions
    from rpr3_gwr_core.io.scene_file import load_scene

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
    for name, joints, mode in MECHANISM_DRAWINGS:
        _save(_mechanism_drawing(name, joints, mode), folder, f"mechanism_{name}.png")
    cli_help(folder)


def overview(folder):
    """Write the README's figure, ``overview.png``: the paper's first example
    over the n-solution field and on its solution sheets."""
    roadmap, planner = _paper_setting()
    from rpr3_gwr_core.figures import plan_figure
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
