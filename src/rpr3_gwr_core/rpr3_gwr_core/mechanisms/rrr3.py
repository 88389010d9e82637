"""The planar 3-RRR as a :class:`Mechanism`.

Conventions: base joints ``A1..A3``; the actuated angles ``(th1, th2, th3)``
[rad] turn the proximal links of length ``l1`` to the elbows
``C_i = A_i + l1 (cos th_i, sin th_i)``; the distal links of length ``l2``
join the elbows to the platform points ``B_i``, placed as the 3-RPR's:
``B1 = (x, y)``, ``B2 = B1 + d1 (cos alpha, sin alpha)``,
``B3 = B1 + d3 (cos(alpha + beta), sin(alpha + beta))``.  The constraint
equations are ``F_i = |B_i - C_i|**2 - l2**2 = 0``; with ``u_i = B_i - C_i``

    Jx / 2 = rows (u_i, (B_i - B1) x u_i),    -Jq / 2 = diag(u_i . dC_i/dth_i).

With the joints fixed the 3-RRR is a 3-RPR whose base points are the
elbows and whose legs all have length ``l2``: its direct kinematics is the
3-RPR's sextic, solved by the three-leg solver with base points per joint
vector (:func:`~.three_leg_solver.solve_with_bases`), so at most six
solutions.  That reduction (:class:`~.moving_base.MovingBaseRPR`) is
shared with the 3-PRR (:mod:`.prr3`), whose base points are its slider
joints.

Parallel singularities are ``det Jx = 0``; the margin normalises ``Jx`` as
the 3-RPR's does.  A serial singularity (a leg stretched or folded, ``u_i``
parallel to ``dC_i/dth_i``) is no obstacle to moving in joint space and is
not treated as one.  As the five-bar's, the pose alone does not fix the
elbows, so :meth:`ThreeRRR.margin` needs the joints.
"""

from dataclasses import dataclass

from .base import positive_length, register_mechanism, revolute_leg_angles
from .moving_base import MovingBaseRPR
from .rpr3 import beta_from_sides

__all__ = ["ThreeRRR", "DEFAULT_THREE_RRR"]


@register_mechanism("3-RRR")
@dataclass(frozen=True)
class ThreeRRR(MovingBaseRPR):
    """The planar 3-RRR parallel manipulator.

    Joints are the actuated base angles ``(th1, th2, th3)`` [rad]; poses are
    ``(x, y, alpha)`` [length unit, length unit, rad] as the 3-RPR's (B1
    and the platform's orientation), and ``alpha`` chooses the assembly
    mode of a request.  A pose has up to 8 working modes
    (:meth:`inverse_kinematics`), one elbow branch per leg: sign +1 where
    the elbow angle (the direction of ``C_i B_i`` relative to ``A_i C_i``)
    lies in ``[0, pi]``, -1 where it lies in ``(-pi, 0)``.  Batches follow
    :class:`~rpr3_gwr_core.mechanisms.base.Mechanism`: joints and poses
    ``(..., 3)``; :meth:`solve` takes joints ``(n, 3)`` and gives counts
    ``(n,)`` (uint8) and poses ``(n, 6, 3)`` sorted by alpha in (-pi, pi],
    NaN beyond the count.

    Attributes
    ----------
    a1, a2, a3 : tuple of float, shape (2,)
        Base joints A1..A3 [length unit].
    d1 : float
        Platform side B1B2 [length unit].
    d3 : float
        Platform side B1B3 [length unit].
    beta : float
        Angle at B1 from B1B2 to B1B3 [rad].
    l1 : float
        Proximal links A_i C_i [length unit].
    l2 : float
        Distal links C_i B_i [length unit].

    Raises
    ------
    InvalidInputError
        If a base point or platform value is not finite (or the platform is
        flat), or a link length is not a finite positive number.
    """

    a1: tuple = (0.0, 0.0)
    a2: tuple = (15.91, 0.0)
    a3: tuple = (0.0, 10.0)
    d1: float = 17.04
    d3: float = 20.84
    beta: float = beta_from_sides(17.04, 16.54, 20.84)
    l1: float = 8.0
    l2: float = 12.0

    joint_names = ("th1", "th2", "th3")
    angular_joints = (True, True, True)
    _moving_points = ("elbows C_i (each may sit on either side of the line from its base "
                      "to its platform point)")

    def __post_init__(self):
        self._check_platform()
        for name in ("l1", "l2"):
            object.__setattr__(self, name, positive_length(getattr(self, name), name))

    @property
    def distal(self):
        """The legs' length of the 3-RPR it reduces to: ``l2``."""
        return self.l2

    @property
    def _actuation(self):
        # Revolute joints turning the proximal links l1.
        return (1.0, self.l1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    def _legs_reaching(self, points):
        # Sign +1: the elbow angle (``elbow{i}`` of body_outline) in [0, pi].
        return revolute_leg_angles(self.platform.base, points, self.l1, self.l2)

    def elbows(self, joints):
        """Elbows ``C_i = A_i + l1 (cos th_i, sin th_i)`` of joints ``(..., 3)``.

        Returns
        -------
        ndarray, shape (..., 3, 2)
            [length unit].
        """
        return self.base_points(joints)


# The default 3-RRR: the paper's base points and platform, l1 = 8 and l2 = 12
# on every leg.  Every joint vector of its slice th1 = 0 is assembled, with
# 2, 4 or 6 solutions.
DEFAULT_THREE_RRR = ThreeRRR()
