"""Benchmark: path quality and plan time at rho1 = 17 against an independent
shortest-path reference.

Run on demand:  python bench/bench_paths.py [--pairs 300] [--seed 1] [--lattice 720]

Configurations are drawn independently of the roadmap on the torus
(theta1, alpha): B1 = A1 + rho1 (cos theta1, sin theta1), the other legs by
inverse kinematics, kept when they lie in the box and the margin is at least
``--margin``.  The reference is the shortest path in the (rho2, rho3) plane
on a lattice over the same torus (16 neighbours per node, each edge's length
the distance between its ends' legs), through nodes and edge midpoints whose
margin keeps the threshold; a lattice path is at most a few per cent longer
than the true shortest one, so the ratios printed are, if anything, low.
The reference also answers feasibility on its own: the pairs it connects
must be the pairs the planner plans.

Prints, as JSON lines: per threshold (the planner's clearance, and the
margin its validated paths keep), the ratio of the planner's default path
length to the reference (median, p95, max), the plan times (default and
smoothed, median and p95), the smallest margin of any default path, and the
agreement on feasibility.
"""

import argparse
import json
import math
import statistics
import time

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from rpr3_gwr_core import GWRError, PAPER_GEOMETRY, Planner, PlanOptions, build_roadmap
from rpr3_gwr_core.paper import PAPER_GRID
from rpr3_gwr_core.planning import DEFAULT_CLEARANCE

RHO1 = 17.0
_NEIGHBOURS = [(1, 0), (0, 1), (1, 1), (1, -1), (1, 2), (2, 1), (1, -2), (2, -1)]


def _torus_legs(theta, alpha):
    """Legs and margin of the poses of the torus points (theta1, alpha)."""
    a1 = np.asarray(PAPER_GEOMETRY.a1)
    pose = np.stack([a1[0] + RHO1 * np.cos(theta), a1[1] + RHO1 * np.sin(theta), alpha],
                    axis=-1)
    return PAPER_GEOMETRY.inverse(pose), PAPER_GEOMETRY.margin(pose)


def _in_box(legs):
    box = PAPER_GRID.axes
    return np.all([(legs[..., a.joint] >= a.low) & (legs[..., a.joint] <= a.high)
                   for a in box], axis=0)


def _configurations(count, seed, min_margin):
    rng = np.random.default_rng(seed)
    rows = []
    while len(rows) < count:
        theta, alpha = rng.uniform(-math.pi, math.pi, (2, 4096))
        legs, margin = _torus_legs(theta, alpha)
        keep = _in_box(legs) & (np.abs(margin) >= min_margin)
        rows += [(t, a) for t, a in zip(theta[keep], alpha[keep])]
    return rows[:count]


def _lattice_graph(n, threshold):
    """The reference lattice: node legs and a graph of edge lengths."""
    angles = -math.pi + 2 * math.pi * np.arange(n) / n
    theta, alpha = np.meshgrid(angles, angles, indexing="ij")
    legs, margin = _torus_legs(theta, alpha)
    ok = _in_box(legs) & (np.abs(margin) >= threshold)
    index = np.arange(n * n).reshape(n, n)
    rows, cols, lengths = [], [], []
    for di, dj in _NEIGHBOURS:
        other = np.roll(np.roll(index, -di, axis=0), -dj, axis=1)
        mid_legs, mid_margin = _torus_legs(theta + math.pi * di / n, alpha + math.pi * dj / n)
        usable = (ok & ok.ravel()[other] & _in_box(mid_legs)
                  & (np.abs(mid_margin) >= threshold)
                  & (np.sign(mid_margin) == np.sign(margin))
                  & (np.sign(margin.ravel()[other]) == np.sign(margin)))
        a, b = index[usable], other[usable]
        flat = legs.reshape(-1, 3)
        length = np.linalg.norm(flat[a, 1:] - flat[b, 1:], axis=1)
        rows += [a, b]
        cols += [b, a]
        lengths += [length, length]
    graph = csr_matrix((np.concatenate(lengths), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(n * n, n * n))
    return graph, ok.ravel()


def _node(theta, alpha, n):
    i = int(round((theta + math.pi) / (2 * math.pi) * n)) % n
    j = int(round((alpha + math.pi) / (2 * math.pi) * n)) % n
    return i * n + j


def _length(joints):
    return float(np.sum(np.linalg.norm(np.diff(joints[:, 1:], axis=0), axis=1)))


def _stats(values, scale=1.0, digits=3):
    values = sorted(values)
    if not values:
        return {}
    return {"median": round(scale * statistics.median(values), digits),
            "p95": round(scale * values[int(0.95 * (len(values) - 1))], digits),
            "max": round(scale * values[-1], digits)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--lattice", type=int, default=720)
    parser.add_argument("--margin", type=float, default=3e-3,
                        help="smallest margin of a drawn configuration")
    args = parser.parse_args()
    planner = Planner(build_roadmap(PAPER_GEOMETRY, PAPER_GRID))
    points = _configurations(2 * args.pairs, args.seed, args.margin)
    pairs = list(zip(points[0::2], points[1::2]))
    # The first plan of a process loads the compiled kernels: reported on
    # its own, not in the statistics.
    begin = time.perf_counter()
    planner.plan((RHO1, 12.0, 18.0, math.radians(122.82)),
                 (RHO1, 10.0, 25.0, math.radians(-24.24)))
    first_ms = 1e3 * (time.perf_counter() - begin)
    plans, default_ms, smooth_ms = [], [], []
    for (t0, a0), (t1, a1) in pairs:
        start = (RHO1, *_torus_legs(t0, a0)[0][1:], a0)
        goal = (RHO1, *_torus_legs(t1, a1)[0][1:], a1)
        for options, times in ((PlanOptions(), default_ms), (PlanOptions(smooth=True), smooth_ms)):
            begin = time.perf_counter()
            try:
                plan = planner.plan(start, goal, options)
            except GWRError:
                plan = None
            times.append(time.perf_counter() - begin)
            if not options.smooth:
                plans.append(plan)
    feasible = [p is not None for p in plans]
    print(json.dumps({"pairs": len(pairs), "planned": sum(feasible),
                      "first_plan_of_the_process_ms": round(first_ms, 1),
                      "plan_default_ms": _stats(default_ms, 1e3, 2),
                      "plan_smoothed_ms": _stats(smooth_ms, 1e3, 2),
                      "smallest_path_margin": round(min(
                          p.validation.min_margin for p in plans if p is not None), 5)}))
    for threshold in (DEFAULT_CLEARANCE, DEFAULT_CLEARANCE / 4):
        graph, ok = _lattice_graph(args.lattice, threshold)
        ratios, compared, agree, reference_only = [], 0, 0, 0
        for ((t0, a0), (t1, a1)), plan in zip(pairs, plans):
            s, g = _node(t0, a0, args.lattice), _node(t1, a1, args.lattice)
            if not (ok[s] and ok[g]):
                continue  # the ends themselves lie closer than the threshold
            distance = dijkstra(graph, indices=s, min_only=True)[g]
            connected = bool(np.isfinite(distance))
            compared += 1
            agree += connected == (plan is not None)
            reference_only += connected and plan is None
            if connected and plan is not None and distance > 0:
                ratios.append(_length(plan.joints) / distance)
        print(json.dumps({"threshold": threshold, "pairs_compared": compared,
                          "feasibility_agrees": agree,
                          "reference_connects_planner_not": reference_only,
                          "length_ratio": _stats(ratios)}))


if __name__ == "__main__":
    main()
