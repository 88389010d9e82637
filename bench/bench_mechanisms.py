"""Benchmark: every mechanism's 2-D slice, built and planned on.

Run on demand, after ``source ros2_ws/env.sh``:

    python bench/bench_mechanisms.py [--cells 401] [--pairs 200] [--repeat 3] [--seed 1]
                                     [--full-refinement 4] [--no-full]

For each mechanism file in ``config/`` (a slice of ``--cells`` x ``--cells``
cells: the paper's 3-RPR at rho1 = 17, the five-bar over its whole torus,
the 3-RRR at th1 = 0, over its torus, the 3-PRR at s1 = 5), the median
build time of the roadmap over ``--repeat`` builds after one of the same
size, as a fraction of the eigenvalue baseline of
``bench_roadmap.py`` measured in the same run (the target: 0.25),
and plans between random same-aspect pairs of cell solutions with margin at
least 0.05 (p50 / p95 / max; target p50 <= 5 ms), with the reasons of the
pairs refused (``unreachable``: the roadmap joins the pair's patches by no
chain of gates).  Then the 3-RRR's full roadmap over its torus (all three
joints turning, ``config/three_rrr.yaml``'s 120 cells a turn as the fine
lattice of an adaptive grid refined ``--full-refinement`` times), built
once in a fresh process: its wall and CPU time, the time of its planning
index, its peak resident memory (``ru_maxrss`` of the child), cells,
regions, patches and gates (the budget: 60 s and 2 GB).  Prints one
JSON line per measurement.
"""

import argparse
from concurrent.futures import ThreadPoolExecutor
import json
import math
import pathlib
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

from rpr3_gwr_core import GWRError, InfeasiblePathError, Planner, build_roadmap
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.workspace.grid import Axis, Grid

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from bench_roadmap import THREADS, eigenvalue_baseline  # noqa: E402

CONFIG = pathlib.Path(__file__).resolve().parents[1] / "config"
# The file and the joint it fixes for the slice.
SLICES = {"paper_3rpr.yaml": {"rho1": 17.0}, "five_bar.yaml": {},
          "three_rrr.yaml": {"th1": 0.0}, "three_prr.yaml": {"s1": 5.0}}

# The full 3-RRR roadmap, in a process of its own so that its peak memory
# is its own; prints one JSON object.
_FULL_BUILD = """
import json, math, sys, time
from rpr3_gwr_core import build_roadmap
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.planning import build_cell_search_index
from rpr3_gwr_core.workspace.adaptive import coarse_base, refine
from concurrent.futures import ThreadPoolExecutor
described = load_mechanism_file(sys.argv[1])
refinement = int(sys.argv[2])
wall, cpu = time.perf_counter(), time.process_time()
with ThreadPoolExecutor(int(sys.argv[3])) as pool:
    grid = refine(described.mechanism, coarse_base(described.grid(), refinement), refinement,
                  workers=pool.map)
    roadmap = build_roadmap(described.mechanism, grid, workers=pool.map)
wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
index = time.perf_counter()
build_cell_search_index(roadmap)
seg = roadmap.segmentation
print(json.dumps({"build_s": round(wall, 2), "build_cpu_s": round(cpu, 2),
                  "search_index_s": round(time.perf_counter() - index, 2),
                  "cells": grid.size, "refined_blocks": int(grid.blocks.size),
                  "blocks": math.prod(grid.block_shape),
                  "regions": seg.n_regions, "patches": len(seg.patches),
                  "gates": len(seg.gates)}))
"""


def _resampled(grid, cells):
    """The grid with ``cells`` cells along each axis over the same range
    (a periodic axis keeps its full turn)."""
    axes = []
    for a in grid.axes:
        if a.periodic:
            step = 2 * math.pi / cells
            axes.append(Axis(a.joint, a.low, a.low + 2 * math.pi - step, step, periodic=True))
        else:
            axes.append(Axis(a.joint, a.low, a.high, (a.high - a.low) / (cells - 1)))
    return Grid(axes=tuple(axes), fixed=grid.fixed)


def _pairs(roadmap, count, rng, min_margin=0.05):
    """Random pairs of cell solutions of one aspect, as configurations."""
    field = roadmap.field
    mechanism = field.mechanism
    cells, slots = np.nonzero(field.valid & (np.abs(field.margin) >= min_margin)
                              & (roadmap.segmentation.patch > 0))
    sign = np.sign(field.margin[cells, slots])
    out = []
    while len(out) < count:
        a, b = rng.integers(cells.size, size=2)
        if sign[a] != sign[b]:
            continue
        out.append(tuple((*roadmap.grid.joints_of(int(cells[k])),
                          float(field.poses[cells[k], slots[k], mechanism.mode_coordinate]))
                         for k in (a, b)))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=401)
    parser.add_argument("--pairs", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--full-refinement", type=int, default=4)
    parser.add_argument("--no-full", action="store_true",
                        help="skip the 3-RRR's full roadmap over its torus")
    args = parser.parse_args()
    baseline = eigenvalue_baseline(args.repeat)
    print(json.dumps({"baseline_s": round(baseline, 3)}), flush=True)
    # The builds run their chunks in a thread per core, as the command line's do.
    pool = ThreadPoolExecutor(THREADS)
    for name, fixed in SLICES.items():
        described = load_mechanism_file(CONFIG / name)
        grid = _resampled(described.grid(fixed), args.cells)
        # A first build of the same size loads (or compiles) the kernels and
        # takes the process's memory to what every build then reuses: the
        # first one pays for fresh pages (a fresh process's first build is
        # bench_fresh.py's), the median is of builds in steady state.
        build_roadmap(described.mechanism, grid, workers=pool.map)
        times = []
        for _ in range(args.repeat):
            begin = time.perf_counter()
            roadmap = build_roadmap(described.mechanism, grid, workers=pool.map)
            times.append(time.perf_counter() - begin)
        build = statistics.median(times)
        seg = roadmap.segmentation
        planner = Planner(roadmap)
        planner.warm_up()
        seconds, failures = [], {}
        for start, goal in _pairs(roadmap, args.pairs, np.random.default_rng(args.seed)):
            begin = time.perf_counter()
            try:
                planner.plan(start, goal)
            except GWRError as exc:
                # "unreachable": the pair's patches lie in two components.
                why = (exc.reason if isinstance(exc, InfeasiblePathError) else None) or exc.code
                failures[why] = failures.get(why, 0) + 1
            seconds.append(time.perf_counter() - begin)
        ms = 1000 * np.array(seconds)
        print(json.dumps({
            "mechanism": described.mechanism.kind, "file": name, "fixed": fixed,
            "grid": list(grid.shape), "build_s": round(build, 3),
            "build_over_baseline": round(build / baseline, 3), "regions": seg.n_regions,
            "patches": len(seg.patches), "gates": len(seg.gates), "pairs": len(seconds),
            "refused": failures, "plan_p50_ms": round(float(np.median(ms)), 2),
            "plan_p95_ms": round(float(np.percentile(ms, 95)), 2),
            "plan_max_ms": round(float(ms.max()), 2)}), flush=True)
    if not args.no_full:
        # Compiled kernels are loaded from numba's cache by the first slice builds.
        out = subprocess.run([sys.executable, "-c", _FULL_BUILD, str(CONFIG / "three_rrr.yaml"),
                              str(args.full_refinement), str(THREADS)], capture_output=True,
                             text=True, check=True).stdout
        row = json.loads(out)
        peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        print(json.dumps({"mechanism": "3-RRR", "file": "three_rrr.yaml", "full": True,
                          "refinement": args.full_refinement, **row,
                          "build_over_baseline": round(row["build_s"] / baseline, 2),
                          "peak_rss_mb": round(peak / 1024, 1)}), flush=True)


if __name__ == "__main__":
    main()
