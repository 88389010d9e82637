"""The rotary disk search (paper section 2.4, Algorithm 1), in d dimensions.

A rotary disk stands for one cell of a d-dimensional grid (here: one
solution sheet over one cell); its 2d vertices are the cell's faces, ordered
``S = (-d, ..., -1, +1, ..., +d)``.  Faces only connect to faces (never
through a vertex), which is the minimal connectivity the paper requires.  The
search is a depth-first search whose order of edges at each disk is the
rotation around the disk: entering a disk through face j, it tries the faces
after j in rotary order until it meets a visited face, then returns to the
branch point of the previous disk.  The implementation keeps explicit stacks
(no recursion), so patches of any size are searched.
"""

import numpy as np

from ..exceptions import InvalidInputError

__all__ = ["rotary_order", "rotary_disk_search", "passage_from_links"]


def rotary_order(dimension):
    """Face indices of a rotary disk in rotary order.

    Parameters
    ----------
    dimension : int
        Number of grid axes d.

    Returns
    -------
    tuple of int
        ``(-d, ..., -1, 1, ..., d)``; face ``+i`` is the upper face along
        axis ``i - 1`` and ``-i`` the lower one.
    """
    if dimension < 1:
        raise InvalidInputError(f"dimension must be at least 1, got {dimension}")
    return tuple(range(-dimension, 0)) + tuple(range(1, dimension + 1))


def rotary_disk_search(start, passage, dimension):
    """Search one connected workspace patch with the rotary disk search.

    Parameters
    ----------
    start : int
        Disk to start from (a disk off the singular locus).
    passage : mapping of int to ndarray of int
        ``passage[face][disk]`` is the disk reached through ``face`` of
        ``disk`` when the two belong to the same patch (same region, the
        solution continues), else -1.  Faces as in :func:`rotary_order`.
    dimension : int
        Number of grid axes d.

    Returns
    -------
    visited : list of int
        The disks of the patch, W in Algorithm 1, in order of first visit.
    boundary : list of int
        The disks having at least one impassable face, B in Algorithm 1.
    """
    faces = rotary_order(dimension)
    n_faces = len(faces)
    position = {face: k for k, face in enumerate(faces)}
    seen_faces = {start: 0}
    visited = [start]
    boundary = set()
    # Each stack entry is a disk and the rotary position of its next face.
    disks = [start]
    cursor = [0]
    while disks:
        disk = disks[-1]
        k = cursor[-1]
        face = faces[k]
        bit = 1 << k
        if seen_faces[disk] & bit:
            # Back at a visited vertex: return to the previous branch point.
            disks.pop()
            cursor.pop()
            continue
        seen_faces[disk] |= bit
        cursor[-1] = (k + 1) % n_faces
        neighbour = int(passage[face][disk])
        if neighbour < 0:
            boundary.add(disk)
            continue
        entry = position[-face]
        if neighbour in seen_faces:
            continue
        seen_faces[neighbour] = 1 << entry
        visited.append(neighbour)
        disks.append(neighbour)
        cursor.append((entry + 1) % n_faces)
    return visited, sorted(boundary)


def passage_from_links(n_disks, links):
    """Build the ``passage`` table of :func:`rotary_disk_search` from links.

    Parameters
    ----------
    n_disks : int
    links : sequence of (ndarray, ndarray)
        Per axis, the ``(lower, upper)`` disks joined through that axis.

    Returns
    -------
    dict of int to ndarray of int
    """
    passage = {}
    for axis, (lower, upper) in enumerate(links, start=1):
        up = np.full(n_disks, -1, dtype=np.int64)
        down = np.full(n_disks, -1, dtype=np.int64)
        up[lower] = upper
        down[upper] = lower
        passage[axis] = up
        passage[-axis] = down
    return passage
