"""Conversions between rpr3_gwr_core values and rpr3_gwr_msgs messages.

Large per-cell arrays travel as ``array.array`` filled from numpy buffers,
the fast path of the generated setters (a list would be checked element by
element), and come back with ``numpy.frombuffer``; per-solution arrays hold
only the solutions that exist (a third of the slots of the full 3-DOF
roadmap, whose field message is then about 150 MB instead of 390).  A roadmap
travels as its field's arrays; patches and gates are derived from them on
arrival by the core's one decoder (``Segmentation.from_arrays``), and the
roadmap message's summary must agree.  A scene travels as obstacles and
named joint ranges and is read by the core's one scene reader
(``scene_from_dict``), which refuses what it cannot use.
"""

import array
import math

import numpy as np
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Point, Point32, Polygon, PoseStamped
from rclpy.serialization import deserialize_message
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.mechanisms import mechanism_from_dict
from rpr3_gwr_core.world import scene_from_dict
from rpr3_gwr_core.workspace import (AdaptiveGrid, Axis, Grid, NSolutionField, Roadmap,
                                     Segmentation, roadmap_graph)
from rpr3_gwr_core.workspace.cusps import known_cusps
from rpr3_gwr_msgs.msg import (AxisLinks, FixedJoint, GridAxis, JointRange, MechanismParameter,
                               Obstacle, PlatformPose)
from rpr3_gwr_msgs.msg import Cusp as CuspMsg
from rpr3_gwr_msgs.msg import Gate as GateMsg
from rpr3_gwr_msgs.msg import Grid as GridMsg
from rpr3_gwr_msgs.msg import Mechanism as MechanismMsg
from rpr3_gwr_msgs.msg import NSolutionField as NSolutionFieldMsg
from rpr3_gwr_msgs.msg import Scene as SceneMsg
from rpr3_gwr_msgs.msg import WorkspacePatch, WorkspaceRoadmap

from .profiles import BASE_FRAME

__all__ = ["MAX_DURATION", "duration_msg", "mechanism_to_msg", "mechanism_from_msg",
           "pose_msg", "pose_from_msg", "pose_stamped_msg", "configuration_from_msg",
           "grid_to_msg", "grid_from_msg",
           "roadmap_to_msgs", "roadmap_from_msgs", "roadmap_matches_msgs", "scene_to_msg",
           "scene_from_msg", "scene_msg_from_bytes", "is_empty_scene",
           "MAX_SCENE_MESSAGE_BYTES"]

# builtin_interfaces/Duration holds int32 seconds.
MAX_DURATION = 2**31 - 1
# How far a pose's quaternion may be from unit length, or from a turn about
# z (a float32 quaternion rounded to float64 is within 1e-7).
_UNIT_QUATERNION_TOL = 1e-6

MAX_SCENE_MESSAGE_BYTES = 128 * 1024
"""Longest serialized rpr3_gwr_msgs/Scene the nodes read [bytes] (128 KiB).

Reading a message takes time in proportion to its obstacles (10,000 discs,
560 KB: 0.15 s of the interpreter), spent before the core can refuse more
than a scene may hold (:data:`~rpr3_gwr_core.world.scene.MAX_OBSTACLES`):
a longer one is refused unread.  The largest scene the core takes, with ids
of a few characters, is about 17 KB."""


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


def mechanism_to_msg(mechanism):
    """A core mechanism as a rpr3_gwr_msgs/Mechanism: its document
    (``Mechanism.to_dict``), numbers as one value and points as their
    coordinates, with its joint and pose names."""
    document = mechanism.to_dict()
    return MechanismMsg(
        kind=document.pop("kind"),
        parameters=[MechanismParameter(name=name, values=[float(v) for v in np.ravel(value)])
                    for name, value in document.items()],
        joint_names=list(mechanism.joint_names), pose_names=list(mechanism.pose_names),
        mode_coordinate=mechanism.mode_coordinate)


def mechanism_from_msg(msg):
    """Inverse of :func:`mechanism_to_msg`.

    Raises
    ------
    InvalidInputError
        If the kind is unknown, a parameter is named twice or malformed, or
        the names and mode coordinate are not the kind's.
    """
    names = [p.name for p in msg.parameters]
    if len(set(names)) != len(names):
        raise InvalidInputError(f"mechanism message: a parameter is named twice in {names}")
    document = {p.name: float(p.values[0]) if len(p.values) == 1 else
                [float(v) for v in p.values] for p in msg.parameters}
    mechanism = mechanism_from_dict(dict(document, kind=msg.kind))
    given = (list(msg.joint_names), list(msg.pose_names), msg.mode_coordinate)
    if given != (list(mechanism.joint_names), list(mechanism.pose_names),
                 mechanism.mode_coordinate):
        raise InvalidInputError(
            f"mechanism message: joints {given[0]}, pose {given[1]} and mode coordinate "
            f"{given[2]} are not the {mechanism.kind}'s {list(mechanism.joint_names)}, "
            f"{list(mechanism.pose_names)} and {mechanism.mode_coordinate}")
    return mechanism


def pose_msg(mechanism, pose):
    """A pose (shape ``(pose_size,)``) as a rpr3_gwr_msgs/PlatformPose."""
    return PlatformPose(names=list(mechanism.pose_names), values=[float(v) for v in pose])


def pose_from_msg(mechanism, msg):
    """A geometry_msgs/PoseStamped of the platform as the core's pose
    (``(x, y, alpha)``, or the five-bar's ``(x, y)``).

    Raises
    ------
    InvalidInputError
        If it is not a pose in the base plane: a number not finite, a frame
        other than ``base`` (or ""), z not 0, a quaternion not of unit length
        (within 1e-6) or turning about another axis than z, or turned at all
        for a mechanism whose pose has no angle.
    """
    frame = msg.header.frame_id
    if frame not in ("", BASE_FRAME):
        raise InvalidInputError(f"a pose is in frame {BASE_FRAME!r} (or \"\"), got {frame!r:.60}")
    p, q = msg.pose.position, msg.pose.orientation
    values = (p.x, p.y, p.z, q.x, q.y, q.z, q.w)
    if not all(math.isfinite(v) for v in values):
        raise InvalidInputError(f"a pose's numbers must be finite, got {values}")
    if p.z != 0.0:
        raise InvalidInputError(f"a pose lies in the base plane: z must be 0, got {p.z}")
    if abs(math.hypot(q.x, q.y, q.z, q.w) - 1.0) > _UNIT_QUATERNION_TOL:
        raise InvalidInputError(f"a pose's orientation must be a unit quaternion, got "
                                f"{(q.x, q.y, q.z, q.w)}")
    if max(abs(q.x), abs(q.y)) > _UNIT_QUATERNION_TOL:
        raise InvalidInputError(f"a pose turns about z only: its quaternion's x and y must be "
                                f"0, got {(q.x, q.y)}")
    yaw = 2.0 * math.atan2(q.z, q.w)
    if not any(mechanism.angular[2:]):
        if abs(math.remainder(yaw, 2 * math.pi)) > _UNIT_QUATERNION_TOL:
            raise InvalidInputError(f"the {mechanism.kind}'s pose has no angle: its "
                                    f"orientation must be the identity, got {yaw:g} rad")
        return (p.x, p.y)
    return (p.x, p.y, math.remainder(yaw, 2 * math.pi))


def pose_stamped_msg(mechanism, pose, stamp=None):
    """The core's pose (shape ``(pose_size,)``) as a geometry_msgs/PoseStamped
    in frame ``base`` (``stamp`` a builtin_interfaces/Time, zero if None)."""
    yaw = float(pose[2]) if len(pose) > 2 and mechanism.angular[2] else 0.0
    msg = PoseStamped()
    msg.header.frame_id = BASE_FRAME
    if stamp is not None:
        msg.header.stamp = stamp
    msg.pose.position.x, msg.pose.position.y = float(pose[0]), float(pose[1])
    msg.pose.orientation.z, msg.pose.orientation.w = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
    return msg


def configuration_from_msg(mechanism, msg):
    """A rpr3_gwr_msgs/Configuration as the core's ``(*joints, mode)``, the
    joints in the mechanism's order; values are not checked here (the core
    checks them where it takes them).

    Raises
    ------
    InvalidInputError
        If there is not one position per joint, or the names are not the
        mechanism's joints (each once, in any order).
    """
    names, positions = list(msg.joint_names), list(msg.positions)
    joints = list(mechanism.joint_names)
    if len(positions) != len(joints):
        raise InvalidInputError(f"a configuration of the {mechanism.kind} has {len(joints)} "
                                f"positions, for {joints}; got {len(positions)}")
    if names:
        if sorted(names) != sorted(joints):
            raise InvalidInputError(f"joint names {names} are not the {mechanism.kind}'s "
                                    f"{joints} (each once, or none for that order)")
        by_name = dict(zip(names, positions))
        positions = [by_name[name] for name in joints]
    return (*positions, msg.mode)


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
    mechanism, grid = mechanism_to_msg(field.mechanism), grid_to_msg(field.grid)
    field_msg = NSolutionFieldMsg(header=header, mechanism=mechanism, grid=grid,
                                  max_solutions=field.max_solutions,
                                  pose_size=field.mechanism.pose_size)
    valid = field.valid
    field_msg.n_solutions = _pack("B", field.count, np.uint8)
    field_msg.region_ids = _pack("i", seg.region, np.int32)
    field_msg.patch_ids = _pack("i", seg.patch[valid], np.int32)
    field_msg.poses = _pack("d", field.poses[valid], np.float64)
    field_msg.singularity_margin = _pack("d", field.margin[valid], np.float64)
    field_msg.links = [AxisLinks(slots=_pack("b", match, np.int8)) for _, _, match in seg.links]
    field_msg.cusps = [CuspMsg(joints=[float(v) for v in c.joints],
                               pose=pose_msg(field.mechanism, c.pose), regions=list(c.regions))
                       for c in known_cusps(roadmap)]
    patches = [WorkspacePatch(id=p.id, region=p.region, layer=p.layer, aspect=p.aspect,
                              n_solutions=p.n_solutions, n_cells=int(p.cells.size),
                              area=roadmap.graph.nodes[p.id]["area"])
               for _, p in sorted(seg.patches.items())]
    gates = [GateMsg(patch_a=a, patch_b=b, n_faces=len(g.faces), width=g.width)
             for (a, b), g in sorted(seg.gates.items())]
    roadmap_msg = WorkspaceRoadmap(header=header, mechanism=mechanism, grid=grid, patches=patches,
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
    mechanism, grid = _message_frame(field_msg, roadmap_msg)
    count, valid, poses, margin, patch_ids, region, links = _field_arrays(field_msg, mechanism,
                                                                          grid)
    n, slots, size = grid.size, mechanism.max_solutions, mechanism.pose_size
    full_poses = np.full((n, slots, size), np.nan)
    full_poses[valid] = poses
    full_margin = np.full((n, slots), np.nan)
    full_margin[valid] = margin
    patch = np.zeros((n, slots), np.int32)
    patch[valid] = patch_ids
    field = NSolutionField(mechanism=mechanism, grid=grid, count=count, poses=full_poses,
                           margin=full_margin)
    segmentation = Segmentation.from_arrays(field, region, patch, links)
    if not _same_patches_and_gates(segmentation, roadmap_msg):
        raise InvalidInputError("the roadmap message's patches and gates do not match its field")
    # The areas come with the patches: summing the cells' volumes again takes
    # most of a second on an adaptive grid of millions of cells.
    areas = {p.id: p.area for p in roadmap_msg.patches}
    if not all(math.isfinite(area) and area > 0 for area in areas.values()):
        raise InvalidInputError("the roadmap message's patch areas are not all positive")
    return Roadmap(segmentation=segmentation, graph=roadmap_graph(segmentation, areas),
                   timings={})


def roadmap_matches_msgs(roadmap, field_msg, roadmap_msg):
    """Whether ``roadmap`` is the one two messages describe, value for
    value: a copy of it from elsewhere (a roadmap cache) can then stand in
    for decoding them.  False for messages that describe no roadmap."""
    try:
        mechanism, grid = _message_frame(field_msg, roadmap_msg)
        count, valid, poses, margin, patch_ids, region, links = _field_arrays(
            field_msg, mechanism, grid)
    except InvalidInputError:
        return False
    seg = roadmap.segmentation
    field = seg.field
    if mechanism != field.mechanism or grid != field.grid \
            or not np.array_equal(field.count, count):
        return False
    return (np.array_equal(seg.region, region) and np.array_equal(seg.patch[valid], patch_ids)
            and np.array_equal(field.margin[valid], margin)
            and np.array_equal(field.poses[valid], poses) and len(links) == len(seg.links)
            and all(np.array_equal(match, sent) for (_, _, match), sent in zip(seg.links, links))
            and _same_patches_and_gates(seg, roadmap_msg))


def _message_frame(field_msg, roadmap_msg):
    """The mechanism and grid two roadmap messages share, checked."""
    mechanism, grid = mechanism_from_msg(field_msg.mechanism), grid_from_msg(field_msg.grid)
    if (mechanism_from_msg(roadmap_msg.mechanism) != mechanism
            or grid_from_msg(roadmap_msg.grid) != grid):
        raise InvalidInputError("field and roadmap messages were built for different "
                                "mechanisms or grids")
    if any(axis.joint >= mechanism.n_joints for axis in grid.axes) or any(
            joint >= mechanism.n_joints for joint, _ in grid.fixed):
        raise InvalidInputError(f"grid message: a joint index beyond the {mechanism.kind}'s "
                                f"{mechanism.n_joints} joints")
    return mechanism, grid


def _field_arrays(field_msg, mechanism, grid):
    """A field message's arrays, checked for size: the counts (n,), which
    slots hold a solution (n, slots), the solutions' poses (m, pose size),
    margins (m,) and patch ids (m,), the region ids (n,) and the links of
    each axis (faces, slots), views of the message where they can be."""
    slots, size = mechanism.max_solutions, mechanism.pose_size
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
    poses = _unpack(field_msg.poses, np.float64, total * size, "poses").reshape(-1, size)
    margin = _unpack(field_msg.singularity_margin, np.float64, total, "singularity_margin")
    patch_ids = _unpack(field_msg.patch_ids, np.int32, total, "patch_ids")
    region = _unpack(field_msg.region_ids, np.int32, n, "region_ids")
    if any(len(axis.slots) % slots for axis in field_msg.links):
        raise InvalidInputError(f"field message: links are not {slots} per face")
    links = [np.frombuffer(axis.slots, np.int8).reshape(-1, slots) if len(axis.slots)
             else np.zeros((0, slots), np.int8) for axis in field_msg.links]
    return count, valid, poses, margin, patch_ids, region, links


def _same_patches_and_gates(segmentation, roadmap_msg):
    return ({p.id for p in roadmap_msg.patches} == set(segmentation.patches)
            and {(g.patch_a, g.patch_b) for g in roadmap_msg.gates} == set(segmentation.gates))


def scene_to_msg(scene, header):
    """A core scene as a rpr3_gwr_msgs/Scene with ``header`` (frame ``base``):
    its polygons, then its discs, and its limits."""
    limits = scene.limits
    obstacles = [Obstacle(id=o.id, type=Obstacle.POLYGON, polygon=Polygon(points=[
        Point32(x=float(x), y=float(y)) for x, y in o.vertices])) for o in scene.polygons]
    obstacles += [Obstacle(id=o.id, type=Obstacle.DISC, radius=float(o.radius),
                           center=Point(x=float(o.center[0]), y=float(o.center[1])))
                  for o in scene.discs]
    return SceneMsg(header=header, obstacles=obstacles,
                    strokes=_joint_ranges(limits.strokes),
                    passive_ranges=_joint_ranges(limits.passive),
                    obstacle_clearance=float(limits.obstacle_clearance))


def _joint_ranges(ranges):
    return [JointRange(name=name, min=float(low), max=float(high))
            for name, (low, high) in ranges.items()]


def scene_msg_from_bytes(data):
    """A serialized rpr3_gwr_msgs/Scene (a raw subscription's), read.

    Raises
    ------
    InvalidInputError
        If it is longer than :data:`MAX_SCENE_MESSAGE_BYTES`.
    """
    if len(data) > MAX_SCENE_MESSAGE_BYTES:
        raise InvalidInputError(f"scene message of {len(data):,} bytes, more than the "
                                f"{MAX_SCENE_MESSAGE_BYTES:,} a scene may take: refused unread")
    return deserialize_message(data, SceneMsg)


def scene_from_msg(msg):
    """A rpr3_gwr_msgs/Scene as a core scene (``scene_from_dict`` checks it);
    joint names are checked against a mechanism where the scene is applied.

    Raises
    ------
    InvalidInputError
        If the frame is not ``base``, an obstacle has no id or no known
        type, a joint is named twice, or the core refuses the scene (a
        number not finite, a radius not positive, a polygon without area or
        with crossing edges, a duplicate id, a range with min above max...).
    """
    if msg.header.frame_id not in ("", BASE_FRAME):
        raise InvalidInputError(f"scene message: frame {msg.header.frame_id!r}, the scene's "
                                f"obstacles must be in {BASE_FRAME!r}")
    obstacles = []
    for k, obstacle in enumerate(msg.obstacles):
        if not obstacle.id:
            raise InvalidInputError(f"scene message: obstacle {k} has no id")
        if obstacle.type == Obstacle.DISC:
            shape = {"disc": {"center": [obstacle.center.x, obstacle.center.y],
                              "radius": obstacle.radius}}
        elif obstacle.type == Obstacle.POLYGON:
            shape = {"polygon": [[p.x, p.y] for p in obstacle.polygon.points]}
        else:
            raise InvalidInputError(f"scene message: obstacle {obstacle.id!r} has type "
                                    f"{obstacle.type}, neither DISC ({Obstacle.DISC}) nor "
                                    f"POLYGON ({Obstacle.POLYGON})")
        obstacles.append({"id": obstacle.id, **shape})
    return scene_from_dict({"obstacles": obstacles, "limits": {
        "strokes": _ranges_from(msg.strokes, "strokes"),
        "passive": _ranges_from(msg.passive_ranges, "passive_ranges"),
        "obstacle_clearance": msg.obstacle_clearance}})


def _ranges_from(ranges, where):
    names = [r.name for r in ranges]
    if len(set(names)) != len(names):
        raise InvalidInputError(f"scene message: a joint is named twice in {where} {names}")
    return {r.name: [r.min, r.max] for r in ranges}


def is_empty_scene(scene):
    """Whether a scene has neither obstacles nor joint ranges: no scene (its
    clearance alone keeps nothing away)."""
    limits = scene.limits
    return not (scene.polygons or scene.discs or limits.strokes or limits.passive)
