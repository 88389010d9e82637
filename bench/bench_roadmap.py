"""Benchmark: full roadmap build (field, regions, patches, gates, graph).

Run on demand:  python bench/bench_roadmap.py [--repeat 5] [--steps 0.25 0.125 0.0625]

Prints, per grid, the median and spread of the wall time of ``build_roadmap``
(imports excluded) and its stages, and the peak resident memory of a separate
process building that grid once.
"""

import argparse
import json
import statistics
import subprocess
import sys
import time

from rpr3_gwr_core import PAPER_GEOMETRY, build_roadmap, rho1_slice

# VmHWM, unlike ru_maxrss, is not inherited across exec from the parent.
_PEAK = """
import sys
from rpr3_gwr_core import PAPER_GEOMETRY, build_roadmap, rho1_slice
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
before = hwm()
build_roadmap(PAPER_GEOMETRY, rho1_slice(step=float(sys.argv[1])))
print(before, hwm())
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--steps", type=float, nargs="+", default=[0.25, 0.125, 0.0625])
    args = parser.parse_args()
    build_roadmap(PAPER_GEOMETRY, rho1_slice(step=1.0))  # warm caches of numpy/scipy code paths
    for step in args.steps:
        grid = rho1_slice(step=step)
        times, stages = [], []
        for _ in range(args.repeat):
            start = time.perf_counter()
            roadmap = build_roadmap(PAPER_GEOMETRY, grid)
            times.append(time.perf_counter() - start)
            stages.append(roadmap.timings)
        peak = subprocess.run([sys.executable, "-c", _PEAK, str(step)], capture_output=True,
                              text=True, check=True).stdout.split()
        n2, n3 = grid.shape
        print(json.dumps({
            "grid": f"{n2}x{n3}", "cells": grid.size, "repeat": args.repeat,
            "median_s": round(statistics.median(times), 3),
            "min_s": round(min(times), 3), "max_s": round(max(times), 3),
            "us_per_cell": round(1e6 * statistics.median(times) / grid.size, 2),
            "stages_median_s": {k: round(statistics.median(s[k] for s in stages), 3)
                                for k in stages[0]},
            "patches": len(roadmap.segmentation.patches),
            "peak_rss_mb": round(int(peak[1]) / 1024, 1),
            "import_rss_mb": round(int(peak[0]) / 1024, 1),
        }))


if __name__ == "__main__":
    main()
