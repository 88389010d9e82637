"""Roadmaps to and from JSON, and to GEXF (the paper drew its GWRs with Gephi).

JSON schema (``format = "rpr3-gwr-roadmap"``, ``version = 2``); lengths in
the mechanism's length unit, angles in radians::

    {
      "format": "rpr3-gwr-roadmap", "version": 2,
      "mechanism": {"kind": "3-RPR", ...its parameters},
      "grid": {"axes": [{"joint": int, "min": float, "max": float,
                         "step": float}, ...],
               "fixed": [{"joint": int, "value": float}, ...]},
          # or, for an adaptive grid: {"kind": "adaptive", "base": {a grid
          # as above}, "refinement": int, "blocks": [refined block, ...]}
      "refinement": {"base_cells": int, "refined_blocks": int,
                     "fine_cells": int, "cells": int},   # adaptive grids only
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

Cells are flat row-major indices over the grid's axes (on an adaptive grid:
its cells in the order of
:class:`~rpr3_gwr_core.workspace.adaptive.AdaptiveGrid`).  Reading a
document back derives patches and gates from the field's arrays
(:meth:`~rpr3_gwr_core.workspace.segmentation.Segmentation.from_arrays`),
as the ROS nodes' message decoder does.
"""

import base64
import json

import networkx as nx
import numpy as np

from ..exceptions import InvalidInputError
from ..mechanisms import mechanism_from_dict
from ..workspace import NSolutionField, Roadmap, Segmentation, aspect_groups, roadmap_graph
from ..workspace.adaptive import AdaptiveGrid, grid_from_dict
from ..workspace.cusps import known_cusps

__all__ = ["FIELD_TYPES", "roadmap_summary", "roadmap_arrays", "roadmap_from_arrays",
           "roadmap_to_json", "roadmap_from_json", "roadmap_to_gexf"]

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
    regions = []
    for r in range(1, seg.n_regions + 1):
        cells = np.flatnonzero(seg.region == r)
        regions.append({"id": r, "n_solutions": int(seg.field.count[cells[0]]),
                        "cells": int(cells.size)})
    patches = []
    for pid, patch in sorted(seg.patches.items()):
        entry = {"id": pid, "region": patch.region, "layer": patch.layer,
                 "aspect": patch.aspect, "n_solutions": patch.n_solutions,
                 "cells": int(patch.cells.size), "area": roadmap.graph.nodes[pid]["area"]}
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
    grid = seg.field.grid
    out = {"format": FORMAT, "version": VERSION,
           "mechanism": seg.field.mechanism.to_dict(), "grid": grid.to_dict(),
           "regions": regions, "patches": patches, "gates": gates,
           "aspect_groups": aspect_groups(roadmap.graph),
           "cusps": [c.to_dict(roadmap.mechanism) for c in known_cusps(roadmap)]}
    if isinstance(grid, AdaptiveGrid):
        out["refinement"] = {"base_cells": grid.base.size, "refined_blocks": int(grid.blocks.size),
                             "fine_cells": grid.size - grid.base.size, "cells": grid.size}
    return out


def _encode(array, dtype):
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode("ascii")


def _decode(text, dtype):
    try:
        return np.frombuffer(base64.b64decode(text), dtype=dtype).copy()
    except (ValueError, TypeError) as exc:
        raise InvalidInputError(f"malformed field array: {exc}") from exc


# The little-endian dtypes of the field's arrays in every stored or sent form.
FIELD_TYPES = {"count": "<u1", "poses": "<f8", "margin": "<f8", "region": "<i4",
                "patch": "<i4"}


def roadmap_arrays(roadmap):
    """The arrays a roadmap is rebuilt from (the ``field`` section of the
    schema, not encoded), by name; ``links`` is a list, one per axis."""
    seg = roadmap.segmentation
    return {"count": seg.field.count, "poses": seg.field.poses, "margin": seg.field.margin,
            "region": seg.region, "patch": seg.patch,
            "links": [match for _, _, match in seg.links]}


def roadmap_from_arrays(mechanism_dict, grid_dict, arrays, tables=None, areas=None,
                        check=True):
    """A roadmap from its mechanism and grid documents and its arrays
    (:func:`roadmap_arrays`); patches and gates are derived from the arrays,
    or taken from ``tables`` when given.

    Parameters
    ----------
    mechanism_dict, grid_dict : dict
        :meth:`Mechanism.to_dict` and the grid's ``to_dict()``.
    arrays : dict
        :func:`roadmap_arrays`.
    tables : dict of str to ndarray, optional
        The segmentation's
        :meth:`~rpr3_gwr_core.workspace.segmentation.Segmentation.tables`.
    areas : ndarray of float, optional
        With ``tables``: each patch's area, in the order of its
        ``patch_ids``.
    check : bool
        With ``tables``: check the tables against the arrays
        (:meth:`~rpr3_gwr_core.workspace.segmentation.Segmentation.from_tables`);
        False for values checked before.

    Raises
    ------
    InvalidInputError
        If the arrays do not fit the grid, or the tables the arrays.
    """
    try:
        mechanism = mechanism_from_dict(mechanism_dict)
        grid = grid_from_dict(grid_dict)
        n, slots, size = grid.size, mechanism.max_solutions, mechanism.pose_size
        shapes = {"count": (n,), "poses": (n, slots, size), "margin": (n, slots),
                  "region": (n,), "patch": (n, slots)}
        array = {name: np.asarray(arrays[name]).reshape(shape) for name, shape in shapes.items()}
        links = [np.asarray(m).reshape(-1, slots) for m in arrays["links"]]
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(f"malformed roadmap arrays: {exc}") from exc
    field = NSolutionField(mechanism=mechanism, grid=grid, count=array["count"],
                           poses=array["poses"], margin=array["margin"])
    if tables is None:
        segmentation = Segmentation.from_arrays(field, array["region"], array["patch"], links)
        return Roadmap(segmentation=segmentation, graph=roadmap_graph(segmentation), timings={})
    segmentation = Segmentation.from_tables(field, array["region"], array["patch"], links,
                                            tables, check=check)
    ids = tables["patch_ids"]
    if areas is None or np.shape(areas) != ids.shape or not np.all(np.isfinite(areas)) \
            or not np.all(np.asarray(areas) > 0):
        raise InvalidInputError("the patches' areas are not a positive number per patch")
    graph = roadmap_graph(segmentation, dict(zip(ids.tolist(), np.asarray(areas).tolist())))
    return Roadmap(segmentation=segmentation, graph=graph, timings={})


def roadmap_to_json(roadmap, include_field=True):
    """Serialise a roadmap to a JSON string (schema in the module doc)."""
    data = roadmap_summary(roadmap, with_faces=True)
    if include_field:
        arrays = roadmap_arrays(roadmap)
        data["field"] = {name: _encode(arrays[name], dtype)
                         for name, dtype in FIELD_TYPES.items()}
        data["field"]["links"] = [_encode(match, "<i1") for match in arrays["links"]]
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
        raw = data["field"]
        arrays = {name: _decode(raw[name], dtype) for name, dtype in FIELD_TYPES.items()}
        arrays["links"] = [_decode(text, "<i1") for text in raw["links"]]
        roadmap = roadmap_from_arrays(data["mechanism"], data["grid"], arrays)
        # The summary sections must describe the roadmap the arrays make.
        listed = ({int(p["id"]) for p in data["patches"]},
                  {tuple(int(i) for i in g["patches"]) for g in data["gates"]})
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(f"malformed roadmap document: {exc}") from exc
    seg = roadmap.segmentation
    if listed != (set(seg.patches), set(seg.gates)):
        raise InvalidInputError("the document's patches and gates do not match its field")
    return roadmap


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
