"""Roadmaps to and from JSON, and to GEXF (the paper drew its GWRs with Gephi).

JSON schema (``format = "rpr3-gwr-roadmap"``, ``version = 2``); lengths in
the mechanism's length unit, angles in radians::

    {
      "format": "rpr3-gwr-roadmap", "version": 2,
      "mechanism": {"kind": "3-RPR", ...its parameters},
      "grid": {"axes": [{"joint": int, "min": float, "max": float,
                         "step": float}, ...],
               "fixed": [{"joint": int, "value": float}, ...]},
      "regions": [{"id": int, "n_solutions": int, "cells": int}],
      "patches": [{"id": int, "region": int, "layer": int, "aspect": +1 | -1,
                   "n_solutions": int, "cells": int, "area": float,
                   "gate_cells": [flat cell index], "singular_cells": [...]}],
      "gates": [{"patches": [id, id], "width": float,
                 "faces": [[cell in first patch, cell in second patch], ...]}],
      "aspect_groups": [[patch id, ...], ...],
      "cusps": [{joint and pose coordinates by name, "regions": [...]}, ...],
               # empty unless a 2-D slice of a mechanism with cusp equations
      "field": {                      # optional; needed to plan from the file
        "count": base64 of uint8[n_cells],
        "poses": base64 of little-endian float64[n_cells, max_solutions,
                 pose_size] (NaN = none),
        "margin": base64 of little-endian float64[n_cells, max_solutions],
        "region": base64 of little-endian int32[n_cells],
        "patch": base64 of little-endian int32[n_cells, max_solutions],
        "links": [base64 of int8[n_faces_of_axis, max_solutions], ...]
                 # per axis, faces in row-major order of their lower cell:
                 # m[k, i] = j links solution i of the lower cell to solution
                 # j of the upper one, -1 none
      }
    }

Cells are flat row-major indices over the grid's axes.  Reading a document
back derives patches and gates from the field's arrays
(:meth:`~rpr3_gwr_core.workspace.segmentation.Segmentation.from_arrays`),
as the ROS nodes' message decoder does.
"""

import base64
import json

import networkx as nx
import numpy as np

from ..exceptions import InvalidInputError
from ..mechanisms import mechanism_from_dict
from ..workspace import (Grid, NSolutionField, Roadmap, Segmentation, aspect_groups,
                         roadmap_graph)
from ..workspace.continuity import neighbour_pairs
from ..workspace.cusps import known_cusps

__all__ = ["roadmap_summary", "roadmap_to_json", "roadmap_from_json", "roadmap_to_gexf"]

FORMAT = "rpr3-gwr-roadmap"
VERSION = 2


def roadmap_summary(roadmap, with_faces=False):
    """The roadmap as plain data (the schema above, without ``field``).

    Parameters
    ----------
    roadmap : Roadmap
    with_faces : bool
        Include per-patch boundary cells and per-gate faces.

    Returns
    -------
    dict
    """
    seg = roadmap.segmentation
    cell_volume = float(np.prod(seg.field.grid.steps))
    regions = []
    for r in range(1, seg.n_regions + 1):
        cells = np.flatnonzero(seg.region == r)
        regions.append({"id": r, "n_solutions": int(seg.field.count[cells[0]]),
                        "cells": int(cells.size)})
    patches = []
    for pid, patch in sorted(seg.patches.items()):
        entry = {"id": pid, "region": patch.region, "layer": patch.layer,
                 "aspect": patch.aspect, "n_solutions": patch.n_solutions,
                 "cells": int(patch.cells.size), "area": float(patch.cells.size * cell_volume)}
        if with_faces:
            entry["gate_cells"] = patch.gate_cells.tolist()
            entry["singular_cells"] = patch.singular_cells.tolist()
        patches.append(entry)
    gates = []
    for key, gate in sorted(seg.gates.items()):
        entry = {"patches": list(key), "width": float(gate.width)}
        if with_faces:
            entry["faces"] = gate.faces.tolist()
        gates.append(entry)
    return {"format": FORMAT, "version": VERSION,
            "mechanism": seg.field.mechanism.to_dict(), "grid": seg.field.grid.to_dict(),
            "regions": regions, "patches": patches, "gates": gates,
            "aspect_groups": aspect_groups(roadmap.graph),
            "cusps": [c.to_dict(roadmap.mechanism) for c in known_cusps(roadmap)]}


def _encode(array, dtype):
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode("ascii")


def _decode(text, dtype, shape):
    try:
        array = np.frombuffer(base64.b64decode(text), dtype=dtype)
        return array.reshape(shape).copy()
    except (ValueError, TypeError) as exc:
        raise InvalidInputError(f"malformed field array: {exc}") from exc


def roadmap_to_json(roadmap, include_field=True):
    """Serialise a roadmap to a JSON string (schema in the module doc)."""
    data = roadmap_summary(roadmap, with_faces=True)
    if include_field:
        seg = roadmap.segmentation
        data["field"] = {"count": _encode(seg.field.count, "<u1"),
                         "poses": _encode(seg.field.poses, "<f8"),
                         "margin": _encode(seg.field.margin, "<f8"),
                         "region": _encode(seg.region, "<i4"),
                         "patch": _encode(seg.patch, "<i4"),
                         "links": [_encode(match, "<i1") for _, _, match in seg.links]}
    return json.dumps(data)


def roadmap_from_json(text):
    """Load a roadmap written by :func:`roadmap_to_json` with its field.

    Raises
    ------
    InvalidInputError
        If the text is not such a roadmap.
    """
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InvalidInputError(f"not JSON: {exc}") from exc
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise InvalidInputError(f"not an {FORMAT} document")
    if data.get("version") != VERSION:
        raise InvalidInputError(f"unsupported version {data.get('version')}")
    if "field" not in data:
        raise InvalidInputError("the document has no field: write it with include_field=True")
    try:
        mechanism = mechanism_from_dict(data["mechanism"])
        grid = Grid.from_dict(data["grid"])
        n, slots, size = grid.size, mechanism.max_solutions, mechanism.pose_size
        raw = data["field"]
        field = NSolutionField(
            mechanism=mechanism, grid=grid, count=_decode(raw["count"], "<u1", (n,)),
            poses=_decode(raw["poses"], "<f8", (n, slots, size)),
            margin=_decode(raw["margin"], "<f8", (n, slots)))
        faces = neighbour_pairs(grid.shape)
        if len(raw["links"]) != len(faces):
            raise InvalidInputError("links do not match the grid's axes")
        links = [_decode(text, "<i1", (lo.size, slots))
                 for (lo, _), text in zip(faces, raw["links"])]
        segmentation = Segmentation.from_arrays(
            field, _decode(raw["region"], "<i4", (n,)), _decode(raw["patch"], "<i4", (n, slots)),
            links)
        # The summary sections must describe the roadmap the arrays make.
        listed = ({int(p["id"]) for p in data["patches"]},
                  {tuple(int(i) for i in g["patches"]) for g in data["gates"]})
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(f"malformed roadmap document: {exc}") from exc
    if listed != (set(segmentation.patches), set(segmentation.gates)):
        raise InvalidInputError("the document's patches and gates do not match its field")
    return Roadmap(segmentation=segmentation, graph=roadmap_graph(segmentation), timings={})


def roadmap_to_gexf(roadmap):
    """The roadmap graph as a GEXF document for Gephi (node label = patch id).

    Returns
    -------
    str
    """
    graph = roadmap.graph.copy()
    for node in graph.nodes:
        graph.nodes[node]["label"] = str(node)
    return "\n".join(nx.generate_gexf(graph))
