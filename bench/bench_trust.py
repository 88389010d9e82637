"""Benchmark: every plan re-checked by an independent continuation in pose space.

Run on demand:  python bench/bench_trust.py [--pairs 500] [--slice-pairs 300] [--seed 1]

Draws same-aspect pairs independently of the roadmap (poses uniform in the
full roadmap's box of legs; on the paper's slice, points of the
(theta1, alpha) torus at rho1 = 17), plans each with joint limits, and
follows every returned path again with the tests' pose-space reference
(``src/rpr3_gwr_core/test/pose_reference.py``: its own legs, margin and
continuation), which must keep the sign, the planner's margin threshold and
end on the goal pose; the trajectory's joint speeds and velocity changes
between points must keep the limits.  Prints, as JSON lines per roadmap: the
pairs, how many planned, how many the reference refused (with the reasons),
the planner's error codes, and plan times (p50 / p95 / max).
"""

import argparse
import collections
import json
import pathlib
import statistics
import sys
import time

import numpy as np

from rpr3_gwr_core import GWRError, PAPER_GEOMETRY, Planner, PlanOptions, build_roadmap
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT, PAPER_GRID

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]
                       / "src" / "rpr3_gwr_core" / "test"))
from pose_reference import (assert_executable, assert_within_limits,  # noqa: E402
                            random_full_configurations, random_slice_configurations,
                            same_aspect_pairs)

_LIMITS = (2.0, 5.0)


def _check(planner, pairs):
    """Plan every pair and re-check each path; a summary dict."""
    times, refused, errors = [], [], collections.Counter()
    options = PlanOptions(max_velocity=_LIMITS[0], max_acceleration=_LIMITS[1])
    for (start, _), (goal, goal_pose) in pairs:
        begin = time.perf_counter()
        try:
            plan = planner.plan(start, goal, options)
        except GWRError as error:
            times.append(time.perf_counter() - begin)
            errors[f"{error.code}: {getattr(error, 'reason', '')}".rstrip(": ")] += 1
            continue
        times.append(time.perf_counter() - begin)
        try:
            assert_executable(plan, goal_pose, planner.min_margin)
            assert_within_limits(plan, *_LIMITS)
        except AssertionError as failure:
            refused.append({"start": list(start), "goal": list(goal), "why": str(failure)})
    ms = sorted(1000 * t for t in times)
    return {"pairs": len(pairs), "planned": len(pairs) - sum(errors.values()),
            "reference_refused": len(refused), "refusals": refused[:5],
            "errors": dict(errors), "plan_p50_ms": round(statistics.median(ms), 2),
            "plan_p95_ms": round(ms[int(0.95 * (len(ms) - 1))], 2),
            "plan_max_ms": round(ms[-1], 2)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=500)
    parser.add_argument("--slice-pairs", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)

    roadmap = build_roadmap(PAPER_GEOMETRY, PAPER_GRID)
    pairs = same_aspect_pairs(random_slice_configurations(
        rng, PAPER_GRID.fixed_value(0), 2 * args.slice_pairs))[:args.slice_pairs]
    print(json.dumps({"roadmap": "slice rho1 = 17", **_check(Planner(roadmap), pairs)}),
          flush=True)

    roadmap, index, _ = cached_planning(PAPER_GEOMETRY, FULL_BASE_GRID,
                                        refinement=FULL_REFINEMENT)
    planner = Planner(roadmap, index)
    pairs = same_aspect_pairs(random_full_configurations(rng, 2 * args.pairs))[:args.pairs]
    print(json.dumps({"roadmap": "full 3-DOF", **_check(planner, pairs)}), flush=True)


if __name__ == "__main__":
    main()
