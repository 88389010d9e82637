"""The paper's setting: the 3-RPR of section 4 and its grids of section 5.

Grids at fixed rho1 over (rho2, rho3), the reduced configuration space the
paper plans in, are built by :func:`rho1_slice`; :data:`PAPER_GRID` is the
paper's 401 x 401 grid at rho1 = 17.

The full 3-DOF space, the paper's future work, is :data:`FULL_BASE_GRID`
refined :data:`FULL_REFINEMENT` times near the singular locus
(:func:`~rpr3_gwr_core.workspace.adaptive.refine`): all three legs in
[0, 50] except rho1 >= 1.  At rho1 = 0 leg 1 vanishes, B1 sits on A1 and
the direct kinematics degenerates (no solution is found); below 1 the slices
hold only a sliver of two-solution cells.  Base step 1, fine step 0.25: a
slice at rho1 = 17 refined so has the 7 regions, 24 patches and 36 gates of
the paper's 0.125 grid, region areas within 0.6 of it (refined 8 times:
within 0.1, and the same gates), from a sixth of its cells.
"""

import math
import numbers

from .exceptions import InvalidInputError
from .mechanisms.rpr3 import PAPER_GEOMETRY
from .workspace.grid import Grid

__all__ = ["PAPER_GEOMETRY", "PAPER_GRID", "rho1_slice", "FULL_BASE_GRID", "FULL_REFINEMENT"]


def rho1_slice(rho1=17.0, rho2_range=(0.0, 50.0), rho3_range=(0.0, 50.0), step=0.125):
    """A grid over (rho2, rho3) at fixed rho1.

    Parameters
    ----------
    rho1 : float
        Fixed first leg, positive [length unit].
    rho2_range, rho3_range : (float, float)
        Inclusive ``(min, max)`` of each axis, ``0 <= min <= max`` [length unit].
    step : float
        Cell spacing on both axes [length unit].

    Returns
    -------
    Grid

    Examples
    --------
    >>> rho1_slice(13.0, (1.0, 9.0), (2.0, 8.0), 0.25).shape
    (33, 25)
    """
    if isinstance(rho1, bool) or not isinstance(rho1, numbers.Real) \
            or not math.isfinite(rho1) or rho1 <= 0:
        raise InvalidInputError(f"rho1 must be a positive number, got {rho1!r}")
    for name, bounds in (("rho2_range", rho2_range), ("rho3_range", rho3_range)):
        bounds = tuple(bounds)
        if len(bounds) != 2:
            raise InvalidInputError(f"{name} is a (min, max) pair, got {bounds!r}")
        if isinstance(bounds[0], numbers.Real) and bounds[0] < 0:
            raise InvalidInputError(f"{name} must satisfy 0 <= min, got {bounds}")
    return Grid.regular({1: tuple(rho2_range), 2: tuple(rho3_range)}, step, fixed={0: rho1})


PAPER_GRID = rho1_slice()

FULL_BASE_GRID = Grid.regular({0: (1.0, 50.0), 1: (0.0, 50.0), 2: (0.0, 50.0)}, 1.0)
FULL_REFINEMENT = 4
