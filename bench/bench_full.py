"""Benchmark: the full 3-DOF roadmap (all three legs free).

Run on demand:  python bench/bench_full.py [--pairs 100] [--seed 1]

Prints, as JSON lines: the cold build of the default box (refinement
included) in a separate process with its peak resident memory, the load from
the on-disk cache (median of three, in-process), the planner's set-up, the
gate distances of every patch (which plans otherwise compute on first use), and
plan times over random pairs of configurations of one aspect with rho1,
rho2 and rho3 all differing.  The pairs are drawn independently of the
roadmap: rho1 uniform in the box, B1 on leg 1's circle at a uniform angle,
a uniform orientation, the other legs by inverse kinematics; kept when all
legs lie in the box and the margin is at least 3e-3.
"""

import argparse
from concurrent.futures import ThreadPoolExecutor
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from rpr3_gwr_core import GWRError, PAPER_GEOMETRY, Planner
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT
from rpr3_gwr_core.planning import build_cell_search_index

from bench_roadmap import THREADS  # bench/ is the script's folder

# VmHWM, unlike ru_maxrss, is not inherited across exec from the parent.
_BUILD = """
import sys, time
from rpr3_gwr_core import PAPER_GEOMETRY
from rpr3_gwr_core.io.cache import cached_roadmap
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
from concurrent.futures import ThreadPoolExecutor
start = time.perf_counter()
with ThreadPoolExecutor(int(sys.argv[2])) as pool:
    roadmap, hit = cached_roadmap(PAPER_GEOMETRY, FULL_BASE_GRID, sys.argv[1],
                                  refinement=FULL_REFINEMENT, workers=pool.map)
print(time.perf_counter() - start, hwm(), hit)
"""


def _configurations(count, seed, min_margin=3e-3):
    """``(rho1, rho2, rho3, alpha)`` rows and their aspect (module doc)."""
    rng = np.random.default_rng(seed)
    box = FULL_BASE_GRID.axes
    rows, signs = [], []
    while len(rows) < count:
        rho1 = rng.uniform(box[0].low, box[0].high, 4096)
        theta1, alpha = rng.uniform(-math.pi, math.pi, (2, 4096))
        a1 = np.asarray(PAPER_GEOMETRY.a1)
        pose = np.stack([a1[0] + rho1 * np.cos(theta1), a1[1] + rho1 * np.sin(theta1), alpha],
                        axis=1)
        legs = PAPER_GEOMETRY.inverse(pose)
        margin = PAPER_GEOMETRY.margin(pose)
        keep = (np.all([(legs[:, a.joint] >= a.low) & (legs[:, a.joint] <= a.high)
                        for a in box], axis=0) & (np.abs(margin) >= min_margin))
        rows += [(*q, a) for q, a in zip(legs[keep], alpha[keep])]
        signs += np.sign(margin[keep]).tolist()
    return rows[:count], signs[:count]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=100)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        seconds, peak_kb, _ = subprocess.run(
            [sys.executable, "-c", _BUILD, cache, str(THREADS)], capture_output=True,
            text=True, check=True).stdout.split()
        print(json.dumps({"stage": "build (cold, refinement included)",
                          "seconds": round(float(seconds), 2),
                          "peak_rss_mb": round(int(peak_kb) / 1024, 1)}))
        loads = []
        for _ in range(3):
            start = time.perf_counter()
            with ThreadPoolExecutor(THREADS) as pool:
                roadmap, index, hit = cached_planning(PAPER_GEOMETRY, FULL_BASE_GRID, cache,
                                                      refinement=FULL_REFINEMENT,
                                                      workers=pool.map)
            loads.append(time.perf_counter() - start)
            assert hit
    seg = roadmap.segmentation
    print(json.dumps({"stage": "load and map from cache (roadmap and planning index)",
                      "median_s": round(statistics.median(loads), 2),
                      "runs_s": [round(t, 2) for t in loads], "cells": roadmap.grid.size,
                      "regions": seg.n_regions, "patches": len(seg.patches),
                      "gates": len(seg.gates)}))
    start = time.perf_counter()
    planner = Planner(roadmap, index)
    print(json.dumps({"stage": "planner set-up", "seconds":
                      round(time.perf_counter() - start, 2)}))
    start = time.perf_counter()
    build_cell_search_index(roadmap)
    print(json.dumps({"stage": "planning index built again (gate distances, node costs)",
                      "seconds": round(time.perf_counter() - start, 2)}))
    rows, signs = _configurations(8 * args.pairs, args.seed)
    by_sign = [[q for q, t in zip(rows, signs) if t == s] for s in (-1.0, 1.0)]
    pairs = [pair for group in by_sign for pair in zip(group[0::2], group[1::2])]
    pairs = [pairs[k] for k in np.random.default_rng(args.seed).permutation(len(pairs))]
    pairs = pairs[:args.pairs]
    times, outcomes = [], {}
    for start_q, goal_q in pairs:
        begin = time.perf_counter()
        try:
            planner.plan(start_q, goal_q)
            outcome = "planned"
        except GWRError as exc:
            outcome = exc.code
        times.append(time.perf_counter() - begin)
        outcomes[outcome] = outcomes.get(outcome, 0) + 1
    times.sort()
    print(json.dumps({"stage": "plan, all legs moving", "pairs": len(pairs),
                      "outcomes": outcomes,
                      "median_ms": round(1e3 * statistics.median(times), 1),
                      "p95_ms": round(1e3 * times[int(0.95 * (len(times) - 1))], 1),
                      "max_ms": round(1e3 * times[-1], 1)}))


if __name__ == "__main__":
    main()
