"""Benchmark: the cost of refining thin regions on mechanism files' slices.

Run on demand, after ``source ros2_ws/env.sh``:

    python bench/bench_thin_regions.py [--repeat 3]

For each mechanism file's default slice (as ``bench_mechanisms.py`` builds
them, on the file's own grid) and for the 3-RRR's slices th1 = 1.5 rad
(where a way runs along a strip narrower than a cell) and th1 = 90 deg, the
median time of ``refine_thin_regions`` and of ``build_roadmap`` on the same
grid, after one build of each, with the rounds, refined blocks and cells;
builds run their chunks in a thread per core, as the command line's do.
Prints one JSON line per slice.
"""

import argparse
from concurrent.futures import ThreadPoolExecutor
import json
import math
import statistics
import time

from rpr3_gwr_core import build_roadmap
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file, roadmap_grid
from rpr3_gwr_core.workspace import refine_thin_regions

from bench_mechanisms import CONFIG, SLICES
from bench_roadmap import THREADS

SLICES_WITH_THIN_REGIONS = (("three_rrr.yaml", {"th1": 1.5}),
                            ("three_rrr.yaml", {"th1": math.pi / 2}))


def _median_time(call, repeat):
    call()
    times = []
    for _ in range(repeat):
        begin = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - begin)
    return statistics.median(times), result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    pool = ThreadPoolExecutor(THREADS)
    for name, fixed in (*SLICES.items(), *SLICES_WITH_THIN_REGIONS):
        described = load_mechanism_file(CONFIG / name)
        grid = roadmap_grid(described, fixed)
        alone, _ = _median_time(lambda: build_roadmap(described.mechanism, grid,
                                                      workers=pool.map), args.repeat)
        refined, (roadmap, report) = _median_time(
            lambda: refine_thin_regions(described.mechanism, grid, workers=pool.map),
            args.repeat)
        print(json.dumps({
            "mechanism": described.mechanism.kind, "file": name, "fixed": fixed,
            "grid_alone_s": round(alone, 3), "thin_refined_s": round(refined, 3),
            "rounds": report.rounds, "refined_blocks": report.refined_blocks,
            "stopped": report.stopped, "thin_left": list(report.thin_left),
            "cells": [grid.size, roadmap.grid.size]}), flush=True)


if __name__ == "__main__":
    main()
