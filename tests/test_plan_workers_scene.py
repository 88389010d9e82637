"""Plan workers plan in the scene they were given, as the node's own planner
does in the same scene, and never in another: a request named for a scene
the workers do not hold is handed back to the caller to plan.  The scene is
the paper's first example with a post on the way of leg 1's platform joint
(config/scenes/paper_example1_blocked.yaml): without it the example plans,
with it the example is blocked."""

import math

import numpy as np
import pytest
from rpr3_gwr_core.exceptions import InfeasiblePathError
from rpr3_gwr_core.mechanisms import PAPER_GEOMETRY
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.planning import NEVER, CellSearchIndex, PlanOptions
from rpr3_gwr_core.world import BodyModel, scene_from_dict
from rpr3_gwr_core.workspace.roadmap import build_roadmap
from rpr3_gwr_nodes.plan_workers import PlanWorkers, WorkersClosed

TIMEOUT = 120.0
START = np.array([17.0, 12.0, 18.0, math.radians(122.82)])
GOAL = np.array([17.0, 10.0, 25.0, math.radians(-24.24)])
POST = {"obstacles": [{"id": "post", "disc": {"center": [-16.0, 0.0], "radius": 1.0}}]}
# Away from every body: the plan is the one without a scene.
FAR = {"obstacles": [{"id": "far", "disc": {"center": [80.0, 80.0], "radius": 1.0}}]}


@pytest.fixture(scope="module")
def workers(tmp_path_factory):
    roadmap = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.25))
    workers = PlanWorkers(roadmap, CellSearchIndex.build(roadmap), 2, TIMEOUT,
                          str(tmp_path_factory.mktemp("planners")))
    try:
        yield workers
    finally:
        workers.close()


def _blocked_reason(planner, world):
    with pytest.raises(InfeasiblePathError) as raised:
        planner.plan(START, GOAL, PlanOptions(), world=world)
    return str(raised.value)


def test_workers_plan_in_the_scene_they_hold_as_the_node_does(workers):
    model = BodyModel()
    assert workers.plan(START, GOAL, PlanOptions(), NEVER).joints.size
    world = workers.planner.apply_scene(scene_from_dict(POST), model)
    reason = _blocked_reason(workers.planner, world)
    workers.apply_scene("post", scene_from_dict(POST), model)
    # Each worker, not only the first idle one, answers in the scene.
    for _ in range(2 * workers.count):
        with pytest.raises(InfeasiblePathError) as raised:
            workers.plan(START, GOAL, PlanOptions(), NEVER, "post")
        assert str(raised.value) == reason
    workers.apply_scene("far", scene_from_dict(FAR), model)
    far = workers.planner.plan(START, GOAL, PlanOptions(),
                               world=workers.planner.apply_scene(scene_from_dict(FAR), model))
    for _ in range(2 * workers.count):
        plan = workers.plan(START, GOAL, PlanOptions(), NEVER, "far")
        np.testing.assert_allclose(plan.joints, far.joints)


def test_a_request_for_a_scene_the_workers_do_not_hold_is_handed_back(workers):
    model = BodyModel()
    workers.apply_scene("post", scene_from_dict(POST), model)
    for key in (None, "far"):
        with pytest.raises(WorkersClosed):
            workers.plan(START, GOAL, PlanOptions(), NEVER, key)
    workers.apply_scene(None, None, model)
    assert workers.scene_key is None
    assert workers.plan(START, GOAL, PlanOptions(), NEVER).joints.size
    with pytest.raises(WorkersClosed):
        workers.plan(START, GOAL, PlanOptions(), NEVER, "post")
