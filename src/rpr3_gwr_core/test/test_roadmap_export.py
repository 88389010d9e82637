"""The roadmap graph, JSON round trip and GEXF export."""

import io
import json

import networkx as nx
import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.export import (roadmap_from_json, roadmap_summary, roadmap_to_gexf,
                                  roadmap_to_json)
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY
from rpr3_gwr_core.workspace.roadmap import aspect_groups, build_roadmap


@pytest.fixture(scope="module")
def json_text(paper_roadmap):
    return roadmap_to_json(paper_roadmap)


@pytest.fixture(scope="module")
def loaded(json_text):
    return roadmap_from_json(json_text)


# --- build_roadmap ---------------------------------------------------------------------

def test_build_roadmap_reports_progress_up_to_done():
    calls = []
    build_roadmap(PAPER_GEOMETRY, rho1_slice(step=1.0), progress=lambda s, f: calls.append((s, f)))
    fractions = [f for _, f in calls]
    assert fractions == sorted(fractions)
    assert calls[-1] == ("done", 1.0)


def test_roadmap_exposes_its_field_grid_and_geometry(paper_roadmap):
    assert paper_roadmap.field is paper_roadmap.segmentation.field
    assert paper_roadmap.grid.shape == (401, 401)
    assert paper_roadmap.mechanism == PAPER_GEOMETRY


def test_roadmap_rds_method_builds_the_same_graph(coarse_paper_roadmap):
    rds = build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.5), method="rds")
    assert set(rds.graph.nodes) == set(coarse_paper_roadmap.graph.nodes)
    assert set(map(frozenset, rds.graph.edges)) == set(
        map(frozenset, coarse_paper_roadmap.graph.edges))


def test_aspect_groups_are_sorted_lists_ordered_by_smallest_id():
    graph = nx.Graph([(31, 12), (12, 55), (41, 11)])
    graph.add_node(7)
    assert aspect_groups(graph) == [[7], [11, 41], [12, 31, 55]]


# --- summary -----------------------------------------------------------------------------

def test_summary_lists_regions_patches_and_gates(paper_roadmap):
    summary = roadmap_summary(paper_roadmap)
    assert summary["format"] == "rpr3-gwr-roadmap" and summary["version"] == 2
    assert [r["id"] for r in summary["regions"]] == list(range(1, 8))
    assert [r["n_solutions"] for r in summary["regions"] if r["id"] in (1, 4, 5)] == [2, 2, 6]
    assert len(summary["patches"]) == 24
    assert len(summary["gates"]) == paper_roadmap.graph.number_of_edges()
    assert summary["aspect_groups"] == aspect_groups(paper_roadmap.graph)
    assert "faces" not in summary["gates"][0]


def test_summary_is_plain_json(paper_roadmap):
    summary = roadmap_summary(paper_roadmap, with_faces=True)
    assert json.loads(json.dumps(summary)) == summary


# --- JSON round trip ---------------------------------------------------------------------

def test_json_round_trip_keeps_the_field_arrays(paper_roadmap, loaded):
    old, new = paper_roadmap.field, loaded.field
    assert new.mechanism == old.mechanism and new.grid == old.grid
    np.testing.assert_array_equal(new.count, old.count)
    np.testing.assert_array_equal(new.poses, old.poses)  # NaN == NaN here
    np.testing.assert_array_equal(new.margin, old.margin)


def test_json_round_trip_keeps_regions_and_patch_array(paper_roadmap, loaded):
    np.testing.assert_array_equal(loaded.segmentation.region, paper_roadmap.segmentation.region)
    np.testing.assert_array_equal(loaded.segmentation.patch, paper_roadmap.segmentation.patch)


def test_json_round_trip_keeps_patches(paper_roadmap, loaded):
    old, new = paper_roadmap.segmentation.patches, loaded.segmentation.patches
    assert new.keys() == old.keys()
    for pid, patch in old.items():
        other = new[pid]
        assert (other.region, other.layer, other.aspect, other.n_solutions) == (
            patch.region, patch.layer, patch.aspect, patch.n_solutions)
        for attribute in ("cells", "slots", "gate_cells", "singular_cells"):
            np.testing.assert_array_equal(getattr(other, attribute), getattr(patch, attribute))


def test_json_round_trip_keeps_gates_with_faces(paper_roadmap, loaded):
    old, new = paper_roadmap.segmentation.gates, loaded.segmentation.gates
    assert list(new) == list(old)
    for key, gate in old.items():
        assert new[key].patches == gate.patches
        assert new[key].width == pytest.approx(gate.width)
        np.testing.assert_array_equal(new[key].faces, gate.faces)


def test_json_round_trip_keeps_links(paper_roadmap, loaded):
    for (lo, up, match), (lo2, up2, match2) in zip(paper_roadmap.segmentation.links,
                                                     loaded.segmentation.links):
        np.testing.assert_array_equal(lo2, lo)
        np.testing.assert_array_equal(up2, up)
        np.testing.assert_array_equal(match2, match)


def test_json_round_trip_keeps_graph_and_aspect_groups(paper_roadmap, loaded):
    assert aspect_groups(loaded.graph) == aspect_groups(paper_roadmap.graph)
    assert set(map(frozenset, loaded.graph.edges)) == set(
        map(frozenset, paper_roadmap.graph.edges))
    for node, data in paper_roadmap.graph.nodes(data=True):
        assert loaded.graph.nodes[node] == data


def test_json_written_twice_is_identical(loaded, json_text):
    assert roadmap_to_json(loaded) == json_text


# --- malformed JSON -----------------------------------------------------------------------

@pytest.fixture(scope="module")
def coarse_document(coarse_paper_roadmap):
    return json.loads(roadmap_to_json(coarse_paper_roadmap))


@pytest.mark.parametrize("text", ["", "not json", "{", "[]", "42", "null", '"rpr3-gwr-roadmap"',
                                  '{"format": "something-else", "version": 1}'])
def test_from_json_rejects_garbage(text):
    with pytest.raises(InvalidInputError):
        roadmap_from_json(text)


def test_from_json_rejects_an_unknown_version(coarse_document):
    document = dict(coarse_document, version=3)
    with pytest.raises(InvalidInputError):
        roadmap_from_json(json.dumps(document))


def test_from_json_rejects_a_document_without_field(coarse_paper_roadmap):
    with pytest.raises(InvalidInputError):
        roadmap_from_json(roadmap_to_json(coarse_paper_roadmap, include_field=False))


@pytest.mark.parametrize("key", ["format", "version", "mechanism", "grid", "patches", "gates",
                                 "field"])
def test_from_json_rejects_a_missing_key(coarse_document, key):
    document = {k: v for k, v in coarse_document.items() if k != key}
    with pytest.raises(InvalidInputError):
        roadmap_from_json(json.dumps(document))


@pytest.mark.parametrize("key", ["count", "poses", "margin", "region", "patch", "links"])
def test_from_json_rejects_a_missing_field_array(coarse_document, key):
    document = dict(coarse_document)
    document["field"] = {k: v for k, v in coarse_document["field"].items() if k != key}
    with pytest.raises(InvalidInputError):
        roadmap_from_json(json.dumps(document))


@pytest.mark.parametrize("value", ["AAAA", "!!not base64!!", 17, None])
def test_from_json_rejects_a_wrong_size_or_type_array(coarse_document, value):
    document = dict(coarse_document)
    document["field"] = dict(coarse_document["field"], poses=value)
    with pytest.raises(InvalidInputError):
        roadmap_from_json(json.dumps(document))


@pytest.mark.parametrize("section, value", [("mechanism", {"kind": "3-RPR", "a1": [0, 0]}),
                                            ("mechanism", [1, 2]),
                                            ("grid", {"axes": [], "fixed": []}),
                                            ("patches", [{"id": 11}]), ("patches", None),
                                            ("gates", [{"patches": [11]}])])
def test_from_json_rejects_malformed_sections(coarse_document, section, value):
    document = dict(coarse_document, **{section: value})
    with pytest.raises(InvalidInputError):
        roadmap_from_json(json.dumps(document))


def test_from_json_rejects_a_field_of_another_grid(coarse_document):
    axes = [dict(axis, step=0.25) for axis in coarse_document["grid"]["axes"]]
    document = dict(coarse_document, grid=dict(coarse_document["grid"], axes=axes))
    with pytest.raises(InvalidInputError):
        roadmap_from_json(json.dumps(document))


# --- GEXF -----------------------------------------------------------------------------------

def test_gexf_parses_with_the_same_nodes_and_edges(paper_roadmap):
    text = roadmap_to_gexf(paper_roadmap)
    graph = nx.read_gexf(io.BytesIO(text.encode("utf-8")), node_type=int)
    assert set(graph.nodes) == set(paper_roadmap.graph.nodes)
    assert set(map(frozenset, graph.edges)) == set(map(frozenset, paper_roadmap.graph.edges))


def test_gexf_keeps_labels_and_attributes(paper_roadmap):
    graph = nx.read_gexf(io.BytesIO(roadmap_to_gexf(paper_roadmap).encode("utf-8")), node_type=int)
    for node, data in paper_roadmap.graph.nodes(data=True):
        assert graph.nodes[node]["label"] == str(node)
        assert graph.nodes[node]["aspect"] == data["aspect"]
        assert graph.nodes[node]["region"] == data["region"]


def test_gexf_does_not_modify_the_roadmap_graph(coarse_paper_roadmap):
    roadmap_to_gexf(coarse_paper_roadmap)
    assert all("label" not in data for _, data in coarse_paper_roadmap.graph.nodes(data=True))
