"""The planning index: built once, saved with the cache, mapped by a fresh
process, and planning there exactly as a planner that built its own."""

import json
import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.planning import DEFAULT_CLEARANCE, CellSearchIndex, PlanOptions, Planner
from rpr3_gwr_core.planning.cell_search import CellSearch
from rpr3_gwr_core.planning.index import COST_UNITS

D = math.radians
GRID = rho1_slice(rho1=17, step=0.25)
# The paper's first example, and an assembly-mode change.
PAIRS = [((17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))),
         ((17, 20, 25, D(29.47)), (17, 20, 25, D(96.13)))]


@pytest.fixture(scope="module")
def cached(tmp_path_factory):
    """A cache folder with the slice's entry, and the roadmap and index it stored."""
    folder = str(tmp_path_factory.mktemp("cache"))
    roadmap, index, hit = cached_planning(PAPER_GEOMETRY, GRID, folder)
    assert not hit
    return folder, roadmap, index


def test_the_index_holds_the_default_clearance_and_the_detour_weight(cached):
    _, roadmap, index = cached
    assert index.clearances == (DEFAULT_CLEARANCE,)
    assert index.weights == (Planner(roadmap, index).retries.detour_weight,)


def test_a_loaded_index_equals_the_built_one(cached):
    folder, _, built = cached
    roadmap, loaded, hit = cached_planning(PAPER_GEOMETRY, GRID, folder)
    assert hit
    for name, array in built.arrays().items():
        np.testing.assert_array_equal(loaded.arrays()[name], array, err_msg=name)


def test_an_index_without_gate_distances_plans_the_same(cached):
    """Computed on first use, patch by patch, the distances give the same plans."""
    _, roadmap, index = cached
    bare = Planner(roadmap, CellSearchIndex.build(roadmap))
    full = Planner(roadmap, index)
    for start, goal in PAIRS:
        for options in (PlanOptions(), PlanOptions(smooth=True, clearance=0.05)):
            np.testing.assert_array_equal(bare.plan(start, goal, options).joints,
                                          full.plan(start, goal, options).joints)


def test_an_index_is_refused_for_another_roadmap(cached):
    _, _, index = cached
    from rpr3_gwr_core import build_roadmap

    other = build_roadmap(PAPER_GEOMETRY, rho1_slice(rho1=14, step=0.25))
    with pytest.raises(InvalidInputError):
        CellSearchIndex.from_arrays(other, index.arrays())


@pytest.mark.parametrize("values", [(-0.1,), (1.0,), (math.nan,)])
def test_clearances_out_of_range_are_refused(cached, values):
    _, roadmap, _ = cached
    with pytest.raises(InvalidInputError):
        CellSearchIndex.build(roadmap, clearances=values)


_FRESH_PROCESS = textwrap.dedent("""
    import json, sys
    from rpr3_gwr_core import PAPER_GEOMETRY
    from rpr3_gwr_core.io.cache import cached_planning
    from rpr3_gwr_core.paper import rho1_slice
    from rpr3_gwr_core.planning import Planner

    roadmap, index, hit = cached_planning(PAPER_GEOMETRY, rho1_slice(rho1=17, step=0.25),
                                          sys.argv[1])
    with open("/proc/self/maps") as maps:
        mapped = sorted({line.split()[-1].rsplit("/", 1)[-1] for line in maps
                         if sys.argv[1] in line})
    planner = Planner(roadmap, index)
    plans = [planner.plan(*pair).joints.tolist() for pair in json.loads(sys.argv[2])]
    print(json.dumps({"hit": hit, "mapped": mapped, "plans": plans,
                      "computed": list(planner.cell_search._extra_fields)}))
""")


def test_a_fresh_process_plans_from_the_mapped_index(cached):
    folder, roadmap, index = cached
    run = subprocess.run([sys.executable, "-c", _FRESH_PROCESS, folder, json.dumps(PAIRS)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    answer = json.loads(run.stdout.splitlines()[-1])
    assert answer["hit"] and answer["computed"] == []
    # Mapped, not read, and not computed: the index's largest arrays are
    # the files of the entry.
    assert {"index_distances.npy", "index_indices.npy", "poses.npy"} <= set(answer["mapped"])
    reference = Planner(roadmap, index)
    for (start, goal), joints in zip(PAIRS, answer["plans"]):
        np.testing.assert_array_equal(np.array(joints), reference.plan(start, goal).joints)


def test_an_index_on_the_graph_of_another_equals_one_built_whole(cached):
    _, roadmap, index = cached
    bare = CellSearchIndex.build(roadmap)
    again = CellSearchIndex.build(roadmap, index.clearances, index.weights, graph_from=bare)
    for name, array in index.arrays().items():
        np.testing.assert_array_equal(again.arrays()[name], array, err_msg=name)


def test_an_index_holding_what_is_asked_is_taken_as_it_is(cached):
    _, roadmap, index = cached
    assert CellSearchIndex.build(roadmap, index.clearances, index.weights,
                               graph_from=index) is index
    assert CellSearchIndex.build(roadmap, (), (), graph_from=index) is index
    other = CellSearchIndex.build(roadmap, (0.05,), index.weights, graph_from=index)
    assert other is not index and other.clearances == (0.05,)


def test_the_centroids_and_gate_middles_are_the_cells_means(cached):
    _, roadmap, index = cached
    seg, grid = roadmap.segmentation, roadmap.grid
    for k, pid in enumerate(index.pids.tolist()):
        np.testing.assert_allclose(index.centroids[k],
                                   grid.joints_at(seg.patches[pid].cells)[:, [1, 2]].mean(axis=0))
    for (k, other), middle in zip(index.gate_pairs.tolist(), index.gate_middles):
        a, b = sorted((int(index.pids[k]), int(index.pids[other])))
        faces = seg.gates[a, b].faces
        np.testing.assert_allclose(middle, grid.joints_at(faces.ravel())[:, [1, 2]].mean(axis=0))


def test_the_cost_floors_are_each_patch_s_smallest_node_cost(cached):
    """The floor scales the search's estimate: below the patch's smallest
    cost it weakens the estimate, above it the path is no longer least-cost."""
    _, roadmap, index = cached
    weight = index.weights[0]
    costs, floors = index.costs(weight)
    on_first_use = CellSearch(roadmap, CellSearchIndex.build(roadmap))
    for k in range(index.pids.size):
        smallest = costs[index.offsets[k]:index.offsets[k + 1]].min()
        assert floors[k] == smallest >= COST_UNITS
        assert on_first_use._costs(weight, k)[1] == smallest
