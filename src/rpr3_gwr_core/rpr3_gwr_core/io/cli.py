"""The ``rpr3-gwr`` command-line tool.

Subcommands::

    rpr3-gwr dk RHO1 RHO2 RHO3
    rpr3-gwr roadmap [--rho1 17] [--rho2 MIN MAX] [--rho3 MIN MAX] [--step 0.125]
                     [--method components|rds] [-o FILE] [--gexf FILE]
                     [--field-figure FILE] [--roadmap-figure FILE]
    rpr3-gwr roadmap --full [--cache-dir DIR] [--gexf FILE] [--roadmap-figure FILE]
                     [--slice-figure FILE] [--slice-rho1 17]
    rpr3-gwr plan --rho1 17 --start RHO2 RHO3 ALPHA_DEG --goal RHO2 RHO3 ALPHA_DEG
                  [--smooth] [--weighted] [--feasibility-only]
                  [--max-velocity V --max-acceleration A] [--time-limit SECONDS] [-o FILE]
    rpr3-gwr plan --full --start RHO1 RHO2 RHO3 ALPHA_DEG --goal RHO1 RHO2 RHO3 ALPHA_DEG
                  [the options above]
    rpr3-gwr plot PLAN.json [-o FIGURE]
    rpr3-gwr cusps [--rho1 17] [--cache-dir DIR]
    rpr3-gwr cusps --trace RHO1_MIN RHO1_MAX RHO1_STEP [--step 0.25]

Results go to stdout as JSON; bad arguments exit with code 2 and one line on
stderr (legs longer than 1e6 length units, a grid over
:data:`~rpr3_gwr_core.workspace.grid.MAX_GRID_CELLS` cells or one that cannot
give a roadmap, a file that cannot be read or written); a plan that cannot be
made prints an ``error`` object with a code and a message and exits with 1;
progress is shown on stderr when it is a terminal.
``plan`` and ``plot`` keep built roadmaps in the cache of
:mod:`~rpr3_gwr_core.cache` (``--cache-dir``).  ``--full`` takes the full
3-DOF roadmap, all three legs free (:data:`~rpr3_gwr_core.paper.FULL_BASE_GRID`
refined :data:`~rpr3_gwr_core.paper.FULL_REFINEMENT` times), from the cache.
"""

import argparse
import json
import math
import os
import sys
import time

import numpy as np

from ..exceptions import GWRError, InvalidInputError
from ..mechanisms import mechanism_from_dict
from ..mechanisms.rpr3 import aspect, direct_kinematics
from ..paper import FULL_BASE_GRID, FULL_REFINEMENT, PAPER_GEOMETRY, rho1_slice
from ..planning import NEVER, PlanOptions, Planner, Termination
from ..workspace import Grid, build_roadmap
from ..workspace.cusps import cusp_curves, find_cusps
from ..workspace.grid import check_roadmap_grid
from .cache import cached_roadmap, default_cache_dir

__all__ = ["main"]

# Longest leg the tool takes [length unit].  The direct kinematics weighs the
# squared legs against the geometry's tens of units, so the leg residual of
# its solutions grows with them (3e-7 at 1e6, 4e-3 at 1e10) until its
# polynomial overflows near 1e77.
_MAX_LEG = 1e6


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message}\n")


def _finite(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return value


def _leg(text):
    value = _finite(text)
    if value > _MAX_LEG:
        raise argparse.ArgumentTypeError(f"{text!r} is out of range: legs are at most "
                                         f"{_MAX_LEG:g} length units")
    return value


def _duration(text):
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} is negative: give a duration in seconds")
    return value


def _figure(path):
    """A figure file whose extension, if any, names a format matplotlib writes
    (checked before anything is built)."""
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    extension = os.path.splitext(path)[1][1:].lower()
    if extension and extension not in formats:
        raise argparse.ArgumentTypeError(f"{path}: unknown figure format {extension!r} "
                                         f"(known: {', '.join(sorted(formats))})")
    return path


def _parser():
    parser = _Parser(prog="rpr3-gwr", description="Global workspace roadmap of the 3-RPR.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    dk = sub.add_parser("dk", help="all direct-kinematic solutions of (rho1, rho2, rho3)")
    for name in ("rho1", "rho2", "rho3"):
        dk.add_argument(name, type=_leg)
    roadmap = sub.add_parser("roadmap", help="build the roadmap and print a JSON summary")
    roadmap.add_argument("--rho1", type=_leg, default=17.0)
    for leg in ("--rho2", "--rho3"):
        roadmap.add_argument(leg, type=_leg, nargs=2, default=(0.0, 50.0),
                             metavar=("MIN", "MAX"))
    roadmap.add_argument("--step", type=_finite, default=0.125)
    roadmap.add_argument("--method", choices=("components", "rds"), default="components")
    roadmap.add_argument("-o", "--output", help="write the full roadmap JSON (with field) here")
    roadmap.add_argument("--gexf", help="write the roadmap graph as GEXF here")
    roadmap.add_argument("--field-figure", type=_figure,
                         help="write the n-solution field figure here (PNG, PDF, SVG)")
    roadmap.add_argument("--roadmap-figure", type=_figure,
                         help="write the roadmap graph figure here")
    roadmap.add_argument("--full", action="store_true",
                         help="the full 3-DOF roadmap, all legs free (cached)")
    roadmap.add_argument("--slice-figure", type=_figure,
                         help="with --full: draw the regions of a slice here")
    roadmap.add_argument("--slice-rho1", type=_leg, default=17.0,
                         help="with --full: rho1 of the slice figure")
    roadmap.add_argument("--cache-dir", default=default_cache_dir())
    plan = sub.add_parser("plan", help="plan a singularity-free path between two configurations")
    plan.add_argument("--rho1", type=_leg, default=17.0)
    plan.add_argument("--full", action="store_true",
                      help="plan on the full 3-DOF roadmap: --start and --goal give rho1 first")
    plan.add_argument("--start", type=_finite, nargs="+", required=True,
                      metavar="[RHO1] RHO2 RHO3 ALPHA_DEG")
    plan.add_argument("--goal", type=_finite, nargs="+", required=True,
                      metavar="[RHO1] RHO2 RHO3 ALPHA_DEG")
    plan.add_argument("--smooth", action="store_true", help="shortcut and round the path")
    plan.add_argument("--weighted", action="store_true", help="rank global paths by weighted cost")
    plan.add_argument("--feasibility-only", action="store_true",
                      help="answer from the roadmap alone, without a trajectory")
    plan.add_argument("--max-velocity", type=_finite, help="joint speed limit [length unit/s]")
    plan.add_argument("--max-acceleration", type=_finite,
                      help="joint acceleration limit [length unit/s^2]")
    plan.add_argument("--alpha-tol-deg", type=_finite, default=1.0,
                      help="tolerance on the start and goal orientations [deg]")
    plan.add_argument("--time-limit", type=_duration, metavar="SECONDS",
                      help="stop planning after this long (the roadmap loaded): the valid path "
                           "found by then, or a TIMEOUT error")
    plan.add_argument("-o", "--output", help="also write the JSON here")
    plan.add_argument("--cache-dir", help="roadmap cache (default: %(default)s)",
                      default=default_cache_dir())
    cusps = sub.add_parser("cusps", help="the cusp points of the singular curve at rho1")
    cusps.add_argument("--rho1", type=_leg, default=17.0)
    cusps.add_argument("--cache-dir", default=default_cache_dir())
    cusps.add_argument("--trace", type=_finite, nargs=3, metavar=("MIN", "MAX", "STEP"),
                       help="trace the cusp curves across rho1 (slices at this many values)")
    cusps.add_argument("--step", type=_finite, default=0.25,
                       help="with --trace: grid step of each slice")
    plot = sub.add_parser("plot", help="draw a plan written by 'rpr3-gwr plan'")
    plot.add_argument("plan_file", metavar="PLAN.json")
    plot.add_argument("-o", "--output", type=_figure,
                      help="figure file (default: PLAN.png beside the plan)")
    plot.add_argument("--cache-dir", default=default_cache_dir())
    return parser


class _Progress:
    """Shows stages on a terminal once a build has taken more than a second."""

    def __init__(self, stream):
        self.stream = stream
        self.start = time.perf_counter()
        self.enabled = stream.isatty()

    def __call__(self, stage, fraction):
        elapsed = time.perf_counter() - self.start
        if self.enabled and elapsed > 1.0:
            end = "\n" if fraction >= 1.0 else ""
            self.stream.write(f"\r\x1b[K[{fraction:4.0%}] {stage} ({elapsed:.1f} s)" + end)
            self.stream.flush()


def _cusps(args):
    if args.trace:
        low, high, step = args.trace
        if not (0 < low <= high <= _MAX_LEG and step > 0) or (high - low) / step > 1000:
            raise InvalidInputError(f"--trace takes 0 < MIN <= MAX <= {_MAX_LEG:g} and a STEP "
                                    "giving at most 1000 slices")
        values = low + step * np.arange(int(math.floor((high - low) / step + 1e-9)) + 1)
        slices = [build_roadmap(PAPER_GEOMETRY, rho1_slice(float(v), step=args.step))
                  for v in values]
        return {"curves": [[c.to_dict(PAPER_GEOMETRY) for c in curve]
                           for curve in cusp_curves(slices)]}
    roadmap, _ = cached_roadmap(PAPER_GEOMETRY, rho1_slice(args.rho1), args.cache_dir,
                                _Progress(sys.stderr))
    return [c.to_dict(PAPER_GEOMETRY) for c in find_cusps(roadmap)]


def _dk(args):
    poses = direct_kinematics(np.array([args.rho1, args.rho2, args.rho3]), PAPER_GEOMETRY)
    signs = aspect(poses, PAPER_GEOMETRY) if len(poses) else []
    return [{"x": float(p[0]), "y": float(p[1]), "alpha": float(p[2]), "aspect": int(s)}
            for p, s in zip(poses, signs)]


def _full_roadmap(cache_dir):
    return cached_roadmap(PAPER_GEOMETRY, FULL_BASE_GRID, cache_dir, _Progress(sys.stderr),
                          refinement=FULL_REFINEMENT)


def _roadmap(args):
    from .export import roadmap_summary, roadmap_to_gexf, roadmap_to_json

    start = time.perf_counter()
    if args.full:
        if args.field_figure:
            raise InvalidInputError("--field-figure draws 2-D grids: with --full use "
                                    "--slice-figure")
        roadmap, hit = _full_roadmap(args.cache_dir)
    else:
        if args.slice_figure:
            raise InvalidInputError("--slice-figure needs --full")
        grid = rho1_slice(args.rho1, tuple(args.rho2), tuple(args.rho3), args.step)
        check_roadmap_grid(PAPER_GEOMETRY, grid)
        roadmap, hit = build_roadmap(PAPER_GEOMETRY, grid, method=args.method,
                                     progress=_Progress(sys.stderr)), False
    summary = roadmap_summary(roadmap)
    summary["timings"] = dict(roadmap.timings, total=time.perf_counter() - start)
    summary["from_cache"] = hit
    if args.slice_figure:
        from .figures import slice_figure

        cusps = find_cusps(build_roadmap(PAPER_GEOMETRY, rho1_slice(args.slice_rho1, step=0.25)))
        _save(args.slice_figure, slice_figure(roadmap, {0: args.slice_rho1}, cusps))
    if args.output:
        _save(args.output, roadmap_to_json(roadmap))
    if args.gexf:
        _save(args.gexf, roadmap_to_gexf(roadmap))
    if args.field_figure or args.roadmap_figure:
        from .figures import field_figure, roadmap_figure

        if args.field_figure:
            _save(args.field_figure, field_figure(roadmap))
        if args.roadmap_figure:
            _save(args.roadmap_figure, roadmap_figure(roadmap))
    return summary


def _save(path, content, dpi=120):
    """Writes text or a figure to ``path``; an OS error names the file (a
    failed write or close carries no file name)."""
    try:
        if isinstance(content, str):
            with open(path, "w", encoding="utf-8") as out:
                out.write(content)
        else:
            content.savefig(path, dpi=dpi)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), exc.filename or path) from None


def _plan(args):
    given = 4 if args.full else 3
    for name in ("start", "goal"):
        if len(getattr(args, name)) != given:
            raise InvalidInputError(
                f"--{name} takes {'RHO1 ' if args.full else ''}RHO2 RHO3 ALPHA_DEG"
                f"{'' if args.full else ' (rho1 is --rho1; --full plans with rho1 free)'}")
    options = PlanOptions(smooth=args.smooth, weighted=args.weighted,
                          feasibility_only=args.feasibility_only,
                          max_velocity=args.max_velocity, max_acceleration=args.max_acceleration,
                          mode_tol=math.radians(args.alpha_tol_deg))
    if args.full:
        roadmap, _ = _full_roadmap(args.cache_dir)
        start, goal = tuple(args.start), tuple(args.goal)
        roadmap_doc = {"mechanism": PAPER_GEOMETRY.to_dict(), "full": True}
    else:
        grid = rho1_slice(args.rho1)
        roadmap, _ = cached_roadmap(PAPER_GEOMETRY, grid, args.cache_dir, _Progress(sys.stderr))
        start, goal = (args.rho1, *args.start), (args.rho1, *args.goal)
        roadmap_doc = {"mechanism": PAPER_GEOMETRY.to_dict(), "grid": grid.to_dict()}
    start = (*start[:3], math.radians(start[3]))
    goal = (*goal[:3], math.radians(goal[3]))
    header = {"roadmap": roadmap_doc, "request": {"start": list(start), "goal": list(goal)}}
    begin = time.perf_counter()
    try:
        planner = Planner(roadmap)
        termination = NEVER if args.time_limit is None else Termination.after(args.time_limit)
        result = dict(header, **planner.plan(start, goal, options, termination).to_dict())
        code = 0
    except GWRError as exc:
        result = dict(header, feasible=False, reason=getattr(exc, "reason", exc.code.lower()),
                      error={"code": exc.code, "message": str(exc)})
        code = 1
    result["plan_time_s"] = time.perf_counter() - begin
    if args.output:
        _save(args.output, json.dumps(result))
    return result, code


def _read_plan(path):
    """The mechanism, grid and plan of a file written by ``plan``; what a
    figure reads of the plan is checked (else ``InvalidInputError``)."""
    try:
        with open(path, encoding="utf-8") as stream:
            plan = json.load(stream)
        if plan["roadmap"].get("full"):
            raise InvalidInputError(f"{path} is a --full plan: 'plot' draws plans at fixed "
                                    "rho1 (the waypoints are in the JSON)")
        mechanism = mechanism_from_dict(plan["roadmap"]["mechanism"])
        grid = Grid.from_dict(plan["roadmap"]["grid"])
        if "error" in plan or not plan.get("waypoints"):
            raise InvalidInputError(f"{path} holds no trajectory to draw")
        for name, size in (("joints", mechanism.n_joints), ("pose", mechanism.pose_size)):
            values = np.array([w[name] for w in plan["waypoints"]], dtype=float)
            if values.shape[1:] != (size,) or not np.all(np.isfinite(values)):
                raise ValueError(f"the waypoints' {name} are not {size} finite numbers each")
        paths = plan.get("global_paths") or [[]]
        if not all(isinstance(p, int) for p in paths[max(plan.get("path_index", 0), 0)]):
            raise ValueError("its global path is not a list of patch ids")
    except InvalidInputError:
        raise
    # ValueError: also a file that is not UTF-8 or not JSON.
    except (KeyError, TypeError, AttributeError, ValueError, IndexError) as exc:
        raise InvalidInputError(f"{path} is not a plan written by 'rpr3-gwr plan' "
                                f"({exc})") from None
    if max([a.high for a in grid.axes] + [v for _, v in grid.fixed]) > _MAX_LEG:
        raise InvalidInputError(f"the grid of {path} is out of range: legs are at most "
                                f"{_MAX_LEG:g} length units")
    return mechanism, grid, plan


def _plot(args):
    from .figures import plan_figure

    mechanism, grid, plan = _read_plan(args.plan_file)
    check_roadmap_grid(mechanism, grid)
    roadmap, _ = cached_roadmap(mechanism, grid, args.cache_dir, _Progress(sys.stderr))
    output = args.output or os.path.splitext(args.plan_file)[0] + ".png"
    _save(output, plan_figure(roadmap, plan), dpi=110)
    return {"figure": output}, 0


def main(argv=None):
    """Entry point of ``rpr3-gwr``; returns the process exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    commands = {"dk": lambda a: (_dk(a), 0), "roadmap": lambda a: (_roadmap(a), 0),
                "cusps": lambda a: (_cusps(a), 0),
                "plan": _plan, "plot": _plot}
    try:
        result, code = commands[args.command](args)
    except GWRError as exc:
        parser.exit(2, f"{parser.prog}: error: {exc}\n")
    except OSError as exc:
        where = f"{exc.filename}: " if exc.filename else ""
        parser.exit(2, f"{parser.prog}: error: {where}{exc.strerror or exc}\n")
    try:
        json.dump(result, sys.stdout, indent=1)
        sys.stdout.write("\n")
        sys.stdout.flush()
    except BrokenPipeError:
        # The reader has gone (``| head``): stop quietly as other tools do,
        # with stdout on /dev/null so that the flush at exit cannot fail again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    return code


if __name__ == "__main__":
    sys.exit(main())
