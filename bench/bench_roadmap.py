"""Benchmark: full roadmap build (field, regions, patches, gates, graph).

Run on demand:  python bench/bench_roadmap.py [--repeat 5] [--steps 0.25 0.125 0.0625]

Prints first the eigenvalue baseline: the median wall time numpy
takes for ``np.linalg.eigvals`` of 160,801 complex 6 x 6 companion matrices,
one per cell of the paper's 401 x 401 grid.  Then, per grid, the median and
spread of the wall time of ``build_roadmap`` (imports excluded) and its
stages, the median over the baseline, the time per cell over the 401 x 401
grid's (1 for linear scaling), and the peak resident memory of a separate
process building that grid once.  A last line sums up the targets:
the 401 x 401 build within a quarter of the baseline, linear scaling to
801 x 801.  Everything but the peak memory is measured in this one process,
so baseline and builds meet the same machine state.
"""

import argparse
from concurrent.futures import ThreadPoolExecutor
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

from rpr3_gwr_core import PAPER_GEOMETRY, build_roadmap, rho1_slice

# VmHWM, unlike ru_maxrss, is not inherited across exec from the parent.
_PEAK = """
import sys
from rpr3_gwr_core import PAPER_GEOMETRY, build_roadmap, rho1_slice
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
from concurrent.futures import ThreadPoolExecutor
before = hwm()
with ThreadPoolExecutor(int(sys.argv[2])) as pool:
    build_roadmap(PAPER_GEOMETRY, rho1_slice(step=float(sys.argv[1])), workers=pool.map)
print(before, hwm())
"""

_PAPER_STEP = 0.125
# Threads of the builds: one per core, four at most, as the command line's.
THREADS = min(4, os.cpu_count() or 1)
_TARGET_RATIO = 0.25


def eigenvalue_baseline(repeat, cells=401 * 401):
    """Median seconds of ``np.linalg.eigvals`` of ``cells`` complex companion
    matrices (a sextic's, random coefficients) [s]."""
    rng = np.random.default_rng(11)
    companion = np.zeros((cells, 6, 6), dtype=complex)
    companion[:, np.arange(1, 6), np.arange(5)] = 1.0
    companion[:, :, 5] = rng.standard_normal((cells, 6)) + 1j * rng.standard_normal((cells, 6))
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        np.linalg.eigvals(companion)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--steps", type=float, nargs="+", default=[0.25, 0.125, 0.0625])
    args = parser.parse_args()
    # The builds run their chunks in a thread per core, as the command line's do.
    pool = ThreadPoolExecutor(THREADS)
    # Warms the caches of numpy's and scipy's code paths.
    build_roadmap(PAPER_GEOMETRY, rho1_slice(step=1.0), workers=pool.map)
    baseline = eigenvalue_baseline(args.repeat)
    print(json.dumps({"baseline": "eigvals of 401x401 complex 6x6 companion matrices",
                      "repeat": args.repeat, "median_s": round(baseline, 3)}))
    # The 401 x 401 grid first: the others' time per cell is compared with it.
    steps = sorted(args.steps, key=lambda step: step != _PAPER_STEP)
    per_cell = {}
    for step in steps:
        grid = rho1_slice(step=step)
        times, stages = [], []
        for _ in range(args.repeat):
            start = time.perf_counter()
            roadmap = build_roadmap(PAPER_GEOMETRY, grid, workers=pool.map)
            times.append(time.perf_counter() - start)
            stages.append(roadmap.timings)
        peak = subprocess.run([sys.executable, "-c", _PEAK, str(step), str(THREADS)],
                              capture_output=True, text=True, check=True).stdout.split()
        n2, n3 = grid.shape
        median = statistics.median(times)
        per_cell[step] = median / grid.size
        line = {
            "grid": f"{n2}x{n3}", "cells": grid.size, "repeat": args.repeat,
            "median_s": round(median, 3),
            "min_s": round(min(times), 3), "max_s": round(max(times), 3),
            "us_per_cell": round(1e6 * per_cell[step], 2),
            "stages_median_s": {k: round(statistics.median(s[k] for s in stages), 3)
                                for k in stages[0]},
            "patches": len(roadmap.segmentation.patches),
            "peak_rss_mb": round(int(peak[1]) / 1024, 1),
            "import_rss_mb": round(int(peak[0]) / 1024, 1),
            "over_baseline": round(median / baseline, 3),
        }
        if _PAPER_STEP in per_cell:
            line["per_cell_over_401"] = round(per_cell[step] / per_cell[_PAPER_STEP], 2)
        print(json.dumps(line))
    if _PAPER_STEP in per_cell:
        paper = per_cell[_PAPER_STEP] * rho1_slice(step=_PAPER_STEP).size
        summary = {"measure": "401x401 build over the eigvals baseline",
                   "ratio": round(paper / baseline, 3), "target": _TARGET_RATIO,
                   "met": paper <= _TARGET_RATIO * baseline}
        if 0.0625 in per_cell:
            summary["per_cell_801_over_401"] = round(per_cell[0.0625] / per_cell[_PAPER_STEP], 2)
        print(json.dumps(summary))


if __name__ == "__main__":
    main()
