"""Figures of the n-solution field and of the roadmap (paper figures 6 and 10).

Functions return :class:`matplotlib.figure.Figure` objects built without
pyplot, so they work headless and write nothing: the caller saves them.
"""

import networkx as nx
import numpy as np
from matplotlib.figure import Figure
from scipy.ndimage import distance_transform_cdt

__all__ = ["field_figure", "roadmap_figure"]


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
    layout = nx.spring_layout(graph, seed=seed, weight=None)
    colors = ["tab:red" if graph.nodes[n]["aspect"] > 0 else "tab:blue" for n in graph.nodes]
    widths = [0.5 + 3.0 * graph.edges[e]["width"] / max(1e-9, max(
        (graph.edges[f]["width"] for f in graph.edges), default=1.0)) for e in graph.edges]
    nx.draw_networkx(graph, pos=layout, ax=ax, node_color=colors, width=widths,
                     node_size=420, font_size=8, font_color="white")
    ax.set_title(rf"global workspace roadmap, $\rho_1$ = {roadmap.grid.rho1:g} "
                 "(red: det Jx > 0, blue: det Jx < 0)")
    ax.set_axis_off()
    return fig
