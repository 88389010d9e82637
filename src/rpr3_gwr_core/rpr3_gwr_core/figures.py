"""Figures of the n-solution field, of the roadmap and of plans (paper
figures 6 and 10 to 13).

Functions return :class:`matplotlib.figure.Figure` objects built without
pyplot, so they work headless and write nothing: the caller saves them.

The figures share their conventions.  A count of direct-kinematic solutions
has one colour per count, explained by a discrete colour bar.  A region has
one colour, and its id is written in a circle of that colour, the same in the
field, roadmap, slice and plan figures.  Angles are drawn in degrees
(the joints and pose coordinates the mechanism marks as angles), other joint
and pose values in the mechanism's length unit.
"""

import math
import textwrap

import networkx as nx
import numpy as np
from matplotlib import colormaps
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch as LegendPatch, Polygon
from scipy import sparse
from scipy.ndimage import distance_transform_cdt, find_objects, label as label_pieces
from scipy.sparse.csgraph import connected_components, dijkstra

from .exceptions import InvalidInputError
from .workspace import aspect_groups
from .workspace.cusps import known_cusps
from .world.bodies import mechanism_bodies

__all__ = ["field_figure", "slice_figure", "roadmap_figure", "plan_figure"]

# The segmentation keeps no region of fewer cells than this: neither does a
# slice's numbering of its pieces.
_MIN_PIECE = 8
# Pieces of a region beyond its largest get their id only from this size on.
_LABELLED_PIECE = 16
_REGION_CAPTION = "Circled: region ids, regions numbered by decreasing area.  "
# The chosen global path and the others, as the legend names them.
_CHOSEN_STYLE = {"color": "tab:orange", "ls": "-", "lw": 2.2, "marker": "o", "ms": 4}
_OTHER_STYLE = {"color": "tab:purple", "ls": "--", "lw": 1.6, "marker": "s", "ms": 4}
# The start a ring, the goal a star inside it: both show where they coincide.
# The bodies at each end are drawn in its colour.
_START_COLOUR, _GOAL_COLOUR = "tab:green", "tab:red"
_START_STYLE = {"marker": "o", "ms": 15, "mfc": "none", "mec": _START_COLOUR, "mew": 2.5,
                "ls": "none"}
_GOAL_STYLE = {"marker": "*", "ms": 11, "color": _GOAL_COLOUR, "mec": "k", "mew": 0.5,
               "ls": "none"}
_OBSTACLE_STYLE = {"fc": "0.6", "ec": "k", "lw": 0.8}
# A global path not planned is drawn along cells of its patches, a step
# costing up to 1 + _EDGE_COST times more near their edges (closer than
# _EDGE_REACH steps).
_EDGE_COST, _EDGE_REACH = 3.0, 6.0


def field_figure(roadmap, world=None):
    """The n-solution field with its region ids, as the paper's figure 6.

    Cells are coloured by their number of direct-kinematic solutions (one
    colour per count, discrete colour bar); cells of no region that have
    solutions (unresolved cells) are white, the boundaries between regions
    are drawn dark and the cusps of the singular curve are marked.  Each
    region's id is written in a circle of the region's colour at the most
    interior cell of each of its pieces (a region crossing the seam of a
    turning joint shows as two); a caption states how patch ids are formed
    from region ids.  With a scene, the cells where it blocks solutions are
    hatched over the field (as the paper's figure 3 darkens singular and
    obstacle cells alike): densely where it blocks every solution.

    Parameters
    ----------
    roadmap : Roadmap
        Over a 2-D grid.
    world : SceneRoadmap, optional
        The roadmap restricted to a scene.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InvalidInputError
        If the grid is not 2-D.
    """
    seg = roadmap.segmentation
    _check_plane(roadmap)
    plane = _Plane(roadmap, {})
    region = seg.region[plane.cells]
    fig, ax = _count_image(roadmap, plane, region,
                           caption=_REGION_CAPTION + _patch_id_caption(roadmap))
    for r, piece in _region_pieces(region):
        if piece["largest"] or piece["size"] >= _LABELLED_PIECE:
            _region_label(ax, plane, piece["at"], r)
    handles = _count_legend_handles(seg, region, plane.cells)
    cusps = known_cusps(roadmap)
    if cusps:
        ax.plot(*plane.space.points([c.joints for c in cusps]).T, "r^", ms=8, label="cusp")
    title = f"n-solution field and regions{_fixed_text(roadmap, prefix=', ')}"
    if world is not None:
        handles += _hatch_blocked(ax, plane, seg, world)
        title += f"\n{world.n_parts} free parts in the scene"
    ax.legend(handles=ax.get_legend_handles_labels()[0] + handles, loc="upper left",
              fontsize=8)
    ax.set_title(title)
    return fig


def slice_figure(roadmap, fixed, cusps=()):
    """Number of solutions and regions of a roadmap over more than two
    joints, on the plane where the others take given values.

    Each pixel (one per fine step) shows the grid cell ``cells_of`` gives for
    it, coloured by its number of solutions as in :func:`field_figure`.  The
    pieces the roadmap's regions leave in the plane are numbered as a 2-D
    roadmap of that plane numbers its regions (by decreasing area; ties: the
    lowest first pixel), so a region has the same id and colour here as in
    the :func:`field_figure` of that plane; each id is written in a circle of
    its colour at the piece's most interior pixel, with the id of the
    roadmap's own region the piece belongs to (the first digits of its patch
    ids) beside it.

    Parameters
    ----------
    roadmap : Roadmap
    fixed : mapping of int to float
        Axis joint to its value, for all axes but two [joint unit: rad for
        angles].
    cusps : sequence of Cusp
        Cusp points to mark (of that plane).

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InvalidInputError
        If ``fixed`` does not leave two axes, or the plane leaves the grid.
    """
    grid, names = roadmap.grid, roadmap.mechanism.joint_names
    if len([a for a in grid.axes if a.joint not in fixed]) != 2 \
            or len(fixed) != grid.ndim - 2:
        raise InvalidInputError(f"a slice fixes all axes but two, got {dict(fixed)} for the "
                                f"axes {[names[a.joint] for a in grid.axes]}")
    plane = _Plane(roadmap, fixed)
    seg = roadmap.segmentation
    region = _plane_regions(roadmap, plane)
    fig, ax = _count_image(roadmap, plane, region, caption=(
        "Circled: the plane's regions, numbered by decreasing area as a 2-D roadmap of this "
        "plane numbers its regions; beside each, 'in r': the roadmap's region r it lies in "
        f"(patch ids: {roadmap.segmentation.id_base} x r + layer)."))
    for number, piece in _region_pieces(region):
        if piece["largest"] or piece["size"] >= _LABELLED_PIECE:
            _region_label(ax, plane, piece["at"], number)
            at = piece["at"]
            ax.annotate(f"in {seg.region[plane.cells[at]]}", (plane.u[at[0]], plane.v[at[1]]),
                        xytext=(9, -9), textcoords="offset points", fontsize=7, va="top")
    handles = _count_legend_handles(seg, region, plane.cells)
    if len(cusps):
        ax.plot(*plane.space.points([c.joints for c in cusps]).T, "r^", ms=8, label="cusp")
    ax.legend(handles=ax.get_legend_handles_labels()[0] + handles, loc="upper left",
              fontsize=8)
    ax.set_title(f"slice {_joint_values_text(roadmap, sorted(dict(fixed).items()))} of the "
                 f"{grid.ndim}-D roadmap: solutions and regions")
    return fig


def roadmap_figure(roadmap, seed=0):
    """The global workspace roadmap as a graph drawing (paper figure 10).

    Nodes are patches labelled by id, filled with their region's colour (as
    in :func:`field_figure`) and ringed by their aspect's (red: positive,
    blue: negative); each aspect's group is laid out apart, and edge widths
    grow with the gate widths.  A legend names the colours and a caption
    states how patch ids are formed.

    Parameters
    ----------
    roadmap : Roadmap
    seed : int
        Seed of the spring layout.

    Returns
    -------
    matplotlib.figure.Figure
    """
    graph = roadmap.graph
    fig = Figure(figsize=(8, 6.5))
    ax = fig.add_subplot()
    fig.subplots_adjust(left=0.03, right=0.8, bottom=0.12, top=0.92)
    # One spring layout per aspect group, side by side, as the paper's figure 10.
    layout = {}
    for column, nodes in enumerate(aspect_groups(graph)):
        part = nx.spring_layout(graph.subgraph(nodes), seed=seed, weight=None)
        layout.update({n: xy + np.array([2.6 * column, 0.0]) for n, xy in part.items()})
    nodes = list(graph.nodes)
    widest = max((graph.edges[e]["width"] for e in graph.edges), default=1.0)
    widths = [0.5 + 3.0 * graph.edges[e]["width"] / max(1e-9, widest) for e in graph.edges]
    nx.draw_networkx(graph, pos=layout, ax=ax, nodelist=nodes,
                     node_color=[_region_colour(graph.nodes[n]["region"]) for n in nodes],
                     edgecolors=[_aspect_colour(graph.nodes[n]["aspect"]) for n in nodes],
                     linewidths=2.5, width=widths, node_size=460, font_size=8)
    regions = sorted({graph.nodes[n]["region"] for n in nodes})
    handles = [Line2D([], [], ls="none", marker="o", ms=11, mfc="none", mew=2.5,
                      mec=_aspect_colour(sign), label=f"{name} aspect")
               for sign, name in ((1, "positive"), (-1, "negative"))]
    handles += [LegendPatch(fc=_region_colour(r), ec="k", label=f"region {r}") for r in regions]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    _caption(fig, "Nodes: patches, filled with their region's colour.  "
             + _patch_id_caption(roadmap))
    ax.set_title(f"global workspace roadmap{_fixed_text(roadmap, prefix=', ')}")
    ax.set_axis_off()
    return fig


def plan_figure(roadmap, plan, world=None, sheet_stride=6):
    """A planned path, as the paper's figures 11 to 13.

    On a 2-D grid: left, the path over the plane of the grid's joints with
    its regions (coloured and numbered as in :func:`field_figure`); right,
    the path in that plane and the pose's mode coordinate (the 3-RPR:
    (rho2, rho3, alpha)) over the sheets of the patches it may go through.
    On any other grid (the full 3-DOF roadmap, tori of three turning joints,
    a roadmap over one joint): the path in the space of the first three
    joints (of two, for a mechanism of two), the pose track in (x, y, angle)
    and each joint against the path's joint-space arc length, with the patch
    the path is in between the dotted lines.

    Every global path of the plan is drawn through its patches, the chosen
    one solid along the plan's waypoints, the others dashed along a path of
    cells of their patches that crosses their gates in order (its vertices
    in those cells, its segments within them), all named in the legend.
    Turning joints and angular pose coordinates are drawn over one turn,
    the lines continuous across its seam: a line that leaves it at one side
    comes back at the other.  The start is a green ring, the goal a red star inside it where
    they coincide, each labelled with its value of the mode coordinate.

    On a slice (a 2-D grid with cusp equations), the cusps of its singular
    curve are marked as in :func:`field_figure`, in both views.

    With a scene, the plane of a 2-D grid is hatched where the scene blocks
    solutions (as in :func:`field_figure`), and a panel on the right draws
    the base plane in the length unit: the obstacles with their ids, the
    mechanism's bodies at the start (green) and at the goal (red) and the
    trace of the platform's reference point (the pose's first two lengths).

    Parameters
    ----------
    roadmap : Roadmap
    plan : dict
        :meth:`~rpr3_gwr_core.planning.Plan.to_dict` output.
    world : SceneRoadmap, optional
        The roadmap restricted to the scene the plan was made in.
    sheet_stride : int
        Draw every n-th cell of the patches' sheets in the 3-D view of a
        2-D grid's plan.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InvalidInputError
        If a global path of the plan goes through patches the roadmap has
        not (it was planned on another grid), or with a scene, if the pose
        has no two lengths to place the platform in the base plane.
    """
    seg = roadmap.segmentation
    paths = [list(p) for p in plan.get("global_paths") or [[]]]
    chosen = max(plan.get("path_index", 0), 0)
    unknown = set().union(*paths) - set(seg.patches)
    if unknown:
        raise InvalidInputError(f"the plan's global path goes through patches "
                                f"{sorted(unknown)} that the roadmap has not: it was planned "
                                "on another grid")
    track = _Track(roadmap, plan)
    lines = _path_lines(roadmap, track, paths, chosen)
    if roadmap.grid.ndim == 2:
        plane = _Plane(roadmap, {})
        return _plane_plan_figure(roadmap, plane, track, paths, chosen, lines, sheet_stride,
                                  world)
    return _space_plan_figure(roadmap, track, paths, chosen, lines, world)


class _Space:
    """Display coordinates of some components of states, a state being a
    joint vector followed by its pose: each scaled to its display unit and,
    where it turns, wrapped into one turn.

    Attributes
    ----------
    columns : list of int
        The state components shown.
    labels : list of str
        Their axis labels, with units.
    """

    def __init__(self, columns, scales, lows, periods, labels):
        self.columns, self.labels = list(columns), list(labels)
        self.scales, self.lows, self.periods = (np.array(x, dtype=float)
                                                for x in (scales, lows, periods))

    @classmethod
    def of_joints(cls, roadmap, joints):
        """Joints, turning axes wrapped into the grid's turn."""
        axes = {a.joint: a for a in roadmap.grid.axes}
        scales = [_joint_scale(roadmap, j) for j in joints]
        turning = [axes[j] if j in axes and axes[j].periodic else None for j in joints]
        return cls(joints, scales,
                   [(a.low - a.step / 2) * s if a else 0.0 for a, s in zip(turning, scales)],
                   [a.period * s if a else 0.0 for a, s in zip(turning, scales)],
                   [_joint_label(roadmap, j) for j in joints])

    @classmethod
    def of_pose(cls, mechanism, coordinates):
        """Pose coordinates, angles wrapped into [-180, 180) degrees."""
        angles = [mechanism.angular[k] for k in coordinates]
        return cls([mechanism.n_joints + k for k in coordinates],
                   [_pose_unit(mechanism, k)[0] for k in coordinates],
                   [-180.0 if a else 0.0 for a in angles], [360.0 if a else 0.0 for a in angles],
                   [_pose_label(mechanism, k) for k in coordinates])

    def __add__(self, other):
        return _Space(self.columns + other.columns, np.append(self.scales, other.scales),
                      np.append(self.lows, other.lows), np.append(self.periods, other.periods),
                      self.labels + other.labels)

    def points(self, states):
        """Display coordinates of states, shape (n, len(columns))."""
        values = np.asarray(states, dtype=float)[:, self.columns] * self.scales
        turning = self.periods > 0
        values[:, turning] = self.lows[turning] + np.mod(values[:, turning] - self.lows[turning],
                                                         self.periods[turning])
        return values

    def line(self, states):
        """Display coordinates of a polyline drawn continuously across the
        seams of its turning coordinates: made continuous (each step the
        shortest way round), cut where it crosses the bounds of the turn
        shown, and each piece moved by whole turns into that turn, so that it
        leaves at one side and comes back at the other.  Pieces that do not
        join are parted by a NaN row; the first and last points are the
        first and last states' :meth:`points`."""
        values = np.asarray(states, dtype=float)[:, self.columns] * self.scales
        turning = self.periods > 0
        if len(values) > 1 and turning.any():
            steps = np.diff(values, axis=0)
            steps[:, turning] -= self.periods[turning] * np.round(
                steps[:, turning] / self.periods[turning])
            values = np.vstack([values[:1], values[0] + np.cumsum(steps, axis=0)])
        return _in_one_turn(values, self.lows, self.periods)

    def axes(self, fig, *position):
        """A subplot of the figure for these coordinates, 3-D for three."""
        ax = fig.add_subplot(*position, **({"projection": "3d"} if len(self.columns) == 3
                                           else {}))
        for setter, label in zip((ax.set_xlabel, ax.set_ylabel, getattr(ax, "set_zlabel", None)),
                                 self.labels):
            setter(label)
        return ax


class _Plane:
    """The pixels of a plane through a grid: one per fine step of its two
    free axes, each showing a cell.

    Attributes
    ----------
    joints : tuple of int
        The two free joints.
    space : _Space
        Their display coordinates.
    u, v : ndarray
        Pixel centres along each, in display units.
    cells : ndarray of int, shape (u.size, v.size)
        Cell of each pixel.
    """

    def __init__(self, roadmap, fixed):
        grid = roadmap.grid
        free = [k for k, a in enumerate(grid.axes) if a.joint not in fixed]
        axes = [grid.axes[k] for k in free]
        self.joints = tuple(a.joint for a in axes)
        self.space = _Space.of_joints(roadmap, self.joints)
        values = [a.values for a in axes]
        points = np.empty((values[0].size * values[1].size, grid.ndim))
        for k, axis in enumerate(grid.axes):
            points[:, k] = fixed.get(axis.joint, 0.0)
        mesh = np.meshgrid(*values, indexing="ij")
        points[:, free[0]], points[:, free[1]] = mesh[0].ravel(), mesh[1].ravel()
        cells = grid.cells_of(points)
        if np.any(cells < 0):
            raise InvalidInputError(f"the slice {dict(fixed)} leaves the grid")
        self.cells = cells.reshape(values[0].size, values[1].size)
        self.u, self.v = (value * scale for value, scale in zip(values, self.space.scales))

    @property
    def extent(self):
        """The outer edges of the pixels: a turning axis spans its turn."""
        du, dv = (np.diff(w[:2]) / 2 if w.size > 1 else np.zeros(1) for w in (self.u, self.v))
        return (float(self.u[0] - du[0]), float(self.u[-1] + du[0]),
                float(self.v[0] - dv[0]), float(self.v[-1] + dv[0]))


class _Track:
    """A plan's waypoints and what is drawn of them.

    Attributes
    ----------
    states : ndarray, shape (n, n_joints + pose_size)
        Joints and pose of each waypoint [joint and pose units].
    patches : ndarray of int
        Patch of each waypoint (-1 where the plan does not say).
    unwrapped : ndarray, shape (n, n_joints)
        The joints, turning ones made continuous (``Grid.unwrap``).
    arc : ndarray, shape (n,)
        Joint-space arc length along the path (turning joints unwrapped),
        normalised to [0, 1].
    ends : list of str
        Legend labels of the start and the goal, with their mode values.
    """

    def __init__(self, roadmap, plan):
        mechanism = roadmap.mechanism
        waypoints = plan["waypoints"]
        joints = np.array([w["joints"] for w in waypoints],
                          dtype=float).reshape(-1, mechanism.n_joints)
        pose = np.array([w["pose"] for w in waypoints],
                        dtype=float).reshape(-1, mechanism.pose_size)
        self.states = np.hstack([joints, pose])
        self.patches = np.array([w.get("patch", -1) for w in waypoints], dtype=int)
        self.unwrapped = roadmap.grid.unwrap(joints)
        steps = np.linalg.norm(np.diff(self.unwrapped, axis=0), axis=1)
        arc = np.concatenate([[0.0], np.cumsum(steps)])
        self.arc = arc / arc[-1] if arc[-1] > 0 else np.linspace(0.0, 1.0, arc.size)
        mode = mechanism.mode_coordinate
        name = mechanism.pose_names[mode]
        self.ends = [f"{end} ({name} = {_value_text(p[mode], *_pose_unit(mechanism, mode))})"
                     for end, p in (("start", pose[0]), ("goal", pose[-1]))]


def _draw_plan(ax, space, track, paths, chosen, lines, named):
    """The trajectory (solid black), the global paths along their
    :func:`_path_lines` and the start and goal of a plan in one space;
    ``named``: with legend labels."""
    ax.plot(*space.line(track.states).T, "k-", lw=1.5, label="trajectory" if named else None,
            gid="trajectory")
    for k, (path, states) in enumerate(zip(paths, lines)):
        if path:
            ax.plot(*space.line(states).T, **(_CHOSEN_STYLE if k == chosen else _OTHER_STYLE),
                    label=_path_text(path, k, chosen) if named else None,
                    gid=f"global path {k + 1}")
    _mark_ends(ax, space.points(track.states[[0, -1]]), track.ends, named)


def _plane_plan_figure(roadmap, plane, track, paths, chosen, lines, sheet_stride, world):
    """:func:`plan_figure` of a 2-D grid."""
    seg, mechanism = roadmap.segmentation, roadmap.mechanism
    mode = mechanism.mode_coordinate
    columns = 2 if world is None else 3
    fig = Figure(figsize=(7 * columns, 6.5))
    # The left margin keeps its width in inches with the scene's panel.
    fig.subplots_adjust(left=0.12 / columns, right=0.97, bottom=0.16, top=0.9, wspace=0.15)
    ax = plane.space.axes(fig, 1, columns, 1)
    region = seg.region[plane.cells]
    ax.imshow(np.transpose(_region_palette(seg.n_regions)[region], (1, 0, 2)), origin="lower",
              extent=plane.extent, interpolation="nearest", aspect="auto")
    hatches = [] if world is None else _hatch_blocked(ax, plane, seg, world)
    for r, piece in _region_pieces(region):
        if piece["largest"]:
            _region_label(ax, plane, piece["at"], r)
    cusps = known_cusps(roadmap)
    if cusps:
        ax.plot(*plane.space.points([c.joints for c in cusps]).T, "r^", ms=8, label="cusp")
    _draw_plan(ax, plane.space, track, paths, chosen, lines, named=True)
    ax.set_title(f"trajectory via global path {chosen + 1}{_fixed_text(roadmap, prefix=', ')}")
    ax.legend(handles=ax.get_legend_handles_labels()[0] + hatches, loc="upper left",
              fontsize=8, framealpha=0.9)
    space = plane.space + _Space.of_pose(mechanism, [mode])
    ax3 = space.axes(fig, 1, columns, 2)
    for pid in sorted(set().union(*paths)):
        patch = seg.patches[pid]
        cells, slots = patch.cells[::sheet_stride], patch.slots[::sheet_stride]
        sheet = space.points(np.hstack([seg.field.grid.joints_at(cells),
                                        seg.field.poses[cells, slots]]))
        ax3.scatter(*sheet.T, s=1, alpha=0.25, label=str(pid))
    if cusps:
        ax3.plot(*space.points([np.concatenate([c.joints, c.pose]) for c in cusps]).T, "r^",
                 ms=6)
    _draw_plan(ax3, space, track, paths, chosen, lines, named=False)
    ax3.legend(loc="upper left", markerscale=8, title="patch", fontsize=8)
    if world is not None:
        _draw_base_plane(fig, (1, 3, 3), mechanism, track, world)
    _caption(fig, _REGION_CAPTION + _patch_id_caption(roadmap))
    return fig


def _space_plan_figure(roadmap, track, paths, chosen, lines, world):
    """:func:`plan_figure` of a grid that is not 2-D."""
    mechanism = roadmap.mechanism
    columns = 2 if world is None else 3
    fig = Figure(figsize=(7 * columns, 11.5))
    fig.subplots_adjust(left=0.12 / columns, right=0.97, bottom=0.1, top=0.88, hspace=0.25)
    legs = _Space.of_joints(roadmap, range(min(3, mechanism.n_joints)))
    ax = legs.axes(fig, 2, columns, 1)
    _draw_plan(ax, legs, track, paths, chosen, lines, named=True)
    ax.set_title(f"legs along the path, via global path {chosen + 1}")
    # Above both views, which draw the same lines: inside one it hides the path.
    fig.legend(*ax.get_legend_handles_labels(), loc="upper center", ncols=2, fontsize=8)
    pose = _Space.of_pose(mechanism, range(min(3, mechanism.pose_size)))
    ax_pose = pose.axes(fig, 2, columns, 2)
    _draw_plan(ax_pose, pose, track, paths, chosen, lines, named=False)
    ax_pose.set_title("pose track of the platform")

    ax_q = fig.add_subplot(2, 1, 2)
    scales = np.array([_joint_scale(roadmap, j) for j in range(mechanism.n_joints)])
    joints = track.unwrapped * scales
    for j in range(mechanism.n_joints):
        ax_q.plot(track.arc, joints[:, j], "-", label=_joint_label(roadmap, j))
    changes = np.flatnonzero(np.diff(track.patches) != 0) + 1
    bounds = np.concatenate([[0], changes, [track.arc.size]])
    for k in changes:
        ax_q.axvline(0.5 * (track.arc[k - 1] + track.arc[k]), color="0.5", ls=":", lw=1)
    for first, end in zip(bounds[:-1], bounds[1:]):
        if track.patches[first] >= 0:
            ax_q.text(0.5 * (track.arc[first] + track.arc[end - 1]), 1.01,
                      str(track.patches[first]), transform=ax_q.get_xaxis_transform(),
                      ha="center", va="bottom", fontsize=8)
    ax_q.plot(track.arc[:1], joints[:1, 0], **_START_STYLE)
    ax_q.plot(track.arc[-1:], joints[-1:, 0], **_GOAL_STYLE)
    units = sorted({_joint_unit(roadmap, j)[1] for j in range(mechanism.n_joints)})
    ax_q.set_xlabel("joint-space arc length along the path (normalised)")
    ax_q.set_ylabel(f"joints [{', '.join(units)}]")
    ax_q.set_title("joints against the path" + (" (patch ids between the dotted lines)" if np.any(
        track.patches >= 0) else ""), pad=16)
    ax_q.legend(loc="best", fontsize=8)
    if world is not None:
        _draw_base_plane(fig, (2, 3, 3), mechanism, track, world)
    _caption(fig, _patch_id_caption(roadmap))
    return fig


def _draw_base_plane(fig, position, mechanism, track, world):
    """The base-plane panel of a plan in a scene: the obstacles with their
    ids, the bodies at the start and at the goal in the colours of their
    marks, and the trace of the platform's reference point."""
    scene = world.scene
    coordinates = _position(mechanism)
    trace = _Space.of_pose(mechanism, coordinates)
    ax = trace.axes(fig, *position)
    shapes = [(o.id, Polygon(o.vertices, **_OBSTACLE_STYLE), o.vertices.mean(axis=0))
              for o in scene.polygons]
    shapes += [(o.id, Circle(o.center, o.radius, **_OBSTACLE_STYLE), o.center)
               for o in scene.discs]
    for name, shape, at in shapes:
        ax.add_patch(shape)
        ax.text(*at, name, ha="center", va="center", fontsize=8,
                bbox={"boxstyle": "round", "fc": "white", "alpha": 0.8, "lw": 0})
    n = mechanism.n_joints
    ends = track.states[[0, -1]]
    bodies = mechanism_bodies(mechanism, ends[:, n:], ends[:, :n], world.index.model)
    handles = [LegendPatch(**_OBSTACLE_STYLE, label="obstacle (its id)")]
    for k, (end, colour) in enumerate((("start", _START_COLOUR), ("goal", _GOAL_COLOUR))):
        for link in bodies.capsules[k]:
            ax.plot(*link.T, "-o", color=colour, lw=2, ms=3)
        for plate in bodies.polygons[k]:
            ax.add_patch(Polygon(plate, fc=colour, ec=colour, alpha=0.3))
        handles.append(Line2D([], [], color=colour, lw=2, marker="o", ms=3,
                              label=f"bodies at the {end}"))
    names = ", ".join(mechanism.pose_names[k] for k in coordinates)
    ax.plot(*trace.line(track.states).T, "k-", lw=1.2, label=f"trace of ({names})")
    # Unlabelled: the labels would hide the bodies, the legends of the other panels name them.
    for point, style in zip(trace.points(ends), (_START_STYLE, _GOAL_STYLE)):
        ax.plot(*([value] for value in point), **style)
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(handles=ax.get_legend_handles_labels()[0] + handles, loc="best", fontsize=8)
    clearance = scene.limits.obstacle_clearance
    ax.set_title("base plane: the scene, the bodies at start and goal"
                 + (f"\n(obstacle clearance {clearance:g})" if clearance else ""))


def _position(mechanism):
    """The pose coordinates of the platform's reference point in the base
    plane: the pose's first two lengths.

    Raises
    ------
    InvalidInputError
        If the pose has fewer.
    """
    lengths = [k for k, angle in enumerate(mechanism.angular) if not angle]
    if len(lengths) < 2:
        raise InvalidInputError(f"the {mechanism.kind}'s pose has no two lengths to place "
                                "its platform in the base plane of a scene")
    return lengths[:2]


def _check_plane(roadmap):
    """InvalidInputError unless the roadmap's grid is 2-D."""
    if roadmap.grid.ndim != 2:
        raise InvalidInputError(f"figures draw 2-D grids, this one has {roadmap.grid.ndim} axes")


def _count_image(roadmap, plane, region, caption):
    """A figure of the number of solutions over a plane (one colour per
    count, white on cells of no region that have solutions), the region
    boundaries drawn dark, with its discrete colour bar and a caption."""
    seg = roadmap.segmentation
    count = seg.field.count[plane.cells].astype(float)
    count[(region == 0) & (count > 0)] = np.nan
    fig = Figure(figsize=(7.5, 7))
    ax = fig.add_subplot()
    fig.subplots_adjust(bottom=0.16, top=0.9)
    top = seg.field.max_solutions
    colours = np.vstack([[[0.85, 0.85, 0.85, 1.0]],
                         colormaps["viridis"].resampled(max(top, 1))(np.arange(top))])
    image = ax.imshow(count.T, origin="lower", extent=plane.extent, aspect="auto",
                      cmap=ListedColormap(colours),
                      norm=BoundaryNorm(np.arange(top + 2) - 0.5, top + 1),
                      interpolation="nearest")
    edges = np.zeros(region.shape, dtype=bool)
    edges[:-1, :] |= region[:-1, :] != region[1:, :]
    edges[:, :-1] |= region[:, :-1] != region[:, 1:]
    ax.contour(plane.u, plane.v, edges.T.astype(float), levels=[0.5], colors="k",
               linewidths=0.6)
    bar = fig.colorbar(image, ax=ax, label="direct-kinematic solutions per cell")
    bar.set_ticks(range(top + 1), labels=[str(n) for n in range(top + 1)])
    ax.set_xlabel(plane.space.labels[0])
    ax.set_ylabel(plane.space.labels[1])
    _caption(fig, caption)
    return fig, ax


def _caption(fig, text):
    """Writes a caption along the bottom of a figure, in lines of its width."""
    fig.text(0.02, 0.01, textwrap.fill(text, int(14 * fig.get_figwidth())), fontsize=8,
             va="bottom")


def _count_legend_handles(seg, region, cells):
    """Legend entries of the count image's region boundaries and, where
    there are any, its white cells."""
    handles = [Line2D([], [], color="k", lw=0.8, label="region boundary")]
    if np.any((region == 0) & (seg.field.count[cells] > 0)):
        handles.append(LegendPatch(fc="white", ec="0.5", label="unresolved cells (no region)"))
    return handles


def _hatch_blocked(ax, plane, seg, world):
    """Hatches the pixels of a plane whose cells have solutions a scene
    blocks: densely where it blocks every one.

    Returns
    -------
    list of matplotlib.patches.Patch
        Legend entries of the hatches drawn.
    """
    solutions = seg.patch > 0
    blocked = (solutions & ~world.free).sum(axis=1)
    some = (blocked > 0)[plane.cells]
    every = (blocked == solutions.sum(axis=1))[plane.cells] & some
    handles = []
    for mask, hatch, name in ((some & ~every, "//", "scene blocks some solutions"),
                              (every, "xxxx", "scene blocks every solution")):
        if mask.any():
            ax.contourf(plane.u, plane.v, mask.T.astype(float), levels=[0.5, 1.5],
                        colors="none", hatches=[hatch])
            handles.append(LegendPatch(fc="none", ec="k", hatch=hatch, label=name))
    return handles


def _plane_regions(roadmap, plane):
    """The regions a 2-D roadmap of a plane through the grid would have: its
    pixels joined where their cells are one, or face-adjacent cells with the
    same number of solutions that all continue across the face, or (where
    the grid's cells of neighbouring pixels are no face of it, as between
    its refined and coarse parts) cells of one of the roadmap's regions.

    Returns
    -------
    ndarray of int, shape of ``plane.cells``
        Region of each pixel, numbered 1.. by decreasing number of pixels
        (ties: the lowest first pixel), as the segmentation numbers regions;
        0 off every region and in sets of fewer than ``_MIN_PIECE``.
    """
    seg = roadmap.segmentation
    count, region3 = seg.field.count, seg.region
    cells = plane.cells.ravel()
    index = np.arange(cells.size).reshape(plane.cells.shape)
    ends = []
    for axis, period in enumerate(plane.space.periods):
        upper = np.roll(index, -1, axis=axis)
        if not period:
            upper = np.delete(upper, -1, axis=axis)
        ends.append((index[tuple(slice(0, n) for n in upper.shape)].ravel(), upper.ravel()))
    a, b = (np.concatenate(side) for side in zip(*ends))
    ca, cb = cells[a], cells[b]
    on_plane = np.zeros(count.size, dtype=bool)
    on_plane[cells] = True
    faces, continued = [], []
    for lower, upper, match in seg.links:
        keep = on_plane[lower] & on_plane[upper]
        lower, upper, match = lower[keep], upper[keep], match[keep]
        n = count[lower]
        faces.append(_pair_keys(lower, upper, count.size))
        continued.append((n == count[upper]) & ((match >= 0).sum(axis=1) == n))
    # Sorted, with a key above all so that every search lands on one.
    faces, continued = np.concatenate(faces), np.concatenate(continued)
    order = np.argsort(faces)
    faces = np.append(faces[order], np.iinfo(np.int64).max)
    continued = np.append(continued[order], False)
    keys = _pair_keys(ca, cb, count.size)
    at = np.searchsorted(faces, keys)
    face = faces[at] == keys
    joined = (region3[ca] > 0) & (region3[cb] > 0) & (
        (ca == cb) | (face & continued[at]) | (~face & (region3[ca] == region3[cb])))
    graph = sparse.coo_matrix((np.ones(np.count_nonzero(joined)), (a[joined], b[joined])),
                              shape=(cells.size,) * 2)
    _, component = connected_components(graph, directed=False)
    component[region3[cells] == 0] = -1
    sizes = np.bincount(component[component >= 0], minlength=cells.size)
    firsts = np.full(cells.size, cells.size)
    np.minimum.at(firsts, component[component >= 0], np.flatnonzero(component >= 0))
    kept = np.flatnonzero(sizes >= _MIN_PIECE)
    number = np.zeros(cells.size, dtype=int)
    number[kept[np.lexsort((firsts[kept], -sizes[kept]))]] = np.arange(1, kept.size + 1)
    return np.where(component >= 0, number[component], 0).reshape(plane.cells.shape)


def _pair_keys(a, b, size):
    """One integer per unordered pair of cells."""
    return np.minimum(a, b).astype(np.int64) * size + np.maximum(a, b)


def _region_pieces(region):
    """The connected pieces of each region in a plane of pixels.

    Returns
    -------
    list of (int, dict)
        Region id and its piece: ``size`` (pixels), ``at`` (its most
        interior pixel) and ``largest`` (whether no other piece of the
        region is larger).
    """
    out = []
    for r in np.unique(region[region > 0]):
        labelled, _ = label_pieces(region == r)
        pieces = []
        for k, box in enumerate(find_objects(labelled), start=1):
            mask = labelled[box] == k
            i, j = _interior_point(mask)
            pieces.append({"size": int(np.count_nonzero(mask)),
                           "at": (i + box[0].start, j + box[1].start), "largest": False})
        max(pieces, key=lambda p: p["size"])["largest"] = True
        out += [(int(r), p) for p in pieces]
    return out


def _interior_point(mask):
    """The cell of a mask farthest from its complement (city-block distance)."""
    depth = distance_transform_cdt(np.pad(mask, 1), metric="taxicab")[1:-1, 1:-1]
    return np.unravel_index(np.argmax(depth), mask.shape)


def _region_colour(r):
    """A region's colour: a light shade of the ten-colour cycle (the id tells
    apart the regions that share one)."""
    return tuple(0.55 * np.array(colormaps["tab10"]((r - 1) % 10)) + 0.45)


def _region_palette(n_regions):
    """RGBA per region id, transparent for 0 (no region)."""
    return np.array([(1.0, 1.0, 1.0, 0.0)] + [_region_colour(r)
                                               for r in range(1, n_regions + 1)])


def _region_label(ax, plane, at, number):
    """Writes a region id in a circle of its colour at a pixel."""
    ax.text(plane.u[at[0]], plane.v[at[1]], str(number), ha="center", va="center",
            fontsize=9, bbox={"boxstyle": "circle", "fc": _region_colour(number), "ec": "k"})


def _aspect_colour(sign):
    return "tab:red" if sign > 0 else "tab:blue"


def _patch_id_caption(roadmap):
    return (f"Patch id = {roadmap.segmentation.id_base} x region + layer: a region with n "
            "solutions has n patches, layers 1..n, negative aspect first, then in the solver's "
            "order of the solutions at the region's first cell.")


def _joint_unit(roadmap, joint):
    """Display unit per joint unit of a joint, and the display unit's name."""
    return ((180.0 / math.pi, "deg") if roadmap.mechanism.angular_joints[joint]
            else (1.0, "length"))


def _joint_scale(roadmap, joint):
    return _joint_unit(roadmap, joint)[0]


def _joint_label(roadmap, joint):
    return f"{roadmap.mechanism.joint_names[joint]} [{_joint_unit(roadmap, joint)[1]}]"


def _pose_unit(mechanism, k):
    """Display unit per pose unit of a pose coordinate, and its name."""
    return (180.0 / math.pi, "deg") if mechanism.angular[k] else (1.0, "length")


def _pose_label(mechanism, k):
    return f"{mechanism.pose_names[k]} [{_pose_unit(mechanism, k)[1]}]"


def _joint_values_text(roadmap, values):
    """``name = value`` of joints, angles in degrees."""
    return ", ".join(f"{roadmap.mechanism.joint_names[j]} = "
                     + _value_text(value, *_joint_unit(roadmap, j)) for j, value in values)


def _value_text(value, scale, unit):
    """A joint or pose value in display units: degrees marked, lengths bare."""
    return f"{value * scale:.1f} deg" if unit == "deg" else f"{value * scale:g}"


def _fixed_text(roadmap, prefix):
    """The grid's fixed joints as text after ``prefix``, empty without any."""
    text = _joint_values_text(roadmap, roadmap.grid.fixed)
    return prefix + text if text else ""


def _in_one_turn(points, lows, periods):
    """A continuous polyline (display coordinates) drawn in one turn of its
    turning coordinates (``periods > 0``): each segment cut where it
    crosses ``lows + m * periods``, each piece moved by whole turns into
    ``[lows, lows + periods]``, NaN rows between pieces that do not join.

    Returns
    -------
    ndarray, shape (m, len(lows))
    """
    points = np.asarray(points, dtype=float)
    turning = periods > 0
    if not turning.any() or len(points) == 0:
        return points
    period = np.where(turning, periods, 1.0)

    def tile(point):
        return np.where(turning, np.floor((point - lows) / period), 0.0)

    if len(points) == 1:
        return points - tile(points[0]) * period
    out, previous = [], None
    for a, b in zip(points[:-1], points[1:]):
        step = b - a
        cuts = [0.0, 1.0]
        for k in np.flatnonzero(turning & (step != 0)):
            ends = sorted(((a[k] - lows[k]) / period[k], (b[k] - lows[k]) / period[k]))
            bounds = lows[k] + period[k] * np.arange(np.ceil(ends[0]), np.floor(ends[1]) + 1)
            cuts.extend((bounds - a[k]) / step[k])
        cuts = np.unique(np.clip(cuts, 0.0, 1.0))
        for t0, t1 in zip(cuts[:-1], cuts[1:]):
            here = tile(a + 0.5 * (t0 + t1) * step)
            shift = here * period
            if previous is None or np.any(here != previous):
                if previous is not None:
                    out.append(np.full(points.shape[1], np.nan))
                out.append(a + t0 * step - shift)
            out.append(a + t1 * step - shift)
            previous = here
    return np.array(out)


def _path_lines(roadmap, track, paths, chosen):
    """The states each global path of a plan is drawn through: the plan's
    waypoints for the chosen one, else :func:`_cell_path` from the start to
    the goal (one point per patch, :func:`_patch_points`, where no path of
    cells joins them).

    Returns
    -------
    list of ndarray, shape (n, n_joints + pose_size)
        One per global path (None for an empty one).
    """
    lines = []
    for k, path in enumerate(paths):
        if not path:
            lines.append(None)
        elif k == chosen:
            lines.append(track.states)
        else:
            states = _cell_path(roadmap, path, track.states[0], track.states[-1])
            if states is None:
                points = _patch_points(roadmap, path)
                states = np.array([points[p] for p in path])
            lines.append(states)
    return lines


def _cell_path(roadmap, path, start, goal):
    """A polyline through the cells of a global path's patches, in order.

    The least-cost path over solutions of the path's patches, from the cell
    nearest the start in its first patch to the cell nearest the goal in its
    last, moving between face-adjacent cells along the solution's
    continuation inside a patch and from one patch to the next only across
    a face of their gate (across the seams of turning joints too); a step
    costs its length in grid steps, more near the patches' edges
    (``_EDGE_COST``, ``_EDGE_REACH``).  It is drawn through the cells on
    both sides of each gate face it crosses and, between them, through as
    few of its cells as keep every straight segment within cells of the
    path's patches (and below a quarter turn in every turning joint and
    angular pose coordinate, so that it is drawn the short way round).

    Parameters
    ----------
    roadmap : Roadmap
    path : list of int
        Patch ids, joined by gates in this order.
    start, goal : ndarray
        States (joints, then pose) whose cells the line starts and ends
        nearest.

    Returns
    -------
    ndarray, shape (n, n_joints + pose_size) or None
        The joints (continuous across seams) and pose of the cells drawn
        through; None where no path of cells joins start and goal.
    """
    seg = roadmap.segmentation
    field, grid = seg.field, seg.field.grid
    width = seg.patch.shape[1]
    per_layer = grid.size * width
    layer_of = np.full(max(seg.patches) + 1, -1)
    layer_of[list(path)] = np.arange(len(path))
    patches = [seg.patches[p] for p in path]
    cells = np.concatenate([p.cells for p in patches])
    slots = np.concatenate([p.slots for p in patches])
    layers = np.repeat(np.arange(len(path)), [p.cells.size for p in patches])
    keys = layers * per_layer + cells * width + slots
    order = np.argsort(keys)
    ordered = keys[order]

    def nodes(layer, cell, slot):
        return order[np.searchsorted(ordered, layer * per_layer + cell * width + slot)]

    rows, columns, weights = [], [], []
    for (lower, upper, match), lengths, step in zip(seg.links, grid.pair_lengths(), grid.steps):
        for slot in range(width):
            linked = np.flatnonzero(match[:, slot] >= 0)
            other = match[linked, slot].astype(np.int64)
            a = layer_of[seg.patch[lower[linked], slot]]
            b = layer_of[seg.patch[upper[linked], other]]
            keep = (a >= 0) & (b >= 0) & (np.abs(a - b) <= 1)
            a, b, linked, other = a[keep], b[keep], linked[keep], other[keep]
            na = nodes(a, lower[linked], slot)
            nb = nodes(b, upper[linked], other)
            weight = lengths[linked] / step
            # Inside a patch both ways, across a gate only forwards.
            rows += [np.where(a <= b, na, nb), nb[a == b]]
            columns += [np.where(a <= b, nb, na), na[a == b]]
            weights += [weight, weight[a == b]]
    n = cells.size
    # Kept off the patches' edges, where a straight line soon leaves them: a
    # step costs more the nearer its cells are to a solution of the path's
    # patches with fewer neighbours than a cell has faces.
    rows, columns = np.concatenate(rows), np.concatenate(columns)
    edge = sparse.csr_matrix((np.ones(rows.size), (rows, columns)), shape=(n, n))
    edge = ((edge + edge.T) > 0).astype(float).tocsr()
    degree = np.diff(edge.indptr)
    depth = np.zeros(n)
    boundary = np.flatnonzero(degree < 2 * grid.ndim)
    if boundary.size:
        depth = np.minimum(dijkstra(edge, directed=False, indices=boundary, min_only=True,
                                    limit=_EDGE_REACH), _EDGE_REACH)
    weights = np.concatenate(weights) * (
        1.0 + _EDGE_COST / (1.0 + np.minimum(depth[rows], depth[columns])))
    rows, columns, weights = [rows], [columns], [weights]
    coordinates = grid.coordinates_of(cells)
    axes = list(grid.axis_joints)

    def distances(state):
        offset = coordinates - np.asarray(state, dtype=float)[axes]
        offset -= grid.periods * np.round(offset / np.where(grid.periods > 0, grid.periods, 1.0))
        return np.linalg.norm(offset / np.array(grid.steps), axis=1)

    # From the start's nearest solution of the first patch, to the goal's of the last.
    first, last = np.flatnonzero(layers == 0), np.flatnonzero(layers == len(path) - 1)
    first, last = first[np.argmin(distances(start)[first])], last[np.argmin(distances(goal)[last])]
    rows += [[n], [last]]
    columns += [[first], [n + 1]]
    weights += [[0.0], [0.0]]
    # Explicit zeros would be no edges.
    graph = sparse.csr_matrix((np.concatenate(weights) + 1e-9,
                               (np.concatenate(rows), np.concatenate(columns))),
                              shape=(n + 2, n + 2))
    distance, previous = dijkstra(graph, indices=n, return_predecessors=True)
    if not np.isfinite(distance[n + 1]):
        return None
    walk = []
    node = previous[n + 1]
    while node != n:
        walk.append(node)
        node = previous[node]
    walk = np.array(walk[::-1])
    joints = grid.unwrap(grid.joints_at(cells[walk]))
    pose = field.poses[cells[walk], slots[walk]].copy()
    angular = np.array(roadmap.mechanism.angular, dtype=bool)
    pose[:, angular] = np.unwrap(pose[:, angular], axis=0)
    states = np.hstack([joints, pose])
    allowed = np.zeros(grid.size, dtype=bool)
    allowed[cells] = True
    turning = np.concatenate([[a.periodic for a in grid.axes], angular])
    columns_turning = np.concatenate([axes, grid.n_joints + np.arange(angular.size)])[turning]
    kept = [0]
    runs = np.flatnonzero(np.diff(layers[walk]) != 0)
    for first, end in zip(np.concatenate([[0], runs + 1]), np.append(runs, walk.size - 1)):
        if first != kept[-1]:
            kept.append(first)
        i = first
        while i < end:
            j = i + 1
            while j < end and _straight(grid, allowed, states[i], states[j + 1],
                                        columns_turning):
                j += 1
            kept.append(j)
            i = j
    return states[kept]


def _straight(grid, allowed, a, b, turning):
    """Whether the straight segment between two states (joints continuous)
    stays within ``allowed`` cells and moves less than a quarter turn along
    each of the ``turning`` columns."""
    if np.any(np.abs(b[turning] - a[turning]) >= 0.5 * math.pi):
        return False
    axes = list(grid.axis_joints)
    start, step = a[axes], b[axes] - a[axes]
    # Cut at every half step: between two cuts the cell does not change.
    cuts = [0.0, 1.0]
    for k, axis in enumerate(grid.axes):
        if step[k] != 0:
            ends = sorted(((start[k] - axis.low) / axis.step * 2,
                           (start[k] + step[k] - axis.low) / axis.step * 2))
            halves = np.arange(np.ceil(ends[0]), np.floor(ends[1]) + 1)
            cuts.extend((axis.low + halves * axis.step / 2 - start[k]) / step[k])
    cuts = np.unique(np.clip(cuts, 0.0, 1.0))
    middles = 0.5 * (cuts[:-1] + cuts[1:])
    cells = grid.cells_of(start + middles[:, None] * step)
    return bool(np.all(cells >= 0) and np.all(allowed[cells]))


def _patch_points(roadmap, ids):
    """One solution of each patch: at its cell nearest the mean of its cells
    (in steps).

    Returns
    -------
    dict of int to ndarray
        Patch id to the state (joints, then pose) of that solution.
    """
    seg = roadmap.segmentation
    grid = seg.field.grid
    points = {}
    for pid in ids:
        patch = seg.patches[pid]
        coordinates = grid.coordinates_of(patch.cells)
        offsets = (coordinates - coordinates.mean(axis=0)) / np.array(grid.steps)
        k = np.argmin(np.einsum("ij,ij->i", offsets, offsets))
        cell = patch.cells[k]
        points[pid] = np.concatenate([grid.joints_at([cell])[0],
                                      seg.field.poses[cell, patch.slots[k]]])
    return points


def _path_text(path, k, chosen):
    """Legend label of a global path; a long one shows its ends."""
    ids = [str(p) for p in path]
    if len(ids) > 8:
        ids = ids[:4] + ["..."] + ids[-2:] + [f"({len(path)} patches)"]
    return (f"global path {k + 1}{' (chosen)' if k == chosen else ''}: "
            + " > ".join(ids))


def _mark_ends(ax, ends, labels, named=True):
    """Marks the start (a ring) and the goal (a star) and writes each's
    label beside it, the start's above and the goal's below, so both show
    where they coincide; ``named``: also in the axes' legend."""
    three_d = ax.name == "3d"
    for point, style, label, offset in zip(ends, (_START_STYLE, _GOAL_STYLE), labels,
                                           ((-10, 16), (10, -18))):
        ax.plot(*([value] for value in point), **style, label=label if named else None)
        if three_d:
            ax.text(*point, ("\n\n" + label) if offset[1] < 0 else (label + "\n\n"),
                    fontsize=7, ha="center", va="center")
        else:
            ax.annotate(label, point, xytext=offset, textcoords="offset points", fontsize=8,
                        ha="right" if offset[0] < 0 else "left",
                        va="bottom" if offset[1] > 0 else "top",
                        bbox={"boxstyle": "round", "fc": "white", "alpha": 0.8, "lw": 0})
