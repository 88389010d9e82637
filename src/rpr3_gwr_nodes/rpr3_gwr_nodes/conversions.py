"""Conversions between rpr3_gwr_core values and rpr3_gwr_msgs messages.

Large per-cell arrays travel as ``array.array`` built from numpy buffers, the
fast path of the generated setters (a list would be checked element by
element), and come back with ``numpy.frombuffer``.
"""

import array

import numpy as np
from builtin_interfaces.msg import Duration
from rpr3_gwr_core.continuity import neighbour_pairs
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.field import Grid, NSolutionField
from rpr3_gwr_core.geometry import Geometry
from rpr3_gwr_core.kinematics import MAX_SOLUTIONS
from rpr3_gwr_core.roadmap import Roadmap, roadmap_graph
from rpr3_gwr_core.segmentation import Gate, Patch, Segmentation
from rpr3_gwr_msgs.msg import Geometry as GeometryMsg
from rpr3_gwr_msgs.msg import Gate as GateMsg
from rpr3_gwr_msgs.msg import Grid as GridMsg
from rpr3_gwr_msgs.msg import NSolutionField as NSolutionFieldMsg
from rpr3_gwr_msgs.msg import WorkspacePatch, WorkspaceRoadmap

__all__ = ["MAX_DURATION", "duration_msg", "geometry_to_msg", "geometry_from_msg",
           "grid_to_msg", "grid_from_msg", "roadmap_to_msgs", "roadmap_from_msgs"]


# builtin_interfaces/Duration holds int32 seconds.
MAX_DURATION = 2**31 - 1


def duration_msg(seconds):
    """A builtin_interfaces/Duration of a non-negative number of seconds.

    Raises
    ------
    InvalidInputError
        If ``seconds`` is negative, not finite or beyond what the message
        holds (``MAX_DURATION`` seconds).
    """
    if not 0.0 <= seconds < MAX_DURATION:
        raise InvalidInputError(f"a duration of {seconds:g} s does not fit "
                                f"builtin_interfaces/Duration (0 to {MAX_DURATION} s)")
    nanoseconds = int(round(seconds * 1e9))
    return Duration(sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000)


def _pack(typecode, values, dtype):
    out = array.array(typecode)
    out.frombytes(np.ascontiguousarray(values, dtype=dtype).tobytes())
    return out


def _unpack(values, dtype, size, name):
    data = np.frombuffer(values, dtype=dtype) if len(values) else np.zeros(0, dtype)
    if data.size != size:
        raise InvalidInputError(f"field message: {name} has {data.size} entries, expected {size}")
    return data


def geometry_to_msg(geometry):
    return GeometryMsg(a1=list(geometry.a1), a2=list(geometry.a2), a3=list(geometry.a3),
                       d1=geometry.d1, d3=geometry.d3, beta=geometry.beta)


def geometry_from_msg(msg):
    return Geometry(a1=tuple(msg.a1), a2=tuple(msg.a2), a3=tuple(msg.a3), d1=msg.d1, d3=msg.d3,
                    beta=msg.beta)


def grid_to_msg(grid):
    n2, n3 = grid.shape
    return GridMsg(rho1=grid.rho1, rho2_min=grid.rho2_range[0], rho2_max=grid.rho2_range[1],
                   rho3_min=grid.rho3_range[0], rho3_max=grid.rho3_range[1], step=grid.step,
                   rho2_count=n2, rho3_count=n3)


def grid_from_msg(msg):
    grid = Grid(rho1=msg.rho1, rho2_range=(msg.rho2_min, msg.rho2_max),
                rho3_range=(msg.rho3_min, msg.rho3_max), step=msg.step)
    if grid.shape != (msg.rho2_count, msg.rho3_count):
        raise InvalidInputError(f"grid message: counts {(msg.rho2_count, msg.rho3_count)} do not "
                                f"match its ranges and step {grid.shape}")
    return grid


def roadmap_to_msgs(roadmap, header):
    """The field and roadmap messages of a built roadmap.

    Parameters
    ----------
    roadmap : rpr3_gwr_core.roadmap.Roadmap
    header : std_msgs.msg.Header

    Returns
    -------
    (rpr3_gwr_msgs.msg.NSolutionField, rpr3_gwr_msgs.msg.WorkspaceRoadmap)
    """
    seg = roadmap.segmentation
    field = seg.field
    geometry, grid = geometry_to_msg(field.geometry), grid_to_msg(field.grid)
    field_msg = NSolutionFieldMsg(header=header, geometry=geometry, grid=grid)
    field_msg.n_solutions = _pack("B", field.count, np.uint8)
    field_msg.region_ids = _pack("i", seg.region, np.int32)
    field_msg.patch_ids = _pack("i", seg.patch, np.int32)
    field_msg.x = _pack("f", field.poses[..., 0], np.float32)
    field_msg.y = _pack("f", field.poses[..., 1], np.float32)
    field_msg.alpha = _pack("f", field.poses[..., 2], np.float32)
    field_msg.singularity_margin = _pack("f", field.margin, np.float32)
    field_msg.links_rho2 = _pack("b", seg.links[0][2], np.int8)
    field_msg.links_rho3 = _pack("b", seg.links[1][2], np.int8)
    cell_area = field.grid.step ** 2
    patches = [WorkspacePatch(id=p.id, region=p.region, layer=p.layer, aspect=p.aspect,
                              n_solutions=p.n_solutions, cells=_pack("I", p.cells, np.uint32),
                              gate_cells=_pack("I", p.gate_cells, np.uint32),
                              singular_cells=_pack("I", p.singular_cells, np.uint32),
                              area=float(p.cells.size * cell_area))
               for _, p in sorted(seg.patches.items())]
    gates = [GateMsg(patch_a=a, patch_b=b, cells_a=_pack("I", g.faces[:, 0], np.uint32),
                     cells_b=_pack("I", g.faces[:, 1], np.uint32), width=g.width)
             for (a, b), g in sorted(seg.gates.items())]
    roadmap_msg = WorkspaceRoadmap(header=header, geometry=geometry, grid=grid, patches=patches,
                                   gates=gates)
    return field_msg, roadmap_msg


def roadmap_from_msgs(field_msg, roadmap_msg):
    """Rebuild a plannable roadmap from its two messages, computing nothing
    but lookups.

    Raises
    ------
    InvalidInputError
        If the messages are inconsistent or do not belong together.
    """
    geometry, grid = geometry_from_msg(field_msg.geometry), grid_from_msg(field_msg.grid)
    if (geometry_from_msg(roadmap_msg.geometry) != geometry
            or grid_from_msg(roadmap_msg.grid) != grid):
        raise InvalidInputError("field and roadmap messages were built for different grids")
    n = grid.size
    per_solution = n * MAX_SOLUTIONS
    count = _unpack(field_msg.n_solutions, np.uint8, n, "n_solutions").copy()
    poses = np.stack([_unpack(getattr(field_msg, k), np.float32, per_solution, k).astype(float)
                      for k in ("x", "y", "alpha")], axis=-1).reshape(n, MAX_SOLUTIONS, 3)
    margin = _unpack(field_msg.singularity_margin, np.float32, per_solution,
                     "singularity_margin").astype(float).reshape(n, MAX_SOLUTIONS)
    field = NSolutionField(geometry=geometry, grid=grid, count=count, poses=poses, margin=margin)
    region = _unpack(field_msg.region_ids, np.int32, n, "region_ids").copy()
    patch = _unpack(field_msg.patch_ids, np.int32, per_solution, "patch_ids").reshape(
        n, MAX_SOLUTIONS).copy()
    links = []
    for (lower, upper), values, name in zip(neighbour_pairs(grid.shape),
                                            (field_msg.links_rho2, field_msg.links_rho3),
                                            ("links_rho2", "links_rho3")):
        match = _unpack(values, np.int8, lower.size * MAX_SOLUTIONS, name)
        links.append((lower, upper, match.reshape(lower.size, MAX_SOLUTIONS).copy()))
    patches = {}
    cells_all, slots_all = np.nonzero(patch)
    order = np.argsort(patch[cells_all, slots_all], kind="stable")
    ids = patch[cells_all, slots_all][order]
    for entry in roadmap_msg.patches:
        lo, hi = np.searchsorted(ids, [entry.id, entry.id + 1])
        cells, slots = cells_all[order[lo:hi]], slots_all[order[lo:hi]]
        if cells.size != len(entry.cells):
            raise InvalidInputError(f"patch {entry.id}: {len(entry.cells)} cells in the roadmap, "
                                    f"{cells.size} in the field")
        patches[entry.id] = Patch(
            id=entry.id, region=entry.region, layer=entry.layer, aspect=entry.aspect,
            n_solutions=entry.n_solutions, cells=cells, slots=slots,
            gate_cells=np.frombuffer(entry.gate_cells, np.uint32).astype(np.int64),
            singular_cells=np.frombuffer(entry.singular_cells, np.uint32).astype(np.int64))
    gates = {}
    for entry in roadmap_msg.gates:
        faces = np.stack([np.frombuffer(entry.cells_a, np.uint32),
                          np.frombuffer(entry.cells_b, np.uint32)], axis=-1).astype(np.int64)
        gates[(entry.patch_a, entry.patch_b)] = Gate(
            patches=(entry.patch_a, entry.patch_b), faces=faces.reshape(-1, 2), width=entry.width)
    segmentation = Segmentation(field=field, region=region, patch=patch, patches=patches,
                                gates=gates, links=links)
    return Roadmap(segmentation=segmentation, graph=roadmap_graph(segmentation), timings={})
