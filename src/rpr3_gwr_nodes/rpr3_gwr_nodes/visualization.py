"""Standard messages for RViz and Foxglove: the mechanism, the n-solution
field, the roadmap, planned paths and a scene's obstacles.

Two frames: ``base`` (:data:`~.profiles.BASE_FRAME`), the plane of the
mechanism, where it and the platform's path are drawn; and ``joint_space``
(:data:`JOINT_SPACE_FRAME`), the grid's plane (x, y = its two free joints,
for the paper's slice rho2 and rho3, in joint units) of a 2-D roadmap,
where the field maps, the roadmap and the joint path are drawn over one
another.  :func:`joint_space_transform` places the second beside the first,
so that one view in ``base`` shows both.
"""

import numpy as np
from geometry_msgs.msg import Point, Pose, TransformStamped
from nav_msgs.msg import MapMetaData, OccupancyGrid
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray
from rpr3_gwr_core.workspace import Grid
from rpr3_gwr_core.world.bodies import mechanism_bodies

from .profiles import BASE_FRAME

__all__ = ["JOINT_SPACE_FRAME", "joint_space_transform", "mechanism_points",
           "mechanism_markers", "field_maps", "roadmap_markers", "path_markers", "margin_color",
           "scene_markers"]

JOINT_SPACE_FRAME = "joint_space"
_BLUE = ColorRGBA(r=0.2, g=0.4, b=0.9, a=1.0)
_GREY = ColorRGBA(r=0.5, g=0.5, b=0.5, a=1.0)
_OBSTACLE = ColorRGBA(r=0.9, g=0.5, b=0.1, a=0.8)
_COLLISION = ColorRGBA(r=1.0, g=0.0, b=1.0, a=1.0)


def joint_space_transform(roadmap, stamp):
    """The static transform from ``base`` to ``joint_space``: the joint
    space's origin three of the mechanism's characteristic lengths
    (:attr:`Mechanism.scale`) along base's x, unturned.

    Returns
    -------
    geometry_msgs.msg.TransformStamped
    """
    transform = TransformStamped(header=Header(stamp=stamp, frame_id=BASE_FRAME),
                                 child_frame_id=JOINT_SPACE_FRAME)
    transform.transform.translation.x = 3.0 * float(roadmap.mechanism.scale)
    transform.transform.rotation.w = 1.0
    return transform


def margin_color(margin, warn, abort):
    """Green at a margin of ``warn`` or more, through yellow to red at ``abort``."""
    level = float(np.clip((abs(margin) - abort) / max(warn - abort, 1e-12), 0.0, 1.0))
    return ColorRGBA(r=float(min(1.0, 2.0 * (1.0 - level))), g=float(min(1.0, 2.0 * level)),
                     b=0.0, a=1.0)


def _points(xy, z=0.0):
    return [Point(x=float(x), y=float(y), z=float(z)) for x, y in xy]


def _marker(stamp, frame, namespace, kind, scale, color, identity=0):
    marker = Marker(header=Header(stamp=stamp, frame_id=frame), ns=namespace, id=identity,
                    type=kind, action=Marker.ADD, pose=Pose(), color=color)
    marker.pose.orientation.w = 1.0
    marker.scale.x = marker.scale.y = marker.scale.z = float(scale)
    return marker


def mechanism_points(mechanism, pose, joints):
    """What :func:`mechanism_markers` draws of a mechanism at a pose and its
    joints, in ``base`` [length unit]: the outline the mechanism gives of its
    bodies (``Mechanism.body_outline``), so any mechanism that describes its
    bodies is drawn, links through its elbows or slider joints included.

    Returns
    -------
    base : ndarray, shape (k, 2)
        The fixed base joints, the first point of each leg.
    legs : ndarray, shape (k, m, 2)
        Each leg as a polyline from its base joint to the platform (through
        its elbow or slider joint when it has one).
    platform : ndarray, shape (p, 2)
        The platform's corners; a mechanism without a platform plate (the
        five-bar) has its legs' common end point, the end effector.
    """
    links, plates, _ = mechanism.body_outline(np.asarray(pose, dtype=float),
                                              np.asarray(joints, dtype=float))
    legs = {}
    for _, leg, _, start, stop, _ in links:
        legs.setdefault(leg, [np.asarray(start)]).append(np.asarray(stop))
    polylines = np.array([legs[leg] for leg in sorted(legs)])
    platform = np.asarray(plates[0][2]) if plates else polylines[:1, -1]
    return polylines[:, 0], polylines, platform


def mechanism_markers(mechanism, pose, joints, margin, warn, abort, stamp, blocked=None):
    """A mechanism at a pose in ``base``: base joints, legs and platform
    (:func:`mechanism_points`), the legs and platform coloured by the margin
    (:func:`margin_color`), and the body that would collide highlighted.

    Parameters
    ----------
    mechanism : rpr3_gwr_core.mechanisms.Mechanism
        The 3-RPR, 3-RRR, 3-PRR or five-bar.
    pose : array_like, shape (pose_size,)
        The platform's pose (the 3-RPR: ``(x, y, alpha)`` [length unit,
        length unit, rad]).
    joints : array_like, shape (n_joints,)
        The joints it solves.
    margin : float
        Its signed normalised det(Jx).
    warn, abort : float
        The driver's margin thresholds.
    stamp : builtin_interfaces.msg.Time
    blocked : str, optional
        The body (a name of
        :func:`~rpr3_gwr_core.world.bodies.mechanism_bodies`, e.g. ``leg2``
        or ``platform``) that a collision stopped.

    Returns
    -------
    visualization_msgs.msg.MarkerArray
        Namespaces ``base`` (a sphere list of the base joints), ``legs`` (a
        line list of each leg's segments: A_i B_i for the 3-RPR, A_i C_i and
        C_i B_i through the elbows or slider joints C_i), ``platform`` (a
        closed line strip B1 B2 B3; the five-bar's end effector as a sphere
        list) and ``collision`` (the ``blocked`` body's outline, magenta and
        thicker; deleted when there is none or it names a joint).
    """
    base, legs, corners = mechanism_points(mechanism, pose, joints)
    color = margin_color(margin, warn, abort)
    bases = _marker(stamp, BASE_FRAME, "base", Marker.SPHERE_LIST, 0.05 * _size(base), _GREY)
    bases.points = _points(base)
    lines = _marker(stamp, BASE_FRAME, "legs", Marker.LINE_LIST, 0.016 * _size(base), color)
    lines.points = _points(np.stack([legs[:, :-1], legs[:, 1:]], axis=2).reshape(-1, 2))
    if len(corners) > 1:
        platform = _marker(stamp, BASE_FRAME, "platform", Marker.LINE_STRIP,
                           0.022 * _size(base), color)
        platform.points = _points(np.vstack([corners, corners[:1]]))
    else:
        platform = _marker(stamp, BASE_FRAME, "platform", Marker.SPHERE_LIST,
                           0.05 * _size(base), color)
        platform.points = _points(corners)
    return MarkerArray(markers=[bases, lines, platform,
                                _blocked_body(mechanism, pose, joints, blocked, base, stamp)])


def _blocked_body(mechanism, pose, joints, name, base, stamp):
    """The ``collision`` marker: the named body's outline, or a deletion."""
    marker = _marker(stamp, BASE_FRAME, "collision", Marker.LINE_STRIP, 0.04 * _size(base),
                     _COLLISION)
    bodies = None if name is None else mechanism_bodies(
        mechanism, np.asarray(pose, dtype=float)[None], np.asarray(joints, dtype=float)[None])
    if bodies is None or name not in bodies.names:
        marker.action = Marker.DELETE
        return marker
    k = bodies.names.index(name)
    n_capsules = bodies.capsules.shape[-3]
    if k < n_capsules:
        marker.points = _points(bodies.capsules.reshape(-1, 2, 2)[k])
    else:
        outline = bodies.polygons.reshape(-1, *bodies.polygons.shape[-2:])[k - n_capsules]
        marker.points = _points(np.vstack([outline, outline[:1]]))
    return marker


def scene_markers(scene, stamp):
    """A scene's obstacles in ``base``: after a deletion of every marker (the
    previous scene's), a flat cylinder per disc and a closed line strip per
    polygon, namespace ``obstacles``, each marker's ``text`` its id.

    Parameters
    ----------
    scene : rpr3_gwr_core.world.Scene or None
        None draws nothing (no scene).
    stamp : builtin_interfaces.msg.Time

    Returns
    -------
    visualization_msgs.msg.MarkerArray
    """
    clear = Marker(header=Header(stamp=stamp, frame_id=BASE_FRAME), action=Marker.DELETEALL)
    markers = [clear]
    if scene is None:
        return MarkerArray(markers=markers)
    for k, polygon in enumerate(scene.polygons):
        marker = _marker(stamp, BASE_FRAME, "obstacles", Marker.LINE_STRIP, 0.1, _OBSTACLE, k)
        marker.points = _points(np.vstack([polygon.vertices, polygon.vertices[:1]]))
        marker.text = polygon.id
        markers.append(marker)
    for k, disc in enumerate(scene.discs, start=len(scene.polygons)):
        marker = _marker(stamp, BASE_FRAME, "obstacles", Marker.CYLINDER, 2 * disc.radius,
                         _OBSTACLE, k)
        marker.scale.z = 0.1
        marker.pose.position = Point(x=float(disc.center[0]), y=float(disc.center[1]), z=0.0)
        marker.text = disc.id
        markers.append(marker)
    return MarkerArray(markers=markers)


def _size(base):
    """Marker sizes scale with the base (the paper's 3-RPR: 15.91 length units)."""
    return max(float(np.ptp(base, axis=0).max()), 1e-9)


def _plane_axes(roadmap):
    """The axes of a uniform 2-D grid, whose cells an occupancy grid's are;
    None for other grids (an adaptive one has cells of several sizes)."""
    grid = roadmap.grid
    if grid.ndim != 2 or not isinstance(grid, Grid):
        return None
    return grid.axes


def field_maps(roadmap, stamp):
    """The n-solution field of a 2-D roadmap as two occupancy grids in
    ``joint_space``, one cell per grid cell: solution counts (value
    ``100 * count / max_solutions``) and regions (``100 * region /
    n_regions``, 0 for none); None for other grids (3-D, adaptive).

    Returns
    -------
    (nav_msgs.msg.OccupancyGrid, nav_msgs.msg.OccupancyGrid) or None
    """
    axes = _plane_axes(roadmap)
    if axes is None:
        return None
    seg = roadmap.segmentation
    u, v = axes
    header = Header(stamp=stamp, frame_id=JOINT_SPACE_FRAME)
    info = MapMetaData(resolution=float(u.step), width=u.count, height=v.count)
    info.origin.position.x, info.origin.position.y = u.low - u.step / 2, v.low - v.step / 2
    info.origin.orientation.w = 1.0
    # Occupancy grids run along x fastest: the transpose of the row-major cells.
    count = 100 * seg.field.count.astype(int) // seg.field.max_solutions
    region = 100 * seg.region.astype(int) // max(seg.n_regions, 1)
    return tuple(OccupancyGrid(header=header, info=info,
                               data=values.reshape(u.count, v.count).T.ravel().astype(
                                   np.int8).tolist())
                 for values in (count, region))


def roadmap_markers(roadmap, stamp):
    """The roadmap of a 2-D grid in ``joint_space``: a label per patch at its
    most interior cell, raised by its layer, and a line per gate between the
    labels of its patches through the middle of its faces; None for other
    grids.

    Returns
    -------
    visualization_msgs.msg.MarkerArray or None
    """
    if _plane_axes(roadmap) is None:
        return None
    seg, grid = roadmap.segmentation, roadmap.grid
    coordinates = grid.coordinates()
    anchor = {}
    markers = []
    for pid, patch in sorted(seg.patches.items()):
        middle = coordinates[patch.cells].mean(axis=0)
        nearest = patch.cells[np.argmin(np.linalg.norm(coordinates[patch.cells] - middle,
                                                        axis=1))]
        anchor[pid] = (*coordinates[nearest], 2.0 * patch.layer)
        color = ColorRGBA(r=0.9, g=0.2, b=0.2, a=1.0) if patch.aspect > 0 else _BLUE
        label = _marker(stamp, JOINT_SPACE_FRAME, "patches", Marker.TEXT_VIEW_FACING, 1.5,
                        color, pid)
        label.pose.position = Point(x=float(anchor[pid][0]), y=float(anchor[pid][1]),
                                    z=float(anchor[pid][2]))
        label.text = str(pid)
        markers.append(label)
    gates = _marker(stamp, JOINT_SPACE_FRAME, "gates", Marker.LINE_LIST, 0.1, _GREY)
    for (a, b), gate in seg.gates.items():
        middle = coordinates[gate.faces.ravel()].mean(axis=0)
        for pid in (a, b):
            gates.points += [Point(x=float(anchor[pid][0]), y=float(anchor[pid][1]),
                                   z=float(anchor[pid][2])),
                             Point(x=float(middle[0]), y=float(middle[1]), z=0.0)]
    markers.append(gates)
    return MarkerArray(markers=markers)


def path_markers(grid, joints, poses, stamp):
    """A planned path: B1's track in ``base`` and, for a 2-D grid, the joint
    path in ``joint_space``.

    Parameters
    ----------
    grid : rpr3_gwr_core.workspace.Grid
    joints : ndarray, shape (n, 3)
        Leg waypoints [length unit].
    poses : ndarray, shape (n, 3)
        Platform poses along them.
    stamp : builtin_interfaces.msg.Time

    Returns
    -------
    visualization_msgs.msg.MarkerArray
    """
    track = _marker(stamp, BASE_FRAME, "platform_path", Marker.LINE_STRIP, 0.2, _BLUE)
    track.points = _points(np.asarray(poses)[:, :2])
    markers = [track]
    if grid.ndim == 2:
        leg_path = _marker(stamp, JOINT_SPACE_FRAME, "joint_path", Marker.LINE_STRIP, 0.2,
                           ColorRGBA(r=0.0, g=0.0, b=0.0, a=1.0))
        leg_path.points = _points(np.asarray(joints)[:, list(grid.axis_joints)])
        markers.append(leg_path)
    return MarkerArray(markers=markers)
