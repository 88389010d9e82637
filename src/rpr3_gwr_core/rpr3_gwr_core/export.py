"""Roadmaps to and from JSON, and to GEXF (the paper drew its GWRs with Gephi).

JSON schema (``format = "rpr3-gwr-roadmap"``, ``version = 1``), all lengths
in the geometry's length unit and angles in radians::

    {
      "format": "rpr3-gwr-roadmap", "version": 1,
      "geometry": {"a1": [x, y], "a2": [x, y], "a3": [x, y],
                   "d1": float, "d3": float, "beta": float},
      "grid": {"rho1": float, "rho2_range": [min, max],
               "rho3_range": [min, max], "step": float},
      "regions": [{"id": int, "n_solutions": int, "cells": int}],
      "patches": [{"id": int, "region": int, "layer": int, "aspect": +1 | -1,
                   "n_solutions": int, "cells": int, "area": float,
                   "gate_cells": [flat cell index], "singular_cells": [...]}],
      "gates": [{"patches": [id, id], "width": float,
                 "faces": [[cell in first patch, cell in second patch], ...]}],
      "aspect_groups": [[patch id, ...], ...],
      "field": {                      # optional; needed to plan from the file
        "count": base64 of uint8[n_cells],
        "poses": base64 of little-endian float64[n_cells, 6, 3] (NaN = none),
        "margin": base64 of little-endian float64[n_cells, 6],
        "region": base64 of little-endian int32[n_cells],
        "patch": base64 of little-endian int32[n_cells, 6],
        "links": [base64 of int8[n_faces_of_axis, 6], ...]  # per axis, faces in
                 # row-major order of their lower cell: m[k, i] = j links solution
                 # i of the lower cell to solution j of the upper one, -1 none
      }
    }

Cells are flat row-major indices ``i * n3 + j`` of ``(rho2[i], rho3[j])``.
"""

import base64
import json

import networkx as nx
import numpy as np

from .continuity import neighbour_pairs
from .exceptions import InvalidInputError
from .field import Grid, NSolutionField
from .geometry import Geometry
from .kinematics import MAX_SOLUTIONS
from .roadmap import Roadmap, aspect_groups, roadmap_graph
from .segmentation import Gate, Patch, Segmentation

__all__ = ["roadmap_summary", "roadmap_to_json", "roadmap_from_json", "roadmap_to_gexf"]

FORMAT = "rpr3-gwr-roadmap"
VERSION = 1


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
    cell_area = seg.field.grid.step ** 2
    regions = []
    for r in range(1, seg.n_regions + 1):
        cells = np.flatnonzero(seg.region == r)
        regions.append({"id": r, "n_solutions": int(seg.field.count[cells[0]]),
                        "cells": int(cells.size)})
    patches = []
    for pid, patch in sorted(seg.patches.items()):
        entry = {"id": pid, "region": patch.region, "layer": patch.layer,
                 "aspect": patch.aspect, "n_solutions": patch.n_solutions,
                 "cells": int(patch.cells.size), "area": float(patch.cells.size * cell_area)}
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
            "geometry": seg.field.geometry.to_dict(), "grid": seg.field.grid.to_dict(),
            "regions": regions, "patches": patches, "gates": gates,
            "aspect_groups": aspect_groups(roadmap.graph)}


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
        geometry = Geometry.from_dict(data["geometry"])
        grid = Grid.from_dict(data["grid"])
        n = grid.size
        raw = data["field"]
        field = NSolutionField(
            geometry=geometry, grid=grid, count=_decode(raw["count"], "<u1", (n,)),
            poses=_decode(raw["poses"], "<f8", (n, MAX_SOLUTIONS, 3)),
            margin=_decode(raw["margin"], "<f8", (n, MAX_SOLUTIONS)))
        region = _decode(raw["region"], "<i4", (n,)).astype(np.int32)
        faces = neighbour_pairs(grid.shape)
        if len(raw["links"]) != len(faces):
            raise InvalidInputError("links do not match the grid's axes")
        links = [(lo, up, _decode(text, "<i1", (lo.size, MAX_SOLUTIONS)))
                 for (lo, up), text in zip(faces, raw["links"])]
        patch = _decode(raw["patch"], "<i4", (n, MAX_SOLUTIONS)).astype(np.int32)
        patches = {}
        for entry in data["patches"]:
            pid = int(entry["id"])
            cells, slots = np.nonzero(patch == pid)
            patches[pid] = Patch(id=pid, region=int(entry["region"]), layer=int(entry["layer"]),
                                 aspect=int(entry["aspect"]),
                                 n_solutions=int(entry["n_solutions"]), cells=cells, slots=slots,
                                 gate_cells=np.array(entry["gate_cells"], dtype=np.int64),
                                 singular_cells=np.array(entry["singular_cells"], dtype=np.int64))
        gates = {}
        for entry in data["gates"]:
            key = tuple(int(p) for p in entry["patches"])
            gates[key] = Gate(patches=key, faces=np.array(entry["faces"], dtype=np.int64).reshape(-1, 2),
                              width=float(entry["width"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(f"malformed roadmap document: {exc}") from exc
    segmentation = Segmentation(field=field, region=region, patch=patch, patches=patches,
                                gates=gates, links=links)
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
