"""The ``rpr3-gwr`` command-line tool.

Subcommands::

    rpr3-gwr dk RHO1 RHO2 RHO3
    rpr3-gwr roadmap [--rho1 17] [--rho2 MIN MAX] [--rho3 MIN MAX] [--step 0.125]
                     [--method components|rds] [-o FILE] [--gexf FILE]
                     [--field-figure FILE] [--roadmap-figure FILE]

Results go to stdout as JSON; bad arguments exit with code 2 and one line on
stderr; progress is shown on stderr when it is a terminal.
"""

import argparse
import json
import math
import sys
import time

import numpy as np

from .exceptions import GWRError
from .field import Grid
from .geometry import PAPER_GEOMETRY
from .kinematics import aspect, direct_kinematics
from .roadmap import build_roadmap

__all__ = ["main"]


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


def _parser():
    parser = _Parser(prog="rpr3-gwr", description="Global workspace roadmap of the 3-RPR.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    dk = sub.add_parser("dk", help="all direct-kinematic solutions of (rho1, rho2, rho3)")
    for name in ("rho1", "rho2", "rho3"):
        dk.add_argument(name, type=_finite)
    roadmap = sub.add_parser("roadmap", help="build the roadmap and print a JSON summary")
    roadmap.add_argument("--rho1", type=_finite, default=17.0)
    roadmap.add_argument("--rho2", type=_finite, nargs=2, default=(0.0, 50.0), metavar=("MIN", "MAX"))
    roadmap.add_argument("--rho3", type=_finite, nargs=2, default=(0.0, 50.0), metavar=("MIN", "MAX"))
    roadmap.add_argument("--step", type=_finite, default=0.125)
    roadmap.add_argument("--method", choices=("components", "rds"), default="components")
    roadmap.add_argument("-o", "--output", help="write the full roadmap JSON (with field) here")
    roadmap.add_argument("--gexf", help="write the roadmap graph as GEXF here")
    roadmap.add_argument("--field-figure", help="write the n-solution field figure here (PNG, PDF, SVG)")
    roadmap.add_argument("--roadmap-figure", help="write the roadmap graph figure here")
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


def _dk(args):
    poses = direct_kinematics(np.array([args.rho1, args.rho2, args.rho3]), PAPER_GEOMETRY)
    signs = aspect(poses, PAPER_GEOMETRY) if len(poses) else []
    return [{"x": float(p[0]), "y": float(p[1]), "alpha": float(p[2]), "aspect": int(s)}
            for p, s in zip(poses, signs)]


def _roadmap(args):
    from .export import roadmap_summary, roadmap_to_gexf, roadmap_to_json

    grid = Grid(rho1=args.rho1, rho2_range=tuple(args.rho2), rho3_range=tuple(args.rho3),
                step=args.step)
    start = time.perf_counter()
    roadmap = build_roadmap(PAPER_GEOMETRY, grid, method=args.method,
                            progress=_Progress(sys.stderr))
    summary = roadmap_summary(roadmap)
    summary["timings"] = dict(roadmap.timings, total=time.perf_counter() - start)
    if args.output:
        with open(args.output, "w", encoding="utf-8") as out:
            out.write(roadmap_to_json(roadmap))
    if args.gexf:
        with open(args.gexf, "w", encoding="utf-8") as out:
            out.write(roadmap_to_gexf(roadmap))
    if args.field_figure or args.roadmap_figure:
        from .figures import field_figure, roadmap_figure

        if args.field_figure:
            field_figure(roadmap).savefig(args.field_figure, dpi=120)
        if args.roadmap_figure:
            roadmap_figure(roadmap).savefig(args.roadmap_figure, dpi=120)
    return summary


def main(argv=None):
    """Entry point of ``rpr3-gwr``; returns the process exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        result = _dk(args) if args.command == "dk" else _roadmap(args)
    except GWRError as exc:
        parser.exit(2, f"{parser.prog}: error: {exc}\n")
    except OSError as exc:
        parser.exit(2, f"{parser.prog}: error: {exc.strerror}: {exc.filename}\n")
    json.dump(result, sys.stdout, indent=1)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
