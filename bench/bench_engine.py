"""Benchmark: the full-roadmap planner against OMPL RRTConnect in pose space.

Run on demand, after ``source ros2_ws/env.sh``:

    python bench/bench_engine.py [--pairs 250] [--seed 1] [--ompl-time 1.0]
                                 [--ompl-step 1.0] [--reference-pairs N] [--repeat 3]
                                 [--clearance 0.02] [--no-smooth]

The pose space is the independent reference: inverse kinematics of the 3-RPR
is unique, so (x, y, alpha) is the configuration space, and a pose path that
keeps the start's sign of the margin (normalised det Jx), a margin magnitude
of at least the planner's threshold and the legs in the full roadmap's box is
a valid joint path.  Same-aspect pairs are drawn in pose space with the tests'
``pose_reference`` (endpoint margins at least 3e-3): a tenth of them with both
endpoints near a face of the box of legs, a tenth with both endpoint margins
in [3e-3, 0.02], the rest uniform.  Each pair is planned

* by the project's planner on the full roadmap (its planning index mapped and
  kernels loaded before timing; smoothed, the service's and the CLI's
  default answer, or not with ``--no-smooth``), its path re-checked by the
  reference's continuation and its legs against the box;
* by OMPL's RRTConnect in pose space, set up as OMPL's own demos set it up:
  a ``SimpleSetup`` on (x, y) in [-50, 50]^2 times SO(2), the rotation
  weighted by the reference's length scale; the reference's predicate as a
  scalar state validity checker, OMPL's discrete motion validator at a fixed
  resolution (``--ompl-step``), the found path simplified by
  ``simplifySolution()`` (a bounded ``simplifyMax``; the time includes it),
  then re-checked by the reference's continuation (steps of an eightieth of
  the margin times the scale, in scaled pose length);
* for the shortest joint path: Dijkstra on a pose lattice (step 1, 128
  orientations, 26 neighbours, edges checked at their ends and middle,
  weighted by the legs' change).

Lengths are in joint space: the sum of the legs' changes, a pose path sampled
at least every 0.05 scaled length units.  The "shortest" of a pair is the
shortest known path: the lattice's path and both planners' checked paths are
each shortened by straight joint segments the project's validator accepts
(their corners then pulled in), and the shortest of these that the
reference's continuation accepts end to end, or of the planners' own paths,
is taken (--reference-pairs limits this to the first N pairs).  Target 4's
times are wall times of fresh ``rpr3-gwr`` processes (median of --repeat)
over the eigenvalue baseline of bench_roadmap.py, measured in the same run,
before anything is loaded here.

Prints JSON lines: the pairs; the baseline and each fresh-process time; per
planner the success, plan times (p50 / p95 / max) and length ratios (p50 /
p95); the shortest-path reference; then each target with its measured value, its
threshold and whether it is met or by how much it is missed.
"""

import argparse
import collections
import json
import math
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from bench_roadmap import eigenvalue_baseline  # bench/ is the script's folder
from rpr3_gwr_core import GWRError, PAPER_GEOMETRY, Planner, PlanOptions
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT
from rpr3_gwr_core.planning import DEFAULT_CLEARANCE, DEFAULT_MIN_MARGIN, validate_path

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]
                       / "src" / "rpr3_gwr_core" / "test"))
from pose_reference import (LEG_RANGE, RHO1_RANGE, SCALE,  # noqa: E402
                            assert_executable, follow, legs_of, margin_of,
                            random_full_configurations, same_aspect_pairs)

_MIN_MARGIN = DEFAULT_MIN_MARGIN
# Both endpoints of a near-face pair have a leg this close to a face of the box.
_NEAR_FACE = 0.5
# Both endpoints of a low-margin pair have a margin magnitude of at most this.
_LOW_MARGIN = 0.02
# The reference continuation's step: the pose moves at most this times the margin
# (scaled length: sqrt(dx**2 + dy**2 + (SCALE * dalpha)**2)).
_RECHECK_STEP = 0.0125 * SCALE
# OMPL's state validity checking resolution [scaled length]: what a user
# tunes it to, the coarsest step whose simplified paths pass the re-check
# (OMPL's default, 1 % of the space's extent, about 2, lets paths through that
# fail it).
_OMPL_STEP = 1.0
# Largest step when a pose path's joint length is measured [scaled length].
_SAMPLE = 0.05
_LATTICE_STEP = 1.0
_ORIENTATIONS = 128
# The paths of target 4: the README's full-roadmap example and the paper's first example.
_FULL_PLAN = ["plan", "--full", "--start", "27.5", "31.67154934", "2.14117832", "-101",
              "--goal", "27.5", "31.67154934", "2.14117832", "158.048263"]
_PAPER_PLAN = ["plan", "--rho1", "17", "--start", "12", "18", "122.82",
               "--goal", "10", "25", "-24.24", "--smooth"]


def _in_box(legs):
    return (RHO1_RANGE[0] <= legs[0] <= RHO1_RANGE[1]
            and LEG_RANGE[0] <= legs[1] <= LEG_RANGE[1]
            and LEG_RANGE[0] <= legs[2] <= LEG_RANGE[1])


def _signed_margin(pose, sign):
    """``sign`` times the margin of a pose with its legs, or -1 and the legs
    when they leave the box."""
    legs = legs_of(pose)
    return (sign * margin_of(pose) if _in_box(legs) else -1.0), legs


def _walk(a, b, sign, fraction, cap=math.inf):
    """Check the straight pose segment from ``a`` to ``b`` (the rotation the
    short way round) in steps of at most ``fraction`` times the margin and
    ``cap`` [scaled length]; whether it keeps the sign, the threshold and the
    box, and the legs' change along it [length unit]."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    da = math.remainder(b[2] - a[2], 2 * math.pi)
    span = math.sqrt(dx * dx + dy * dy + (SCALE * da) ** 2)
    margin, legs = _signed_margin(a, sign)
    length, t = 0.0, 0.0
    while margin >= _MIN_MARGIN:
        if t >= 1.0:
            return True, length
        t = min(1.0, t + min(fraction * margin, cap) / span) if span > 0 else 1.0
        margin, new = _signed_margin((a[0] + t * dx, a[1] + t * dy, a[2] + t * da), sign)
        length += math.dist(new, legs)
        legs = new
    return False, length


def _same_pose(a, b, tol=1e-6):
    return (abs(a[0] - b[0]) < tol and abs(a[1] - b[1]) < tol
            and abs(math.remainder(a[2] - b[2], 2 * math.pi)) < tol)


def _draw_pairs(rng, count):
    """``count`` same-aspect pairs ``((joints, pose), (joints, pose))`` and their
    kinds: a tenth near the box's faces, a tenth of low endpoint margin."""
    def near_face(legs):
        return min(legs[0] - RHO1_RANGE[0], RHO1_RANGE[1] - legs[0],
                   *(legs[1:] - LEG_RANGE[0]), *(LEG_RANGE[1] - legs[1:])) <= _NEAR_FACE

    def low_margin(pose):
        return abs(margin_of(pose)) <= _LOW_MARGIN

    kinds = (("near_face", count // 10, lambda c: near_face(np.array(c[0][:3]))),
             ("low_margin", count // 10, lambda c: low_margin(c[1])),
             ("uniform", count - 2 * (count // 10), lambda c: True))
    pairs = []
    for kind, wanted, keep in kinds:
        found = []
        while len(same_aspect_pairs(found)) < wanted:
            found += [c for c in random_full_configurations(rng, 256) if keep(c)]
        pairs += [(kind, pair) for pair in same_aspect_pairs(found)[:wanted]]
    return pairs


def _pose(state):
    xy = state[0]
    return (xy[0], xy[1], state[1].value)


class _OmplPoseSpace:
    """OMPL's RRTConnect on (x, y, alpha), set up as OMPL's own demos do: a
    ``SimpleSetup`` with a scalar state validity checker (the reference's
    predicate), OMPL's discrete motion validator at a fixed resolution and
    its bounded simplifier (``simplifySolution()``: ``simplifyMax``)."""

    def __init__(self, seed, step):
        ou.setLogLevel(ou.LOG_ERROR)
        ou.RNG.setSeed(seed)
        plane = ob.RealVectorStateSpace(2)
        bounds = ob.RealVectorBounds(2)
        bounds.setLow(-50.0)
        bounds.setHigh(50.0)
        plane.setBounds(bounds)
        space = ob.CompoundStateSpace()
        space.addSubspace(plane, 1.0)
        space.addSubspace(ob.SO2StateSpace(), SCALE)
        self.sign = 1.0
        self.setup = og.SimpleSetup(space)
        self.setup.setStateValidityChecker(
            lambda state: _signed_margin(_pose(state), self.sign)[0] >= _MIN_MARGIN)
        si = self.setup.getSpaceInformation()
        si.setStateValidityCheckingResolution(step / space.getMaximumExtent())
        self.setup.setPlanner(og.RRTConnect(si))
        self.setup.setup()

    def _state(self, pose):
        state = self.setup.getSpaceInformation().allocState()
        state[0][0], state[0][1] = float(pose[0]), float(pose[1])
        state[1].value = float(math.remainder(pose[2], 2 * math.pi))
        return state

    def solve(self, start_pose, goal_pose, seconds):
        """The simplified pose path (ndarray, shape (n, 3)) or None, and the
        seconds taken."""
        begin = time.perf_counter()
        self.sign = math.copysign(1.0, margin_of(start_pose))
        self.setup.clear()
        self.setup.setStartAndGoalStates(self._state(start_pose), self._state(goal_pose))
        self.setup.solve(seconds)
        if not self.setup.haveExactSolutionPath():
            return None, time.perf_counter() - begin
        self.setup.simplifySolution()
        path = self.setup.getSolutionPath()
        elapsed = time.perf_counter() - begin
        return np.array([_pose(state) for state in path.getStates()]), elapsed


def _check_pose_path(poses, start_pose, goal_pose):
    """Re-check an OMPL path densely: ``(why or "", joint length)``."""
    if not (_same_pose(poses[0], start_pose) and _same_pose(poses[-1], goal_pose)):
        return "does not join the start and goal poses", math.nan
    sign = math.copysign(1.0, margin_of(start_pose))
    total = 0.0
    for a, b in zip(poses[:-1], poses[1:]):
        ok, length = _walk(a, b, sign, _RECHECK_STEP, _SAMPLE)
        if not ok:
            return "leaves the box, the aspect or the margin threshold", math.nan
        total += length
    return "", total


class _PoseLattice:
    """Shortest joint paths on a pose lattice, one graph per aspect."""

    def __init__(self, step=_LATTICE_STEP, orientations=_ORIENTATIONS):
        self.xy = np.arange(-50.0, 50.0 + step / 2, step)
        self.alpha = -math.pi + 2 * math.pi * np.arange(orientations) / orientations
        self.step = step
        n, m = self.xy.size, orientations
        self.poses = np.stack(np.meshgrid(self.xy, self.xy, self.alpha, indexing="ij"),
                              axis=-1).reshape(-1, 3)
        self.legs = PAPER_GEOMETRY.inverse(self.poses)
        margin = PAPER_GEOMETRY.margin(self.poses)
        inside = self._inside(self.legs)
        self.valid = {s: inside & (s * margin >= _MIN_MARGIN) for s in (1, -1)}
        ids = np.arange(n * n * m).reshape(n, n, m)
        edges = {1: [], -1: []}
        for offset in [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
                       if (i, j, k) > (0, 0, 0)]:
            di, dj, dk = offset
            src = ids[max(0, -di):n - max(0, di), max(0, -dj):n - max(0, dj)].ravel()
            dst = np.roll(ids, -dk, axis=2)[max(0, di):n - max(0, -di),
                                            max(0, dj):n - max(0, -dj)].ravel()
            either = ((self.valid[1][src] & self.valid[1][dst])
                      | (self.valid[-1][src] & self.valid[-1][dst]))
            src, dst = src[either], dst[either]
            middle = self.poses[src] + 0.5 * np.array(
                [di * step, dj * step, dk * 2 * math.pi / orientations])
            legs = PAPER_GEOMETRY.inverse(middle)
            margin = PAPER_GEOMETRY.margin(middle)
            weight = (np.linalg.norm(legs - self.legs[src], axis=1)
                      + np.linalg.norm(self.legs[dst] - legs, axis=1))
            for s in (1, -1):
                keep = (self.valid[s][src] & self.valid[s][dst] & self._inside(legs)
                        & (s * margin >= _MIN_MARGIN))
                edges[s].append((src[keep], dst[keep], weight[keep]))
        self.graphs = {}
        for s in (1, -1):
            nodes = np.flatnonzero(self.valid[s])
            index = np.full(ids.size, -1)
            index[nodes] = np.arange(nodes.size)
            src, dst, weight = (np.concatenate(parts) for parts in zip(*edges[s]))
            graph = csr_matrix((np.concatenate([weight, weight]),
                                (index[np.concatenate([src, dst])],
                                 index[np.concatenate([dst, src])])),
                               shape=(nodes.size, nodes.size))
            self.graphs[s] = (graph, nodes, index)

    @staticmethod
    def _inside(legs):
        return ((legs[:, 0] >= RHO1_RANGE[0]) & (legs[:, 0] <= RHO1_RANGE[1])
                & np.all((legs[:, 1:] >= LEG_RANGE[0]) & (legs[:, 1:] <= LEG_RANGE[1]), axis=1))

    def _connectors(self, pose, sign):
        """Graph nodes around ``pose`` joined to it by a checked straight pose segment."""
        n, m = self.xy.size, self.alpha.size
        index = self.graphs[sign][2]
        i = int(np.floor((pose[0] - self.xy[0]) / self.step))
        j = int(np.floor((pose[1] - self.xy[0]) / self.step))
        k = int(np.floor((math.remainder(pose[2], 2 * math.pi) + math.pi) * m / (2 * math.pi)))
        for reach in (1, 2, 3):
            around = [(a * n + b) * m + c % m
                      for a in range(max(0, i - reach + 1), min(n, i + reach + 1))
                      for b in range(max(0, j - reach + 1), min(n, j + reach + 1))
                      for c in range(k - reach + 1, k + reach + 1)]
            found = [index[node] for node in around if self.valid[sign][node]
                     and _walk(pose, self.poses[node], sign, _RECHECK_STEP)[0]]
            if found:
                return found
        return []

    def path(self, start_pose, goal_pose):
        """Pose waypoints of the lattice's shortest path, or None."""
        sign = 1 if margin_of(start_pose) > 0 else -1
        graph, nodes, _ = self.graphs[sign]
        sources = self._connectors(start_pose, sign)
        targets = self._connectors(goal_pose, sign)
        if not sources or not targets:
            return None
        distance, previous, _ = dijkstra(graph, indices=sources, return_predecessors=True,
                                         min_only=True)
        goal_legs = legs_of(goal_pose)
        cost = [distance[t] + np.linalg.norm(self.legs[nodes[t]] - goal_legs) for t in targets]
        node = targets[int(np.argmin(cost))]
        if not np.isfinite(min(cost)):
            return None
        chain = []
        while node >= 0:
            chain.append(nodes[node])
            node = previous[node]
        return [np.asarray(start_pose, float), *self.poses[chain[::-1]],
                np.asarray(goal_pose, float)]


def _accepts(joints, poses):
    # A hair above the threshold: the reference's continuation samples the
    # margin elsewhere than the validator does.
    return validate_path(PAPER_GEOMETRY, np.array(joints), poses[0], poses[-1],
                         1.05 * _MIN_MARGIN)


def _densify(pose_path, spacing=0.25):
    """Poses along a pose polyline (the rotation the short way round), at
    most ``spacing`` scaled length apart."""
    poses = []
    for a, b in zip(pose_path[:-1], pose_path[1:]):
        delta = np.array([b[0] - a[0], b[1] - a[1], math.remainder(b[2] - a[2], 2 * math.pi)])
        pieces = max(1, math.ceil(math.hypot(delta[0], delta[1], SCALE * delta[2]) / spacing))
        poses += [np.asarray(a, float) + t * delta for t in np.arange(pieces) / pieces]
    poses.append(np.asarray(pose_path[-1], float))
    return poses


def _shorten(joints, poses, rounds=4):
    """Shorten a joint polyline by straight joint segments the project's
    validator accepts, then pull its corners in; consecutive waypoints are
    taken as joined.  The waypoints and their poses."""
    joints, poses = [np.asarray(q, float) for q in joints], list(poses)
    for _ in range(rounds):
        # The farthest waypoint a straight segment reaches, by bisection.
        keep, at = [0], 0
        while at < len(joints) - 1:
            low, high = at + 1, len(joints) - 1
            if high > low and _accepts([joints[at], joints[high]], [poses[at], poses[high]]).ok:
                low = high
            while high - low > 1:
                middle = (low + high) // 2
                if _accepts([joints[at], joints[middle]], [poses[at], poses[middle]]).ok:
                    low = middle
                else:
                    high = middle
            keep.append(low)
            at = low
        joints, poses = [joints[k] for k in keep], [poses[k] for k in keep]
        # Corners move towards the middle of their neighbours while it stays valid.
        for v in range(1, len(joints) - 1):
            before = np.linalg.norm(joints[v] - joints[v - 1]) + np.linalg.norm(
                joints[v + 1] - joints[v])
            for share in (1.0, 0.5, 0.25, 0.125):
                moved = joints[v] + share * (0.5 * (joints[v - 1] + joints[v + 1]) - joints[v])
                if np.linalg.norm(moved - joints[v - 1]) + np.linalg.norm(
                        joints[v + 1] - moved) >= before - 1e-9:
                    break
                checked = _accepts([joints[v - 1], moved, joints[v + 1]],
                                   [poses[v - 1], poses[v + 1]])
                if checked.ok:
                    joints[v], poses[v] = moved, checked.poses[1]
                    break
    return np.array(joints), poses


def _length(joints):
    return float(np.linalg.norm(np.diff(joints, axis=0), axis=1).sum())


def _shortest(candidates, start_pose, goal_pose):
    """The shortest of the shortened candidates ``{name: (joints, poses)}``
    that the reference's continuation accepts end to end: its length and
    name, or (inf, "")."""
    shortened = sorted((_length(joints), name, joints) for name, joints in
                       ((name, _shorten(*path)[0]) for name, path in candidates.items()))
    for length, name, joints in shortened:
        followed = follow(joints, start_pose, _MIN_MARGIN * (1 - 1e-3))
        if followed["ok"] and _same_pose(followed["pose"], goal_pose):
            return length, name
    return math.inf, ""


def _quantiles(values):
    ordered = sorted(values)
    if not ordered:
        return math.nan, math.nan, math.nan
    return statistics.median(ordered), ordered[int(0.95 * (len(ordered) - 1))], ordered[-1]


def _wall(args, cache_dir=None):
    """Seconds of one fresh ``rpr3-gwr`` process."""
    command = [shutil.which("rpr3-gwr"), *args]
    if cache_dir is not None:
        command += ["--cache-dir", cache_dir]
    begin = time.perf_counter()
    subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=True)
    return time.perf_counter() - begin


def _fresh_processes(repeat):
    """Median seconds of each of target 4's commands."""
    _wall(_FULL_PLAN)  # the cached roadmaps these plans load, built now if missing
    _wall(_PAPER_PLAN)
    timings = {
        "plan --full (cached roadmap)": [_wall(_FULL_PLAN) for _ in range(repeat)],
        "plan, paper's first example (cached roadmap)":
            [_wall(_PAPER_PLAN) for _ in range(repeat)],
        "--help": [_wall(["--help"]) for _ in range(repeat)],
    }
    roadmaps = []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as empty:
            roadmaps.append(_wall(["roadmap"], cache_dir=empty))
    timings["roadmap 401 x 401 (empty cache)"] = roadmaps
    return {name: statistics.median(times) for name, times in timings.items()}


def _summary(name, records, kinds):
    ms = [1000 * r["seconds"] for r in records]
    p50, p95, worst = _quantiles(ms)
    ratios = [r["ratio"] for r in records if "ratio" in r]
    r50, r95, _ = _quantiles(ratios)
    succeeded = sum(r["ok"] for r in records)
    by_kind = collections.defaultdict(lambda: [0, 0])
    for record, kind in zip(records, kinds):
        by_kind[kind][0] += record["ok"]
        by_kind[kind][1] += 1
    return {"planner": name, "pairs": len(records), "succeeded": succeeded,
            "success_pct": round(100 * succeeded / len(records), 2),
            "success_by_kind": {kind: f"{ok}/{n}" for kind, (ok, n) in by_kind.items()},
            "failures": dict(collections.Counter(r["why"] for r in records if not r["ok"])),
            "plan_p50_ms": round(p50, 2), "plan_p95_ms": round(p95, 2),
            "plan_max_ms": round(worst, 2), "length_ratio_pairs": len(ratios),
            "length_ratio_p50": round(r50, 4), "length_ratio_p95": round(r95, 4)}


def _target(name, measured, threshold, at_least=False):
    met = measured >= threshold if at_least else measured <= threshold
    line = {"target": name, "measured": round(measured, 4), "threshold": round(threshold, 4),
            "met": bool(met)}
    if not met:
        line["missed_by"] = round(abs(measured - threshold), 4)
        line["missed_by_pct"] = round(100 * abs(measured - threshold) / threshold, 1)
    return line


def _emit(line):
    print(json.dumps(line), flush=True)


def _plan_project(pairs, clearance, smooth):
    """Plan every pair with the project's planner, re-check each path."""
    begin = time.perf_counter()
    roadmap, index, _ = cached_planning(PAPER_GEOMETRY, FULL_BASE_GRID,
                                        refinement=FULL_REFINEMENT)
    loaded = time.perf_counter() - begin
    planner = Planner(roadmap, index)
    planner.warm_up()
    _emit({"stage": "project planner set up (load and map the index, warm-up)",
           "load_s": round(loaded, 2), "total_s": round(time.perf_counter() - begin, 2)})
    records, options = [], PlanOptions(smooth=smooth, clearance=clearance)
    for (start, start_pose), (goal, goal_pose) in pairs:
        begin = time.perf_counter()
        try:
            plan = planner.plan(start, goal, options)
        except GWRError as error:
            records.append({"ok": False, "why": error.code,
                            "seconds": time.perf_counter() - begin})
            continue
        record = {"ok": True, "why": "", "seconds": time.perf_counter() - begin}
        try:
            assert_executable(plan, goal_pose, planner.min_margin)
            assert all(_in_box(legs) for legs in plan.joints), "legs leave the box"
            record.update(length=_length(plan.joints), path=(plan.joints, plan.poses))
        except AssertionError as failure:
            record.update(ok=False, why=f"re-check: {str(failure).splitlines()[0]}")
        records.append(record)
    return records


def _plan_ompl(pairs, seed, seconds, step):
    """Plan every pair with OMPL in pose space, re-check each path."""
    space = _OmplPoseSpace(seed, step)
    space.solve(pairs[0][0][1], pairs[0][1][1], seconds)  # loads OMPL's code paths
    records = []
    for (_, start_pose), (_, goal_pose) in pairs:
        poses, spent = space.solve(start_pose, goal_pose, seconds)
        record = {"ok": poses is not None, "why": "" if poses is not None else "no solution",
                  "seconds": spent}
        if poses is not None:
            why, record["length"] = _check_pose_path(poses, start_pose, goal_pose)
            dense = _densify(poses)
            record.update(ok=not why, why=f"re-check: {why}" if why else "",
                          path=([legs_of(p) for p in dense], dense))
        records.append(record)
    return records


def _shortest_paths(pairs, project, ompl):
    """The shortest known path of each pair, the planners' length ratios
    (set in their records) and a summary."""
    begin = time.perf_counter()
    lattice = _PoseLattice()
    built = time.perf_counter() - begin
    missing, source, times = 0, collections.Counter(), []
    for k, ((_, start_pose), (_, goal_pose)) in enumerate(pairs):
        begin = time.perf_counter()
        candidates = {name: records[k]["path"] for name, records in (("project", project),
                                                                      ("ompl", ompl))
                      if records[k]["ok"]}
        pose_path = lattice.path(start_pose, goal_pose)
        if pose_path is None:
            missing += 1
        else:
            dense = _densify(pose_path)
            candidates["lattice"] = ([legs_of(p) for p in dense], dense)
        shortest, name = _shortest(candidates, start_pose, goal_pose)
        for planner, records in (("project", project), ("ompl", ompl)):
            if records[k]["ok"] and records[k]["length"] < shortest:
                shortest, name = records[k]["length"], f"{planner} as planned"
        times.append(time.perf_counter() - begin)
        source[name or "none"] += 1
        for records in (project, ompl):
            if records[k]["ok"]:
                records[k]["ratio"] = records[k]["length"] / shortest
    return {"reference": "shortest known path: the shortest, re-checked, of the lattice's, "
                         "the project's and OMPL's paths, each shortened in joint space",
            "lattice": f"{_LATTICE_STEP} x {_LATTICE_STEP} x 2 pi / {_ORIENTATIONS}",
            "lattice_nodes": {"+": int(lattice.valid[1].sum()),
                              "-": int(lattice.valid[-1].sum())},
            "lattice_build_s": round(built, 2), "pairs": len(pairs),
            "lattice_missing": missing, "shortest_from": dict(source),
            "per_pair_p50_ms": round(1000 * statistics.median(times), 1) if times else None}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=250)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--ompl-time", type=float, default=1.0,
                        help="OMPL's time limit per pair, simplification included [s]")
    parser.add_argument("--ompl-step", type=float, default=_OMPL_STEP,
                        help="OMPL's state validity checking resolution, as a step "
                             "[scaled pose length]")
    parser.add_argument("--reference-pairs", type=int, default=None,
                        help="shortest paths for the first N pairs only (default: all)")
    parser.add_argument("--clearance", type=float, default=DEFAULT_CLEARANCE,
                        help="the planner's clearance (a larger margin from singularities, "
                             "kept where the roadmap allows, makes paths longer)")
    parser.add_argument("--smooth", action=argparse.BooleanOptionalAction, default=True,
                        help="plan with smoothing, the service's and the CLI's default answer "
                             "(--no-smooth: the cell path as it is)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="runs of each fresh-process timing (median)")
    args = parser.parse_args()
    if args.pairs < 10:
        parser.error("--pairs must be at least 10")
    started = time.perf_counter()

    drawn = _draw_pairs(np.random.default_rng(args.seed), args.pairs)
    kinds = [kind for kind, _ in drawn]
    pairs = [pair for _, pair in drawn]
    _emit({"pairs": len(pairs), "kinds": dict(collections.Counter(kinds)), "seed": args.seed})

    baseline = eigenvalue_baseline(5)
    _emit({"baseline": "eigvals of 401x401 complex 6x6 companion matrices", "repeat": 5,
           "median_s": round(baseline, 3)})
    fresh = _fresh_processes(args.repeat)
    for command, seconds in fresh.items():
        _emit({"fresh_process": f"rpr3-gwr {command}", "repeat": args.repeat,
               "median_s": round(seconds, 3), "over_baseline": round(seconds / baseline, 3)})

    project = _plan_project(pairs, args.clearance, args.smooth)
    ompl = _plan_ompl(pairs, args.seed, args.ompl_time, args.ompl_step)
    count = len(pairs) if args.reference_pairs is None else min(args.reference_pairs, len(pairs))
    _emit(_shortest_paths(pairs[:count], project, ompl))

    ours = _summary("rpr3-gwr (in process, index mapped"
                    + (", smoothed)" if args.smooth else ", not smoothed)"), project, kinds)
    theirs = _summary(f"OMPL RRTConnect in pose space, SimpleSetup, discrete motion validator "
                      f"(step {args.ompl_step}), simplifySolution() (limit {args.ompl_time} s)",
                      ompl, kinds)
    _emit(ours)
    _emit(theirs)
    for line in (
            _target("1 success on same-aspect pairs [%]", ours["success_pct"], 100.0,
                    at_least=True),
            _target("2 plan p95 [ms] <= 0.3 x OMPL's", ours["plan_p95_ms"],
                    0.3 * theirs["plan_p95_ms"]),
            _target("2 plan max [ms] <= 0.8 x OMPL's", ours["plan_max_ms"],
                    0.8 * theirs["plan_max_ms"]),
            _target("2 plan p50 [ms] <= 0.15 x OMPL's", ours["plan_p50_ms"],
                    0.15 * theirs["plan_p50_ms"]),
            _target("3 length / shortest, p50", ours["length_ratio_p50"], 1.05),
            _target("3 length / shortest, p95", ours["length_ratio_p95"], 1.25),
            _target("4 rpr3-gwr plan --full, cached / baseline",
                    fresh["plan --full (cached roadmap)"] / baseline, 0.6),
            _target("4 rpr3-gwr plan (paper's first example), cached / baseline",
                    fresh["plan, paper's first example (cached roadmap)"] / baseline, 0.4),
            _target("4 rpr3-gwr --help / baseline", fresh["--help"] / baseline, 0.1),
            _target("4 rpr3-gwr roadmap 401 x 401, empty cache / baseline",
                    fresh["roadmap 401 x 401 (empty cache)"] / baseline, 0.6)):
        _emit(line)
    _emit({"run_s": round(time.perf_counter() - started, 1)})


if __name__ == "__main__":
    main()
