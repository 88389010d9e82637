"""The planar 3-PRR as a :class:`Mechanism`.

Conventions: base points ``A1..A3``; the actuated sliders ``(s1, s2, s3)``
[length unit] move the slider joints along fixed directions ``gamma_i``
[rad]: ``C_i = A_i + s_i (cos gamma_i, sin gamma_i)``; the distal links of
length ``l`` join them to the platform points ``B_i``, placed as the
3-RPR's: ``B1 = (x, y)``, ``B2 = B1 + d1 (cos alpha, sin alpha)``,
``B3 = B1 + d3 (cos(alpha + beta), sin(alpha + beta))``.  The constraint
equations are ``F_i = |B_i - C_i|**2 - l**2 = 0``; with ``u_i = B_i - C_i``

    Jx / 2 = rows (u_i, (B_i - B1) x u_i),    -Jq / 2 = diag(u_i . (cos gamma_i, sin gamma_i)).

As the 3-RRR (:mod:`.rrr3`), with the sliders fixed the 3-PRR is a 3-RPR
whose base points are the slider joints and whose legs all have length
``l``: both share that reduction (``rrr3._MovingBaseRPR``: the 3-RPR's
batch solver with base points per joint vector, its margin, predictor and
corrector), and differ only in how ``C_i`` and ``dC_i/dq_i`` follow from the
joints.  The sliders' joints are lengths, not angles: no axis is periodic,
and the stroke range is the box of the mechanism file
(``config/three_prr.yaml``).  A serial singularity (``u_i`` perpendicular to
its slider) is no obstacle to moving in joint space and is not treated as
one.  The pose alone does not fix the slider joints, so
:meth:`ThreePRR.margin` needs the joints.
"""

from dataclasses import dataclass
import functools
import math
import numbers

import numba
import numpy as np
from numba.extending import register_jitable

from ..exceptions import InvalidInputError
from .base import STEP_KERNEL_SIGNATURE, positive_length, register_mechanism
from .rpr3 import _adjugate_product, _corrected, _row_terms, beta_from_sides
from .rrr3 import _MovingBaseRPR

__all__ = ["ThreePRR", "DEFAULT_THREE_PRR"]


@register_jitable
def _slider_parameters(parameters, s1, s2, s3):
    """The 3-RPR parameters whose base points are the slider joints of ``(s1, s2, s3)``."""
    a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta, g1, g2, g3, _ = parameters
    return (a1x + s1 * np.cos(g1), a1y + s1 * np.sin(g1), a2x + s2 * np.cos(g2),
            a2y + s2 * np.sin(g2), a3x + s3 * np.cos(g3), a3y + s3 * np.sin(g3), d1, d3, beta)


@register_jitable
def _slider_rates(rows, parameters):
    """``u_i . (cos gamma_i, sin gamma_i)``, the diagonal of ``-Jq / 2``."""
    u1x, u1y, u2x, u2y, _, u3x, u3y, _ = rows
    g1, g2, g3 = parameters[9], parameters[10], parameters[11]
    return (np.cos(g1) * u1x + np.sin(g1) * u1y, np.cos(g2) * u2x + np.sin(g2) * u2y,
            np.cos(g3) * u3x + np.sin(g3) * u3y)


@numba.njit(cache=True)
def _compiled_step(parameters, scale, x, y, alpha, a1, a2, a3, b1, b2, b3):
    """One predictor-corrector step from joints ``(a1, a2, a3)`` to
    ``(b1, b2, b3)``: ``(converged, x, y, alpha, margin)``."""
    leg = parameters[12]
    rows = _row_terms(x, y, alpha, _slider_parameters(parameters, a1, a2, a3))
    v1, v2, v3 = _slider_rates(rows, parameters)
    q1, q2, q3 = b1 - a1, b2 - a2, b3 - a3
    (dx, dy, da), det = _adjugate_product(rows, v1 * q1, v2 * q2, v3 * q3)
    if det == 0.0:
        return False, x, y, alpha, 0.0
    px, py, palpha = x + dx / det, y + dy / det, alpha + da / det
    # As the 3-RRR's: the corrector's move is measured against the
    # predictor's or the slider joints' move, whichever is longer, so that a
    # serial singularity (a leg perpendicular to its slider) is crossed.
    predicted = max(math.sqrt((dx / det) ** 2 + (dy / det) ** 2 + (da / det * scale) ** 2),
                    max(abs(q1), abs(q2), abs(q3)))
    return _corrected(_slider_parameters(parameters, b1, b2, b3), (leg, leg, leg), scale, px,
                      py, palpha, predicted)


@numba.njit(STEP_KERNEL_SIGNATURE, cache=True)
def _step_kernel(parameters, pose, joints_from, joints_to):
    """:func:`_compiled_step` as :data:`~.base.STEP_KERNEL_SIGNATURE` takes
    it; ``parameters`` are :attr:`ThreePRR.parameters`, then the scale."""
    p = parameters
    ok, x, y, alpha, margin = _compiled_step(
        (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11], p[12]),
        p[13], pose[0], pose[1], pose[2], joints_from[0], joints_from[1], joints_from[2],
        joints_to[0], joints_to[1], joints_to[2])
    if not ok:
        return np.nan
    pose[0], pose[1], pose[2] = x, y, alpha
    return margin


@register_mechanism("3-PRR")
@dataclass(frozen=True)
class ThreePRR(_MovingBaseRPR):
    """The planar 3-PRR parallel manipulator.

    Joints are the actuated sliders ``(s1, s2, s3)`` [length unit]; poses are
    ``(x, y, alpha)`` [length unit, length unit, rad] as the 3-RPR's, and
    ``alpha`` chooses the assembly mode of a request.  Batches follow
    :class:`~rpr3_gwr_core.mechanisms.base.Mechanism`: joints and poses
    ``(..., 3)``; :meth:`solve` takes joints ``(n, 3)`` and gives counts
    ``(n,)`` (uint8) and poses ``(n, 6, 3)`` sorted by alpha in (-pi, pi],
    NaN beyond the count.

    The default geometry (:data:`DEFAULT_THREE_PRR`): the paper's base points
    and platform (as the 3-RRR's), sliders along ``gamma = (0, pi/2, pi/4)``
    (leg 1 along the x axis, leg 2 straight up from A2, leg 3 diagonally
    from A3), distal links ``l = 15`` and strokes ``[0, 30]`` on every slider
    (``config/three_prr.yaml``).  Its slice ``s1 = 5`` (121 x 121 over
    ``s2, s3`` in ``[0, 30]``, step 0.25) is assembled everywhere, with 2, 4
    or 6 solutions, and segments (measured) into 12 regions, 40 patches and
    51 gates.  It has a non-singular assembly-mode change: the joints
    ``(5, 26.5, 10)`` have, among their four solutions, ``alpha = 0.4778``
    at ``(-8.378, 6.784)`` and ``alpha = 0.7657`` at ``(17.317, 8.561)``,
    both of margin +0.541, in two patches of region 3 that the roadmap joins
    through region 1 (patches 34, 14, 33 or 34, 15, 33), and the planner
    plans between them.  The geometry was chosen among ``l`` in 12, 15, 18
    and ``s1`` in 5, 10, 15 (all but two of those slices have such a change)
    for its many regions and the margin of its example.

    Attributes
    ----------
    a1, a2, a3 : tuple of float, shape (2,)
        Base points A1..A3, where each slider is at 0 [length unit].
    gamma1, gamma2, gamma3 : float
        Slider directions [rad]: ``C_i = A_i + s_i (cos gamma_i, sin gamma_i)``.
    l : float
        Distal links C_i B_i [length unit].
    d1 : float
        Platform side B1B2 [length unit].
    d3 : float
        Platform side B1B3 [length unit].
    beta : float
        Angle at B1 from B1B2 to B1B3 [rad].

    Raises
    ------
    InvalidInputError
        If a base point, direction or platform value is not finite (or the
        platform is flat), or ``l`` is not a finite positive number.
    """

    a1: tuple = (0.0, 0.0)
    a2: tuple = (15.91, 0.0)
    a3: tuple = (0.0, 10.0)
    gamma1: float = 0.0
    gamma2: float = math.pi / 2
    gamma3: float = math.pi / 4
    l: float = 15.0  # noqa: E741 - the distal length, named as in the literature
    d1: float = 17.04
    d3: float = 20.84
    beta: float = beta_from_sides(17.04, 16.54, 20.84)

    joint_names = ("s1", "s2", "s3")
    _moving_points = ("slider joints C_i (the sliders, not the pose, place them on their "
                      "lines)")

    def __post_init__(self):
        self._check_platform()
        for name in ("gamma1", "gamma2", "gamma3"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Real) \
                    or not math.isfinite(value):
                raise InvalidInputError(f"{name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        object.__setattr__(self, "l", positive_length(self.l, "l"))

    @functools.cached_property
    def parameters(self):
        """``(a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta, gamma1, gamma2, gamma3,
        l)``: the geometry as the constraint equations (and their compiled
        form) take it."""
        return (*self.a1, *self.a2, *self.a3, self.d1, self.d3, self.beta, self.gamma1,
                self.gamma2, self.gamma3, self.l)

    @property
    def distal(self):
        """The legs' length of the 3-RPR it reduces to: ``l``."""
        return self.l

    _base_parameters = staticmethod(_slider_parameters)
    _compiled_step = staticmethod(_compiled_step)
    _step_kernel = staticmethod(_step_kernel)

    def _directions(self, base):
        # Each slider moves its joint along its own direction.
        return np.broadcast_to(self._slider_directions.reshape((6,) + (1,) * np.ndim(base[0])),
                               (6,) + np.shape(base[0]))

    @functools.cached_property
    def _slider_directions(self):
        return np.array([f(g) for g in (self.gamma1, self.gamma2, self.gamma3)
                         for f in (math.cos, math.sin)])

    def _change(self, joints_from, joints_to):
        return joints_to - joints_from

    def slider_joints(self, joints):
        """Slider joints ``C_i = A_i + s_i (cos gamma_i, sin gamma_i)`` of
        joints ``(..., 3)``.

        Returns
        -------
        ndarray, shape (..., 3, 2)
            [length unit].
        """
        return self.base_points(joints)


DEFAULT_THREE_PRR = ThreePRR()
