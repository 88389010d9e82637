"""Benchmark: what a scene costs the planner node's plan workers.

Run on demand, after ``source ros2_ws/env.sh``:
    python bench/bench_scene_workers.py [--full] [--workers 2] [--scenes 5] [--pairs 60]

Prints, as JSON lines, for the paper's 2-D roadmap (rho1 = 17, 401 x 401)
and with ``--full`` the full 3-DOF roadmap (both from the cache, or built and
cached), with ``--workers`` plan workers as the planner node starts them: the
workers' resident memory (each, summed) before any scene, after the first
scene and after the last; the time to give every worker a scene (the first,
which indexes the body model, and the median of the others); and plan times
(p50, p95) of the same requests in the last scene planned by the node's
process and by the workers.  The scenes and pairs are bench_scene.py's.
"""

import argparse
import json
import os
import statistics
import tempfile
import time

import numpy as np

from rpr3_gwr_core import GWRError, PAPER_GEOMETRY, Planner
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT, PAPER_GRID
from rpr3_gwr_core.planning import NEVER, PlanOptions
from rpr3_gwr_core.world import BodyModel
from rpr3_gwr_nodes.plan_workers import PlanWorkers

from bench_scene import free_pairs, random_scene  # bench/ is the script's folder


def _children_rss_mb():
    """Resident memory [MB] of this process's children (the workers)."""
    pid = os.getpid()
    with open(f"/proc/{pid}/task/{pid}/children") as stream:
        children = stream.read().split()
    sizes = []
    for child in children:
        with open(f"/proc/{child}/status") as stream:
            for line in stream:
                if line.startswith("VmRSS:"):
                    sizes.append(int(line.split()[1]) / 1024)
    return [round(size, 1) for size in sizes]


def _plan_ms(plan, pairs):
    times = []
    for start, goal in pairs:
        begin = time.perf_counter()
        try:
            plan(start, goal)
        except GWRError:
            pass
        times.append(1000 * (time.perf_counter() - begin))
    return {"p50_ms": round(statistics.median(times), 2),
            "p95_ms": round(float(np.percentile(times, 95)), 2)}


def run(name, roadmap, index, args, folder):
    rng = np.random.default_rng(args.seed)
    scenes = [random_scene(rng, args.obstacles) for _ in range(args.scenes)]
    model = BodyModel()
    planner = Planner(roadmap, index)
    workers = PlanWorkers(roadmap, index, args.workers, 600.0, folder)
    try:
        before = _children_rss_mb()
        seconds = []
        for key, scene in enumerate(scenes, start=1):
            begin = time.perf_counter()
            workers.apply_scene(key, scene, model)
            seconds.append(time.perf_counter() - begin)
            if key == 1:
                first = _children_rss_mb()
        last = _children_rss_mb()
        world = planner.apply_scene(scenes[-1], model)
        pairs = free_pairs(roadmap, world, rng, args.pairs)
        options = PlanOptions()
        here = _plan_ms(lambda s, g: planner.plan(s, g, options, world=world), pairs)
        there = _plan_ms(lambda s, g: workers.plan(s, g, options, NEVER, len(scenes)), pairs)
    finally:
        workers.close()
    print(json.dumps({
        "roadmap": name, "workers": args.workers, "scenes": args.scenes,
        "worker_rss_mb": {"before": before, "first_scene": first, "last_scene": last},
        "added_per_worker_mb": round((sum(last) - sum(before)) / len(before), 1),
        "apply_s": {"first": round(seconds[0], 3),
                    "others_median": round(statistics.median(seconds[1:]), 3)},
        "plan_in_scene": {"pairs": len(pairs), "node_process": here, "workers": there}}),
        flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--scenes", type=int, default=5)
    parser.add_argument("--obstacles", type=int, default=10)
    parser.add_argument("--pairs", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if args.scenes < 2:
        parser.error("--scenes must be at least 2")
    grids = [("paper slice", PAPER_GRID, {})]
    if args.full:
        grids.append(("full 3-DOF", FULL_BASE_GRID, {"refinement": FULL_REFINEMENT}))
    with tempfile.TemporaryDirectory() as folder:
        for name, grid, extra in grids:
            roadmap, index, _ = cached_planning(PAPER_GEOMETRY, grid, **extra)
            run(name, roadmap, index, args, folder)


if __name__ == "__main__":
    main()
