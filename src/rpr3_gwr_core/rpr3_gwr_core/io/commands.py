"""The subcommands of ``rpr3-gwr`` (:mod:`.cli` parses their arguments).

Each command imports what only it needs when it runs (the planner, the cache,
the cusps, figures): a fresh process pays for its own command alone.
"""

import json
import math
import os
import sys
import time

import numpy as np

from ..exceptions import GWRError, InvalidInputError
from ..mechanisms import Mechanism, mechanism_from_dict
from ..paper import FULL_BASE_GRID, FULL_REFINEMENT, PAPER_GEOMETRY, rho1_slice
from ..workspace import Grid, build_roadmap
from ..workspace.grid import check_roadmap_grid
from .cli import MAX_LEG

__all__ = ["run"]

# Grid step of the slices of ``cusps --trace`` [length unit].
_TRACE_STEP = 0.25


def run(args):
    """Run the parsed command: ``(JSON-able result, exit code)``."""
    commands = {"dk": lambda a: (_dk(a), 0), "roadmap": lambda a: (_roadmap(a), 0),
                "cusps": lambda a: (_cusps(a), 0), "plan": _plan, "plot": _plot}
    return commands[args.command](args)


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
    from ..workspace.cusps import cusp_curves, find_cusps
    from .cache import cached_roadmap

    _paper_slice_options(args, ("rho1",))
    if args.mechanism is not None and (args.trace or args.step is not None):
        raise InvalidInputError(f"{'--trace' if args.trace else '--step'}: the paper's 3-RPR "
                                "across rho1; with --mechanism the slice is the file's box "
                                "and --fix")
    if args.trace:
        low, high, step = args.trace
        if not (0 < low <= high <= MAX_LEG and step > 0) or (high - low) / step > 1000:
            raise InvalidInputError(f"--trace takes 0 < MIN <= MAX <= {MAX_LEG:g} and a STEP "
                                    "giving at most 1000 slices")
        values = low + step * np.arange(int(math.floor((high - low) / step + 1e-9)) + 1)
        slice_step = _TRACE_STEP if args.step is None else args.step
        slices = [build_roadmap(PAPER_GEOMETRY, rho1_slice(float(v), step=slice_step))
                  for v in values]
        return {"curves": [[c.to_dict(PAPER_GEOMETRY) for c in curve]
                           for curve in cusp_curves(slices)]}
    if args.mechanism is None:
        mechanism, grid = PAPER_GEOMETRY, rho1_slice(args.rho1)
    else:
        described, grid = _file_roadmap(args)
        mechanism = described.mechanism
        # Refused before the roadmap is built: without its own equations the
        # mechanism would fail at the first seed.
        if type(mechanism).refine_cusp is Mechanism.refine_cusp:
            raise InvalidInputError(f"the {mechanism.kind} has no cusp equations: 'cusps' "
                                    "takes mechanisms that have them (the 3-RPR)")
        if grid.ndim != 2:
            raise InvalidInputError(f"cusps are points of 2-D slices: --fix all joints but "
                                    f"two (the grid has {grid.ndim} axes)")
    roadmap, _ = cached_roadmap(mechanism, grid, args.cache_dir, _Progress(sys.stderr))
    try:
        cusps = find_cusps(roadmap)
    except NotImplementedError as exc:
        raise InvalidInputError(f"{exc}: 'cusps' takes mechanisms with cusp equations") from None
    return [c.to_dict(mechanism) for c in cusps]


def _dk(args):
    if args.mechanism is not None:
        from .mechanism_file import load_mechanism_file

        mechanism = load_mechanism_file(args.mechanism).mechanism
    else:
        mechanism = PAPER_GEOMETRY
    names = mechanism.joint_names
    if len(args.joints) != len(names):
        raise InvalidInputError(f"dk takes the {len(names)} joints "
                                f"{' '.join(n.upper() for n in names)} (all required), "
                                f"got {len(args.joints)}")
    joints = np.array([args.joints], dtype=float)
    mechanism.check_joints(joints)
    count, poses = mechanism.solve(joints)
    poses = poses[0, :count[0]]
    signs = mechanism.aspect(poses, np.repeat(joints, len(poses), axis=0)) if len(poses) else []
    return [{**{name: float(v) for name, v in zip(mechanism.pose_names, p)}, "aspect": int(s)}
            for p, s in zip(poses, signs)]


def _full_roadmap(cache_dir):
    """The full 3-DOF roadmap, its planning index, and whether they came from the cache."""
    from .cache import cached_planning

    return cached_planning(PAPER_GEOMETRY, FULL_BASE_GRID, cache_dir, _Progress(sys.stderr),
                           refinement=FULL_REFINEMENT)


def _roadmap(args):
    from .export import roadmap_summary, roadmap_to_gexf, roadmap_to_json

    _paper_slice_options(args, ("rho1", "rho2", "rho3", "step"))
    start = time.perf_counter()
    if args.mechanism is not None:
        from .cache import cached_roadmap
        from .mechanism_file import roadmap_grid

        described, grid = _file_roadmap(args)
        base, refinement = roadmap_grid(grid)
        roadmap, hit = cached_roadmap(described.mechanism, base, args.cache_dir,
                                      _Progress(sys.stderr), refinement=refinement)
        if args.slice_figure:
            raise InvalidInputError("--slice-figure needs --full")
    elif args.full:
        if args.field_figure:
            raise InvalidInputError("--field-figure draws 2-D grids: with --full use "
                                    "--slice-figure")
        roadmap, _, hit = _full_roadmap(args.cache_dir)
    else:
        if args.slice_figure:
            raise InvalidInputError("--slice-figure needs --full")
        grid = rho1_slice(args.rho1, tuple(args.rho2), tuple(args.rho3), args.step)
        check_roadmap_grid(PAPER_GEOMETRY, grid)
        roadmap, hit = build_roadmap(PAPER_GEOMETRY, grid, method=args.method,
                                     progress=_Progress(sys.stderr)), False
    summary = roadmap_summary(roadmap)
    world = None
    if args.scene is not None:
        from ..planning import Planner

        world = _applied(Planner(roadmap), _load_scene(args.scene), args)
        solutions = roadmap.segmentation.patch > 0
        summary["scene"] = {"file": args.scene, "parts": world.n_parts,
                            "blocked_solutions": int((solutions & ~world.free).sum()),
                            "solutions": int(solutions.sum())}
    summary["timings"] = dict(roadmap.timings, total=time.perf_counter() - start)
    summary["from_cache"] = hit
    if args.slice_figure:
        from ..workspace.cusps import find_cusps
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
            _save(args.field_figure, field_figure(roadmap, world))
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


def _paper_slice_options(args, names):
    """Refuse the paper's slice options beside ``--mechanism``, and give the
    others their defaults (the paper's slice: rho1 = 17, legs in [0, 50],
    step 0.125)."""
    given = [f"--{name.replace('_', '-')}" for name in names
             if getattr(args, name, None) is not None]
    if args.mechanism is not None:
        if given or getattr(args, "full", False):
            raise InvalidInputError(f"{', '.join(given) or '--full'}: the paper's 3-RPR; with "
                                    "--mechanism the grid is the file's box and --fix")
        return
    if args.fix:
        raise InvalidInputError("--fix needs --mechanism")
    defaults = {"rho1": 17.0, "rho2": (0.0, 50.0), "rho3": (0.0, 50.0), "step": 0.125}
    for name in names:
        if getattr(args, name) is None:
            setattr(args, name, defaults[name])


def _file_roadmap(args):
    """The :class:`~.mechanism_file.MechanismFile` of ``--mechanism`` and the
    grid of its box and ``--fix``."""
    from .mechanism_file import load_mechanism_file

    described = load_mechanism_file(args.mechanism)
    grid = described.grid(dict(args.fix))
    check_roadmap_grid(described.mechanism, grid)
    return described, grid


def _bodies(args):
    """The body model of ``--mechanism``'s file, None for the defaults."""
    if args.mechanism is None:
        return None
    from .mechanism_file import load_mechanism_file

    return load_mechanism_file(args.mechanism).bodies


def _load_scene(path):
    """The scene of a file, its errors naming the file."""
    from ..world import load_scene

    try:
        return load_scene(path)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{path}: {exc}") from None


def _applied(planner, scene, args):
    """The planner's roadmap restricted to ``--scene``, its errors naming the file."""
    try:
        return planner.apply_scene(scene, _bodies(args))
    except InvalidInputError as exc:
        raise InvalidInputError(f"{args.scene}: {exc}") from None


def _plan(args):
    from ..planning import PlanOptions
    from .cache import cached_planning

    _paper_slice_options(args, ("rho1",))
    if args.mechanism is not None:
        return _plan_on_file(args)
    if args.mode_tol is not None:
        raise InvalidInputError("--mode-tol needs --mechanism; the paper's 3-RPR takes "
                                "--alpha-tol-deg")
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
        roadmap, index, _ = _full_roadmap(args.cache_dir)
        start, goal = tuple(args.start), tuple(args.goal)
        roadmap_doc = {"mechanism": PAPER_GEOMETRY.to_dict(), "full": True}
    else:
        grid = rho1_slice(args.rho1)
        roadmap, index, _ = cached_planning(PAPER_GEOMETRY, grid, args.cache_dir,
                                            _Progress(sys.stderr))
        start, goal = (args.rho1, *args.start), (args.rho1, *args.goal)
        roadmap_doc = {"mechanism": PAPER_GEOMETRY.to_dict(), "grid": grid.to_dict()}
    start = (*start[:3], math.radians(start[3]))
    goal = (*goal[:3], math.radians(goal[3]))
    return _answer(args, roadmap, index, start, goal, options, roadmap_doc)


def _plan_on_file(args):
    from ..planning import PlanOptions
    from .cache import cached_planning
    from .mechanism_file import roadmap_grid

    described, grid = _file_roadmap(args)
    mechanism = described.mechanism
    start, goal = tuple(args.start), tuple(args.goal)
    for name, values in (("start", start), ("goal", goal)):
        if len(values) != mechanism.n_joints + 1:
            raise InvalidInputError(
                f"--{name} takes {' '.join(n.upper() for n in mechanism.joint_names)} and the "
                f"mode coordinate {mechanism.pose_names[mechanism.mode_coordinate].upper()} "
                "(angles in radians)")
    tolerance = {} if args.mode_tol is None else {"mode_tol": args.mode_tol}
    options = PlanOptions(smooth=args.smooth, weighted=args.weighted,
                          feasibility_only=args.feasibility_only,
                          max_velocity=args.max_velocity, max_acceleration=args.max_acceleration,
                          **tolerance)
    base, refinement = roadmap_grid(grid)
    roadmap, index, _ = cached_planning(mechanism, base, args.cache_dir, _Progress(sys.stderr),
                                        refinement=refinement)
    roadmap_doc = {"mechanism": mechanism.to_dict(), "grid": grid.to_dict()}
    return _answer(args, roadmap, index, start, goal, options, roadmap_doc)


def _answer(args, roadmap, index, start, goal, options, roadmap_doc):
    """The plan's JSON and exit code (1 when there is no plan)."""
    from ..planning import NEVER, Planner, Termination

    header = {"roadmap": roadmap_doc, "request": {"start": list(start), "goal": list(goal)}}
    scene = None if args.scene is None else _load_scene(args.scene)
    if scene is not None:
        header["scene"] = scene.to_dict()
    begin = time.perf_counter()
    planner = Planner(roadmap, index)
    # A scene that does not fit the mechanism is bad input, not "no plan".
    world = None if scene is None else _applied(planner, scene, args)
    try:
        termination = NEVER if args.time_limit is None else Termination.after(args.time_limit)
        plan = planner.plan(start, goal, options, termination, world)
        result = dict(header, **plan.to_dict())
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
    if max([a.high for a in grid.axes] + [v for _, v in grid.fixed]) > MAX_LEG:
        raise InvalidInputError(f"the grid of {path} is out of range: legs are at most "
                                f"{MAX_LEG:g} length units")
    return mechanism, grid, plan


def _plot(args):
    from .cache import cached_roadmap
    from .figures import plan_figure

    mechanism, grid, plan = _read_plan(args.plan_file)
    check_roadmap_grid(mechanism, grid)
    roadmap, _ = cached_roadmap(mechanism, grid, args.cache_dir, _Progress(sys.stderr))
    output = args.output or os.path.splitext(args.plan_file)[0] + ".png"
    _save(output, plan_figure(roadmap, plan), dpi=110)
    return {"figure": output}, 0
