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
``l``: both share that reduction (:class:`~.moving_base.MovingBaseRPR`:
the three-leg solver with base points per joint vector, its margin,
predictor and corrector), and differ only in how ``C_i`` and ``dC_i/dq_i`` follow from the
joints.  The sliders' joints are lengths, not angles: no axis is periodic,
and the stroke range is the box of the mechanism file
(``config/three_prr.yaml``).  A serial singularity (``u_i`` perpendicular to
its slider) is no obstacle to moving in joint space and is not treated as
one.  The pose alone does not fix the slider joints, so
:meth:`ThreePRR.margin` needs the joints.
"""

from dataclasses import dataclass
import math
import numbers

import numpy as np

from ..exceptions import InvalidInputError
from .base import positive_length, register_mechanism
from .moving_base import MovingBaseRPR
from .rpr3 import beta_from_sides

__all__ = ["ThreePRR", "DEFAULT_THREE_PRR"]

# A leg's reach compared with rounding [l**2]: a platform point at exactly
# the distal link's length from the rail computes a negative square by a
# few ulps, and is reached.
_REACH_ROUNDING = 1e-12


@register_mechanism("3-PRR")
@dataclass(frozen=True)
class ThreePRR(MovingBaseRPR):
    """The planar 3-PRR parallel manipulator.

    Joints are the actuated sliders ``(s1, s2, s3)`` [length unit]; poses are
    ``(x, y, alpha)`` [length unit, length unit, rad] as the 3-RPR's (B1
    and the platform's orientation), and ``alpha`` chooses the assembly
    mode of a request.  A pose has up to 8 working modes
    (:meth:`inverse_kinematics`), one slider branch per leg: along its rail
    the slider joint ``C_i`` lies beyond the foot of ``B_i``'s perpendicular
    (``(B_i - C_i) . (cos gamma_i, sin gamma_i) <= 0``, the larger ``s_i``)
    on sign +1, before it on sign -1.  Batches follow
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
    angle_parameters = ("gamma1", "gamma2", "gamma3", "beta")
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

    @property
    def distal(self):
        """The legs' length of the 3-RPR it reduces to: ``l``."""
        return self.l

    @property
    def _actuation(self):
        # Sliders along the unit vectors (cos gamma_i, sin gamma_i).
        return (0.0, 1.0, *(f(g) for g in (self.gamma1, self.gamma2, self.gamma3)
                            for f in (math.cos, math.sin)))

    def _legs_reaching(self, points):
        # |A_i + s e_i - B_i| = l: s = t +- sqrt(t**2 - |B_i - A_i|**2 + l**2)
        # with t = (B_i - A_i) . e_i, the larger root first (sign +1).
        rails = np.array([[math.cos(g), math.sin(g)]
                          for g in (self.gamma1, self.gamma2, self.gamma3)])
        reach = points - self.platform.base
        along = np.sum(reach * rails, axis=-1)
        square = along * along - np.sum(reach * reach, axis=-1) + self.l * self.l
        reached = square >= -_REACH_ROUNDING * self.l * self.l
        half_chord = np.sqrt(np.where(reached, np.maximum(square, 0.0), 0.0))
        sliders = np.stack([along + half_chord, along - half_chord], axis=-1)
        return np.where(reached[..., None], sliders, np.nan)

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
