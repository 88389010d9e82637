"""Planning and world objects print a one-line summary, not their arrays."""

import dataclasses
import pathlib

import numpy as np
import pytest

from rpr3_gwr_core.planning.planner import Planner, PlanOptions, PlanStatus
from rpr3_gwr_core.io.scene_file import load_scene

from test_planning import Q1, Q2

_CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config" / "scenes"


@pytest.fixture(scope="module")
def planner(paper_roadmap):
    return Planner(paper_roadmap)


def _short(text):
    assert "\n" not in text and "array(" not in text and len(text) < 300, text
    return text


def test_plan_and_its_parts_summarise(planner):
    plan = planner.plan(Q1, Q2, PlanOptions(smooth=True, max_velocity=1.0,
                                                         max_acceleration=1.0))
    text = _short(repr(plan))
    path = " -> ".join(map(str, plan.global_paths[plan.path_index].patches))
    assert text.startswith("Plan(") and path in text
    assert f"{len(plan.joints)} waypoints" in text and "valid" in text
    assert _short(repr(plan.start)).startswith("Location(")
    assert f"patch {plan.start.patch}" in repr(plan.start)
    assert _short(repr(plan.validation)).startswith("Validation(ok")
    assert _short(repr(planner)).startswith("Planner(")


def test_an_approximate_plan_says_what_the_deadline_skipped(planner):
    plan = planner.plan(Q1, Q2, PlanOptions(feasibility_only=True))
    assert plan.status is PlanStatus.EXACT_SOLUTION and "approximate" not in repr(plan)
    cut = dataclasses.replace(plan, status=PlanStatus.APPROXIMATE_SOLUTION,
                              skipped=("rounding",))
    assert _short(repr(cut)).endswith("approximate: the deadline skipped rounding)")


def test_scene_and_scene_roadmap_summarise(planner):
    scene = load_scene(_CONFIG / "paper_narrowed.yaml")
    text = _short(repr(scene))
    assert text == "Scene(1 polygon, 1 disc, obstacle clearance 0.5)"
    assert _short(repr(scene.discs[0])) == "DiscObstacle('post', center (6, 28), radius 2)"
    world = planner.apply_scene(scene)
    text = _short(repr(world))
    assert text.startswith(f"SceneRoadmap({world.n_parts} parts")
    blocked = world.index.disks.size - np.count_nonzero(world.free)
    assert blocked > 0 and f"{blocked} of {world.index.disks.size} patch solutions blocked" in text
