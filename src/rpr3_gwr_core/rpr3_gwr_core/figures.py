"""Figures of the n-solution field and of the roadmap (paper figures 6 and 10).

Functions return :class:`matplotlib.figure.Figure` objects built without
pyplot, so they work headless and write nothing: the caller saves them.
"""

import networkx as nx
import numpy as np
from matplotlib.figure import Figure
from scipy.ndimage import distance_transform_cdt

from .roadmap import aspect_groups

__all__ = ["field_figure", "roadmap_figure", "plan_figure"]


def field_figure(roadmap):
    """The n-solution field with its region ids, as the paper's figure 6.

    Cells are coloured by their number of solutions; region ids are written
    at each region's most interior cell; cells of no region are white and the
    boundaries between regions are drawn dark.

    Parameters
    ----------
    roadmap : Roadmap

    Returns
    -------
    matplotlib.figure.Figure
    """
    seg = roadmap.segmentation
    grid = seg.field.grid
    shape = grid.shape
    count = seg.field.count.reshape(shape).astype(float)
    region = seg.region.reshape(shape)
    count[region == 0] = np.nan
    extent = (grid.rho2[0], grid.rho2[-1], grid.rho3[0], grid.rho3[-1])
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot()
    image = ax.imshow(count.T, origin="lower", extent=extent, cmap="viridis", vmin=0, vmax=6,
                      interpolation="nearest")
    edges = np.zeros(shape, dtype=bool)
    edges[:-1, :] |= region[:-1, :] != region[1:, :]
    edges[:, :-1] |= region[:, :-1] != region[:, 1:]
    ax.contour(grid.rho2, grid.rho3, edges.T.astype(float), levels=[0.5], colors="k",
               linewidths=0.6)
    for r in range(1, seg.n_regions + 1):
        i, j = _interior_point(region == r)
        ax.text(grid.rho2[i], grid.rho3[j], str(r), ha="center", va="center", fontsize=10,
                bbox={"boxstyle": "circle", "fc": "white", "ec": "k"})
    fig.colorbar(image, ax=ax, label="number of solutions")
    ax.set_xlabel(r"$\rho_2$")
    ax.set_ylabel(r"$\rho_3$")
    ax.set_title(rf"n-solution field and regions, $\rho_1$ = {grid.rho1:g}")
    return fig


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
    ax.set_title(rf"global workspace roadmap, $\rho_1$ = {roadmap.grid.rho1:g} "
                 "(red: det Jx > 0, blue: det Jx < 0)")
    ax.set_axis_off()
    return fig


def plan_figure(roadmap, plan, sheet_stride=6):
    """A planned path over the field and in (rho2, rho3, alpha), as the
    paper's figures 11 to 13.

    Parameters
    ----------
    roadmap : Roadmap
    plan : dict
        :meth:`~rpr3_gwr_core.planner.Plan.to_dict` output.
    sheet_stride : int
        Draw every n-th cell of the traversed patches in the 3-D view.

    Returns
    -------
    matplotlib.figure.Figure
    """
    seg = roadmap.segmentation
    grid = seg.field.grid
    rho = np.array([w["rho"] for w in plan["waypoints"]]).reshape(-1, 3)
    pose = np.array([w["pose"] for w in plan["waypoints"]]).reshape(-1, 3)
    fig = Figure(figsize=(13, 6))
    ax = fig.add_subplot(1, 2, 1)
    region = seg.region.reshape(grid.shape).astype(float)
    region[region == 0] = np.nan
    extent = (grid.rho2[0], grid.rho2[-1], grid.rho3[0], grid.rho3[-1])
    ax.imshow(region.T, origin="lower", extent=extent, cmap="Pastel1", interpolation="nearest")
    ax.plot(rho[:, 1], rho[:, 2], "k-", lw=1.5)
    ax.plot(rho[:1, 1], rho[:1, 2], "go", ms=8, label="start")
    ax.plot(rho[-1:, 1], rho[-1:, 2], "r*", ms=12, label="goal")
    ax.set_xlabel(r"$\rho_2$")
    ax.set_ylabel(r"$\rho_3$")
    paths = plan.get("global_paths") or [[]]
    chosen = paths[max(plan.get("path_index", 0), 0)]
    ax.set_title("global path " + " → ".join(str(p) for p in chosen))
    ax.legend(loc="upper left")
    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    for pid in sorted(set(chosen)):
        patch = seg.patches[pid]
        cells, slots = patch.cells[::sheet_stride], patch.slots[::sheet_stride]
        r = grid.rho()[cells] if cells.size else np.zeros((0, 3))
        ax3.scatter(r[:, 1], r[:, 2], seg.field.poses[cells, slots, 2], s=1, alpha=0.25,
                    label=str(pid))
    ax3.plot(rho[:, 1], rho[:, 2], pose[:, 2], "k-", lw=2)
    ax3.set_xlabel(r"$\rho_2$")
    ax3.set_ylabel(r"$\rho_3$")
    ax3.set_zlabel(r"$\alpha$ [rad]")
    ax3.legend(loc="upper left", markerscale=8, title="patch")
    return fig
