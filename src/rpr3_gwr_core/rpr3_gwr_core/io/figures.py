"""Figures of the n-solution field and of the roadmap (paper figures 6 and 10).

Functions return :class:`matplotlib.figure.Figure` objects built without
pyplot, so they work headless and write nothing: the caller saves them.
"""

import networkx as nx
import numpy as np
from matplotlib.figure import Figure
from scipy.ndimage import distance_transform_cdt, label as label_pieces

from ..exceptions import InvalidInputError
from ..workspace import aspect_groups
from ..workspace.cusps import known_cusps

__all__ = ["field_figure", "slice_figure", "roadmap_figure", "plan_figure"]


def field_figure(roadmap, world=None):
    """The n-solution field with its region ids, as the paper's figure 6.

    Cells are coloured by their number of solutions; region ids are written
    at each region's most interior cell; cells of no region are white, the
    boundaries between regions are drawn dark and the cusps of the singular
    curve are marked.  With a scene, the cells where it blocks solutions
    are hatched over the field (as the paper's figure 3 darkens singular
    and obstacle cells alike): densely where it blocks every solution.

    Parameters
    ----------
    roadmap : Roadmap
    world : SceneRoadmap, optional
        The roadmap restricted to a scene.

    Returns
    -------
    matplotlib.figure.Figure
    """
    seg = roadmap.segmentation
    grid = seg.field.grid
    u, v, labels, fixed = _plane(roadmap)
    shape = grid.shape
    region = seg.region.reshape(shape)
    fig, ax = _regions_image(u, v, seg.field.count.reshape(shape), region,
                             seg.field.max_solutions)
    for r in range(1, seg.n_regions + 1):
        i, j = _interior_point(region == r)
        ax.text(u[i], v[j], str(r), ha="center", va="center", fontsize=10,
                bbox={"boxstyle": "circle", "fc": "white", "ec": "k"})
    cusps = np.array([c.joints[list(grid.axis_joints)] for c in known_cusps(roadmap)])
    if cusps.size:
        ax.plot(cusps[:, 0], cusps[:, 1], "r^", ms=8, label="cusp")
    title = f"n-solution field and regions{fixed}"
    if world is not None:
        solutions = seg.patch > 0
        blocked = (solutions & ~world.free).sum(axis=1)
        some = (blocked > 0).reshape(shape)
        every = (blocked == solutions.sum(axis=1)).reshape(shape) & some
        for mask, hatch, name in ((some & ~every, "//", "scene blocks some solutions"),
                                  (every, "xxxx", "scene blocks every solution")):
            if mask.any():
                ax.contourf(u, v, mask.T.astype(float), levels=[0.5, 1.5], colors="none",
                            hatches=[hatch])
                ax.plot([], [], "s", mfc="none", mec="k", label=name)
        title += f"\n{world.n_parts} free parts in the scene"
    if cusps.size or world is not None:
        ax.legend(loc="upper left")
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.set_title(title)
    return fig


def slice_figure(roadmap, fixed, cusps=()):
    """Number of solutions and regions of a roadmap over more than two
    joints, on the plane where the others take given values.

    Each pixel (one per fine step) shows the grid cell ``cells_of`` gives for
    it; region ids are those of the whole roadmap, written at the most
    interior pixel of each of their pieces in the plane.

    Parameters
    ----------
    roadmap : Roadmap
    fixed : mapping of int to float
        Axis joint to its value, for all axes but two.
    cusps : sequence of Cusp
        Cusp points to mark (of that plane).

    Returns
    -------
    matplotlib.figure.Figure
    """
    grid, names = roadmap.grid, roadmap.mechanism.joint_names
    free = [k for k, a in enumerate(grid.axes) if a.joint not in fixed]
    if len(free) != 2 or len(fixed) != grid.ndim - 2:
        raise InvalidInputError(f"a slice fixes all axes but two, got {dict(fixed)} for the "
                                f"axes {[names[a.joint] for a in grid.axes]}")
    axes = [grid.axes[k] for k in free]
    u, v = axes[0].values, axes[1].values
    points = np.empty((u.size * v.size, grid.ndim))
    for k, axis in enumerate(grid.axes):
        points[:, k] = fixed.get(axis.joint, 0.0)
    mesh = np.meshgrid(u, v, indexing="ij")
    points[:, free[0]], points[:, free[1]] = mesh[0].ravel(), mesh[1].ravel()
    cells = grid.cells_of(points)
    if np.any(cells < 0):
        raise InvalidInputError(f"the slice {dict(fixed)} leaves the grid")
    seg = roadmap.segmentation
    region = seg.region[cells].reshape(u.size, v.size)
    fig, ax = _regions_image(u, v, seg.field.count[cells].reshape(u.size, v.size), region,
                             seg.field.max_solutions)
    for r in range(1, seg.n_regions + 1):
        pieces, n = label_pieces(region == r)
        for piece in range(1, n + 1):
            if np.count_nonzero(pieces == piece) >= 16:
                i, j = _interior_point(pieces == piece)
                ax.text(u[i], v[j], str(r), ha="center", va="center", fontsize=9,
                        bbox={"boxstyle": "circle", "fc": "white", "ec": "k"})
    at = dict(fixed)
    cusps = np.array([c.joints[[axes[0].joint, axes[1].joint]] for c in cusps])
    if cusps.size:
        ax.plot(cusps[:, 0], cusps[:, 1], "r^", ms=8, label="cusp")
        ax.legend(loc="upper left")
    ax.set_xlabel(names[axes[0].joint])
    ax.set_ylabel(names[axes[1].joint])
    plane = ", ".join(f"{names[j]} = {value:g}" for j, value in sorted(at.items()))
    ax.set_title(f"slice {plane} of the {grid.ndim}-D roadmap: solutions and regions")
    return fig


def _regions_image(u, v, count, region, max_solutions):
    """A figure of the number of solutions over a plane (white off every
    region), region boundaries drawn dark, with its colour bar."""
    count = count.astype(float)
    count[region == 0] = np.nan
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot()
    image = ax.imshow(count.T, origin="lower", extent=(u[0], u[-1], v[0], v[-1]),
                      cmap="viridis", vmin=0, vmax=max_solutions, interpolation="nearest")
    edges = np.zeros(region.shape, dtype=bool)
    edges[:-1, :] |= region[:-1, :] != region[1:, :]
    edges[:, :-1] |= region[:, :-1] != region[:, 1:]
    ax.contour(u, v, edges.T.astype(float), levels=[0.5], colors="k", linewidths=0.6)
    fig.colorbar(image, ax=ax, label="number of solutions")
    return fig, ax


def _plane(roadmap):
    """Axis values, axis labels and a title suffix naming the fixed joints
    of a roadmap's 2-D grid."""
    grid, names = roadmap.grid, roadmap.mechanism.joint_names
    if grid.ndim != 2:
        raise InvalidInputError(f"figures draw 2-D grids, this one has {grid.ndim} axes")
    labels = [names[a.joint] for a in grid.axes]
    fixed = ", ".join(f"{names[j]} = {value:g}" for j, value in grid.fixed)
    return grid.axes[0].values, grid.axes[1].values, labels, f", {fixed}" if fixed else ""


def _interior_point(mask):
    """The cell of a mask farthest from its complement (city-block distance)."""
    depth = distance_transform_cdt(np.pad(mask, 1), metric="taxicab")[1:-1, 1:-1]
    return np.unravel_index(np.argmax(depth), mask.shape)


def roadmap_figure(roadmap, seed=0):
    """The global workspace roadmap as a graph drawing (paper figure 10).

    Nodes are patches labelled by id and coloured by aspect; edge widths grow
    with the gate widths.

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
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot()
    # One spring layout per aspect group, side by side, as the paper's figure 10.
    layout = {}
    for column, nodes in enumerate(aspect_groups(graph)):
        part = nx.spring_layout(graph.subgraph(nodes), seed=seed, weight=None)
        layout.update({n: xy + np.array([2.6 * column, 0.0]) for n, xy in part.items()})
    colors = ["tab:red" if graph.nodes[n]["aspect"] > 0 else "tab:blue" for n in graph.nodes]
    widths = [0.5 + 3.0 * graph.edges[e]["width"] / max(1e-9, max(
        (graph.edges[f]["width"] for f in graph.edges), default=1.0)) for e in graph.edges]
    nx.draw_networkx(graph, pos=layout, ax=ax, node_color=colors, width=widths,
                     node_size=420, font_size=8, font_color="white")
    fixed = ", ".join(f"{roadmap.mechanism.joint_names[j]} = {value:g}"
                      for j, value in roadmap.grid.fixed)
    ax.set_title(f"global workspace roadmap{', ' + fixed if fixed else ''} "
                 "(red: positive aspect, blue: negative)")
    ax.set_axis_off()
    return fig


def plan_figure(roadmap, plan, sheet_stride=6):
    """A planned path over the field and in the grid's plane and the pose's
    mode coordinate (the 3-RPR: (rho2, rho3, alpha)), as the paper's figures
    11 to 13.

    Parameters
    ----------
    roadmap : Roadmap
    plan : dict
        :meth:`~rpr3_gwr_core.planning.Plan.to_dict` output.
    sheet_stride : int
        Draw every n-th cell of the traversed patches in the 3-D view.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InvalidInputError
        If the grid is not 2-D, or the plan's global path goes through
        patches the roadmap has not (it was planned on another grid).
    """
    seg = roadmap.segmentation
    grid = seg.field.grid
    mechanism = roadmap.mechanism
    u, v, labels, _ = _plane(roadmap)
    paths = plan.get("global_paths") or [[]]
    chosen = paths[max(plan.get("path_index", 0), 0)]
    unknown = set(chosen) - set(seg.patches)
    if unknown:
        raise InvalidInputError(f"the plan's global path goes through patches "
                                f"{sorted(unknown)} that the roadmap has not: it was planned "
                                "on another grid")
    iu, iv = grid.axis_joints
    mode = mechanism.mode_coordinate
    joints = np.array([w["joints"] for w in plan["waypoints"]]).reshape(-1, mechanism.n_joints)
    pose = np.array([w["pose"] for w in plan["waypoints"]]).reshape(-1, mechanism.pose_size)
    fig = Figure(figsize=(13, 6))
    ax = fig.add_subplot(1, 2, 1)
    region = seg.region.reshape(grid.shape).astype(float)
    region[region == 0] = np.nan
    ax.imshow(region.T, origin="lower", extent=(u[0], u[-1], v[0], v[-1]), cmap="Pastel1",
              interpolation="nearest")
    ax.plot(joints[:, iu], joints[:, iv], "k-", lw=1.5)
    ax.plot(joints[:1, iu], joints[:1, iv], "go", ms=8, label="start")
    ax.plot(joints[-1:, iu], joints[-1:, iv], "r*", ms=12, label="goal")
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.set_title("global path " + " → ".join(str(p) for p in chosen))
    ax.legend(loc="upper left")
    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    for pid in sorted(set(chosen)):
        patch = seg.patches[pid]
        cells, slots = patch.cells[::sheet_stride], patch.slots[::sheet_stride]
        coords = grid.coordinates()[cells]
        ax3.scatter(coords[:, 0], coords[:, 1], seg.field.poses[cells, slots, mode], s=1,
                    alpha=0.25, label=str(pid))
    ax3.plot(joints[:, iu], joints[:, iv], pose[:, mode], "k-", lw=2)
    ax3.set_xlabel(labels[0])
    ax3.set_ylabel(labels[1])
    ax3.set_zlabel(mechanism.pose_names[mode])
    ax3.legend(loc="upper left", markerscale=8, title="patch")
    return fig
