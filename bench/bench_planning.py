"""Benchmark: planning on the paper's roadmap (rho1 = 17, 401 x 401).

Run on demand:  python bench/bench_planning.py [--pairs 1000] [--repeat 21] [--seed 0]

Prints the median plan time of the paper's two examples (global + local +
stitching + validation, roadmap already built and the planner's lookups
warm), the median feasibility-only time, and for random start/goal pairs
drawn from the roadmap's cells: how many the roadmap connects, how many of
those were planned, and p50/p95 plan times.
"""

import argparse
import json
import math
import statistics
import time

import networkx as nx
import numpy as np

from rpr3_gwr_core.exceptions import GWRError
from rpr3_gwr_core.planning.planner import PlanOptions, Planner
from rpr3_gwr_core.paper import PAPER_GEOMETRY, PAPER_GRID
from rpr3_gwr_core.workspace.roadmap import build_roadmap

EXAMPLES = {
    "two_configurations": ((17, 12, 18, math.radians(122.82)), (17, 10, 25, math.radians(-24.24))),
    "assembly_mode_change": ((17, 20, 25, math.radians(29.47)), (17, 20, 25, math.radians(96.13))),
}


def _timed(call, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def random_configuration(roadmap, rng):
    """A configuration at a random cell of a random patch, on that patch's sheet."""
    seg = roadmap.segmentation
    pid = rng.choice(sorted(seg.patches))
    patch = seg.patches[pid]
    k = rng.integers(patch.cells.size)
    cell, slot = patch.cells[k], patch.slots[k]
    rho = roadmap.grid.joints_of(cell)
    return (rho[0], rho[1], rho[2], float(seg.field.poses[cell, slot, 2])), pid


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=21)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    roadmap = build_roadmap(PAPER_GEOMETRY, PAPER_GRID)
    planner = Planner(roadmap)
    for name, (start, goal) in EXAMPLES.items():
        planner.plan(start, goal)  # warm the patch profiles
        print(json.dumps({
            "example": name,
            "plan_median_ms": round(
                1e3 * _timed(lambda: planner.plan(start, goal), args.repeat), 2),
            "smooth_plan_median_ms": round(1e3 * _timed(
                lambda: planner.plan(start, goal, PlanOptions(smooth=True)), args.repeat), 2),
            "feasibility_median_ms": round(1e3 * _timed(
                lambda: planner.plan(start, goal, PlanOptions(feasibility_only=True)),
                args.repeat * 5), 3)}))
    rng = np.random.default_rng(args.seed)
    connected = planned = 0
    times, failures = [], []
    for _ in range(args.pairs):
        (start, ps), (goal, pg) = (random_configuration(roadmap, rng),
                                   random_configuration(roadmap, rng))
        linked = nx.has_path(roadmap.graph, ps, pg)
        connected += linked
        begin = time.perf_counter()
        try:
            planner.plan(start, goal)
            ok = True
        except GWRError as exc:
            ok = False
            if linked:
                failures.append({"start": start, "goal": goal, "error": exc.code,
                                 "message": str(exc)})
        times.append(time.perf_counter() - begin)
        planned += ok and linked
    print(json.dumps({
        "pairs": args.pairs, "connected": connected, "planned_connected": planned,
        "success_rate_connected": round(planned / max(connected, 1), 4),
        "p50_ms": round(1e3 * float(np.percentile(times, 50)), 2),
        "p95_ms": round(1e3 * float(np.percentile(times, 95)), 2),
        "failures": failures[:5]}))


if __name__ == "__main__":
    main()
