"""Local planning inside patches and stitching along a global path
(paper section 3.3).

Every cell of a patch costs ``1 + clearance_weight / d``, where ``d`` is its
distance in cells to the nearest cell outside the patch (singular edge, gate,
other region or grid edge alike, as in the paper; Euclidean on uniform grids,
along faces on adaptive ones), so paths keep clear of every boundary until
they must cross the planned gate; cells whose solution is nearly singular
cost a hundred times more on top.  Moving between face-adjacent cells costs
their distance times the mean cost of the two.

Rather than planning patch by patch to a chosen gate cell, the patches of a
global path are stacked as layers of one directed graph: edges inside a layer
are the patch's own continuation links, and the only edges between layers are
the faces of the planned gate from layer k to layer k + 1.  One shortest-path
search (Dijkstra, i.e. A* with a zero heuristic, in ``scipy.sparse.csgraph``)
from the start cell to the goal cell of the last layer then gives the best
stitched path: it crosses exactly the gates of the global path, in order, and
never a singular boundary or another gate, because no other edge exists.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sparse
from scipy.sparse.csgraph import dijkstra

from ..exceptions import InfeasiblePathError, InvalidInputError

__all__ = ["LocalPlanner", "LocalPath", "DEFAULT_CLEARANCE_WEIGHT"]

DEFAULT_CLEARANCE_WEIGHT = 10.0
_LOW_MARGIN_FACTOR = 100.0
_UNRESOLVED_DEPTH = 0.5


@dataclass(frozen=True)
class LocalPath:
    """A stitched cell path.

    Attributes
    ----------
    cells : ndarray of int, shape (n,)
        Flat cell indices from the start cell to the goal cell.
    patches : ndarray of int, shape (n,)
        The patch of each cell.
    slots : ndarray of int, shape (n,)
        The solution slot of each cell in its patch.
    cost : float
        Weighted length [length unit].
    """

    cells: np.ndarray
    patches: np.ndarray
    slots: np.ndarray
    cost: float


@dataclass(frozen=True)
class _Profile:
    cells: np.ndarray       # sorted flat cells of the patch
    slots: np.ndarray       # solution slot of each
    cost: np.ndarray        # clearance cost of each
    lower: np.ndarray       # local indices of linked face pairs
    upper: np.ndarray
    weight: np.ndarray

    def local(self, cells):
        return np.searchsorted(self.cells, cells)


class LocalPlanner:
    """Cost-weighted planning on the profiles of a roadmap's patches (cells of
    any dimension).

    Parameters
    ----------
    roadmap : Roadmap
    clearance_weight : float
        ``w`` of the cell cost ``1 + w / d``; 0 gives shortest paths.
    low_margin : float
        Cells whose solution's normalised |det Jx| is below this cost
        ``_LOW_MARGIN_FACTOR`` times more.
    """

    def __init__(self, roadmap, clearance_weight=DEFAULT_CLEARANCE_WEIGHT, low_margin=0.0):
        if not np.isfinite(clearance_weight) or clearance_weight < 0:
            raise InvalidInputError("clearance_weight must be finite and non-negative")
        self.segmentation = roadmap.segmentation
        self.clearance_weight = float(clearance_weight)
        self.low_margin = float(low_margin)
        self._profiles = {}
        self._links, self._face_keys, self._face_lengths = self._links_by_patch()

    def _links_by_patch(self):
        """Per patch, the (lower, upper) cells of its continuation links and
        their lengths; and the lengths of the gates' faces, by face key
        ``lower * n_cells + upper``."""
        seg = self.segmentation
        n_cells = seg.field.grid.size
        found = {}
        face_keys, face_lengths = [np.zeros(0, np.int64)], [np.zeros(0)]
        for (lower, upper, match), lengths in zip(seg.links, seg.field.grid.pair_lengths()):
            rows, slots = np.nonzero(match >= 0)
            a = seg.patch[lower[rows], slots]
            b = seg.patch[upper[rows], match[rows, slots].astype(np.int64)]
            gate = (a != b) & (a > 0) & (b > 0)
            face_keys.append(lower[rows][gate] * n_cells + upper[rows][gate])
            face_lengths.append(lengths[rows][gate])
            keep = (a == b) & (a > 0)
            pids, lo, up, length = a[keep], lower[rows][keep], upper[rows][keep], \
                lengths[rows][keep]
            order = np.argsort(pids, kind="stable")
            pids, lo, up, length = pids[order], lo[order], up[order], length[order]
            bounds = np.flatnonzero(np.diff(pids)) + 1
            for chunk in zip(np.split(pids, bounds), np.split(lo, bounds), np.split(up, bounds),
                             np.split(length, bounds)):
                if chunk[0].size:
                    found.setdefault(int(chunk[0][0]), []).append(chunk[1:])
        links = {pid: tuple(np.concatenate([link[k] for link in v]) for k in range(3))
                 for pid, v in found.items()}
        face_keys, face_lengths = np.concatenate(face_keys), np.concatenate(face_lengths)
        order = np.argsort(face_keys)
        return links, face_keys[order], face_lengths[order]

    def _face_length(self, cells_a, cells_b):
        """Length of gate faces given by their two cells [joint unit]."""
        n_cells = self.segmentation.field.grid.size
        keys = np.minimum(cells_a, cells_b) * n_cells + np.maximum(cells_a, cells_b)
        return self._face_lengths[np.searchsorted(self._face_keys, keys)]

    def profile(self, pid):
        """The patch's cells, clearance costs and weighted links (cached)."""
        if pid not in self._profiles:
            self._profiles[pid] = self._build_profile(pid)
        return self._profiles[pid]

    def clearance(self, pid):
        """Distance of each cell of a patch to its nearest outside cell [cells].

        Cells the patch took from unresolved sets (region 0, see
        :mod:`~rpr3_gwr_core.segmentation`) lie on the singular locus: they
        count as outside for the others, and as half a cell deep themselves.
        """
        seg = self.segmentation
        patch = seg.patches[pid]
        own = seg.region[patch.cells] == patch.region
        depth = np.full(patch.cells.size, _UNRESOLVED_DEPTH)
        depth[own] = seg.field.grid.depth(patch.cells[own])
        return depth

    def _build_profile(self, pid):
        patch = self.segmentation.patches[pid]
        cost = 1.0 + self.clearance_weight / self.clearance(pid)
        # Cells whose solution is nearly singular (next to a cusp, say) cost
        # far more, so a path crosses them only where nothing else leads on.
        margin = np.abs(self.segmentation.field.margin[patch.cells, patch.slots])
        cost = np.where(margin < self.low_margin, cost * _LOW_MARGIN_FACTOR, cost)
        lower, upper, length = self._links.get(pid, (np.zeros(0, int), np.zeros(0, int),
                                                     np.zeros(0)))
        lower, upper = np.searchsorted(patch.cells, lower), np.searchsorted(patch.cells, upper)
        weight = 0.5 * length * (cost[lower] + cost[upper])
        return _Profile(cells=patch.cells, slots=patch.slots, cost=cost, lower=lower,
                        upper=upper, weight=weight)

    def plan(self, patches, start_cell, goal_cell, blocked=()):
        """Best cell path from a start cell to a goal cell through given patches.

        Parameters
        ----------
        patches : sequence of int
            A global path: patch ids, consecutive ones joined by a gate.
        start_cell, goal_cell : int
            Flat cells of the first and the last patch.
        blocked : collection of (int, int)
            Cell pairs not to move between (either way), such as a step the
            validator refused.

        Returns
        -------
        LocalPath

        Raises
        ------
        InvalidInputError
            If the cells are not in the end patches or two consecutive patches
            share no gate.
        InfeasiblePathError
            If no path exists (a patch's profile is cut between its gates).
        """
        seg = self.segmentation
        profiles = [self.profile(pid) for pid in patches]
        for cell, profile, which in ((start_cell, profiles[0], "start"),
                                     (goal_cell, profiles[-1], "goal")):
            k = profile.local(cell)
            if k >= profile.cells.size or profile.cells[k] != cell:
                raise InvalidInputError(f"{which} cell {cell} is not in its patch")
        offsets = np.cumsum([0] + [p.cells.size for p in profiles])
        n_cells = seg.field.grid.size
        refused = np.array([min(a, b) * n_cells + max(a, b) for a, b in blocked], dtype=np.int64)
        rows, cols, weights = [], [], []
        for k, profile in enumerate(profiles):
            lower, upper, weight = profile.lower, profile.upper, profile.weight
            if refused.size:
                a, b = profile.cells[lower], profile.cells[upper]
                keep = ~np.isin(np.minimum(a, b) * n_cells + np.maximum(a, b), refused)
                lower, upper, weight = lower[keep], upper[keep], weight[keep]
            rows += [lower + offsets[k], upper + offsets[k]]
            cols += [upper + offsets[k], lower + offsets[k]]
            weights += [weight, weight]
        for k, (a, b) in enumerate(zip(patches, patches[1:])):
            gate = seg.gates.get((min(a, b), max(a, b)))
            if gate is None:
                raise InvalidInputError(f"patches {a} and {b} share no gate")
            cells_a, cells_b = (gate.faces[:, 0], gate.faces[:, 1]) if a < b else (
                gate.faces[:, 1], gate.faces[:, 0])
            la, lb = profiles[k].local(cells_a), profiles[k + 1].local(cells_b)
            rows.append(la + offsets[k])
            cols.append(lb + offsets[k + 1])
            weights.append(0.5 * self._face_length(cells_a, cells_b)
                           * (profiles[k].cost[la] + profiles[k + 1].cost[lb]))
        n = int(offsets[-1])
        graph = sparse.csr_matrix((np.concatenate(weights),
                                   (np.concatenate(rows), np.concatenate(cols))),
                                  shape=(n, n))
        source = int(profiles[0].local(start_cell))
        target = int(offsets[-2] + profiles[-1].local(goal_cell))
        distance, predecessor = dijkstra(graph, directed=True, indices=source,
                                         return_predecessors=True)
        if not np.isfinite(distance[target]):
            raise InfeasiblePathError(f"no local path through patches {list(patches)}")
        nodes = [target]
        while nodes[-1] != source:
            nodes.append(int(predecessor[nodes[-1]]))
        nodes = np.array(nodes[::-1])
        layer = np.searchsorted(offsets, nodes, side="right") - 1
        cells = np.empty(nodes.size, dtype=np.int64)
        slots = np.empty(nodes.size, dtype=np.int64)
        for k, profile in enumerate(profiles):
            here = layer == k
            cells[here] = profile.cells[nodes[here] - offsets[k]]
            slots[here] = profile.slots[nodes[here] - offsets[k]]
        return LocalPath(cells=cells, patches=np.asarray(patches)[layer], slots=slots,
                         cost=float(distance[target]))
