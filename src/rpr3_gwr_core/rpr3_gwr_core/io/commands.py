"""The subcommands of ``rpr3-gwr`` (:mod:`.cli` parses their arguments).

Each command imports what only it needs when it runs (the planner, the cache,
the cusps, figures): a fresh process pays for its own command alone.

Angles are degrees here and radians in the core: the arguments are converted
on the way in, the answers on the way out, for the joints and pose
coordinates the mechanism marks as angles (``Mechanism.angular_joints`` and
``Mechanism.angular``).  A key holding an angle ends in ``_deg``; a list of
joints or pose coordinates is converted entry by entry, its entries named in
the answer's ``columns``.  The documents the core reads back (``mechanism``,
``grid``, ``scene``, the roadmap JSON of ``-o``) keep the core's units.
"""

from concurrent.futures import ThreadPoolExecutor
import json
import math
import os
import shutil
import sys
import time

import numpy as np

from ..exceptions import GWRError, InfeasiblePathError, InvalidInputError, UndecidedError
from ..mechanisms import Mechanism, mechanism_from_dict
from ..mechanisms.base import working_mode_label
from ..paper import FULL_BASE_GRID, FULL_REFINEMENT, PAPER_GEOMETRY, rho1_slice
from ..workspace import build_roadmap, refine_thin_regions
from ..workspace.adaptive import grid_from_dict
from ..workspace.grid import check_roadmap_grid
from ..workspace.progress import part
from ..workspace.thin_regions import DEFAULT_THIN_REFINEMENT
from .limits import MAX_LEG

__all__ = ["run"]

# Grid step of the slices of ``cusps --trace`` [length unit].
_TRACE_STEP = 0.25


def run(args):
    """Run the parsed command: ``(JSON-able result, exit code)``."""
    commands = {"dk": _dk, "ik": _ik, "roadmap": _roadmap, "cusps": _cusps, "plan": _plan,
                "plot": _plot}
    progress = _Progress(sys.stderr)
    # The core's builds and loads run their chunks with this pool's map: a
    # thread a core (numpy, CRC-32 and the compiled kernels release the
    # interpreter's lock); its threads start with the first chunk.
    try:
        with ThreadPoolExecutor(max_workers=min(4, os.cpu_count() or 1)) as pool:
            answer = commands[args.command](args, progress, pool.map)
    finally:
        progress.close()
    # Only a plan can fail without an error: it answers with its exit code.
    return answer if args.command == "plan" else (answer, 0)


class _Progress:
    """The core's ``progress(stage, fraction)`` callback of one command, shown
    on ``stream`` once the command has run for :attr:`DELAY` seconds: a bar
    redrawn in place on a terminal, else a line such as ``rpr3-gwr: [ 40%]
    stage (3.1 s)`` every :attr:`LOG_EVERY` seconds and at the end, which a
    log keeps and a reader tells from the error line.  Meant for stderr:
    stdout is the answer's."""

    BAR = 20
    DELAY = 2.0
    LOG_EVERY = 2.0

    def __init__(self, stream):
        self.stream = stream
        self.start = time.perf_counter()
        self.terminal = stream.isatty()
        self.logged = -math.inf
        self.open_line = False

    def __call__(self, stage, fraction):
        elapsed = time.perf_counter() - self.start
        if elapsed < self.DELAY:
            return
        if self.terminal:
            filled = int(self.BAR * min(max(fraction, 0.0), 1.0))
            line = (f"[{'#' * filled}{'.' * (self.BAR - filled)}] {fraction:4.0%} {stage} "
                    f"({elapsed:.1f} s)")
            # A line wider than the terminal would wrap, and \r go back one row only.
            width = shutil.get_terminal_size((80, 24)).columns - 1
            self.stream.write(f"\r\x1b[K{line[:width]}")
            self.open_line = True
            if fraction >= 1.0:
                self.close()
        elif fraction >= 1.0 or elapsed - self.logged >= self.LOG_EVERY:
            self.stream.write(f"rpr3-gwr: [{fraction:4.0%}] {stage} ({elapsed:.1f} s)\n")
            self.logged = elapsed
        self.stream.flush()

    def close(self):
        """End the bar's line, so that what follows starts on a line of its own."""
        if self.open_line:
            self.stream.write("\n")
            self.stream.flush()
            self.open_line = False


# -- angles: degrees on the command line, radians in the core ----------------------------

def _angles(mechanism):
    """Which joints and which pose coordinates are angles: two tuples of bool."""
    return tuple(mechanism.angular_joints), tuple(mechanism.angular)


def _labels(names, angles):
    """The names of values shown in degrees where they are angles: ``alpha_deg``."""
    return [f"{name}_deg" if angle else name for name, angle in zip(names, angles)]


def _shown(values, angles):
    """Core values [rad] as the command line shows them [deg], a list of float."""
    return [math.degrees(v) if angle else float(v) for v, angle in zip(values, angles)]


def _taken(values, angles):
    """Command-line values [deg] as the core takes them [rad], a tuple of float."""
    return tuple(math.radians(v) if angle else float(v) for v, angle in zip(values, angles))


def _named(names, values, angles):
    """``{label: shown value}`` of some joints or pose coordinates."""
    return dict(zip(_labels(names, angles), _shown(values, angles)))


def _in_degrees(entry, mechanism):
    """A dict of the core's with joints and pose coordinates by name
    (``Cusp.to_dict``) as the command line shows it, in order."""
    joint_angles, pose_angles = _angles(mechanism)
    names = (*mechanism.joint_names, *mechanism.pose_names)
    angle = dict(zip(names, (*joint_angles, *pose_angles)))
    return {f"{key}_deg" if angle.get(key) else key:
            math.degrees(value) if angle.get(key) else value for key, value in entry.items()}


def _columns(mechanism):
    """What each entry of the answers' joint and pose lists is."""
    joint_angles, pose_angles = _angles(mechanism)
    return {"joints": _labels(mechanism.joint_names, joint_angles),
            "pose": _labels(mechanism.pose_names, pose_angles)}


def _joint_rate(mechanism, value, name):
    """A joint speed or acceleration limit [length unit or deg per s, s^2] in
    the core's joint unit: one limit binds every joint, so they share a unit."""
    joint_angles, _ = _angles(mechanism)
    if value is None or not any(joint_angles):
        return value
    if not all(joint_angles):
        raise InvalidInputError(f"--{name}: the {mechanism.kind}'s joints are lengths and "
                                "angles, which one limit cannot bound")
    return math.radians(value)


def _cusps(args, progress, workers):
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
        # The slices' builds take most of the time, the curves through them the rest.
        slices = [build_roadmap(PAPER_GEOMETRY, rho1_slice(float(v), step=slice_step),
                                progress=part(progress, 0.8 * k / len(values),
                                              0.8 * (k + 1) / len(values), f"rho1 = {v:g}"),
                                workers=workers)
                  for k, v in enumerate(values)]
        curves = cusp_curves(slices, progress=part(progress, 0.8, 1.0))
        return {"curves": [[_in_degrees(c.to_dict(PAPER_GEOMETRY), PAPER_GEOMETRY)
                            for c in curve] for curve in curves]}
    if args.mechanism is None:
        mechanism, grid = PAPER_GEOMETRY, rho1_slice(args.rho1)
    else:
        described, grid = _file_roadmap(args, progress, workers, free_joints=2,
                                        purpose="cusps are points of 2-D slices")
        mechanism = described.mechanism
        # Refused before the roadmap is built: without its own equations the
        # mechanism would fail at the first seed.
        if type(mechanism).refine_cusp is Mechanism.refine_cusp:
            raise InvalidInputError(f"the {mechanism.kind} has no cusp equations: 'cusps' "
                                    "takes mechanisms that have them (the 3-RPR)")
    roadmap, _ = cached_roadmap(mechanism, grid, args.cache_dir, progress, workers=workers,
                                thin_refinement=_thin_refinement(args, grid))
    try:
        cusps = find_cusps(roadmap)
    except NotImplementedError as exc:
        raise InvalidInputError(f"{exc}: 'cusps' takes mechanisms with cusp equations") from None
    return [_in_degrees(c.to_dict(mechanism), mechanism) for c in cusps]


def _dk(args, progress, workers):
    if args.mechanism is not None:
        from .mechanism_file import load_mechanism_file

        mechanism = load_mechanism_file(args.mechanism).mechanism
    else:
        _refuse_file_options(args)
        mechanism = PAPER_GEOMETRY
    names = mechanism.joint_names
    joint_angles, pose_angles = _angles(mechanism)
    if len(args.joints) != len(names):
        raise InvalidInputError(f"dk takes the {len(names)} joints "
                                f"{' '.join(_labels(names, joint_angles)).upper()} (all "
                                f"required), got {len(args.joints)}")
    if args.patches or args.start_mode is not None:
        return _located_modes(args, mechanism, progress, workers)
    if args.full or args.fix:
        raise InvalidInputError(f"{'--full' if args.full else '--fix'} needs --patches or "
                                "--from")
    joints = np.array([_taken(args.joints, joint_angles)])
    mechanism.check_joints(joints)
    count, poses = mechanism.solve(joints)
    poses = poses[0, :count[0]]
    if not len(poses):
        return []
    joints = np.repeat(joints, len(poses), axis=0)
    return [{**_named(mechanism.pose_names, p, pose_angles), "aspect": int(a),
             "signed_margin": float(m)}
            for p, a, m in zip(poses, mechanism.aspect(poses, joints),
                               mechanism.margin(poses, joints))]


def _ik(args, progress, workers):
    """Every working mode of a pose: its joints, aspect, signed margin and
    whether the joints lie in the box (the file's, or the paper's full
    roadmap's)."""
    if args.mechanism is not None:
        from .mechanism_file import load_mechanism_file

        described = load_mechanism_file(args.mechanism)
        mechanism, axes = described.mechanism, described.axes
    else:
        mechanism, axes = PAPER_GEOMETRY, FULL_BASE_GRID.axes
    pose = _pose_argument(mechanism, args.pose, "ik")
    joint_angles, _ = _angles(mechanism)
    answers = []
    for signs, joints in zip(mechanism.working_modes, mechanism.inverse_kinematics(pose)):
        if np.isnan(joints).any():
            continue
        margin = float(mechanism.margin(pose, joints))
        answers.append({"working_mode": working_mode_label(signs),
                        **_named(mechanism.joint_names, joints, joint_angles),
                        "aspect": int(np.sign(margin)), "signed_margin": margin,
                        "in_box": all(axis.periodic or axis.low <= joints[axis.joint] <= axis.high
                                      for axis in axes)})
    return answers


def _pose_argument(mechanism, values, option):
    """A pose of the command line [length unit, deg] in the core's units, a
    float array of shape (pose_size,)."""
    _, pose_angles = _angles(mechanism)
    if len(values) != mechanism.pose_size:
        raise InvalidInputError(f"{option} takes the {mechanism.kind}'s pose "
                                f"{' '.join(_labels(mechanism.pose_names, pose_angles)).upper()}"
                                f", got {len(values)} numbers")
    if any(abs(v) > MAX_LEG for v, angle in zip(values, pose_angles) if not angle):
        raise InvalidInputError(f"{option}: positions are at most {MAX_LEG:g} length units "
                                "from the origin")
    return np.array(_taken(values, pose_angles))


def _pose_ends(args, mechanism):
    """The ``--start-pose`` and ``--goal-pose`` of a plan as
    :class:`~rpr3_gwr_core.planning.PoseEnd` (None for an end given as
    joints), their working modes checked."""
    from ..planning import PoseEnd

    labels = [working_mode_label(m) for m in mechanism.working_modes]
    ends = []
    for end in ("start", "goal"):
        pose, mode = getattr(args, f"{end}_pose"), getattr(args, f"{end}_working_mode")
        if pose is None:
            if mode is not None:
                raise InvalidInputError(f"--{end}-working-mode needs --{end}-pose")
            ends.append(None)
            continue
        if mode is not None and mode not in labels:
            raise InvalidInputError(f"--{end}-working-mode is one of {', '.join(labels)} (a "
                                    f"branch sign per leg), got {mode!r}")
        ends.append(PoseEnd(tuple(_pose_argument(mechanism, pose, f"--{end}-pose")), mode))
    return ends


def _located_modes(args, mechanism, progress, workers):
    """``dk --patches`` / ``--from``: every mode located on the roadmap a plan
    of these joints uses, and with ``--from`` the command that plans to each
    mode a path reaches."""
    from ..planning import Planner, assembly_modes
    from .cache import cached_planning

    angles = _request_angles(mechanism)
    first = mechanism.joint_names[0]
    if args.mechanism is None:
        if args.full:
            roadmap, index, _ = _full_roadmap(args.cache_dir, progress, workers)
            where = ["--full"]
        else:
            grid = rho1_slice(args.joints[0])
            roadmap, index, _ = cached_planning(PAPER_GEOMETRY, grid, args.cache_dir,
                                                progress, workers=workers,
                                                thin_refinement=_thin_refinement(args, grid))
            where = ["--rho1", f"{args.joints[0]:g}"]
    else:
        if not args.full and not args.fix:
            args.fix = [(first, args.joints[0])]
        if args.full and args.fix:
            raise InvalidInputError("--full covers every joint: give it or --fix")
        described, grid = _file_roadmap(args, progress, workers)
        roadmap, index, _ = cached_planning(mechanism, grid, args.cache_dir, progress,
                                            workers=workers,
                                            thin_refinement=_thin_refinement(args, grid))
        where = ["--mechanism", args.mechanism,
                 *(f"--fix {name}={value:g}" for name, value in args.fix)]
    start_mode = None
    if args.start_mode is not None:
        start_mode = _taken([args.start_mode], angles[-1:])[0]
    progress("locating the modes", 0.0)
    modes = assembly_modes(Planner(roadmap, index), _taken(args.joints, angles[:-1]),
                           start_mode)
    _, pose_angles = _angles(mechanism)
    answers = []
    for mode in modes:
        answer = {**_named(mechanism.pose_names, mode.pose, pose_angles),
                  "aspect": mode.aspect, "signed_margin": mode.margin,
                  **{key: value for key, value in mode.to_dict().items()
                     if key in ("patch", "region", "layer", "feasibility")}}
        if mode.unlocated:
            answer["unlocated"] = mode.unlocated
        if mode.reachable and mode.feasibility != "start":
            start, goal = (_shown_request(c, angles, args.mechanism is None and not args.full)
                           for c in (modes[[m.feasibility for m in modes].index("start")]
                                     .configuration, mode.configuration))
            answer["plan"] = " ".join(["rpr3-gwr plan", *where, "--start", start,
                                       "--goal", goal])
        answers.append(answer)
    return answers


def _shown_request(configuration, angles, paper_slice):
    """A configuration as ``plan --start`` takes it: angles in degrees, the
    paper slice's rho1 left to ``--rho1``."""
    values = _shown(configuration, angles)[1 if paper_slice else 0:]
    return " ".join(f"{v:.10g}" for v in values)


def _full_roadmap(cache_dir, progress, workers):
    """The full 3-DOF roadmap, its planning index, and whether they came from the cache."""
    from .cache import cached_planning

    return cached_planning(PAPER_GEOMETRY, FULL_BASE_GRID, cache_dir, progress,
                           refinement=FULL_REFINEMENT, workers=workers)


def _roadmap(args, progress, workers):
    from .export import roadmap_summary, roadmap_to_gexf, roadmap_to_json

    _paper_slice_options(args, ("rho1", "rho2", "rho3", "step"))
    start = time.perf_counter()
    if args.mechanism is not None:
        from .cache import cached_roadmap

        described, grid = _file_roadmap(args, progress, workers)
        roadmap, hit = cached_roadmap(described.mechanism, grid, args.cache_dir, progress,
                                      workers=workers,
                                      thin_refinement=_thin_refinement(args, grid))
        if args.slice_figure:
            raise InvalidInputError("--slice-figure needs --full")
    elif args.full:
        if args.field_figure:
            raise InvalidInputError("--field-figure draws 2-D grids: with --full use "
                                    "--slice-figure")
        roadmap, _, hit = _full_roadmap(args.cache_dir, progress, workers)
    else:
        if args.slice_figure:
            raise InvalidInputError("--slice-figure needs --full")
        grid = rho1_slice(args.rho1, tuple(args.rho2), tuple(args.rho3), args.step)
        check_roadmap_grid(PAPER_GEOMETRY, grid)
        thin = _thin_refinement(args, grid)
        if thin is None:
            roadmap = build_roadmap(PAPER_GEOMETRY, grid, method=args.method,
                                    progress=progress, workers=workers)
        else:
            roadmap, _ = refine_thin_regions(PAPER_GEOMETRY, grid, thin, method=args.method,
                                             progress=progress, workers=workers)
        hit = False
    summary = roadmap_summary(roadmap)
    summary["cusps"] = [_in_degrees(c, roadmap.mechanism) for c in summary["cusps"]]
    world = None
    if args.scene is not None:
        from ..planning import Planner
        from .scene_file import load_scene

        progress("the scene's blocked solutions", 0.0)
        world = _applied(Planner(roadmap), load_scene(args.scene), _bodies(args), args.scene)
        progress("the scene's blocked solutions", 1.0)
        solutions = roadmap.segmentation.patch > 0
        summary["scene"] = {"file": args.scene, "parts": world.n_parts,
                            "blocked_solutions": int((solutions & ~world.free).sum()),
                            "solutions": int(solutions.sum())}
    summary["timings"] = dict(roadmap.timings, total=time.perf_counter() - start)
    summary["from_cache"] = hit
    if args.slice_figure:
        from ..workspace.cusps import find_cusps
        from ..figures import slice_figure

        cusps = find_cusps(build_roadmap(PAPER_GEOMETRY, rho1_slice(args.slice_rho1, step=0.25),
                                         workers=workers))
        _save(args.slice_figure, slice_figure(roadmap, {0: args.slice_rho1}, cusps))
    if args.output:
        _save(args.output, roadmap_to_json(roadmap))
    if args.gexf:
        _save(args.gexf, roadmap_to_gexf(roadmap))
    if args.field_figure or args.roadmap_figure:
        from ..figures import field_figure, roadmap_figure

        # Drawing takes as long as a slice's build: the progress names it.
        if args.field_figure:
            progress(f"drawing {args.field_figure}", 1.0)
            _save(args.field_figure, field_figure(roadmap, world))
        if args.roadmap_figure:
            progress(f"drawing {args.roadmap_figure}", 1.0)
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
    _refuse_file_options(args)
    defaults = {"rho1": 17.0, "rho2": (0.0, 50.0), "rho3": (0.0, 50.0), "step": 0.125}
    for name in names:
        if getattr(args, name) is None:
            setattr(args, name, defaults[name])


def _refuse_file_options(args):
    """``--fix`` is a mechanism file's."""
    if args.fix:
        raise InvalidInputError("--fix needs --mechanism")


def _thin_refinement(args, grid):
    """``--thin-refinement`` for a build on ``grid``: None (no thin regions
    refined) when 0, or when the grid is not uniform (the file's box over
    more cells than a uniform grid may have: refined by rule already)."""
    from ..workspace import Grid

    if args.thin_refinement == 1:
        raise InvalidInputError("--thin-refinement is 0 (off) or at least 2 fine points a "
                                "cell, got 1")
    if args.thin_refinement == 0 or not isinstance(grid, Grid):
        return None
    return DEFAULT_THIN_REFINEMENT if args.thin_refinement is None else args.thin_refinement


def _plan_thin_refinement(path, plan):
    """The thin refinement a plan file's roadmap was built with."""
    thin = plan["roadmap"].get("thin_refinement")
    if thin is not None and (type(thin) is not int or thin < 2):
        raise InvalidInputError(f"{path}: its roadmap's thin_refinement is an integer >= 2 "
                                f"or null, got {thin!r:.40}")
    return thin


def _file_roadmap(args, progress, workers, free_joints=None, purpose=None):
    """The :class:`~.mechanism_file.MechanismFile` of ``--mechanism`` and the
    grid of a roadmap of its box and ``--fix`` (angles in degrees),
    :func:`~.mechanism_file.roadmap_grid`'s; with ``free_joints``, refused
    for ``purpose`` unless it leaves that many joints free."""
    from .mechanism_file import load_mechanism_file, roadmap_grid

    described = load_mechanism_file(args.mechanism)
    mechanism = described.mechanism
    free = mechanism.n_joints - len({name for name, _ in args.fix})
    if free_joints is not None and free != free_joints:
        raise InvalidInputError(f"{purpose}: --fix all joints but {free_joints} (the grid "
                                f"has {free} axes)")
    angle = dict(zip(mechanism.joint_names, _angles(mechanism)[0]))
    axes = dict(zip(mechanism.joint_names, described.axes))
    for name, value in args.fix:
        # The file's range of an angle, as the user gave the value: in degrees.
        axis = axes.get(name)
        if angle.get(name) and not axis.periodic and not (
                axis.low <= math.radians(value) <= axis.high):
            raise InvalidInputError(f"--fix {name}={value:g} deg lies outside its range "
                                    f"[{math.degrees(axis.low):g}, "
                                    f"{math.degrees(axis.high):g}] deg")
    fixed = {name: math.radians(value) if angle.get(name) else value for name, value in args.fix}
    return described, roadmap_grid(described, fixed, progress=progress, workers=workers)


def _bodies(args):
    """The body model of ``--mechanism``'s file, None for the defaults."""
    if args.mechanism is None:
        return None
    from .mechanism_file import load_mechanism_file

    return load_mechanism_file(args.mechanism).bodies


def _applied(planner, scene, model, source):
    """The planner's roadmap restricted to a scene with a body model (None:
    the defaults), its errors naming ``source``, where the scene comes from."""
    try:
        return planner.apply_scene(scene, model)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{source}: {exc}") from None


def _plan(args, progress, workers):
    from .cache import cached_planning

    if args.full and args.step is not None:
        raise InvalidInputError("--step: the full 3-DOF roadmap's grid is its own")
    _paper_slice_options(args, ("rho1", "step"))
    if args.mechanism is not None:
        return _plan_on_file(args, progress, workers)
    if args.mode_tol is not None:
        raise InvalidInputError("--mode-tol needs --mechanism; the paper's 3-RPR takes "
                                "--alpha-tol-deg")
    given = 4 if args.full else 3
    for name in ("start", "goal"):
        if getattr(args, name) is not None and len(getattr(args, name)) != given:
            raise InvalidInputError(
                f"--{name} takes {'RHO1 ' if args.full else ''}RHO2 RHO3 ALPHA_DEG"
                f"{'' if args.full else ' (rho1 is --rho1; --full plans with rho1 free)'}")
    poses = _pose_ends(args, PAPER_GEOMETRY)
    options = _options(args, PAPER_GEOMETRY, math.radians(args.alpha_tol_deg))
    if args.full:
        roadmap, index, _ = _full_roadmap(args.cache_dir, progress, workers)
        start, goal = args.start, args.goal
        roadmap_doc = {"mechanism": PAPER_GEOMETRY.to_dict(), "full": True}
    else:
        grid = rho1_slice(args.rho1, step=args.step)
        thin = _thin_refinement(args, grid)
        roadmap, index, _ = cached_planning(PAPER_GEOMETRY, grid, args.cache_dir, progress,
                                            workers=workers, thin_refinement=thin)
        start, goal = ((args.rho1, *legs) if legs is not None else None
                       for legs in (args.start, args.goal))
        roadmap_doc = {"mechanism": PAPER_GEOMETRY.to_dict(), "grid": grid.to_dict(),
                       "thin_refinement": thin}
    start, goal = (pose or joints for pose, joints in zip(poses, (start, goal)))
    return _answer(args, progress, roadmap, index, start, goal, options, roadmap_doc)


def _plan_on_file(args, progress, workers):
    from .cache import cached_planning

    described, grid = _file_roadmap(args, progress, workers)
    mechanism = described.mechanism
    labels = _request_labels(mechanism)
    for name in ("start", "goal"):
        if getattr(args, name) is not None and len(getattr(args, name)) != len(labels):
            raise InvalidInputError(
                f"--{name} takes {' '.join(labels[:-1]).upper()} and the mode coordinate "
                f"{labels[-1].upper()} (angles in degrees)")
    poses = _pose_ends(args, mechanism)
    tolerance = args.mode_tol
    if tolerance is not None and _request_angles(mechanism)[-1]:
        tolerance = math.radians(tolerance)
    options = _options(args, mechanism, tolerance)
    thin = _thin_refinement(args, grid)
    roadmap, index, _ = cached_planning(mechanism, grid, args.cache_dir, progress,
                                        workers=workers, thin_refinement=thin)
    roadmap_doc = {"mechanism": mechanism.to_dict(), "grid": grid.to_dict(),
                   "thin_refinement": thin}
    start, goal = (pose or joints for pose, joints in zip(poses, (args.start, args.goal)))
    return _answer(args, progress, roadmap, index, start, goal, options, roadmap_doc)


def _options(args, mechanism, mode_tol):
    """The :class:`~rpr3_gwr_core.planning.PlanOptions` of the arguments, the
    mode tolerance in the core's unit (None: the default)."""
    from ..planning import PlanOptions

    given = {} if mode_tol is None else {"mode_tol": mode_tol}
    if args.clearance is not None:
        given["clearance"] = args.clearance
    limits = (_joint_rate(mechanism, args.max_velocity, "max-velocity"),
              _joint_rate(mechanism, args.max_acceleration, "max-acceleration"))
    if args.joint_limit:
        limits = _joint_limits(mechanism, limits, args.joint_limit)
    return PlanOptions(smooth=args.smooth, weighted=args.weighted,
                       feasibility_only=args.feasibility_only, max_velocity=limits[0],
                       max_acceleration=limits[1], **given)


def _joint_limits(mechanism, limits, entries):
    """Per-joint speed and acceleration limits in the core's joint units:
    ``limits`` (for all joints, in those units) with the ``(name, speed,
    acceleration)`` entries of ``--joint-limit`` (in the joint's unit, deg
    for an angle; 0 keeps the limit for all joints) put in."""
    if None in limits:
        raise InvalidInputError("--joint-limit: give --max-velocity and --max-acceleration "
                                "too, the limits of the joints it does not name")
    names = mechanism.joint_names
    joint_angles, _ = _angles(mechanism)
    per_joint = [[limit] * len(names) for limit in limits]
    named = set()
    for name, *values in entries:
        if name not in names or name in named:
            raise InvalidInputError(f"--joint-limit: {name!r} is not a joint of the "
                                    f"{mechanism.kind} ({', '.join(names)}), or is named twice")
        named.add(name)
        at = names.index(name)
        for column, value in zip(per_joint, values):
            if value:
                column[at] = math.radians(value) if joint_angles[at] else value
    return tuple(map(tuple, per_joint))


def _request_angles(mechanism):
    """Which values of a request (every joint, then the mode coordinate) are angles."""
    joint_angles, pose_angles = _angles(mechanism)
    return (*joint_angles, pose_angles[mechanism.mode_coordinate])


def _request_labels(mechanism):
    """The labels of a request's values: ``rho1 rho2 rho3 alpha_deg``."""
    return _labels((*mechanism.joint_names, mechanism.pose_names[mechanism.mode_coordinate]),
                   _request_angles(mechanism))


def _answer(args, progress, roadmap, index, start, goal, options, roadmap_doc):
    """The plan's JSON and exit code (1 when there is no plan); ``start`` and
    ``goal`` as given (angles in degrees), or as a
    :class:`~rpr3_gwr_core.planning.PoseEnd` (the core's units)."""
    from ..planning import NEVER, Planner, PoseEnd, Termination, resolve_ends

    mechanism = roadmap.mechanism
    angles = _request_angles(mechanism)
    _, pose_angles = _angles(mechanism)
    labels = _request_labels(mechanism)

    def requested(end):
        if not isinstance(end, PoseEnd):
            return dict(zip(labels, map(float, end)))
        shown = _named(mechanism.pose_names, end.pose, pose_angles)
        return shown if end.working_mode is None else dict(shown, working_mode=end.working_mode)

    header = {"roadmap": roadmap_doc, "columns": _columns(mechanism),
              "request": {"start": requested(start), "goal": requested(goal)}}
    scene = model = None
    if args.scene is not None:
        from .scene_file import load_scene

        scene, model = load_scene(args.scene), _bodies(args)
        header["scene"] = scene.to_dict()
        # What the scene blocks depends on the bodies: 'plot' draws it with these.
        if model is not None:
            header["bodies"] = model.to_dict()
    begin = time.perf_counter()
    planner = Planner(roadmap, index)
    # A scene that does not fit the mechanism is bad input, not "no plan".
    world = None if scene is None else _applied(planner, scene, model, args.scene)
    try:
        termination = NEVER if args.time_limit is None else Termination.after(args.time_limit)
        progress("planning", 0.0)
        ends = resolve_ends(planner, *(end if isinstance(end, PoseEnd) else _taken(end, angles)
                                       for end in (start, goal)), options.mode_tol)
        plan = planner.plan(ends.start, ends.goal, options, termination, world)
        progress("planning", 1.0)
        result = dict(header, **_plan_shown(plan.to_dict(), mechanism))
        for end, mode in (("start", ends.start_mode), ("goal", ends.goal_mode)):
            if mode is not None:
                result[end]["working_mode"] = mode.label
        code = 0
    except GWRError as exc:
        reason = exc.reason if isinstance(exc, InfeasiblePathError) else None
        result = dict(header, feasible=False, reason=reason or exc.code.lower(),
                      error={"code": exc.code, "message": str(exc)})
        if isinstance(exc, UndecidedError):
            result["undecided"] = _undecided(args, exc, roadmap, roadmap_doc)
        code = 1
    result["plan_time_s"] = time.perf_counter() - begin
    if args.output:
        _save(args.output, json.dumps(result))
    return result, code


def _undecided(args, exc, roadmap, roadmap_doc):
    """Where and at which size the roadmap could not decide, and the option
    that asks at a finer size: on a uniform grid ``--thin-refinement`` twice
    as fine (the default where it was 0); on a file's whole box (an
    adaptive grid) its steps halved; on the paper's full roadmap a slice."""
    mechanism = roadmap.mechanism
    joint_angles, _ = _angles(mechanism)
    steps = {mechanism.joint_names[axis.joint] + ("_deg" if joint_angles[axis.joint] else ""):
             math.degrees(step) if joint_angles[axis.joint] else step
             for axis, step in zip(roadmap.grid.axes, exc.steps)}
    thin = roadmap_doc.get("thin_refinement")
    if thin is not None:
        finer = f"--thin-refinement {2 * thin}"
    elif "thin_refinement" in roadmap_doc and args.thin_refinement == 0:
        finer = f"--thin-refinement {DEFAULT_THIN_REFINEMENT}"
    elif args.mechanism is not None:
        finer = "the steps of the mechanism file's box halved"
    else:
        finer = "a slice (--rho1 R), refined where its thin regions are"
    return {"thin_patches": list(exc.thin_patches), "finest_steps": steps, "finer": finer}


def _plan_shown(plan, mechanism):
    """:meth:`Plan.to_dict` as the command line shows it: angles in degrees
    (the joint lists, velocities and accelerations per joint, the pose lists
    per coordinate; ``columns`` names them), margins named signed or not."""
    joint_angles, pose_angles = _angles(mechanism)

    def configuration(entry):
        return dict(entry, joints=_shown(entry["joints"], joint_angles),
                    pose=_shown(entry["pose"], pose_angles))

    out = dict(plan, waypoints=[configuration(w) for w in plan["waypoints"]])
    for end in ("start", "goal"):
        if out.get(end) is not None:
            location = configuration(out[end])
            location["signed_margin"] = location.pop("margin")
            out[end] = location
    for rate in ("velocities", "accelerations"):
        if rate in out:
            out[rate] = [_shown(v, joint_angles) for v in out[rate]]
    if out.get("validation") is not None:
        validation = dict(out["validation"])
        validation["min_abs_margin"] = validation.pop("min_margin")
        out["validation"] = validation
    return out


def _read_plan(path):
    """The mechanism, grid and plan of a file written by ``plan``, its
    waypoints in the core's units (radians); what a figure reads of the plan
    is checked (else ``InvalidInputError``)."""
    try:
        with open(path, encoding="utf-8") as stream:
            plan = json.load(stream)
        mechanism = mechanism_from_dict(plan["roadmap"]["mechanism"])
        # A --full plan's roadmap is the paper's full 3-DOF one, named, not described.
        grid = None if plan["roadmap"].get("full") else grid_from_dict(plan["roadmap"]["grid"])
        if "error" in plan or not plan.get("waypoints"):
            raise InvalidInputError(f"{path} holds no trajectory to draw")
        if plan.get("columns") != _columns(mechanism):
            raise ValueError(f"its columns are not {_columns(mechanism)}")
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
    if grid is not None and max([a.high for a in grid.axes]
                                + [v for _, v in grid.fixed]) > MAX_LEG:
        raise InvalidInputError(f"the grid of {path} is out of range: legs are at most "
                                f"{MAX_LEG:g} length units")
    joint_angles, pose_angles = _angles(mechanism)
    plan["waypoints"] = [dict(w, joints=list(_taken(w["joints"], joint_angles)),
                              pose=list(_taken(w["pose"], pose_angles)))
                         for w in plan["waypoints"]]
    return mechanism, grid, plan


def _plan_scene(path, plan):
    """The scene of a plan file and the body model it was planned with
    (None: the defaults), None for a plan without a scene."""
    from ..world import body_model_from_dict, scene_from_dict

    if plan.get("scene") is None:
        return None
    try:
        scene = scene_from_dict(plan["scene"])
        model = None if plan.get("bodies") is None else body_model_from_dict(plan["bodies"])
    except InvalidInputError as exc:
        raise InvalidInputError(f"the scene of {path}: {exc}") from None
    return scene, model


def _plot(args, progress, workers):
    from .cache import cached_planning
    from ..figures import plan_figure

    mechanism, grid, plan = _read_plan(args.plan_file)
    in_scene = _plan_scene(args.plan_file, plan)
    if grid is None:
        roadmap, index, _ = _full_roadmap(args.cache_dir, progress, workers)
    else:
        check_roadmap_grid(mechanism, grid)
        roadmap, index, _ = cached_planning(
            mechanism, grid, args.cache_dir, progress, workers=workers,
            thin_refinement=_plan_thin_refinement(args.plan_file, plan))
    world = None
    if in_scene is not None:
        from ..planning import Planner

        progress("the scene's blocked solutions", 0.0)
        world = _applied(Planner(roadmap, index), *in_scene, f"the scene of {args.plan_file}")
        progress("the scene's blocked solutions", 1.0)
    output = args.output or os.path.splitext(args.plan_file)[0] + ".png"
    _save(output, plan_figure(roadmap, plan, world), dpi=110)
    return {"figure": output}
