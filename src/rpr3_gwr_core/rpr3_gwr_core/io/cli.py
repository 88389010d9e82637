"""The ``rpr3-gwr`` command-line tool.

Subcommands::

    rpr3-gwr dk RHO1 RHO2 RHO3
    rpr3-gwr dk --mechanism FILE.yaml JOINT [JOINT ...]        (angular joints in degrees)
    rpr3-gwr roadmap [--rho1 17] [--rho2 MIN MAX] [--rho3 MIN MAX] [--step 0.125]
                     [--method components|rds] [-o FILE] [--gexf FILE]
                     [--field-figure FILE] [--roadmap-figure FILE]
    rpr3-gwr roadmap --full [--cache-dir DIR] [--gexf FILE] [--roadmap-figure FILE]
                     [--slice-figure FILE] [--slice-rho1 17]
    rpr3-gwr plan --rho1 17 --start RHO2 RHO3 ALPHA_DEG --goal RHO2 RHO3 ALPHA_DEG
                  [--no-smooth] [--weighted] [--clearance 0.02] [--feasibility-only]
                  [--max-velocity V --max-acceleration A [--joint-limit NAME=V,A ...]]
                  [--time-limit SECONDS] [-o FILE]
    rpr3-gwr plan --full --start RHO1 RHO2 RHO3 ALPHA_DEG --goal RHO1 RHO2 RHO3 ALPHA_DEG
                  [the options above]
    rpr3-gwr plan --mechanism FILE.yaml [--fix NAME=VALUE ...] --start JOINT ... MODE
                  --goal JOINT ... MODE [--mode-tol TOL] [the options above]
    rpr3-gwr plan [--mechanism FILE.yaml ...] --start-pose X Y [ALPHA_DEG]
                  --goal-pose X Y [ALPHA_DEG] [--start-working-mode=SIGNS]
                  [--goal-working-mode=SIGNS] [the options above]
                  (either end may be --start or --goal instead)
    rpr3-gwr ik [--mechanism FILE.yaml] X Y [ALPHA_DEG]
    rpr3-gwr plot PLAN.json [-o FIGURE]
    rpr3-gwr cusps [--rho1 17] [--cache-dir DIR]
    rpr3-gwr cusps --mechanism FILE.yaml --fix NAME=VALUE [...] [--cache-dir DIR]
    rpr3-gwr cusps --trace RHO1_MIN RHO1_MAX RHO1_STEP [--step 0.25]

Angles are in degrees, in the arguments and in the answers (:data:`ANGLES`);
results go to stdout as JSON; bad arguments exit with code 2 and one line on
stderr (legs longer than 1e6 length units, a grid over
:data:`~rpr3_gwr_core.workspace.grid.MAX_GRID_CELLS` cells or one that cannot
give a roadmap, a file that cannot be read or written); a plan that cannot be
made prints an ``error`` object with a code and a message and exits with 1;
builds that take seconds show their progress on stderr (a bar on a terminal,
log lines otherwise), never on stdout.
``--mechanism FILE.yaml`` names a robot of one's own
(:mod:`~rpr3_gwr_core.io.mechanism_file`) instead of the paper's 3-RPR;
``cusps`` takes it when it has cusp equations.
``plan``, ``plot`` and ``cusps`` keep built roadmaps in the cache of
:mod:`~rpr3_gwr_core.cache` (``--cache-dir``).  ``--full`` takes the full
3-DOF roadmap, all three legs free (:data:`~rpr3_gwr_core.paper.FULL_BASE_GRID`
refined :data:`~rpr3_gwr_core.paper.FULL_REFINEMENT` times), from the cache.
"""

import argparse
import json
import math
import os
import sys

from ..exceptions import GWRError
from .limits import MAX_LEG
from .paths import default_cache_dir

__all__ = ["main", "ANGLES"]

ANGLES = ("Angles are in degrees [deg], in the arguments and in the JSON answer (its keys "
          "that hold angles end in _deg; 'columns' names the entries of its joint and pose "
          "lists); lengths in the mechanism's length unit.  The 'mechanism', 'grid' and "
          "'scene' documents it echoes keep the core's units (radians), as files and "
          "messages carry them.")
"""The unit rule of every command (their ``--help``): the core and the ROS
interfaces work in radians, the command line converts."""


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


def _clearance(text):
    value = _finite(text)
    if not 0 <= value < 1:
        raise argparse.ArgumentTypeError(f"a clearance lies in [0, 1), got {text!r}")
    return value


def _leg(text):
    value = _finite(text)
    if value > MAX_LEG:
        raise argparse.ArgumentTypeError(f"{text!r} is out of range: legs are at most "
                                         f"{MAX_LEG:g} length units")
    return value


def _duration(text):
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} is negative: give a duration in seconds")
    return value


def _count(text):
    """A non-negative integer."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} is negative")
    return value


def _fixed_joint(text):
    """``NAME=VALUE`` of ``--fix``."""
    name, equals, value = text.partition("=")
    if not equals or not name:
        raise argparse.ArgumentTypeError(f"{text!r} is not NAME=VALUE")
    return name, _finite(value)


def _joint_limit(text):
    """``NAME=V,A`` of ``--joint-limit``."""
    name, equals, values = text.partition("=")
    velocity, comma, acceleration = values.partition(",")
    if not (equals and comma and name):
        raise argparse.ArgumentTypeError(f"{text!r} is not NAME=V,A")
    limits = _finite(velocity), _finite(acceleration)
    if min(limits) < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: limits are 0 (keep the one for all "
                                         "joints) or positive")
    return name, *limits


def _mechanism_options(command):
    command.add_argument("--mechanism", metavar="FILE.yaml",
                         help="a robot of your own (config/*.yaml): the roadmap covers the "
                              "file's box of joints instead of the paper's 3-RPR slice")
    command.add_argument("--fix", type=_fixed_joint, action="append", default=[],
                         metavar="NAME=VALUE",
                         help="with --mechanism: a joint held fixed (repeatable) [length "
                              "unit, deg for an angle]; the others are the roadmap's axes")
    command.add_argument("--thin-refinement", type=_count, metavar="N",
                         help="fine points per cell where a slice's roadmap refines its "
                              "thin regions, strips a few cells wide that may go on narrower "
                              "than a cell (default 4); 0 leaves the grid as it is")


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
    parser = _Parser(prog="rpr3-gwr", epilog=ANGLES,
                     description="Global workspace roadmap of a planar parallel mechanism "
                                 "(the paper's 3-RPR unless --mechanism names another).")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def command(name, text):
        return sub.add_parser(name, help=text, description=text, epilog=ANGLES)

    dk = command("dk", "all direct-kinematic solutions (assembly modes) of (rho1, rho2, "
                       "rho3), or of the joints of --mechanism: each pose [length unit, deg], "
                       "its aspect and its signed margin; with --patches or --from, where each "
                       "lies on the roadmap and which a singularity-free path reaches")
    dk.add_argument("joints", type=_leg, nargs="+", metavar="JOINT",
                    help="RHO1 RHO2 RHO3 [length unit], or with --mechanism every joint of "
                         "the file [length unit, deg for an angle]")
    _mechanism_options(dk)
    dk.add_argument("--patches", action="store_true",
                    help="each mode's patch, region and layer on the roadmap the planner "
                         "uses: the slice through the first joint's value (or --fix), or "
                         "with --full the full roadmap (cached)")
    dk.add_argument("--from", type=_finite, dest="start_mode", metavar="MODE",
                    help="the mode coordinate of the mode to start from [length unit, deg "
                         "for an angle] (implies --patches): each mode's feasibility from it, "
                         "and for each one a path reaches, the plan command that plans it")
    dk.add_argument("--full", action="store_true",
                    help="with --patches: the full roadmap (the paper's, or the file's box)")
    dk.add_argument("--cache-dir", default=default_cache_dir())
    ik = command("ik", "every working mode of a platform pose (the inverse kinematics): "
                       "its branch sign per leg (+ or -), its joints [length unit, deg], "
                       "aspect and signed margin, and whether the joints lie in the box "
                       "(the file's, or the paper's full roadmap's)")
    ik.add_argument("pose", type=_finite, nargs="+", metavar="X Y [ALPHA_DEG]",
                    help="the pose: the platform vertex B1 and the orientation alpha [length "
                         "unit, deg], or the five-bar's end point X Y")
    ik.add_argument("--mechanism", metavar="FILE.yaml",
                    help="a robot of your own (config/*.yaml) instead of the paper's 3-RPR")
    roadmap = command("roadmap", "build the roadmap and print a JSON summary (its cusps' "
                                 "angles [deg])")
    # The paper's slice; defaults filled in by the command, so that a
    # --mechanism run can refuse them.
    roadmap.add_argument("--rho1", type=_leg, help="[length unit] default 17")
    for leg in ("--rho2", "--rho3"):
        roadmap.add_argument(leg, type=_leg, nargs=2, metavar=("MIN", "MAX"),
                             help="[length unit] default 0 50")
    roadmap.add_argument("--step", type=_finite, help="[length unit] default 0.125")
    _mechanism_options(roadmap)
    roadmap.add_argument("--method", choices=("components", "rds"), default="components")
    roadmap.add_argument("-o", "--output",
                         help="write the full roadmap JSON (with field) here, in the core's "
                              "units (radians)")
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
                         help="with --full: rho1 of the slice figure [length unit]")
    roadmap.add_argument("--cache-dir", default=default_cache_dir())
    roadmap.add_argument("--scene", metavar="FILE.yaml",
                         help="a scene of obstacles and limits: the summary counts the parts "
                              "it leaves, the field figure hatches what it blocks")
    plan = command("plan", "plan a singularity-free path between two configurations, each "
                           "its joints and the mode coordinate [length unit, deg]; the "
                           "answer gives the signed_margin of its ends (its sign the aspect) "
                           "and the path's min_abs_margin")
    plan.add_argument("--rho1", type=_leg, help="[length unit] default 17")
    plan.add_argument("--step", type=_finite,
                      help="[length unit] default 0.125: the slice's cell size; a finer grid "
                           "sees ways narrower than a cell, as along a fold")
    _mechanism_options(plan)
    plan.add_argument("--full", action="store_true",
                      help="plan on the full 3-DOF roadmap: --start and --goal give rho1 first")
    for end in ("start", "goal"):
        given = plan.add_mutually_exclusive_group(required=True)
        given.add_argument(f"--{end}", type=_finite, nargs="+",
                           metavar="[RHO1] RHO2 RHO3 ALPHA_DEG",
                           help="the legs [length unit] (RHO1 with --full) and alpha [deg]; "
                                "with --mechanism every joint, then the mode coordinate "
                                "[length unit, deg for an angle]" if end == "start"
                           else "as --start")
        given.add_argument(f"--{end}-pose", type=_finite, nargs="+", metavar="X Y [ALPHA_DEG]",
                           help=f"the {end} as a platform pose instead: B1 and alpha [length "
                                "unit, deg] (the five-bar: its end point X Y); the working "
                                "mode is the one a path reaches, of largest margin, unless "
                                f"--{end}-working-mode names one")
        plan.add_argument(f"--{end}-working-mode", metavar="SIGNS",
                          help=f"with --{end}-pose: each leg's branch, + or - (the output of "
                               f"'rpr3-gwr ik'), written --{end}-working-mode=-+- when it "
                               "starts with -")
    plan.add_argument("--smooth", action=argparse.BooleanOptionalAction, default=True,
                      help="shortcut, pull taut (on a roadmap of all the joints) and round "
                           "the path, each step kept only if it validates; --no-smooth gives "
                           "the validated path through the roadmap's cells as it is "
                           "(default: smooth)")
    plan.add_argument("--weighted", action="store_true", help="rank global paths by weighted cost")
    plan.add_argument("--clearance", type=_clearance,
                      help="margin (normalised |det Jx|) the path keeps from the singular "
                           "locus wherever the roadmap allows, in [0, 1): larger keeps "
                           "farther and is longer, 0 the shortest (default: the "
                           "planner's, 0.02)")
    plan.add_argument("--feasibility-only", action="store_true",
                      help="answer from the roadmap alone, without a trajectory")
    plan.add_argument("--max-velocity", type=_finite,
                      help="joint speed limit [length unit/s, deg/s for angular joints]")
    plan.add_argument("--max-acceleration", type=_finite,
                      help="joint acceleration limit [length unit/s^2, deg/s^2 for angular "
                           "joints]")
    plan.add_argument("--joint-limit", type=_joint_limit, action="append", default=[],
                      metavar="NAME=V,A",
                      help="with --max-velocity and --max-acceleration: the speed and "
                           "acceleration limits of one joint, in its unit (deg for an "
                           "angle), 0 keeping the one for all joints; repeat for others")
    plan.add_argument("--alpha-tol-deg", type=_finite, default=1.0,
                      help="tolerance on the start and goal orientations [deg]")
    plan.add_argument("--mode-tol", type=_finite,
                      help="with --mechanism: tolerance on the mode coordinate [length "
                           "unit, deg for an angle]")
    plan.add_argument("--time-limit", type=_duration, metavar="SECONDS",
                      help="stop planning after this long (the roadmap loaded): the valid path "
                           "found by then, or a TIMEOUT error")
    plan.add_argument("--scene", metavar="FILE.yaml",
                      help="plan among its obstacles and within its limits (exit 1 with "
                           "IN_COLLISION or reason blocked when they forbid it)")
    plan.add_argument("-o", "--output", help="also write the JSON here")
    plan.add_argument("--cache-dir", help="roadmap cache (default: %(default)s)",
                      default=default_cache_dir())
    cusps = command("cusps", "the cusp points of the singular curve at rho1: joints and pose "
                             "[length unit, deg] and the regions around each")
    cusps.add_argument("--rho1", type=_leg, help="[length unit] default 17")
    _mechanism_options(cusps)
    cusps.add_argument("--cache-dir", default=default_cache_dir())
    cusps.add_argument("--trace", type=_finite, nargs=3, metavar=("MIN", "MAX", "STEP"),
                       help="trace the cusp curves across rho1 [length unit]: a slice at "
                            "each value from MIN to MAX by STEP")
    cusps.add_argument("--step", type=_finite, help="with --trace: grid step of each slice "
                                                    "[length unit] (default 0.25)")
    plot = command("plot", "draw a plan written by 'rpr3-gwr plan'")
    plot.add_argument("plan_file", metavar="PLAN.json")
    plot.add_argument("-o", "--output", type=_figure,
                      help="figure file (default: PLAN.png beside the plan)")
    plot.add_argument("--cache-dir", default=default_cache_dir())
    return parser


def main(argv=None):
    """Entry point of ``rpr3-gwr``: runs the command of ``argv`` and returns
    the process exit code.

    Without ``argv`` (the process's own arguments, as the console script
    runs it) the process ends once its answer is written and flushed, with
    :func:`os._exit`: the interpreter's teardown would unload the compiled
    kernels one by one, a third of a second and more, for nothing (every file
    is written and closed by then, no thread is left running).
    """
    if argv is not None:
        return _run(argv)
    try:
        code = _run(None)
    except SystemExit as stop:  # argparse's exits: --help and argument errors
        code = stop.code if isinstance(stop.code, int) else int(stop.code is not None)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except BrokenPipeError:
            code = 1
    os._exit(code)


def _run(argv):
    parser = _parser()
    args = parser.parse_args(argv)
    # Imported once the arguments are read: the commands load numpy and the
    # compiled kernels, which ``--help`` and a bad argument need not wait for.
    from . import commands

    try:
        result, code = commands.run(args)
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
