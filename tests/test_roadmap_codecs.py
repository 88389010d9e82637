"""A roadmap through ROS messages and through JSON comes back the same, and
plans the same, with no DDS involved: both decoders are the core's one
``Segmentation.from_arrays``."""

import math

import numpy as np
import pytest
from rpr3_gwr_core import (PAPER_GEOMETRY, PAPER_GRID, Axis, Grid, Planner, PlanOptions,
                           build_roadmap)
from rpr3_gwr_core.io.export import roadmap_from_json, roadmap_to_json
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.mechanisms import (DEFAULT_FIVE_BAR, DEFAULT_THREE_PRR, DEFAULT_THREE_RRR,
                                      PAPER_GEOMETRY as PAPER_3RPR)
from rpr3_gwr_core.workspace.cusps import find_cusps
from rpr3_gwr_msgs.msg import Configuration
from rpr3_gwr_nodes.conversions import (configuration_from_msg, mechanism_from_msg,
                                        mechanism_to_msg, roadmap_from_msgs, roadmap_to_msgs)
from std_msgs.msg import Header

D = math.radians
REQUESTS = [((17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))),
            ((17, 20, 25, D(29.47)), (17, 20, 25, D(96.13))),
            ((17, 32.44684871137472, 28.63922926571835, D(58.37334330639168)),
             (17, 25.791714909487556, 14.864184868961233, D(-143.59793965686987)))]


@pytest.fixture(scope="module")
def built():
    return build_roadmap(PAPER_GEOMETRY, PAPER_GRID)


@pytest.fixture(scope="module")
def decoded(built):
    return {"messages": roadmap_from_msgs(*roadmap_to_msgs(built, Header(frame_id="base"))),
            "json": roadmap_from_json(roadmap_to_json(built))}


@pytest.mark.parametrize("codec", ["messages", "json"])
def test_the_decoded_roadmap_is_the_built_one(built, decoded, codec):
    a, b = built.segmentation, decoded[codec].segmentation
    for name in ("count", "poses", "margin"):
        np.testing.assert_array_equal(getattr(a.field, name), getattr(b.field, name))
    np.testing.assert_array_equal(a.region, b.region)
    np.testing.assert_array_equal(a.patch, b.patch)
    for (_, _, m1), (_, _, m2) in zip(a.links, b.links):
        np.testing.assert_array_equal(m1, m2)
    assert a.patches.keys() == b.patches.keys() and a.gates.keys() == b.gates.keys()
    for pid, patch in a.patches.items():
        other = b.patches[pid]
        assert (patch.region, patch.layer, patch.aspect, patch.n_solutions) == (
            other.region, other.layer, other.aspect, other.n_solutions)
        for name in ("cells", "slots", "gate_cells", "singular_cells"):
            np.testing.assert_array_equal(getattr(patch, name), getattr(other, name))
    for key, gate in a.gates.items():
        np.testing.assert_array_equal(gate.faces, b.gates[key].faces)
        assert gate.width == b.gates[key].width


@pytest.mark.parametrize("start, goal", REQUESTS)
def test_decoded_roadmaps_plan_identically(built, decoded, start, goal):
    options = PlanOptions(smooth=True, max_velocity=1.0, max_acceleration=2.0)
    reference = Planner(built).plan(start, goal, options)
    for roadmap in decoded.values():
        plan = Planner(roadmap).plan(start, goal, options)
        assert [g.patches for g in plan.global_paths] == [g.patches
                                                         for g in reference.global_paths]
        np.testing.assert_array_equal(plan.joints, reference.joints)
        np.testing.assert_array_equal(plan.poses, reference.poses)
        np.testing.assert_array_equal(plan.times, reference.times)


def test_the_field_message_carries_the_cusps(built):
    field_msg, _ = roadmap_to_msgs(built, Header())
    assert [list(c.joints) for c in field_msg.cusps] == [c.joints.tolist()
                                                        for c in find_cusps(built)]
    assert len(field_msg.cusps) == 6 and all(c.regions for c in field_msg.cusps)


def test_a_roadmap_message_that_disagrees_with_its_field_is_refused(built):
    field_msg, roadmap_msg = roadmap_to_msgs(built, Header())
    roadmap_msg.gates = roadmap_msg.gates[1:]
    with pytest.raises(InvalidInputError):
        roadmap_from_msgs(field_msg, roadmap_msg)


def test_the_decoded_graph_keeps_the_patch_areas_sent(built, decoded):
    for pid, attributes in built.graph.nodes(data=True):
        assert decoded["messages"].graph.nodes[pid]["area"] == attributes["area"]


@pytest.mark.parametrize("area", [0.0, -1.0, math.nan, math.inf])
def test_a_roadmap_message_with_an_area_not_positive_is_refused(built, area):
    field_msg, roadmap_msg = roadmap_to_msgs(built, Header())
    roadmap_msg.patches[3].area = area
    with pytest.raises(InvalidInputError, match="areas"):
        roadmap_from_msgs(field_msg, roadmap_msg)


def _truncated(values):
    return values[:-1]


@pytest.mark.parametrize("damage", [
    lambda m: setattr(m, "poses", _truncated(m.poses)),
    lambda m: setattr(m, "singularity_margin", _truncated(m.singularity_margin)),
    lambda m: setattr(m, "patch_ids", _truncated(m.patch_ids)),
    lambda m: setattr(m, "n_solutions", _truncated(m.n_solutions)),
    lambda m: m.n_solutions.__setitem__(0, 7),
    lambda m: setattr(m.links[0], "slots", _truncated(m.links[0].slots)),
])
def test_a_field_message_of_the_wrong_sizes_is_refused(built, damage):
    """Per-solution arrays hold the solutions n_solutions counts, no more."""
    field_msg, roadmap_msg = roadmap_to_msgs(built, Header())
    damage(field_msg)
    with pytest.raises(InvalidInputError):
        roadmap_from_msgs(field_msg, roadmap_msg)


def test_the_field_message_lists_only_existing_solutions(built):
    field_msg, _ = roadmap_to_msgs(built, Header())
    total = int(built.field.count.sum())
    assert len(field_msg.singularity_margin) == len(field_msg.patch_ids) == total
    assert len(field_msg.poses) == 3 * total
    assert not np.isnan(np.frombuffer(field_msg.poses)).any()


@pytest.mark.parametrize("grid", [
    PAPER_GRID,
    Grid(axes=(Axis(0, -math.pi, math.pi - math.pi / 60, math.pi / 60, periodic=True),
               Axis(1, 0.0, 5.0, 0.5)), fixed=((2, 1.0),)),
], ids=["paper", "periodic"])
def test_a_grid_crosses_as_a_message_with_its_periodic_axes(grid):
    from rpr3_gwr_nodes.conversions import grid_from_msg, grid_to_msg

    msg = grid_to_msg(grid)
    assert [a.periodic for a in msg.axes] == [a.periodic for a in grid.axes]
    assert grid_from_msg(msg) == grid


@pytest.mark.parametrize("mechanism", [PAPER_3RPR, DEFAULT_FIVE_BAR, DEFAULT_THREE_RRR,
                                       DEFAULT_THREE_PRR], ids=lambda m: m.kind)
def test_every_mechanism_crosses_as_a_message(mechanism):
    msg = mechanism_to_msg(mechanism)
    assert msg.kind == mechanism.kind and list(msg.joint_names) == list(mechanism.joint_names)
    assert list(msg.pose_names) == list(mechanism.pose_names)
    assert mechanism_from_msg(msg) == mechanism


@pytest.mark.parametrize("damage, reason", [
    (lambda m: setattr(m, "kind", "7R"), "unknown mechanism kind"),
    (lambda m: setattr(m, "joint_names", ["a", "b", "c"]), "not the 3-RPR's"),
    (lambda m: setattr(m, "mode_coordinate", 0), "not the 3-RPR's"),
    (lambda m: m.parameters.append(m.parameters[0]), "named twice"),
    (lambda m: setattr(m, "parameters", m.parameters[1:]), "malformed"),
    (lambda m: setattr(m.parameters[0], "values", [1.0]), "malformed"),
    (lambda m: setattr(m.parameters[3], "values", [math.nan]), "finite"),
])
def test_a_malformed_mechanism_message_is_refused(damage, reason):
    msg = mechanism_to_msg(PAPER_3RPR)
    damage(msg)
    with pytest.raises(InvalidInputError, match=reason):
        mechanism_from_msg(msg)


def test_a_configuration_takes_its_joints_by_name_or_in_order():
    ordered = Configuration(positions=[17.0, 12.0, 18.0], mode=2.0)
    named = Configuration(joint_names=["rho3", "rho1", "rho2"], positions=[18.0, 17.0, 12.0],
                          mode=2.0)
    assert configuration_from_msg(PAPER_3RPR, ordered) == (17.0, 12.0, 18.0, 2.0)
    assert configuration_from_msg(PAPER_3RPR, named) == (17.0, 12.0, 18.0, 2.0)
    for bad in (Configuration(positions=[17.0, 12.0], mode=2.0),
                Configuration(joint_names=["rho1", "rho1", "rho2"], positions=[1.0] * 3),
                Configuration(joint_names=["th1", "th2", "th3"], positions=[1.0] * 3)):
        with pytest.raises(InvalidInputError):
            configuration_from_msg(PAPER_3RPR, bad)
