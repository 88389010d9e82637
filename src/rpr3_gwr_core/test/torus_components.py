"""Connected components of sign-labelled lattices on a torus, for the
independent references' configuration spaces at a fixed first joint.

A lattice point is a configuration with the sign of its det Jx (0: none
there, or out of the box); two face-adjacent points (the lattice wraps
around both axes) of one nonzero sign are joined, as are the point pairs
given.  Written with scipy alone, sharing nothing with the package.
"""

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["torus_components"]


def torus_components(sign, joins=()):
    """Labels of the connected components of nonzero-sign lattice points.

    Parameters
    ----------
    sign : ndarray of int, shape (sheets, n, m)
        Per sheet of the space (a choice of branches), the sign of det Jx at
        each point of the (n, m) torus lattice, 0 where it has no point.
    joins : iterable of (ndarray, ndarray)
        More pairs of points joined, as flat indices into ``sign``.

    Returns
    -------
    ndarray of int, shape of ``sign``
        The component of each point, -1 where the sign is 0.
    """
    index = np.arange(sign.size).reshape(sign.shape)
    rows, cols = [], []
    for axis in (1, 2):
        beside = np.roll(sign, -1, axis=axis)
        same = (sign != 0) & (sign == beside)
        rows.append(index[same])
        cols.append(np.roll(index, -1, axis=axis)[same])
    for a, b in joins:
        rows.append(np.asarray(a).ravel())
        cols.append(np.asarray(b).ravel())
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(rows.size, np.int8), (rows, cols)), shape=(sign.size,) * 2)
    _, label = connected_components(graph, directed=False)
    label = label.reshape(sign.shape)
    label[sign == 0] = -1
    return label
