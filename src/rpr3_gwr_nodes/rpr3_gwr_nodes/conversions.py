"""Conversions between rpr3_gwr_core values and rpr3_gwr_msgs messages.

Large per-cell arrays travel as ``array.array`` filled from numpy buffers,
the fast path of the generated setters (a list would be checked element by
element), and come back with ``numpy.frombuffer``; per-solution arrays hold
only the solutions that exist (a third of the slots of the full 3-DOF
roadmap, whose field message is then about 150 MB instead of 390).  A roadmap
travels as its field's arrays; patches and gates are derived from them on
arrival by the core's one decoder (``Segmentation.from_arrays``), and the
roadmap message's summary must agree.
"""

import array

import numpy as np
from builtin_interfaces.msg import Duration
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.mechanisms import ThreeRPR
from rpr3_gwr_core.workspace import (AdaptiveGrid, Axis, Grid, NSolutionField, Roadmap,
                                     Segmentation, roadmap_graph)
from rpr3_gwr_core.workspace.cusps import known_cusps
from rpr3_gwr_msgs.msg import AxisLinks, FixedJoint, GridAxis, PlatformPose
from rpr3_gwr_msgs.msg import Cusp as CuspMsg
from rpr3_gwr_msgs.msg import Gate as GateMsg
from rpr3_gwr_msgs.msg import Geometry as GeometryMsg
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
    out.frombytes(memoryview(np.ascontiguousarray(values, dtype=dtype)).cast("B"))
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
    return ThreeRPR(a1=tuple(msg.a1), a2=tuple(msg.a2), a3=tuple(msg.a3), d1=msg.d1, d3=msg.d3,
                    beta=msg.beta)


def grid_to_msg(grid):
    """A uniform or adaptive grid as a rpr3_gwr_msgs/Grid."""
    adaptive = isinstance(grid, AdaptiveGrid)
    base = grid.base if adaptive else grid
    msg = GridMsg(axes=[GridAxis(joint=a.joint, min=a.low, max=a.high, step=a.step,
                                 count=a.count, periodic=a.periodic) for a in base.axes],
                  fixed=[FixedJoint(joint=j, value=v) for j, v in base.fixed])
    if adaptive:
        msg.refinement = grid.refinement
        msg.refined_blocks = _pack("I", grid.blocks, np.uint32)
    return msg


def grid_from_msg(msg):
    """Inverse of :func:`grid_to_msg`.

    Raises
    ------
    InvalidInputError
        If the counts do not match the ranges and steps, or the refinement
        or its blocks do not fit the grid.
    """
    grid = Grid(axes=tuple(Axis(a.joint, a.min, a.max, a.step, a.periodic) for a in msg.axes),
                fixed=tuple((f.joint, f.value) for f in msg.fixed))
    counts = tuple(a.count for a in msg.axes)
    if grid.shape != counts:
        raise InvalidInputError(f"grid message: counts {counts} do not match its ranges and "
                                f"steps {grid.shape}")
    if msg.refinement:
        blocks = np.frombuffer(msg.refined_blocks, np.uint32) if len(msg.refined_blocks) \
            else np.zeros(0, np.uint32)
        return AdaptiveGrid(grid, msg.refinement, blocks)
    return grid


def roadmap_to_msgs(roadmap, header):
    """The field and roadmap messages of a built roadmap.

    Parameters
    ----------
    roadmap : rpr3_gwr_core.workspace.Roadmap
    header : std_msgs.msg.Header

    Returns
    -------
    (rpr3_gwr_msgs.msg.NSolutionField, rpr3_gwr_msgs.msg.WorkspaceRoadmap)
    """
    seg = roadmap.segmentation
    field = seg.field
    geometry, grid = geometry_to_msg(field.mechanism), grid_to_msg(field.grid)
    field_msg = NSolutionFieldMsg(header=header, geometry=geometry, grid=grid,
                                  max_solutions=field.max_solutions,
                                  pose_size=field.mechanism.pose_size)
    valid = field.valid
    field_msg.n_solutions = _pack("B", field.count, np.uint8)
    field_msg.region_ids = _pack("i", seg.region, np.int32)
    field_msg.patch_ids = _pack("i", seg.patch[valid], np.int32)
    field_msg.poses = _pack("d", field.poses[valid], np.float64)
    field_msg.singularity_margin = _pack("d", field.margin[valid], np.float64)
    field_msg.links = [AxisLinks(slots=_pack("b", match, np.int8)) for _, _, match in seg.links]
    field_msg.cusps = [CuspMsg(legs=[float(v) for v in c.joints],
                               pose=PlatformPose(x=float(c.pose[0]), y=float(c.pose[1]),
                                                 alpha=float(c.pose[2])),
                               regions=list(c.regions))
                       for c in known_cusps(roadmap)]
    patches = [WorkspacePatch(id=p.id, region=p.region, layer=p.layer, aspect=p.aspect,
                              n_solutions=p.n_solutions, n_cells=int(p.cells.size),
                              area=roadmap.graph.nodes[p.id]["area"])
               for _, p in sorted(seg.patches.items())]
    gates = [GateMsg(patch_a=a, patch_b=b, n_faces=len(g.faces), width=g.width)
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
    slots, size = geometry.max_solutions, geometry.pose_size
    if (field_msg.max_solutions, field_msg.pose_size) != (slots, size):
        raise InvalidInputError(f"field message: {field_msg.max_solutions} solutions of "
                                f"{field_msg.pose_size} coordinates, the mechanism has "
                                f"{slots} of {size}")
    n = grid.size
    count = _unpack(field_msg.n_solutions, np.uint8, n, "n_solutions")
    if count.max(initial=0) > slots:
        raise InvalidInputError(f"field message: a cell has {count.max()} solutions, the "
                                f"mechanism at most {slots}")
    valid = np.arange(slots) < count[:, None]
    total = int(count.sum(dtype=np.int64))
    poses = np.full((n, slots, size), np.nan)
    poses[valid] = _unpack(field_msg.poses, np.float64, total * size, "poses").reshape(-1, size)
    margin = np.full((n, slots), np.nan)
    margin[valid] = _unpack(field_msg.singularity_margin, np.float64, total,
                            "singularity_margin")
    patch = np.zeros((n, slots), np.int32)
    patch[valid] = _unpack(field_msg.patch_ids, np.int32, total, "patch_ids")
    field = NSolutionField(mechanism=geometry, grid=grid, count=count, poses=poses,
                           margin=margin)
    if any(len(axis.slots) % slots for axis in field_msg.links):
        raise InvalidInputError(f"field message: links are not {slots} per face")
    links = [np.frombuffer(axis.slots, np.int8).reshape(-1, slots) if len(axis.slots)
             else np.zeros((0, slots), np.int8) for axis in field_msg.links]
    segmentation = Segmentation.from_arrays(
        field, _unpack(field_msg.region_ids, np.int32, n, "region_ids"), patch, links)
    if ({p.id for p in roadmap_msg.patches} != set(segmentation.patches)
            or {(g.patch_a, g.patch_b) for g in roadmap_msg.gates} != set(segmentation.gates)):
        raise InvalidInputError("the roadmap message's patches and gates do not match its field")
    return Roadmap(segmentation=segmentation, graph=roadmap_graph(segmentation), timings={})
