"""The planar 3-RPR: its geometry, and its kinematics as a :class:`Mechanism`.

The geometry of a planar 3-RPR manipulator as an immutable value.

The paper (section 4) gives A1 = (0, 0), A2 = (15.91, 0), A3 = (0, 10),
d1 = 17.04, d3 = 20.84 and prints beta = 37 deg.  With beta = 37 deg none of
the paper's own example configurations is a direct-kinematic solution (the
closest root misses (12, 18, 122.82 deg) by several degrees).  The geometry is
the literature's classic one (Innocenti and Parenti-Castelli; Zein, Wenger and
Chablat), whose platform triangle has sides d1 = 17.04, d2 = 16.54 and
d3 = 20.84; the angle at B1 between B1B2 and B1B3 is then

    beta = arccos((d1**2 + d3**2 - d2**2) / (2 d1 d3)) = 0.8824 rad = 50.56 deg,

and with it all four example configurations of the paper come out within
0.01 deg (see ``test_paper_examples_are_direct_kinematic_solutions``).  The
default :data:`PAPER_GEOMETRY` therefore uses that beta.

Inverse and direct kinematics, Jacobians, aspects and degeneracy of the 3-RPR.

Conventions (paper section 4.1): the platform pose is ``(x, y, alpha)`` with
``B1 = (x, y)``, ``B2 = B1 + d1 (cos alpha, sin alpha)`` and
``B3 = B1 + d3 (cos(alpha + beta), sin(alpha + beta))``; the legs are
``rho_i = |B_i - A_i|``.  The constraint equations are
``F_i = |B_i - A_i|**2 - rho_i**2 = 0`` and their time derivative is
``Jq dq/dt = Jx dx/dt`` with ``Jx = dF/dx`` and ``Jq = diag(2 rho)``.
The direct kinematics, the margin, the corrector and the residuals are
those of the three-leg solver (:mod:`.three_leg_solver`), which the 3-RRR
and the 3-PRR share.
"""

from dataclasses import dataclass
import functools
import math
import numbers

import numba
import numpy as np

from ..exceptions import InvalidInputError
from .base import (PREDICT_KERNEL_SIGNATURE, STEP_KERNEL_SIGNATURE, Mechanism, first_class,
                   register_mechanism)
from .three_leg_solver import (
    MAX_SOLUTIONS,
    adjugate_product,
    checked_legs,
    corrected,
    degenerate_orientations,
    leg_residuals,
    newton,
    pose_rows,
    residuals,
    row_terms,
    rows_margin,
    singularity_margin,
    solve_legs,
    solve_rows,
    wrap_angle,
)

__all__ = [
    "ThreeRPR",
    "PAPER_GEOMETRY",
    "beta_from_sides",
    "serial_jacobian",
]


def _real(value):
    """``float(value)`` for real numbers only (no strings)."""
    if not isinstance(value, numbers.Real):
        raise TypeError(f"not a real number: {value!r}")
    return float(value)


def beta_from_sides(d1, d2, d3):
    """Platform angle at B1 of a triangle with sides ``d1 = |B1B2|``,
    ``d2 = |B2B3|`` and ``d3 = |B1B3|``.

    Parameters
    ----------
    d1, d2, d3 : float
        Side lengths [length unit]; must satisfy the triangle inequality.

    Returns
    -------
    float
        beta [rad] in (0, pi).
    """
    sides = (d1, d2, d3)
    if not all(math.isfinite(s) and s > 0 for s in sides):
        raise InvalidInputError(f"platform sides must be finite and positive, got {sides}")
    cos_beta = (d1 * d1 + d3 * d3 - d2 * d2) / (2.0 * d1 * d3)
    if not -1.0 < cos_beta < 1.0:
        raise InvalidInputError(f"sides {sides} do not form a triangle")
    return math.acos(cos_beta)


@register_mechanism("3-RPR")
@dataclass(frozen=True)
class ThreeRPR(Mechanism):
    """Base points and platform of a 3-RPR manipulator: the 3-RPR mechanism.

    Joints are the leg lengths ``(rho1, rho2, rho3)`` [length unit], poses
    ``(x, y, alpha)`` [length unit, length unit, rad]: the platform vertex B1
    and the direction of B1B2.  A pose fixes the legs: the inverse
    kinematics has one working mode, ``+++``.  The methods of
    :class:`~rpr3_gwr_core.mechanisms.base.Mechanism` are this module's
    kinematics.

    Attributes
    ----------
    a1, a2, a3 : tuple of float, shape (2,)
        Base joint positions A1..A3 [length unit].
    d1 : float
        Platform side B1B2 [length unit].
    d3 : float
        Platform side B1B3 [length unit].
    beta : float
        Angle at B1 from B1B2 to B1B3 [rad].
    """

    a1: tuple = (0.0, 0.0)
    a2: tuple = (15.91, 0.0)
    a3: tuple = (0.0, 10.0)
    d1: float = 17.04
    d3: float = 20.84
    beta: float = beta_from_sides(17.04, 16.54, 20.84)

    joint_names = ("rho1", "rho2", "rho3")
    pose_names = ("x", "y", "alpha")
    angular = (False, False, True)
    mode_coordinate = 2
    max_solutions = MAX_SOLUTIONS
    angle_parameters = ("beta",)

    def __post_init__(self):
        for name in ("a1", "a2", "a3"):
            try:
                point = tuple(_real(v) for v in getattr(self, name))
            except (TypeError, ValueError):
                raise InvalidInputError(
                    f"{name} must be two numbers, got {getattr(self, name)!r}") from None
            if len(point) != 2 or not all(math.isfinite(v) for v in point):
                raise InvalidInputError(f"{name} must be two finite numbers, got {point}")
            object.__setattr__(self, name, point)
        for name in ("d1", "d3", "beta"):
            try:
                value = _real(getattr(self, name))
            except (TypeError, ValueError):
                raise InvalidInputError(
                    f"{name} must be a number, got {getattr(self, name)!r}") from None
            if not math.isfinite(value):
                raise InvalidInputError(f"{name} must be finite, got {value}")
            object.__setattr__(self, name, value)
        if self.d1 <= 0 or self.d3 <= 0:
            raise InvalidInputError("platform sides d1 and d3 must be positive")
        # A flat platform (beta = 0 or pi) makes every pose degenerate.
        if abs(math.sin(self.beta)) < 1e-9:
            raise InvalidInputError(f"beta = {self.beta} makes the platform flat")

    @property
    def d2(self):
        """Platform side B2B3 [length unit]."""
        return math.sqrt(self.d1**2 + self.d3**2 - 2 * self.d1 * self.d3 * math.cos(self.beta))

    @property
    def base(self):
        """Base points as an array, shape (3, 2) [length unit]."""
        return np.array([self.a1, self.a2, self.a3])

    @functools.cached_property
    def scale(self):
        """Characteristic length (longest platform side) used to make the
        orientation column of the Jacobian commensurable with positions."""
        return max(self.d1, self.d2, self.d3)

    @functools.cached_property
    def parameters(self):
        """``(a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta)``: the geometry as the
        constraint equations (and their compiled form) take it."""
        return (*self.a1, *self.a2, *self.a3, self.d1, self.d3, self.beta)

    def to_dict(self):
        """Plain-data form, for JSON, messages and cache keys."""
        return {"kind": self.kind, "a1": list(self.a1), "a2": list(self.a2),
                "a3": list(self.a3), "d1": self.d1, "d3": self.d3, "beta": self.beta}

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(a1=tuple(data["a1"]), a2=tuple(data["a2"]), a3=tuple(data["a3"]),
                       d1=data["d1"], d3=data["d3"], beta=data["beta"])
        except (KeyError, TypeError) as exc:
            raise InvalidInputError(f"malformed geometry: {exc}") from exc

    # The Mechanism interface and the 3-RPR's own kinematics, served by the
    # functions below.

    def check_joints(self, joints):
        checked_legs(joints)

    def inverse(self, poses):
        """Leg lengths of platform poses (the inverse kinematics).

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            ``(x, y, alpha)`` [length unit, length unit, rad], finite.

        Returns
        -------
        ndarray, shape (..., 3)
            ``(rho1, rho2, rho3)`` [length unit].
        """
        return _inverse_kinematics(_as_pose(poses), self)

    def leg_joints(self, poses):
        """Each leg's length at poses, ``rho_i = |B_i - A_i|``: one branch,
        every pose reached (:meth:`Mechanism.leg_joints`).

        Returns
        -------
        ndarray, shape (..., 3, 1)
            [length unit].
        """
        return self.inverse(poses)[..., None]

    def solve(self, joints):
        """All real direct-kinematic solutions of many leg configurations.

        Parameters
        ----------
        joints : array_like, shape (n, 3)
            Leg lengths ``(rho1, rho2, rho3)`` [length unit], finite and
            non-negative.

        Returns
        -------
        count : ndarray of uint8, shape (n,)
            Number of real solutions.
        poses : ndarray, shape (n, 6, 3)
            ``(x, y, alpha)`` [length unit, length unit, rad] of each solution
            sorted by alpha in (-pi, pi]; NaN beyond ``count``.  Near a
            degenerate orientation, where two assembly modes share alpha, the
            two differ in (x, y).
        """
        rho = checked_legs(joints)
        if rho.ndim != 2:
            raise InvalidInputError(f"rho must have shape (n, 3), got {rho.shape}")
        return solve_legs(rho, self)

    def direct_kinematics(self, joints):
        """All real direct-kinematic solutions of one leg configuration.

        Parameters
        ----------
        joints : array_like, shape (3,)
            ``(rho1, rho2, rho3)`` [length unit], finite and non-negative.

        Returns
        -------
        ndarray, shape (k, 3)
            ``(x, y, alpha)`` [length unit, length unit, rad] of each of the
            ``k <= 6`` solutions, sorted by alpha in (-pi, pi].
        """
        rho = checked_legs(joints)
        if rho.shape != (3,):
            raise InvalidInputError(f"rho must have shape (3,), got {rho.shape}")
        return _direct_kinematics(rho, self)

    def passive_angles(self, poses):
        """Directions of the legs, the passive joint angles theta1..theta3.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            ``(x, y, alpha)`` [length unit, length unit, rad], finite.

        Returns
        -------
        ndarray, shape (..., 3)
            ``theta_i = atan2(B_i - A_i)`` [rad] in (-pi, pi].
        """
        return _passive_angles(_as_pose(poses), self)

    def platform_points(self, poses):
        """Platform joints ``B1..B3`` of poses ``(..., 3)``, shape (..., 3, 2) [length unit]."""
        legs, _ = _leg_vectors(_as_pose(poses), self)
        return legs + self.base

    def body_outline(self, poses, joints):
        """Legs ``A_i B_i`` (prismatic), the platform triangle, and the
        passive angles: ``base{i}`` the leg's direction theta_i, ``platform{i}``
        it relative to the platform, ``theta_i - alpha`` (:meth:`Mechanism.body_outline`)."""
        points = self.platform_points(poses)
        base = np.broadcast_to(self.base, points.shape)
        theta = self.passive_angles(poses)
        relative = wrap_angle(theta - np.asarray(poses)[..., 2:3])
        links = [(f"leg{i + 1}", i, (f"A{i + 1}", f"B{i + 1}"), base[..., i, :],
                  points[..., i, :], True) for i in range(3)]
        passive = ([(f"base{i + 1}", theta[..., i]) for i in range(3)]
                   + [(f"platform{i + 1}", relative[..., i]) for i in range(3)])
        return links, [("platform", ("B1", "B2", "B3"), points)], passive

    def parallel_jacobian(self, poses):
        """The parallel Jacobian ``Jx = dF/d(x, y, alpha)``.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            ``(x, y, alpha)`` [length unit, length unit, rad], finite.

        Returns
        -------
        ndarray, shape (..., 3, 3)
            Row i is ``2 (u_x, u_y, u . dB_i/dalpha)`` with ``u = B_i - A_i``
            [length unit in the first two columns, length unit**2 in the third].
        """
        return _parallel_jacobian(_as_pose(poses), self)

    def degenerate_orientations(self):
        """Orientations where the direct kinematics degenerates.

        At these alpha the lines for B1 given by legs 2 and 3 are parallel
        (``AE - BD = 0``), so two assembly modes can share alpha with different
        positions (paper section 4.2.3).

        Returns
        -------
        ndarray, shape (k,)
            Sorted orientations [rad] in (-pi, pi], ``k`` 0 or 2.
        """
        return degenerate_orientations(self)

    def margin(self, poses, joints=None):
        """Signed, normalised distance from a parallel singularity
        (:meth:`Mechanism.margin`).

        The orientation column of ``Jx`` is divided by :attr:`scale` so that
        all columns are lengths, then ``det(Jx)`` is divided by the product of
        the row norms (Hadamard's bound).  The result lies in [-1, 1], is 0
        exactly on a parallel singularity (and where a leg has zero length)
        and its sign is the aspect.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            ``(x, y, alpha)`` [length unit, length unit, rad].
        joints : array_like, optional
            Ignored: the 3-RPR's pose fixes its legs.

        Returns
        -------
        ndarray, shape (...)
            Dimensionless; a NumPy scalar for one pose.
        """
        poses = np.asarray(poses, dtype=float)
        if poses.shape == (3,):  # one pose, as the validator asks: no array overhead
            return np.float64(_pose_margin(self.parameters, self.scale, *poses.tolist()))
        return singularity_margin(poses, self)

    def predict(self, poses, joints_from, joints_to):
        return _predict(poses, joints_from, joints_to, self)

    def correct(self, poses, joints, iterations):
        """Newton steps on the constraint equations at fixed legs.

        Parameters
        ----------
        poses : ndarray, shape (..., 3)
            Initial guesses ``(x, y, alpha)`` [length unit, length unit, rad];
            not modified.
        joints : ndarray, shape (..., 3)
            Leg lengths to satisfy [length unit].
        iterations : int

        Returns
        -------
        ndarray, shape (..., 3)
            Corrected poses (alpha is not wrapped).
        """
        return newton(poses, joints, self, iterations)

    def residual(self, poses, joints):
        """Constraint residuals ``F(q, x) = |B_i - A_i|**2 - rho_i**2``.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            ``(x, y, alpha)`` [length unit, length unit, rad].
        joints : array_like, shape (..., 3)
            ``(rho1, rho2, rho3)`` [length unit].

        Returns
        -------
        ndarray, shape (..., 3)
            One per leg [length unit**2].
        """
        poses, joints = np.asarray(poses, dtype=float), np.asarray(joints, dtype=float)
        if poses.shape == joints.shape == (3,):
            return np.array(leg_residuals(_pose_rows(self.parameters, *poses.tolist()),
                                           joints.tolist()))
        return residuals(poses, joints, self)

    def step(self, pose, joints_from, joints_to):
        return _step(self, pose, joints_from, joints_to)

    @functools.cached_property
    def step_kernel(self):
        return (first_class(_step_kernel, STEP_KERNEL_SIGNATURE),
                np.array([*self.parameters, self.scale]))

    @functools.cached_property
    def predict_kernel(self):
        return first_class(_predict_kernel, PREDICT_KERNEL_SIGNATURE), np.array(self.parameters)

    def refine_cusp(self, pose, fixed):
        if set(fixed) != {0}:
            raise InvalidInputError("cusp equations are written for slices at fixed rho1")
        return _refine_cusp(self, pose, float(fixed[0]))


PAPER_GEOMETRY = ThreeRPR()


def _as_pose(pose):
    pose = np.asarray(pose, dtype=float)
    if pose.shape[-1:] != (3,):
        raise InvalidInputError(f"a pose has 3 components (x, y, alpha), got shape {pose.shape}")
    if not np.all(np.isfinite(pose)):
        raise InvalidInputError("pose contains NaN or infinity")
    return pose


def _leg_vectors(pose, geometry):
    """``B_i - A_i`` and the platform offsets, shapes (..., 3, 2)."""
    x, y, alpha = pose[..., 0], pose[..., 1], pose[..., 2]
    e1 = np.stack([np.cos(alpha), np.sin(alpha)], axis=-1)
    e3 = np.stack([np.cos(alpha + geometry.beta), np.sin(alpha + geometry.beta)], axis=-1)
    b1 = np.stack([x, y], axis=-1)
    offsets = np.stack([np.zeros_like(e1), geometry.d1 * e1, geometry.d3 * e3], axis=-2)
    legs = b1[..., None, :] + offsets - geometry.base
    return legs, offsets


def _inverse_kinematics(pose, geometry):
    """:meth:`ThreeRPR.inverse` of checked poses."""
    legs, _ = _leg_vectors(pose, geometry)
    return np.linalg.norm(legs, axis=-1)


def _passive_angles(pose, geometry):
    """:meth:`ThreeRPR.passive_angles` of checked poses."""
    legs, _ = _leg_vectors(pose, geometry)
    return np.arctan2(legs[..., 1], legs[..., 0])


def _parallel_jacobian(pose, geometry):
    """:meth:`ThreeRPR.parallel_jacobian` of checked poses."""
    u1x, u1y, u2x, u2y, w2, u3x, u3y, w3 = pose_rows(pose, geometry)
    zero = np.zeros_like(u1x)
    return 2.0 * np.stack([np.stack([u1x, u1y, zero], -1), np.stack([u2x, u2y, w2], -1),
                           np.stack([u3x, u3y, w3], -1)], -2)


def serial_jacobian(rho):
    """The serial Jacobian ``Jq = diag(2 rho)``, shape (..., 3, 3).

    Its determinant ``8 rho1 rho2 rho3`` vanishes only with a zero leg.
    """
    rho = checked_legs(rho)
    return 2.0 * rho[..., :, None] * np.eye(3)


def _predict(pose, rho_from, rho_to, geometry):
    """Euler step of the platform for a change of legs: ``Jx dx = Jq drho``."""
    drho = rho_to - rho_from
    return pose + solve_rows(pose_rows(pose, geometry), *np.moveaxis(rho_from * drho, -1, 0))


def _step(geometry, pose, rho_from, rho_to):
    """One predictor-corrector step of one pose (:meth:`ThreeRPR.step`)."""
    x, y, alpha = (float(v) for v in pose)
    ok, x, y, alpha, margin = _compiled_step(
        geometry.parameters, geometry.scale, x, y, alpha,
        *(float(v) for v in rho_from), *(float(v) for v in rho_to))
    return ((x, y, alpha), margin) if ok else None


@numba.njit(cache=True)
def _pose_rows(parameters, x, y, alpha):
    return row_terms(x, y, alpha, parameters)


@numba.njit(cache=True)
def _pose_margin(parameters, scale, x, y, alpha):
    return rows_margin(row_terms(x, y, alpha, parameters), scale)


@numba.njit(cache=True)
def _compiled_step(parameters, scale, x, y, alpha, r1, r2, r3, t1, t2, t3):
    """:func:`_step` on floats: ``(converged, x, y, alpha, margin)``."""
    rows = row_terms(x, y, alpha, parameters)
    (dx, dy, da), det = adjugate_product(rows, r1 * (t1 - r1), r2 * (t2 - r2), r3 * (t3 - r3))
    if det == 0.0:
        return False, x, y, alpha, 0.0
    px, py, palpha = x + dx / det, y + dy / det, alpha + da / det
    predicted = math.sqrt((dx / det) ** 2 + (dy / det) ** 2 + (da / det * scale) ** 2)
    return corrected(parameters, (t1, t2, t3), scale, px, py, palpha, predicted)


@numba.njit(STEP_KERNEL_SIGNATURE, cache=True)
def _step_kernel(parameters, pose, joints_from, joints_to):
    """:func:`_compiled_step` as :data:`~.base.STEP_KERNEL_SIGNATURE` takes
    it; ``parameters`` are :attr:`ThreeRPR.parameters`, then the scale."""
    p = parameters
    ok, x, y, alpha, margin = _compiled_step(
        (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]), p[9], pose[0], pose[1], pose[2],
        joints_from[0], joints_from[1], joints_from[2], joints_to[0], joints_to[1], joints_to[2])
    if not ok:
        return np.nan
    pose[0], pose[1], pose[2] = x, y, alpha
    return margin


@numba.njit(cache=True, nogil=True)
def _predict_kernel(parameters, poses, joints_from, joints_to, out):
    """:func:`_predict` of the solutions of one leg configuration, as
    :data:`~.base.PREDICT_KERNEL_SIGNATURE` takes it; ``parameters`` are
    :attr:`ThreeRPR.parameters`."""
    p = parameters
    geometry = (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8])
    r1, r2, r3 = joints_from[0], joints_from[1], joints_from[2]
    change = (r1 * (joints_to[0] - r1), r2 * (joints_to[1] - r2), r3 * (joints_to[2] - r3))
    for r in range(poses.shape[0]):
        rows = row_terms(poses[r, 0], poses[r, 1], poses[r, 2], geometry)
        (dx, dy, da), det = adjugate_product(rows, *change)
        # A singular system leaves the pose, as solve_rows does.
        inv = 1.0 / det if det != 0.0 else 0.0
        out[r, 0], out[r, 1] = poses[r, 0] + dx * inv, poses[r, 1] + dy * inv
        out[r, 2] = poses[r, 2] + da * inv


# --- cusps of the slices at fixed rho1 ----------------------------------------------
#
# At fixed rho1 the poses are the torus (theta1, alpha): B1 = A1 + rho1 (cos
# theta1, sin theta1), and the legs rho2, rho3 follow in closed form.  The
# map phi(theta1, alpha) = (rho2**2, rho3**2) is singular where det(d phi) = 0
# (the parallel singularities), and has a cusp where, moreover, the kernel
# of d phi is tangent to that curve: grad(det d phi) . k = 0.  Newton on
# these two equations in (theta1, alpha) uses the pose equations themselves,
# so it is as well conditioned at the degenerate orientations as elsewhere.

_CUSP_ITERATIONS = 40
_CUSP_DIFFERENCE = 1e-7
_CUSP_TOL = 1e-12


def _cusp_equations(geometry, theta, alpha, rho1):
    """``(det d phi, grad(det d phi) . k)`` with ``k`` the unit kernel of d phi,
    and the squared legs ``(rho2**2, rho3**2)``."""
    # In scalars: Newton calls it thousands of times per slice, and numpy's
    # two-element arrays would cost ten times the arithmetic.
    rx, ry = rho1 * math.cos(theta), rho1 * math.sin(theta)
    tx, ty = -ry, rx
    b1x, b1y = geometry.a1[0] + rx, geometry.a1[1] + ry
    rows, d_theta, d_alpha, legs = [], [], [], []
    for (ax, ay), d, phase in ((geometry.a2, geometry.d1, alpha),
                               (geometry.a3, geometry.d3, alpha + geometry.beta)):
        ex, ey = d * math.cos(phase), d * math.sin(phase)
        qx, qy = -ey, ex  # e', the derivative of e in the phase
        ux, uy = b1x + ex - ax, b1y + ey - ay
        rows.append((2 * (ux * tx + uy * ty), 2 * (ux * qx + uy * qy)))
        d_theta.append((2 * (rho1 * rho1 - (ux * rx + uy * ry)), 2 * (qx * tx + qy * ty)))
        d_alpha.append((2 * (tx * qx + ty * qy), 2 * (d * d - (ux * ex + uy * ey))))
        legs.append(ux * ux + uy * uy)
    (a, b), (c, d) = rows
    det = a * d - b * c

    def derivative(partial):
        (pa, pb), (pc, pd) = partial
        return pa * d + a * pd - pb * c - b * pc

    kx, ky = (b, -a) if a * a + b * b >= c * c + d * d else (d, -c)
    norm = math.sqrt(kx * kx + ky * ky)
    tangent = (derivative(d_theta) * kx + derivative(d_alpha) * ky) / norm
    return (det, tangent), legs


def _refine_cusp(geometry, pose, rho1):
    x, y, alpha = (float(v) for v in pose)
    theta = math.atan2(y - geometry.a1[1], x - geometry.a1[0])
    h = _CUSP_DIFFERENCE
    for _ in range(_CUSP_ITERATIONS):
        (f, g), _ = _cusp_equations(geometry, theta, alpha, rho1)
        # The Jacobian's columns by central differences along theta, then alpha.
        columns = []
        for dt, da in ((h, 0.0), (0.0, h)):
            (fp, gp), _ = _cusp_equations(geometry, theta + dt, alpha + da, rho1)
            (fm, gm), _ = _cusp_equations(geometry, theta - dt, alpha - da, rho1)
            columns.append(((fp - fm) / (2 * h), (gp - gm) / (2 * h)))
        (j11, j21), (j12, j22) = columns
        det = j11 * j22 - j12 * j21
        if det == 0.0:
            return None
        move_theta, move_alpha = (j12 * g - j22 * f) / det, (j21 * f - j11 * g) / det
        theta, alpha = theta + move_theta, alpha + move_alpha
        if max(abs(move_theta), abs(move_alpha)) < _CUSP_TOL:
            break
    else:
        return None
    _, legs = _cusp_equations(geometry, theta, alpha, rho1)
    cusp_pose = np.array([geometry.a1[0] + rho1 * math.cos(theta),
                          geometry.a1[1] + rho1 * math.sin(theta), float(wrap_angle(alpha))])
    return cusp_pose, np.array([rho1, math.sqrt(legs[0]), math.sqrt(legs[1])])


def _direct_kinematics(rho, geometry):
    """:meth:`ThreeRPR.direct_kinematics` of checked legs, shape (3,)."""
    count, poses = solve_legs(rho[None, :], geometry)
    return poses[0, : count[0]]
