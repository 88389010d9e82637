"""The margins the cell search reads (:mod:`~rpr3_gwr_core.planning.link_margins`),
checked against references that share no code with the project: the
pose-space continuation of :mod:`pose_reference` for the 3-RPR, and the
five-bar's closed form (two circles meeting) written here."""

import dataclasses
import math
import pathlib

import numpy as np
import pytest

from pose_reference import follow
from rpr3_gwr_core import PAPER_GEOMETRY, PAPER_GRID
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.mechanisms.rpr3 import ThreeRPR
from rpr3_gwr_core.planning import PlanningProblem
from rpr3_gwr_core.planning.link_margins import DIP_FRACTION, LinkEnds, link_margins
from rpr3_gwr_core.workspace.roadmap import build_roadmap

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"

# Pairs whose least-cost ways, on the cell centres' margins alone, cross a
# link over which the sheet folds (the first pair: the platform cannot
# follow it from one cell centre to the other, so the roadmap's continuity,
# which follows it as the validator does, makes no such link) or dips to a
# fifth of its ends' margins (the second: linked, its nodes lowered), where
# the motion checker refuses the cell path.
FOLDED_WAYS = [
    ((14.15332319230562, 16.067184360952666, 29.740855993582887, -0.19308822856563745),
     (14.185606064006135, 10.26581888665126, 12.731883348227026, 1.6273097014865279),
     ((7.0, 15.0, 12.5), (7.0, 15.25, 12.5)), False),
    ((48.46173510340648, 44.03442338692189, 47.52627271367191, 0.41375865579296445),
     (15.305124387550505, 12.20348810590452, 9.190602137081916, 1.8457294410124376),
     ((28.5, 28.0, 13.25), (28.5, 27.75, 13.25)), True),
]


def _plain_margins(roadmap, index):
    seg, graph = roadmap.segmentation, index.graph
    return np.abs(seg.field.margin[graph.node_cell, index.node_slot])


def _reference_dips(roadmap, index, u, v, plain):
    """Whether the reference, followed from node u's solution to node v's
    cell, falls below DIP_FRACTION of the lesser end's margin or lands on
    another solution."""
    graph, seg = index.graph, roadmap.segmentation
    joints = roadmap.grid.joints_at(graph.node_cell[[u, v]])
    poses = seg.field.poses[graph.node_cell[[u, v]], index.node_slot[[u, v]]]
    followed = follow(joints, poses[0], DIP_FRACTION * min(plain[u], plain[v]))
    if not followed["ok"]:
        return True
    miss = np.array(followed["pose"]) - poses[1]
    miss[2] = math.remainder(miss[2], 2 * math.pi)
    return np.max(np.abs(miss)) > 1e-6 * PAPER_GEOMETRY.scale


def _links(index, u):
    graph = index.graph
    return graph.indices[graph.indptr[u]:graph.indptr[u + 1]].tolist()


def test_the_paper_s_slice_lowers_only_nodes_next_to_a_link_the_reference_sees_dip():
    roadmap, index, _ = cached_planning(PAPER_GEOMETRY, PAPER_GRID)
    plain = _plain_margins(roadmap, index)
    lowered = np.flatnonzero(index.node_margin < plain)
    assert lowered.size > 0
    assert np.all(index.node_margin <= plain)
    for u in lowered.tolist():
        assert any(_reference_dips(roadmap, index, u, v, plain) for v in _links(index, u)), u


def test_links_the_full_roadmap_keeps_do_not_dip_in_the_reference(full_planning):
    roadmap, index = full_planning
    plain = _plain_margins(roadmap, index)
    kept = np.flatnonzero(index.node_margin >= plain)
    rng = np.random.default_rng(3)
    checked = 0
    for u in rng.choice(kept, 150, replace=False).tolist():
        v = int(rng.choice(_links(index, u)))
        if index.node_margin[v] >= plain[v]:
            assert not _reference_dips(roadmap, index, u, v, plain), (u, v)
            checked += 1
    assert checked > 100


@pytest.mark.parametrize("start, goal, link, linked", FOLDED_WAYS)
def test_a_way_once_refused_over_a_folding_link_now_keeps_off_it(full_planner, start, goal,
                                                                  link, linked):
    roadmap, index = full_planner.roadmap, full_planner.search_index
    plain = _plain_margins(roadmap, index)
    problem = PlanningProblem(full_planner.locate(start), full_planner.locate(goal), 0.02)
    s, g = problem.start, problem.goal
    # The link's nodes that the reference finds dipping are lowered; a link
    # the platform cannot follow is not made.
    nodes = np.flatnonzero(np.isin(index.graph.node_cell, roadmap.grid.cells_of(np.array(link))))
    folded = [u for u in nodes.tolist() for v in _links(index, u)
              if v in nodes and _reference_dips(roadmap, index, u, v, plain)]
    assert bool(folded) == linked and all(index.node_margin[u] < plain[u] for u in folded)
    path = full_planner.cell_search.search((s.patch, g.patch), s.cell, g.cell,
                                           clearance=problem.clearance, any_gates=True)
    assert not set(folded) & set(_path_nodes(index, path).tolist())
    joints, patches, _ = full_planner.repairer.waypoints(problem, path.cells, path.patches)
    assert full_planner.checker.check(joints, problem,
                                      problem.kept_margin(full_planner.min_margin)).ok
    followed = follow(joints, s.pose, problem.kept_margin(full_planner.min_margin))
    assert followed["ok"], followed["why"]


def _path_nodes(index, path):
    """The node of each cell of a cell path."""
    offsets = index.offsets[np.searchsorted(index.pids, path.patches)]
    ends = index.offsets[np.searchsorted(index.pids, path.patches) + 1]
    cells = index.graph.node_cell
    return np.array([o + np.searchsorted(cells[o:e], c)
                     for o, e, c in zip(offsets, ends, path.cells)])


# --- the five-bar, against its closed form --------------------------------------------------

FIVE_BAR = load_mechanism_file(CONFIG / "five_bar.yaml")


def _five_bar_solution(mechanism, joints, side):
    """The closed form at ``joints``: the end effector on one side of the
    line from the first elbow to the second (+1: to its left) and its
    margin, or None where the distal circles do not meet or the elbows
    coincide."""
    d, l1, l2 = mechanism.parameters
    c1 = np.array([l1 * math.cos(joints[0]), l1 * math.sin(joints[0])])
    c2 = np.array([d + l1 * math.cos(joints[1]), l1 * math.sin(joints[1])])
    gap = c2 - c1
    dist = float(np.hypot(*gap))
    if not 1e-9 < dist <= 2 * l2:
        return None
    phi = math.atan2(gap[1], gap[0]) + side * math.acos(dist / (2 * l2))
    point = c1 + l2 * np.array([math.cos(phi), math.sin(phi)])
    u1, u2 = point - c1, point - c2
    return point, (u1[0] * u2[1] - u1[1] * u2[0]) / (np.linalg.norm(u1) * np.linalg.norm(u2))


def _five_bar_side(mechanism, joints, pose):
    """The side (+1 or -1) whose closed-form solution is the pose."""
    return min((1, -1), key=lambda side: np.linalg.norm(
        _five_bar_solution(mechanism, joints, side)[0] - pose))


def test_the_five_bar_lowers_no_node_whose_links_the_closed_form_finds_smooth():
    """Along each link, the short way round across the seams of the torus,
    the closed form keeps the solution on the end's side, of the end's sign,
    at no less than DIP_FRACTION of the lesser end's margin: then neither
    node is lowered."""
    roadmap = build_roadmap(FIVE_BAR.mechanism, FIVE_BAR.grid())
    _, index, _ = cached_planning(FIVE_BAR.mechanism, roadmap.grid)
    mechanism, graph = roadmap.mechanism, index.graph
    plain = _plain_margins(roadmap, index)
    signed = roadmap.segmentation.field.margin[graph.node_cell, index.node_slot]
    joints = roadmap.grid.joints_at(graph.node_cell)
    poses = roadmap.segmentation.field.poses[graph.node_cell, index.node_slot]
    seams = smooth_nodes = 0
    for u in range(index.n_nodes):
        side = _five_bar_side(mechanism, joints[u], poses[u])
        smooth = True
        for v in _links(index, u):
            seams += bool(np.any(np.abs(joints[v] - joints[u]) > math.pi))
            change = np.remainder(joints[v] - joints[u] + math.pi, 2 * math.pi) - math.pi
            floor = DIP_FRACTION * min(plain[u], plain[v])
            for t in np.linspace(0.0, 1.0, 9)[1:-1]:
                at = _five_bar_solution(mechanism, joints[u] + t * change, side)
                if at is None or at[1] * signed[u] < floor:
                    smooth = False
        if smooth:
            smooth_nodes += 1
            assert index.node_margin[u] == plain[u], u
    assert seams > 0 and smooth_nodes > index.n_nodes // 2


def test_a_mechanism_without_a_compiled_step_reads_its_solutions_margins():
    class Interpreted(ThreeRPR):
        @property
        def step_kernel(self):
            return None

    margin = np.array([0.3, -0.01, 0.2])
    ends = LinkEnds(np.array([0, 1, 3, 4]), np.array([1, 0, 2, 1], np.int32),
                    np.zeros((3, 3)), np.zeros(3), np.zeros((3, 3)), margin,
                    np.array([False, False, True]))
    mechanism = Interpreted(**{f.name: getattr(PAPER_GEOMETRY, f.name)
                               for f in dataclasses.fields(PAPER_GEOMETRY)})
    assert np.array_equal(link_margins(mechanism, ends), np.abs(margin))
