"""Benchmark: a scene applied to a built roadmap (obstacles, collisions, parts).

Run on demand:  python bench/bench_scene.py [--full] [--obstacles 10] [--scenes 21] [--seed 0]

Prints, as JSON lines, for the paper's 2-D roadmap (rho1 = 17, 401 x 401)
and with ``--full`` the full 3-DOF roadmap (both loaded from the cache, or
built and cached): the world index's one-off build, then over random scenes
of ``--obstacles`` obstacles (discs and quadrilaterals in the workspace
around the base, clearance 0.25) the median and largest time from a scene
to its usable scene roadmap (blocked solutions, parts, part components), the
feasibility of the paper's first example, and the resident memory after
the first and the last scene (no growth with the number of scenes); then
plan times (p50, p95, max) of ``--pairs`` random same-aspect pairs of patch
solutions the last scene leaves free, without a scene and in it, and their
ratio (target: within 2x).
"""

import argparse
import json
import math
import statistics
import time

import numpy as np

from rpr3_gwr_core import GWRError, PAPER_GEOMETRY, Planner
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT, PAPER_GRID
from rpr3_gwr_core.planning.locate import locate
from rpr3_gwr_core.world import WorldIndex, scene_from_dict

EXAMPLE = ((17, 12, 18, math.radians(122.82)), (17, 10, 25, math.radians(-24.24)))


def random_scene(rng, count):
    """``count`` obstacles around the base: discs and quadrilaterals."""
    obstacles = []
    for k in range(count):
        x, y = rng.uniform(-40, 50, 2)
        if k % 2:
            obstacles.append({"id": k, "disc": {"center": [float(x), float(y)],
                                                "radius": float(rng.uniform(0.5, 2.0))}})
        else:
            w, h = rng.uniform(1, 4, 2)
            obstacles.append({"id": k, "polygon": [[x, y], [x + w, y], [x + w, y + h],
                                                   [x, y + h]]})
    return scene_from_dict({"obstacles": obstacles, "limits": {"obstacle_clearance": 0.25}})


def resident_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def free_pairs(roadmap, restricted, rng, count):
    """Same-aspect pairs of patch solutions the scene leaves free, as
    configurations (joints, then the mode coordinate)."""
    seg = roadmap.segmentation
    mechanism = roadmap.mechanism
    cells, slots = np.nonzero(restricted.free & (seg.patch > 0))
    aspect = np.sign(seg.field.margin[cells, slots])
    pairs = []
    while len(pairs) < count:
        a, b = rng.integers(cells.size, size=2)
        if aspect[a] == aspect[b] and abs(seg.field.margin[cells[a], slots[a]]) > 0.01 \
                and abs(seg.field.margin[cells[b], slots[b]]) > 0.01:
            pairs.append(tuple(
                (*roadmap.grid.joints_of(int(cells[k])),
                 float(seg.field.poses[cells[k], slots[k], mechanism.mode_coordinate]))
                for k in (a, b)))
    return pairs


def _plan_times(planner, pairs, world):
    """Milliseconds of each plan (failures included) and how many succeeded."""
    times, succeeded = [], 0
    for start, goal in pairs:
        begin = time.perf_counter()
        try:
            planner.plan(start, goal, world=world)
            succeeded += 1
        except GWRError:
            pass
        times.append(1e3 * (time.perf_counter() - begin))
    return times, succeeded


def _quantiles(times):
    ordered = sorted(times)
    p95 = ordered[int(0.95 * (len(ordered) - 1))]
    return [round(statistics.median(ordered), 2), round(p95, 2), round(ordered[-1], 2)]


def run(name, roadmap, index, args, example):
    start = time.perf_counter()
    world = WorldIndex(roadmap)
    built = time.perf_counter() - start
    world.apply(random_scene(np.random.default_rng(99), args.obstacles))  # compiles
    rng = np.random.default_rng(args.seed)
    times, cpu, blocked, parts = [], [], [], []
    first_memory = None
    for k in range(args.scenes):
        scene = random_scene(rng, args.obstacles)
        start, start_cpu = time.perf_counter(), time.process_time()
        restricted = world.apply(scene)
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
        blocked.append(1 - restricted.free.sum() / world.disks.size)
        parts.append(restricted.n_parts)
        if k == 0:
            first_memory = resident_mb()
    answer = None
    if example is not None:
        start_location, goal_location = (locate(roadmap, c) for c in example)
        answer = restricted.feasibility(start_location, goal_location).reason
    print(json.dumps({
        "roadmap": name, "solutions": int(world.disks.size), "index_build_s": round(built, 3),
        "obstacles": args.obstacles, "scenes": args.scenes,
        "apply_median_ms": round(1e3 * statistics.median(times), 1),
        "apply_max_ms": round(1e3 * max(times), 1),
        "apply_cpu_median_ms": round(1e3 * statistics.median(cpu), 1),
        "blocked_fraction_median": round(statistics.median(blocked), 3),
        "parts_median": statistics.median(parts), "last_example_feasibility": answer,
        "rss_mb_after_first_scene": round(first_memory),
        "rss_mb_after_last": round(resident_mb())}),
        flush=True)
    planner = Planner(roadmap, index)
    planner.warm_up()
    in_scene = planner.apply_scene(scene)
    pairs = free_pairs(roadmap, in_scene, np.random.default_rng(args.seed + 1), args.pairs)
    _plan_times(planner, pairs[:3], in_scene)  # the scene's kernels load
    empty, empty_ok = _plan_times(planner, pairs, None)
    scened, scened_ok = _plan_times(planner, pairs, in_scene)
    line = {"roadmap": name, "pairs": len(pairs),
            "plan_ms_p50_p95_max_without_scene": _quantiles(empty),
            "succeeded_without_scene": empty_ok,
            "plan_ms_p50_p95_max_in_scene": _quantiles(scened), "succeeded_in_scene": scened_ok}
    line["ratio_p50_p95"] = [round(b / a, 2) for a, b in zip(line[
        "plan_ms_p50_p95_max_without_scene"][:2], line["plan_ms_p50_p95_max_in_scene"][:2])]
    print(json.dumps(line), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true")
    parser.add_argument("--obstacles", type=int, default=10)
    parser.add_argument("--scenes", type=int, default=21)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pairs", type=int, default=100,
                        help="random pairs planned without and in a scene")
    args = parser.parse_args()
    roadmap, index, _ = cached_planning(PAPER_GEOMETRY, PAPER_GRID)
    run("paper_rho17_401x401", roadmap, index, args, EXAMPLE)
    if args.full:
        del roadmap, index
        roadmap, index, _ = cached_planning(PAPER_GEOMETRY, FULL_BASE_GRID,
                                            refinement=FULL_REFINEMENT)
        run("full_3dof", roadmap, index, args, None)


if __name__ == "__main__":
    main()
