"""The main job: build the paper's roadmap, plan its two examples, show the result.

Writes figures and plans to out/ and prints a short report.
"""

import json
import math
import pathlib
import sys
import time

from rpr3_gwr_core.figures import field_figure, plan_figure, roadmap_figure
from rpr3_gwr_core.planner import PlanOptions, Planner
from rpr3_gwr_core.roadmap import aspect_groups, build_roadmap

OUT = pathlib.Path(__file__).resolve().parents[1] / "out"
EXAMPLES = {
    "paper_5_2_two_configurations": ((17, 12, 18, 122.82), (17, 10, 25, -24.24)),
    "paper_5_3_assembly_mode_change": ((17, 20, 25, 29.47), (17, 20, 25, 96.13)),
}


def main():
    OUT.mkdir(exist_ok=True)
    start = time.perf_counter()
    roadmap = build_roadmap()
    seg = roadmap.segmentation
    print(f"roadmap (rho1 = 17, 401 x 401): {seg.n_regions} regions, {len(seg.patches)} patches, "
          f"{len(seg.gates)} gates, aspect groups {aspect_groups(roadmap.graph)} "
          f"[{time.perf_counter() - start:.2f} s]")
    field_figure(roadmap).savefig(OUT / "field.png", dpi=110)
    roadmap_figure(roadmap).savefig(OUT / "roadmap.png", dpi=110)
    planner = Planner(roadmap)
    for name, (q1, q2) in EXAMPLES.items():
        s = (*q1[:3], math.radians(q1[3]))
        g = (*q2[:3], math.radians(q2[3]))
        begin = time.perf_counter()
        plan = planner.plan(s, g, PlanOptions(smooth=True, max_velocity=2.0, max_acceleration=4.0))
        took = time.perf_counter() - begin
        data = plan.to_dict()
        data["roadmap"] = {"geometry": roadmap.geometry.to_dict(), "grid": roadmap.grid.to_dict()}
        (OUT / f"{name}.json").write_text(json.dumps(data))
        plan_figure(roadmap, data).savefig(OUT / f"{name}.png", dpi=110)
        paths = ", ".join(" -> ".join(map(str, p.patches)) for p in plan.global_paths)
        print(f"{name}: global paths [{paths}]; {len(plan.rho)} waypoints, "
              f"{plan.times[-1]:.1f} s at 2 units/s; min singularity margin "
              f"{plan.validation.min_margin:.4f}; ends at alpha = "
              f"{math.degrees(plan.poses[-1, 2]):.2f} deg [{1e3 * took:.0f} ms]")
    print(f"figures and plans in {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
