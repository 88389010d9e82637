"""The roadmap restricted to a scene, without rebuilding the field.

The field, the patches and the gates do not depend on the scene.  A
:class:`WorldIndex` keeps, once per roadmap and body model, what every scene
reads: each patch solution's bounding box of its bodies and whether its own
bodies interfere.  :meth:`WorldIndex.apply` (or :func:`scene_roadmap`) then
marks the patch solutions a scene blocks (the compiled kernel runs only on
those whose box meets an obstacle, or on all when passive ranges are set),
and splits what remains of each patch into its *parts*: the sets of free
solutions joined by the roadmap's continuation links inside the patch (along
a periodic axis across its seam too).  Parts are joined where a gate's link
has both its solutions free.  Two free solutions are connectible in the scene
exactly when their parts are in one connected component of that graph, so a
"no path" stays exact on the grid.
"""

import copy
import dataclasses
from dataclasses import dataclass
import functools

import networkx as nx
import numba
import numpy as np

from ..exceptions import InvalidInputError
from ..workspace.components import find_root, join
from ..workspace.thin_regions import thin_patches
from .bodies import mechanism_bodies
from .collision import FREE, check_bodies, compile_scene
from .scene import EMPTY_SCENE

__all__ = ["WorldIndex", "SceneRoadmap", "SceneFeasibility", "scene_roadmap"]

# Configurations per batch of the kernel: bounds the temporaries of the
# bodies' numpy arrays.
_CHUNK = 32768
# Largest size of a roadmap's bodies kept by its index [bytes].
_KEEP_BYTES = 256 * 2**20


@dataclass(frozen=True)
class SceneFeasibility:
    """Whether a scene leaves two located configurations connectible.

    Attributes
    ----------
    feasible : bool
    reason : str
        ``"same_part"``, ``"connected"``, ``"in_collision"`` (the start's or
        goal's cell solution is blocked), ``"blocked"`` (the roadmap joins
        them, the scene does not), ``"other_aspect"``, ``"unreachable"`` or
        ``"undecided"`` (as
        :class:`~rpr3_gwr_core.planning.global_planning.Feasibility`).
    start_part, goal_part : int
        Their parts, -1 for a blocked one.
    """

    feasible: bool
    reason: str
    start_part: int
    goal_part: int


class WorldIndex:
    """What every scene on one roadmap reads, computed once.

    Parameters
    ----------
    roadmap : Roadmap
    model : BodyModel, optional
        Widths and layers of the mechanism's bodies.

    Attributes
    ----------
    roadmap : Roadmap
    model : BodyModel or None
    disks : ndarray of int64, shape (n,)
        The patch solutions, as ``cell * max_solutions + slot``.
    boxes : ndarray of float32, shape (n, 4)
        Bounding box of each one's bodies, ``(xmin, ymin, xmax, ymax)``,
        rounded outwards [length unit].
    interfering : ndarray of bool, shape (n,)
        Whether its own bodies overlap (bodies sharing a layer).
    """

    def __init__(self, roadmap, model=None):
        self.model = model
        self._read(roadmap)
        mechanism = roadmap.mechanism
        self._width = roadmap.segmentation.field.max_solutions
        self.disks = np.flatnonzero(self._patch > 0)
        self._joints = roadmap.segmentation.field.grid.joints()
        self.boxes = np.empty((self.disks.size, 4), dtype=np.float32)
        self.interfering = np.zeros(self.disks.size, dtype=bool)
        sample = self._bodies(self.disks[:1])
        self.passive_names = sample.passive_names
        empty = compile_scene(EMPTY_SCENE, mechanism, sample)
        # Kept whole when small enough (a 2-D roadmap's): a scene then only
        # runs the kernel; a full roadmap's are recomputed per batch.
        size = self.disks.size * sum(
            a.nbytes for a in (sample.capsules, sample.polygons, sample.passive))
        self._kept = None
        if size <= _KEEP_BYTES:
            self._kept = self._bodies(self.disks)
            self._disk_joints = self._joints[self.disks // self._width]
        rows = np.empty((_CHUNK, 3), dtype=np.int32)
        for start in range(0, self.disks.size, _CHUNK):
            part = slice(start, start + _CHUNK)
            bodies = self._bodies(self.disks[part]) if self._kept is None else _slice(
                self._kept, part)
            self.boxes[part] = _bounding_boxes(bodies)
            if bodies.pairs.size:
                self.interfering[part] = check_bodies(
                    empty, bodies, self._joints[self.disks[part] // self._width],
                    rows)[:, 0] != FREE
        # The roadmap's own answer for pairs of patches.
        self._component = {}
        for label, nodes in enumerate(nx.connected_components(roadmap.graph)):
            for node in nodes:
                self._component[node] = label
        self._aspect = nx.get_node_attributes(roadmap.graph, "aspect")
        self._thin_aspects = {self._aspect[pid] for pid in thin_patches(roadmap)}

    def _read(self, roadmap):
        """Refer to the roadmap's arrays (those of the field and the
        segmentation the index reads, not copies)."""
        self.roadmap = roadmap
        segmentation = roadmap.segmentation
        self._patch = np.ascontiguousarray(segmentation.patch.ravel())
        self._poses = segmentation.field.poses.reshape(-1, roadmap.mechanism.pose_size)
        self._links = segmentation.links

    def on_roadmap(self, roadmap):
        """This index on an equal roadmap, without computing it again.

        What the index computed is shared; the roadmap's own arrays are
        read from ``roadmap`` (for example the same roadmap mapped from
        planning files), so the index keeps no reference to this one's.

        Parameters
        ----------
        roadmap : Roadmap
            Of the same mechanism, grid and patches.

        Returns
        -------
        WorldIndex

        Raises
        ------
        InvalidInputError
            If ``roadmap`` differs from this index's in its mechanism, its
            grid or its patch array.
        """
        if (roadmap.mechanism.to_dict() != self.roadmap.mechanism.to_dict()
                or roadmap.grid != self.roadmap.grid
                or not np.array_equal(roadmap.segmentation.patch.ravel(), self._patch)):
            raise InvalidInputError("a world index moves only to an equal roadmap")
        moved = copy.copy(self)
        moved._read(roadmap)
        return moved

    def _bodies(self, disks):
        return mechanism_bodies(self.roadmap.mechanism, self._poses[disks],
                                self._joints[disks // self._width], self.model)

    def apply(self, scene):
        """The roadmap restricted to a scene.

        Parameters
        ----------
        scene : Scene

        Returns
        -------
        SceneRoadmap

        Raises
        ------
        InvalidInputError
            If the scene's limits name joints or passive angles the
            mechanism lacks.
        """
        blocked = self.blocked(scene, self.interfering.copy())
        free = np.zeros(self._patch.size, dtype=bool)
        free[self.disks[~blocked]] = True
        return SceneRoadmap(self, scene, free)

    def blocked(self, scene, blocked):
        """Which patch solutions a scene blocks, besides those already blocked.

        Parameters
        ----------
        scene : Scene
        blocked : ndarray of bool, shape (n,)
            Per entry of :attr:`disks`; updated in place.

        Returns
        -------
        ndarray of bool, shape (n,)
            ``blocked``.
        """
        arrays = compile_scene(scene, self.roadmap.mechanism, self._bodies(self.disks[:1]))
        if np.isfinite(arrays.stroke_low).any() or np.isfinite(arrays.stroke_high).any():
            outside = ((self._joints < arrays.stroke_low)
                       | (self._joints > arrays.stroke_high)).any(axis=1)
            blocked |= outside[self.disks // self._width]
        if (arrays.passive_span >= 0).any():
            candidates = np.flatnonzero(~blocked)
        else:
            candidates = _near_obstacles(self.boxes, arrays.boxes, blocked)
        if self._kept is not None:
            blocked[candidates] = check_bodies(arrays, self._kept, self._disk_joints,
                                               chosen=candidates)[:, 0] != FREE
            return blocked
        rows = np.empty((_CHUNK, 3), dtype=np.int32)
        for start in range(0, candidates.size, _CHUNK):
            chosen = candidates[start:start + _CHUNK]
            disks = self.disks[chosen]
            blocked[chosen] = check_bodies(arrays, self._bodies(disks),
                                           self._joints[disks // self._width], rows)[:, 0] != FREE
        return blocked

    def roadmap_reason(self, start_patch, goal_patch):
        """The roadmap's own feasibility reason for two patches."""
        if start_patch == goal_patch:
            return "same_patch"
        if self._component[start_patch] == self._component[goal_patch]:
            return "connected"
        if self._aspect[start_patch] != self._aspect[goal_patch]:
            return "other_aspect"
        return "undecided" if self._aspect[start_patch] in self._thin_aspects else "unreachable"


class SceneRoadmap:
    """A roadmap restricted to a scene: free solutions, parts and their graph.

    Attributes
    ----------
    index : WorldIndex
    scene : Scene
    free : ndarray of bool, shape (n_cells, max_solutions)
        Patch solutions the scene leaves free.
    part : ndarray of int32, shape (n_cells, max_solutions)
        Part of each free patch solution, -1 elsewhere.
    part_patch : ndarray of int32, shape (n_parts,)
        The patch each part lies in.
    component : ndarray of int32, shape (n_parts,)
        Connected component of each part in the scene.
    gates : ndarray of int64, shape (n_gates, 3)
        ``(part, part, n_links)``: parts joined across gates, lower first,
        and how many free continuation links join them.
    """

    def __init__(self, index, scene, free):
        self.index = index
        self.scene = scene
        width = index._width
        n = free.size
        part_parent = np.arange(n, dtype=np.int64)
        component_parent = np.arange(n, dtype=np.int64)
        for lower, upper, match in index._links:
            _join_axis(part_parent, component_parent, lower, upper, match, index._patch, free,
                       width)
        part, first = _label(part_parent, free)
        self.free = free.reshape(-1, width)
        self.part = part.reshape(-1, width)
        self.part_patch = index._patch[first].astype(np.int32)
        self.component = np.empty(first.size, dtype=np.int32)
        roots = np.array([find_root(component_parent, d) for d in first.tolist()],
                         dtype=np.int64)
        self.component[:] = np.unique(roots, return_inverse=True)[1]
        pairs = [_gate_pairs(lower, upper, match, index._patch, part, width)
                 for lower, upper, match in index._links]
        pairs = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
        keys, counts = np.unique(pairs[:, 0] * max(1, first.size) + pairs[:, 1],
                                 return_counts=True)
        self.gates = np.stack([keys // max(1, first.size), keys % max(1, first.size), counts],
                              axis=1).astype(np.int64).reshape(-1, 3)

    @functools.cached_property
    def crowded(self):
        """Free patch solutions within twice ``obstacle_clearance`` of an
        obstacle, shape (n_cells, max_solutions), read-only: where a local
        path pays for passing close, as below the singular clearance (all
        False when the scene's clearance is 0)."""
        crowded = np.zeros(self.free.shape, dtype=bool)
        clearance = self.scene.limits.obstacle_clearance
        if clearance > 0:
            wider = dataclasses.replace(self.scene, limits=dataclasses.replace(
                self.scene.limits, obstacle_clearance=2 * clearance))
            disks = self.index.disks
            near = self.index.blocked(wider, ~self.free.ravel()[disks])
            crowded.ravel()[disks[near]] = True
            crowded &= self.free
        crowded.flags.writeable = False
        return crowded

    def __repr__(self):
        patch_solutions = int(self.index.disks.size)
        blocked = patch_solutions - int(np.count_nonzero(self.free))
        return (f"SceneRoadmap({self.n_parts} parts, {len(self.gates)} part gates, "
                f"{blocked} of {patch_solutions} patch solutions blocked; {self.scene!r})")

    @property
    def n_parts(self):
        """Number of parts."""
        return int(self.part_patch.size)

    @functools.cached_property
    def graph(self):
        """The scene's global roadmap: parts as nodes (``patch``, ``aspect``,
        ``n_solutions``), gates as edges (``n_links``), as networkx."""
        graph = nx.Graph()
        sizes = np.bincount(self.part[self.part >= 0], minlength=self.n_parts)
        aspect = self.index._aspect
        for p, (patch, size) in enumerate(zip(self.part_patch.tolist(), sizes.tolist())):
            graph.add_node(p, patch=patch, aspect=aspect[patch], n_solutions=size)
        for a, b, links in self.gates.tolist():
            graph.add_edge(a, b, n_links=links)
        return graph

    def parts_of(self, patch):
        """The parts of a patch, ascending."""
        return np.flatnonzero(self.part_patch == patch)

    def feasibility(self, start, goal):
        """Whether the scene leaves two located configurations connectible.

        Parameters
        ----------
        start, goal : Location
            From :func:`~rpr3_gwr_core.planning.locate.locate` (their
            ``cell``, ``slot`` and ``patch`` are read).

        Returns
        -------
        SceneFeasibility

        Raises
        ------
        InvalidInputError
            If a location's cell and slot are not a solution of the patch it
            names.
        """
        parts = []
        for location in (start, goal):
            cell, slot = int(location.cell), int(location.slot)
            if not (0 <= cell < self.part.shape[0] and 0 <= slot < self.part.shape[1]) or int(
                    self.index._patch[cell * self.part.shape[1] + slot]) != int(location.patch):
                raise InvalidInputError(f"cell {cell}, slot {slot} is not a solution of patch "
                                        f"{location.patch}")
            parts.append(int(self.part[cell, slot]))
        a, b = parts
        if a < 0 or b < 0:
            return SceneFeasibility(False, "in_collision", a, b)
        if a == b:
            return SceneFeasibility(True, "same_part", a, b)
        if self.component[a] == self.component[b]:
            return SceneFeasibility(True, "connected", a, b)
        reason = self.index.roadmap_reason(int(start.patch), int(goal.patch))
        if reason in ("same_patch", "connected"):
            return SceneFeasibility(False, "blocked", a, b)
        return SceneFeasibility(False, reason, a, b)


def scene_roadmap(roadmap, scene, model=None):
    """The roadmap restricted to a scene (:meth:`WorldIndex.apply`).

    Builds the :class:`WorldIndex` first: keep it and call its ``apply`` for
    each new scene.

    Parameters
    ----------
    roadmap : Roadmap
    scene : Scene
    model : BodyModel, optional

    Returns
    -------
    SceneRoadmap
    """
    return WorldIndex(roadmap, model).apply(scene)


def _slice(bodies, part):
    """Bodies of a slice of a batch of shape (n,)."""
    return bodies._replace(capsules=bodies.capsules[part], polygons=bodies.polygons[part],
                           passive=bodies.passive[part])


def _bounding_boxes(bodies):
    """Each configuration's box around all its bodies, float32 rounded out."""
    n = bodies.capsules.shape[0]
    caps = bodies.capsules.reshape(n, -1, 2, 2)
    plates = bodies.polygons.reshape(n, -1, bodies.polygons.shape[-2], 2)
    low = (caps.min(axis=2) - bodies.capsule_radius[:, None]).min(axis=1, initial=np.inf)
    high = (caps.max(axis=2) + bodies.capsule_radius[:, None]).max(axis=1, initial=-np.inf)
    if plates.shape[1]:
        low = np.minimum(low, (plates.min(axis=2) - bodies.polygon_radius[:, None]).min(axis=1))
        high = np.maximum(high, (plates.max(axis=2) + bodies.polygon_radius[:, None]).max(axis=1))
    box = np.concatenate([low, high], axis=1)
    out = box.astype(np.float32)
    # float32 rounds to nearest: step outwards so that the box still holds.
    out[:, :2] = np.nextafter(out[:, :2], np.float32(-np.inf))
    out[:, 2:] = np.nextafter(out[:, 2:], np.float32(np.inf))
    return out


@numba.njit(cache=True, nogil=True)
def _near_obstacles(boxes, obstacles, blocked):
    """Indices of the unblocked configurations whose box meets an obstacle's."""
    out = np.empty(boxes.shape[0], dtype=np.int64)
    used = 0
    for c in range(boxes.shape[0]):
        if blocked[c]:
            continue
        for o in range(obstacles.shape[0]):
            if (boxes[c, 0] <= obstacles[o, 2] and boxes[c, 2] >= obstacles[o, 0]
                    and boxes[c, 1] <= obstacles[o, 3] and boxes[c, 3] >= obstacles[o, 1]):
                out[used] = c
                used += 1
                break
    return out[:used]


@numba.njit(cache=True, nogil=True)
def _join_axis(part_parent, component_parent, lower, upper, match, patch, free, width):
    """Join the free patch solutions one axis's links join: within a patch
    in ``part_parent``, across gates too in ``component_parent``."""
    for k in range(match.shape[0]):
        for i in range(width):
            j = match[k, i]
            if j < 0:
                continue
            a, b = lower[k] * width + i, upper[k] * width + j
            if not (free[a] and free[b]) or patch[a] <= 0 or patch[b] <= 0:
                continue
            join(component_parent, a, b)
            if patch[a] == patch[b]:
                join(part_parent, a, b)


@numba.njit(cache=True, nogil=True)
def _label(parent, free):
    """Part of each disk (-1 where not free), numbered by their first disks,
    and those first disks."""
    label = np.full(parent.size, -1, dtype=np.int32)
    first = np.empty(parent.size, dtype=np.int64)
    n = 0
    for d in range(parent.size):
        if not free[d]:
            continue
        root = find_root(parent, d)
        if label[root] < 0:
            label[root] = n
            first[n] = d
            n += 1
        label[d] = label[root]
    return label, first[:n].copy()


@numba.njit(cache=True, nogil=True)
def _gate_pairs(lower, upper, match, patch, part, width):
    """``(part, part)``, lower first, of every free link across a gate."""
    out = np.empty((0, 2), dtype=np.int64)
    # Counted first, then filled: the gates' links are few.
    for fill in range(2):
        used = 0
        for k in range(match.shape[0]):
            for i in range(width):
                j = match[k, i]
                if j < 0:
                    continue
                a, b = lower[k] * width + i, upper[k] * width + j
                if part[a] < 0 or part[b] < 0 or patch[a] == patch[b]:
                    continue
                if fill:
                    out[used, 0], out[used, 1] = min(part[a], part[b]), max(part[a], part[b])
                used += 1
        if not fill:
            out = np.empty((used, 2), dtype=np.int64)
    return out
