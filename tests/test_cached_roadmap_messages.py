"""A planner that receives a roadmap its machine's roadmap cache holds maps
the cache's entry, full planning index included, instead of decoding the
messages and indexing them; only an entry equal to the messages, value for
value, stands in for them.  No DDS: the messages are built and read here."""

import numpy as np
import pytest
from rpr3_gwr_core import PAPER_GEOMETRY, PlanOptions, Planner, build_roadmap
from rpr3_gwr_core.io.cache import cached_planning
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.planning import DEFAULT_CLEARANCE
from rpr3_gwr_nodes.conversions import roadmap_matches_msgs, roadmap_to_msgs
from rpr3_gwr_nodes.planner import received_roadmap
from std_msgs.msg import Header

GRID = rho1_slice(rho1=17, step=1.0)
EXAMPLE = ((17, 12, 18, np.radians(122.82)), (17, 10, 25, np.radians(-24.24)))


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """A cache folder holding the slice's entry, and the roadmap built there."""
    folder = str(tmp_path_factory.mktemp("cache"))
    roadmap, _, hit = cached_planning(PAPER_GEOMETRY, GRID, folder)
    assert not hit
    return folder, roadmap


def _messages(roadmap):
    return roadmap_to_msgs(roadmap, Header(frame_id="base"))


def test_a_roadmap_in_the_cache_is_mapped_with_its_gate_distances(cache):
    folder, built = cache
    roadmap, index, cached = received_roadmap(*_messages(built), cache_dir=folder)
    assert cached
    assert index.distances(DEFAULT_CLEARANCE) is not None
    options = PlanOptions(smooth=True, max_velocity=1.0, max_acceleration=2.0)
    reference = Planner(built).plan(*EXAMPLE, options)
    plan = Planner(roadmap, index).plan(*EXAMPLE, options)
    np.testing.assert_array_equal(plan.joints, reference.joints)
    np.testing.assert_array_equal(plan.times, reference.times)


def test_a_roadmap_not_in_the_cache_is_decoded_with_its_node_graph_only(cache, tmp_path):
    _, built = cache
    roadmap, index, cached = received_roadmap(*_messages(built), cache_dir=str(tmp_path))
    assert not cached and index.clearances == ()
    np.testing.assert_array_equal(roadmap.segmentation.patch, built.segmentation.patch)


def _pose_nudged(field_msg, _):
    field_msg.poses[5] += 1e-12


def _margin_flipped(field_msg, _):
    field_msg.singularity_margin[7] *= -1


def _patch_renamed(field_msg, _):
    field_msg.patch_ids[0] += 1


def _link_cut(field_msg, _):
    field_msg.links[1].slots[next(i for i, v in enumerate(field_msg.links[1].slots)
                                  if v >= 0)] = -1


def _region_moved(field_msg, _):
    field_msg.region_ids[0] += 1


def _gate_dropped(_, roadmap_msg):
    roadmap_msg.gates = roadmap_msg.gates[1:]


def _poses_cut_short(field_msg, _):
    field_msg.poses = field_msg.poses[:-1]


@pytest.mark.parametrize("change", [_pose_nudged, _margin_flipped, _patch_renamed, _link_cut,
                                    _region_moved, _gate_dropped, _poses_cut_short])
def test_only_messages_equal_to_the_entry_are_matched_by_it(cache, change):
    folder, built = cache
    field_msg, roadmap_msg = _messages(built)
    assert roadmap_matches_msgs(built, field_msg, roadmap_msg)
    change(field_msg, roadmap_msg)
    assert not roadmap_matches_msgs(built, field_msg, roadmap_msg)
    if change is _pose_nudged:
        # Messages the cache's entry differs from are decoded, not replaced by it.
        roadmap, _, cached = received_roadmap(field_msg, roadmap_msg, cache_dir=folder)
        assert not cached
        assert roadmap.segmentation.field.poses[built.segmentation.field.valid][1, 2] == \
            field_msg.poses[5]


def test_another_grid_finds_no_entry(cache):
    folder, _ = cache
    other = build_roadmap(PAPER_GEOMETRY, rho1_slice(rho1=17, step=2.0))
    _, _, cached = received_roadmap(*_messages(other), cache_dir=folder)
    assert not cached
