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

The direct kinematics eliminates (x, y) to the paper's equation (7), a
trigonometric polynomial of degree 3 in alpha (its degree-4 harmonics cancel),
i.e. the classic sextic.  Its seven Fourier coefficients are linear in
``(u**2, u v, v**2, u, v, 1, rho1**2)`` with ``u = rho2**2 - rho1**2`` and
``v = rho3**2 - rho1**2``, so they cost one small matrix product per batch of
configurations.  A compiled sampler (:mod:`.trig_roots`) proves most
configurations' roots simple and polishes them; only those whose roots come
close to merging, near the singular locus or a degenerate orientation, take
the eigenvalues of a companion matrix in ``t = tan((alpha - alpha0) / 2)``,
``alpha0`` chosen per configuration so that no root sits near ``t = inf``.
The same solver takes base points per configuration
(:func:`solve_with_bases`), for mechanisms that reduce to a 3-RPR whose base
points move with their joints (the 3-RRR, base points its elbows).
"""

from dataclasses import dataclass
import functools
import math
import numbers

import numba
from numba.extending import register_jitable
import numpy as np

from ..exceptions import InvalidInputError
from .base import (PREDICT_KERNEL_SIGNATURE, STEP_KERNEL_SIGNATURE, Mechanism, first_class,
                   register_mechanism)
from .trig_roots import sampled_roots

__all__ = [
    "ThreeRPR",
    "PAPER_GEOMETRY",
    "beta_from_sides",
    "MAX_SOLUTIONS",
    "wrap_angle",
    "serial_jacobian",
    "solve_with_bases",
]

MAX_SOLUTIONS = 6


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
    ``(x, y, alpha)`` [length unit, length unit, rad]; the methods of
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
        _as_rho(joints)

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
        rho = _as_rho(joints)
        if rho.ndim != 2:
            raise InvalidInputError(f"rho must have shape (n, 3), got {rho.shape}")
        return _solve(rho, self)

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
        rho = _as_rho(joints)
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
        return _degenerate_orientations(self)

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
        return _singularity_margin(poses, self)

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
        return _newton(poses, joints, self, iterations)

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
            return np.array(_leg_residuals(_pose_rows(self.parameters, *poses.tolist()),
                                           joints.tolist()))
        return _residuals(poses, joints, self)

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

# A root of the sextic is real when its orientation's imaginary part is below
# this; a double root splits into a pair whose imaginary parts are of order
# sqrt(machine epsilon), so a degenerate (non-singular) double root stays real.
_IMAG_TOL = 1e-6
# |AE - BD| below this (relative to its scale) makes (x, y) ill-conditioned in
# the linear formula: the pose then comes from the circle of leg 1 instead.
# Between it and _POLISH_TOL the linear formula is polished by Newton.
_DEGENERATE_TOL = 1e-3
_POLISH_TOL = 1e-2
# A root whose pose misses the legs by this much [scale**2] is not a solution.
_FAKE_RESIDUAL = 1e-3
# Two roots closer than this are the halves of one double root [rad].
_PAIR_GAP = 1e-3
_SAMPLES = 64


def wrap_angle(angle):
    """Angles wrapped to (-pi, pi] [rad], elementwise."""
    return np.pi - np.remainder(np.pi - np.asarray(angle, dtype=float), 2 * np.pi)


def _as_pose(pose):
    pose = np.asarray(pose, dtype=float)
    if pose.shape[-1:] != (3,):
        raise InvalidInputError(f"a pose has 3 components (x, y, alpha), got shape {pose.shape}")
    if not np.all(np.isfinite(pose)):
        raise InvalidInputError("pose contains NaN or infinity")
    return pose


def _as_rho(rho):
    rho = np.asarray(rho, dtype=float)
    if rho.shape[-1:] != (3,):
        raise InvalidInputError(f"rho has 3 components, got shape {rho.shape}")
    if not np.all(np.isfinite(rho)):
        raise InvalidInputError("rho contains NaN or infinity")
    if np.any(rho < 0):
        raise InvalidInputError("leg lengths rho must be non-negative")
    return rho


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
    u1x, u1y, u2x, u2y, w2, u3x, u3y, w3 = _rows(pose, geometry)
    zero = np.zeros_like(u1x)
    return 2.0 * np.stack([np.stack([u1x, u1y, zero], -1), np.stack([u2x, u2y, w2], -1),
                           np.stack([u3x, u3y, w3], -1)], -2)


# The constraint equations are written once, as arithmetic that runs on numpy
# arrays for batches (the field, continuity) and, compiled by numba, on floats
# for the sequential continuation of one pose (validator, driver), where
# numpy's per-call cost would dominate.

def _rows(pose, geometry):
    """Entries of ``Jx / 2`` of poses ``(..., 3)`` (see :func:`_row_terms`)."""
    return _row_terms(pose[..., 0], pose[..., 1], pose[..., 2], geometry.parameters)


@register_jitable
def _row_terms(x, y, alpha, parameters):
    """Entries of ``Jx / 2``: legs ``u_i = B_i - A_i`` and ``w_i = u_i . dB_i/dalpha``
    (``w_1 = 0`` because B1 is the platform's reference point)."""
    a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta = parameters
    c, s = np.cos(alpha), np.sin(alpha)
    c3, s3 = np.cos(alpha + beta), np.sin(alpha + beta)
    u1x, u1y = x - a1x, y - a1y
    u2x, u2y = x + d1 * c - a2x, y + d1 * s - a2y
    u3x, u3y = x + d3 * c3 - a3x, y + d3 * s3 - a3y
    w2 = d1 * (c * u2y - s * u2x)
    w3 = d3 * (c3 * u3y - s3 * u3x)
    return u1x, u1y, u2x, u2y, w2, u3x, u3y, w3


@register_jitable
def _det_rows(u1x, u1y, u2x, u2y, w2, u3x, u3y, w3):
    return u1x * (u2y * w3 - w2 * u3y) + u1y * (w2 * u3x - u2x * w3)


@register_jitable
def _adjugate_product(rows, r1, r2, r3):
    """``det(Jx / 2) (Jx / 2)^-1 r`` and ``det(Jx / 2)``."""
    a, b, c, d, e, f, g, h = rows
    return (((d * h - e * g) * r1 - b * h * r2 + b * e * r3,
             (e * f - c * h) * r1 + a * h * r2 - a * e * r3,
             (c * g - d * f) * r1 + (b * f - a * g) * r2 + (a * d - b * c) * r3),
            _det_rows(*rows))


def _solve_rows(rows, r1, r2, r3):
    """``(Jx / 2)^-1 r`` by the adjugate of the rows; a singular system gives 0."""
    (dx, dy, da), det = _adjugate_product(rows, r1, r2, r3)
    inv = np.where(det != 0, 1.0 / np.where(det != 0, det, 1.0), 0.0)
    return np.stack([dx * inv, dy * inv, da * inv], axis=-1)


@register_jitable
def _leg_residuals(rows, rho):
    """``|B_i - A_i|**2 - rho_i**2`` from the rows, one per leg."""
    u1x, u1y, u2x, u2y, _, u3x, u3y, _ = rows
    return (u1x * u1x + u1y * u1y - rho[0] * rho[0], u2x * u2x + u2y * u2y - rho[1] * rho[1],
            u3x * u3x + u3y * u3y - rho[2] * rho[2])


@register_jitable
def _row_norms(rows, scale):
    """Norms of the rows of ``Jx / 2`` with the orientation column over ``scale``."""
    u1x, u1y, u2x, u2y, w2, u3x, u3y, w3 = rows
    w2, w3 = w2 / scale, w3 / scale
    return (np.hypot(u1x, u1y), np.sqrt(u2x * u2x + u2y * u2y + w2 * w2),
            np.sqrt(u3x * u3x + u3y * u3y + w3 * w3))


@register_jitable
def _normalised_det(rows, norms, scale):
    """det of the rows divided by their norms: normalising before the
    determinant keeps tiny legs from underflowing the product of the norms."""
    u1x, u1y, u2x, u2y, w2, u3x, u3y, w3 = rows
    n1, n2, n3 = norms
    return _det_rows(u1x / n1, u1y / n1, u2x / n2, u2y / n2, w2 / scale / n2,
                     u3x / n3, u3y / n3, w3 / scale / n3)


def serial_jacobian(rho):
    """The serial Jacobian ``Jq = diag(2 rho)``, shape (..., 3, 3).

    Its determinant ``8 rho1 rho2 rho3`` vanishes only with a zero leg.
    """
    rho = _as_rho(rho)
    return 2.0 * rho[..., :, None] * np.eye(3)


def _singularity_margin(pose, geometry):
    """:meth:`ThreeRPR.margin` of many poses."""
    rows = _rows(pose, geometry)
    norms = _row_norms(rows, geometry.scale)
    with np.errstate(invalid="ignore", divide="ignore"):
        margin = _normalised_det(rows, norms, geometry.scale)
    return np.where((norms[0] > 0) & (norms[1] > 0) & (norms[2] > 0), margin, 0.0)


def _newton(pose, rho, geometry, iterations):
    legs = np.moveaxis(rho, -1, 0)
    for _ in range(iterations):
        rows = _rows(pose, geometry)
        pose = pose - 0.5 * _solve_rows(rows, *_leg_residuals(rows, legs))
    return pose


def _predict(pose, rho_from, rho_to, geometry):
    """Euler step of the platform for a change of legs: ``Jx dx = Jq drho``."""
    drho = rho_to - rho_from
    return pose + _solve_rows(_rows(pose, geometry), *np.moveaxis(rho_from * drho, -1, 0))


# The scalar continuation step: converged when every leg's residual is below
# _RESIDUAL_TOL * scale**2, after at most _NEWTON_STEPS corrector steps, and
# refused when the corrector moved the pose more than _JUMP_RATIO times the
# predictor's move plus _JUMP_FLOOR * scale (the residual tolerance's reach).
_NEWTON_STEPS = 6
_RESIDUAL_TOL = 1e-9
_JUMP_RATIO = 0.5
_JUMP_FLOOR = 1e-7


def _step(geometry, pose, rho_from, rho_to):
    """One predictor-corrector step of one pose (:meth:`ThreeRPR.step`)."""
    x, y, alpha = (float(v) for v in pose)
    ok, x, y, alpha, margin = _compiled_step(
        geometry.parameters, geometry.scale, x, y, alpha,
        *(float(v) for v in rho_from), *(float(v) for v in rho_to))
    return ((x, y, alpha), margin) if ok else None


@numba.njit(cache=True)
def _pose_rows(parameters, x, y, alpha):
    return _row_terms(x, y, alpha, parameters)


@register_jitable
def _rows_margin(rows, scale):
    """:func:`_singularity_margin` from the rows of one pose: 0 with a zero row."""
    norms = _row_norms(rows, scale)
    if norms[0] > 0 and norms[1] > 0 and norms[2] > 0:
        return _normalised_det(rows, norms, scale)
    return 0.0


@numba.njit(cache=True)
def _pose_margin(parameters, scale, x, y, alpha):
    return _rows_margin(_row_terms(x, y, alpha, parameters), scale)


@numba.njit(cache=True)
def _compiled_step(parameters, scale, x, y, alpha, r1, r2, r3, t1, t2, t3):
    """:func:`_step` on floats: ``(converged, x, y, alpha, margin)``."""
    rows = _row_terms(x, y, alpha, parameters)
    (dx, dy, da), det = _adjugate_product(rows, r1 * (t1 - r1), r2 * (t2 - r2), r3 * (t3 - r3))
    if det == 0.0:
        return False, x, y, alpha, 0.0
    px, py, palpha = x + dx / det, y + dy / det, alpha + da / det
    predicted = math.sqrt((dx / det) ** 2 + (dy / det) ** 2 + (da / det * scale) ** 2)
    return _corrected(parameters, (t1, t2, t3), scale, px, py, palpha, predicted)


@register_jitable
def _corrected(parameters, legs, scale, px, py, palpha, predicted):
    """Newton from the predicted pose ``(px, py, palpha)`` onto the legs of a
    3-RPR of base and platform ``parameters``, judged against the
    predictor's move ``predicted``: ``(converged, x, y, alpha, margin)``."""
    x, y, alpha = px, py, palpha
    tol = _RESIDUAL_TOL * scale * scale
    for _ in range(_NEWTON_STEPS):
        rows = _row_terms(x, y, alpha, parameters)
        e1, e2, e3 = _leg_residuals(rows, legs)
        if max(abs(e1), abs(e2), abs(e3)) < tol:
            corrected = math.sqrt((x - px) ** 2 + (y - py) ** 2 + ((alpha - palpha) * scale) ** 2)
            # The predictor is first order, so on the followed branch the
            # correction is of second order in the step: one as long as the
            # prediction itself landed on another solution of these legs.
            if corrected > _JUMP_RATIO * predicted + _JUMP_FLOOR * scale:
                return False, x, y, alpha, 0.0
            return True, x, y, alpha, _rows_margin(rows, scale)
        (dx, dy, da), det = _adjugate_product(rows, e1, e2, e3)
        if det == 0.0:
            return False, x, y, alpha, 0.0
        x, y, alpha = x - 0.5 * dx / det, y - 0.5 * dy / det, alpha - 0.5 * da / det
    return False, x, y, alpha, 0.0


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
        rows = _row_terms(poses[r, 0], poses[r, 1], poses[r, 2], geometry)
        (dx, dy, da), det = _adjugate_product(rows, *change)
        # A singular system leaves the pose, as _solve_rows does.
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


# --- direct kinematics ---------------------------------------------------------

def _linear_terms(alpha, geometry):
    """The paper's A..F of equation (7) at orientations ``alpha``."""
    (a2x, a2y), (a3x, a3y) = geometry.a2, geometry.a3
    d1, d3, beta = geometry.d1, geometry.d3, geometry.beta
    c1, s1 = np.cos(alpha), np.sin(alpha)
    c3, s3 = np.cos(alpha + beta), np.sin(alpha + beta)
    # Leg 1 is at the origin of the paper's derivation: shift the base so A1 = 0.
    a1x, a1y = geometry.a1
    a2x, a2y, a3x, a3y = a2x - a1x, a2y - a1y, a3x - a1x, a3y - a1y
    big_a = -2 * a2x + 2 * d1 * c1
    big_b = -2 * a2y + 2 * d1 * s1
    big_c = d1**2 + a2x**2 + a2y**2 - 2 * d1 * (a2x * c1 + a2y * s1)
    big_d = -2 * a3x + 2 * d3 * c3
    big_e = -2 * a3y + 2 * d3 * s3
    big_f = d3**2 + a3x**2 + a3y**2 - 2 * d3 * (a3x * c3 + a3y * s3)
    return big_a, big_b, big_c, big_d, big_e, big_f


@functools.lru_cache(maxsize=16)
def _basis_coefficients(geometry):
    """Fourier coefficients of the seven basis functions of equation (7).

    Returns an array (7, 7): row j is basis function j, columns are
    ``(a0, a1, b1, a2, b2, a3, b3)`` of ``a0 + sum a_k cos k alpha + b_k sin k alpha``.
    """
    n = 16
    alpha = 2 * np.pi * np.arange(n) / n
    big_a, big_b, big_c, big_d, big_e, big_f = _linear_terms(alpha, geometry)
    k1 = big_b * big_f - big_e * big_c
    k2 = big_d * big_c - big_a * big_f
    delta = big_a * big_e - big_b * big_d
    basis = np.stack([
        big_e**2 + big_d**2,
        -2 * (big_e * big_b + big_d * big_a),
        big_a**2 + big_b**2,
        2 * (big_e * k1 - big_d * k2),
        2 * (big_a * k2 - big_b * k1),
        k1**2 + k2**2,
        delta**2,
    ], axis=-2)
    spectrum = np.fft.rfft(basis, axis=-1) / n
    coeffs = np.empty(basis.shape[:-1] + (7,))
    coeffs[..., 0] = spectrum[..., 0].real
    coeffs[..., 1::2] = 2 * spectrum[..., 1:4].real
    coeffs[..., 2::2] = -2 * spectrum[..., 1:4].imag
    return coeffs


# Equation (7) with base points per row is sampled at _ROW_SAMPLES
# orientations in one compiled pass: a trigonometric cubic (its degree-4
# harmonics cancel, and would alias only into the harmonic 4 dropped) is
# fixed by 8 samples, and no basis is built per row.
_ROW_SAMPLES = 8


@numba.njit(cache=True, nogil=True)
def _moving_base_coefficients(bases, rho, platform):
    """Equation (7)'s Fourier coefficients for base points per row: the
    terms of :func:`_linear_terms` combined as :func:`_basis_coefficients`
    and :func:`_equation7_coefficients` combine them.

    ``bases`` has shape (n, 3, 2) [length unit], ``rho`` (n, 3) [length
    unit], ``platform`` is ``(d1, d3, beta)``; returns shape (n, 7),
    ``(a0, a1, b1, a2, b2, a3, b3)``.
    """
    d1, d3, beta = platform
    n = _ROW_SAMPLES
    cos1, sin1 = np.empty(n), np.empty(n)
    cos3, sin3 = np.empty(n), np.empty(n)
    # The discrete Fourier transform onto (a0, a1, b1, ..., b3).
    transform = np.empty((n, 7))
    for j in range(n):
        alpha = 2 * math.pi * j / n
        cos1[j], sin1[j] = math.cos(alpha), math.sin(alpha)
        cos3[j], sin3[j] = math.cos(alpha + beta), math.sin(alpha + beta)
        transform[j, 0] = 1.0 / n
        for k in range(1, 4):
            transform[j, 2 * k - 1] = 2.0 / n * math.cos(k * alpha)
            transform[j, 2 * k] = 2.0 / n * math.sin(k * alpha)
    out = np.zeros((bases.shape[0], 7))
    for r in range(bases.shape[0]):
        # Leg 1 at the origin, as in _linear_terms.
        a2x, a2y = bases[r, 1, 0] - bases[r, 0, 0], bases[r, 1, 1] - bases[r, 0, 1]
        a3x, a3y = bases[r, 2, 0] - bases[r, 0, 0], bases[r, 2, 1] - bases[r, 0, 1]
        far2 = d1 * d1 + a2x * a2x + a2y * a2y
        far3 = d3 * d3 + a3x * a3x + a3y * a3y
        u = rho[r, 1] ** 2 - rho[r, 0] ** 2
        v = rho[r, 2] ** 2 - rho[r, 0] ** 2
        w = rho[r, 0] ** 2
        for j in range(n):
            big_a = -2 * a2x + 2 * d1 * cos1[j]
            big_b = -2 * a2y + 2 * d1 * sin1[j]
            big_c = far2 - 2 * d1 * (a2x * cos1[j] + a2y * sin1[j])
            big_d = -2 * a3x + 2 * d3 * cos3[j]
            big_e = -2 * a3y + 2 * d3 * sin3[j]
            big_f = far3 - 2 * d3 * (a3x * cos3[j] + a3y * sin3[j])
            k1 = big_b * big_f - big_e * big_c
            k2 = big_d * big_c - big_a * big_f
            delta = big_a * big_e - big_b * big_d
            value = (u * u * (big_e * big_e + big_d * big_d)
                     - 2 * u * v * (big_e * big_b + big_d * big_a)
                     + v * v * (big_a * big_a + big_b * big_b)
                     + 2 * u * (big_e * k1 - big_d * k2) + 2 * v * (big_a * k2 - big_b * k1)
                     + k1 * k1 + k2 * k2 - w * delta * delta)
            for m in range(7):
                out[r, m] += value * transform[j, m]
    return out


@numba.njit(cache=True, nogil=True)
def _moving_base_linear(points, rho, rows, alpha, platform):
    """The linear formula of :func:`_solve` for base points per row, root by
    root: the arithmetic of :func:`_linear_terms` and :func:`_solve`, in
    their order, so the poses are numpy's to the bit.

    ``points`` has shape (n, 3, 2) [length unit], ``rho`` (n, 3) [length
    unit]; root k is ``alpha[k]`` of row ``rows[k]``; ``platform`` is
    ``(d1, d3, beta, d1**2, d3**2)``, the squares as :func:`_linear_terms`
    takes them (Python's power, not a product).  Returns the candidate
    poses (m, 3), the terms ``(A, B, D, E, g, h)`` (6, m) that
    :func:`_degenerate_poses` takes, and per root whether it is regular
    (``_DEGENERATE_TOL``) and whether it is to be polished (``_POLISH_TOL``).
    """
    d1, d3, beta, d1_squared, d3_squared = platform
    m = alpha.size
    candidate = np.empty((m, 3))
    terms = np.empty((6, m))
    regular = np.empty(m, dtype=np.bool_)
    rough = np.empty(m, dtype=np.bool_)
    for k in range(m):
        row = rows[k]
        # Leg 1 at the origin, as in _linear_terms.
        a1x, a1y = points[row, 0, 0], points[row, 0, 1]
        a2x, a2y = points[row, 1, 0] - a1x, points[row, 1, 1] - a1y
        a3x, a3y = points[row, 2, 0] - a1x, points[row, 2, 1] - a1y
        c1, s1 = math.cos(alpha[k]), math.sin(alpha[k])
        c3, s3 = math.cos(alpha[k] + beta), math.sin(alpha[k] + beta)
        big_a = -2 * a2x + 2 * d1 * c1
        big_b = -2 * a2y + 2 * d1 * s1
        big_c = d1_squared + a2x * a2x + a2y * a2y - 2 * d1 * (a2x * c1 + a2y * s1)
        big_d = -2 * a3x + 2 * d3 * c3
        big_e = -2 * a3y + 2 * d3 * s3
        big_f = d3_squared + a3x * a3x + a3y * a3y - 2 * d3 * (a3x * c3 + a3y * s3)
        r1, r2, r3 = rho[row, 0], rho[row, 1], rho[row, 2]
        g = r2 * r2 - r1 * r1 - big_c
        h = r3 * r3 - r1 * r1 - big_f
        delta = big_a * big_e - big_b * big_d
        scale = abs(big_a * big_e) + abs(big_b * big_d) + 1.0
        regular[k] = abs(delta) > _DEGENERATE_TOL * scale
        rough[k] = abs(delta) < _POLISH_TOL * scale
        safe = delta if regular[k] else 1.0
        candidate[k, 0] = (big_e * g - big_b * h) / safe + a1x
        candidate[k, 1] = (big_a * h - big_d * g) / safe + a1y
        candidate[k, 2] = alpha[k]
        terms[0, k], terms[1, k], terms[2, k] = big_a, big_b, big_d
        terms[3, k], terms[4, k], terms[5, k] = big_e, g, h
    return candidate, terms, regular, rough


@numba.njit(cache=True, nogil=True)
def _moving_base_fake(points, rho, rows, poses, platform, limit):
    """Which poses miss their legs by more than ``limit``, as :func:`_solve`
    judges them from :func:`_residuals` (a NaN residual is no miss), for
    base points per row: pose k is of row ``rows[k]``, ``platform`` is
    ``(d1, d3, beta)``."""
    d1, d3, beta = platform
    fake = np.empty(poses.shape[0], dtype=np.bool_)
    for k in range(poses.shape[0]):
        row = rows[k]
        parameters = (points[row, 0, 0], points[row, 0, 1], points[row, 1, 0],
                      points[row, 1, 1], points[row, 2, 0], points[row, 2, 1], d1, d3, beta)
        e1, e2, e3 = _leg_residuals(_row_terms(poses[k, 0], poses[k, 1], poses[k, 2], parameters),
                                    (rho[row, 0], rho[row, 1], rho[row, 2]))
        fake[k] = (e1 == e1 and e2 == e2 and e3 == e3
                   and (abs(e1) > limit or abs(e2) > limit or abs(e3) > limit))
    return fake


def _tan_half_matrix():
    """Map from trigonometric coefficients to the sextic in t = tan(phi / 2).

    ``(1 + t**2)**3 exp(i k phi) = (1 + i t)**(2 k) (1 + t**2)**(3 - k)``.
    Rows follow ``(a0, a1, b1, a2, b2, a3, b3)``; columns are ascending powers.
    """
    one_it = np.array([1.0, 1.0j])
    one_t2 = np.array([1.0, 0.0, 1.0])
    rows = []
    for k in range(4):
        poly = np.polynomial.polynomial.polymul(
            np.polynomial.polynomial.polypow(one_it, 2 * k),
            np.polynomial.polynomial.polypow(one_t2, 3 - k))
        poly = np.pad(poly, (0, 7 - len(poly)))
        rows.append(poly.real)
        if k:
            rows.append(poly.imag)
    return np.array(rows)


_TAN_HALF = _tan_half_matrix()


def _trig_basis(phi):
    """Basis values ``(1, cos phi, sin phi, ..., sin 3 phi)``, shape (7, len(phi))."""
    rows = [np.ones_like(phi)]
    for k in (1, 2, 3):
        rows += [np.cos(k * phi), np.sin(k * phi)]
    return np.array(rows)


def _equation7_coefficients(rho1, rho2, rho3, geometry):
    u = rho2**2 - rho1**2
    v = rho3**2 - rho1**2
    weights = np.stack([u * u, u * v, v * v, u, v, np.ones_like(u), -rho1**2], axis=-1)
    return weights @ _basis_coefficients(geometry)


def _shift(coeffs, alpha0):
    """Coefficients of ``phi -> f(alpha0 + phi)``."""
    out = coeffs.copy()
    for k in (1, 2, 3):
        c, s = np.cos(k * alpha0), np.sin(k * alpha0)
        a, b = coeffs[:, 2 * k - 1], coeffs[:, 2 * k]
        out[:, 2 * k - 1] = a * c + b * s
        out[:, 2 * k] = b * c - a * s
    return out


def _real_roots(coeffs):
    """Real roots of trigonometric cubics, shape (n, 6) [rad], NaN-padded."""
    # Sampling settles most rows, those whose roots are simple and apart;
    # only where roots come close to merging (near the singular locus) does
    # it take every root of the sextic.
    certified, roots = sampled_roots(coeffs, _SAMPLES, MAX_SOLUTIONS)
    hard = np.flatnonzero(~certified)
    if hard.size:
        h = 2 * np.pi / _SAMPLES
        phi = h * np.arange(_SAMPLES)
        coeffs = coeffs[hard]
        values = coeffs @ _trig_basis(phi)
        roots[hard] = np.sort(_companion_roots(coeffs, phi, values), axis=1)
    return roots


def _companion_roots(coeffs, phi, values):
    """Real roots from the eigenvalues of the sextic's companion matrix."""
    # Put t = inf where |f| is largest so the sextic keeps its degree.
    alpha0 = phi[np.argmax(np.abs(values), axis=1)] + np.pi
    poly = _shift(coeffs, alpha0) @ _TAN_HALF
    companion = np.zeros((len(coeffs), 6, 6))
    companion[:, np.arange(1, 6), np.arange(5)] = 1.0
    companion[:, :, 5] = -poly[:, :6] / poly[:, 6:7]
    t = np.linalg.eigvals(companion)
    # Im(2 atan(a + ib)) = 2b / (1 + a**2) to first order in the small b
    # that decides whether a root is real.
    real = np.abs(2 * t.imag) < _IMAG_TOL * (1 + t.real**2)
    return np.where(real, wrap_angle(2 * np.arctan(t.real) + alpha0[:, None]), np.nan)


class _BasePerRow:
    """A 3-RPR geometry whose base points differ per row of a batch: it
    answers the attributes the batch solver reads of a :class:`ThreeRPR`
    (``a1``..``a3`` as pairs of arrays, shape (n,)), keeps the base points
    as one array ``points`` (n, 3, 2), and :meth:`take` gives the rows the
    solver works on next."""

    def __init__(self, points, platform):
        self.points = points
        self.a1, self.a2, self.a3 = ((points[:, i, 0], points[:, i, 1]) for i in range(3))
        self.d1, self.d3, self.beta = platform.d1, platform.d3, platform.beta
        self.scale = platform.scale
        self.parameters = (*self.a1, *self.a2, *self.a3, self.d1, self.d3, self.beta)

    def take(self, index):
        """The rows ``index`` (integer or boolean array)."""
        return _BasePerRow(self.points[index], self)


def _take(geometry, index):
    """Rows ``index`` of per-row base points; a fixed geometry is its own."""
    return geometry.take(index) if isinstance(geometry, _BasePerRow) else geometry


def solve_with_bases(rho, bases, platform):
    """Direct kinematics of 3-RPRs whose base points differ per row.

    The batch solver of :meth:`ThreeRPR.solve` (same sextic, root finder and
    ordering), for mechanisms that reduce to a 3-RPR whose base points move
    with their joints, such as the 3-RRR (base points its elbows).

    Parameters
    ----------
    rho : ndarray, shape (n, 3)
        Leg lengths [length unit], finite and non-negative.
    bases : ndarray, shape (n, 3, 2)
        Base points A1..A3 of each row [length unit], finite.
    platform : ThreeRPR
        Gives the platform (``d1``, ``d3``, ``beta``) and the scale; its base
        points are not used.

    Returns
    -------
    count : ndarray of uint8, shape (n,)
    poses : ndarray, shape (n, 6, 3)
        As :meth:`ThreeRPR.solve`'s.
    """
    rho = _as_rho(rho)
    bases = np.ascontiguousarray(bases, dtype=float)
    if rho.ndim != 2 or bases.shape != (rho.shape[0], 3, 2):
        raise InvalidInputError(
            f"rho must have shape (n, 3) and bases (n, 3, 2), got {rho.shape}, {bases.shape}")
    if not np.all(np.isfinite(bases)):
        raise InvalidInputError("base points contain NaN or infinity")
    return _solve(rho, _BasePerRow(bases, platform))


def _linear_poses(a, r, geometry):
    """The poses of orientations ``a`` (m,) by equation (7)'s linear formula,
    legs ``r`` (m, 3), one root a row (``geometry`` of m rows or fixed).

    Returns
    -------
    candidate : ndarray, shape (m, 3)
    terms : tuple of ndarray
        ``(A, B, D, E, g, h)`` of the formula, which a degenerate root needs.
    regular, rough : ndarray of bool, shape (m,)
        Whether the formula holds there, and whether it lost digits.
    """
    big_a, big_b, big_c, big_d, big_e, big_f = _linear_terms(a, geometry)
    g = r[:, 1] ** 2 - r[:, 0] ** 2 - big_c
    h = r[:, 2] ** 2 - r[:, 0] ** 2 - big_f
    delta = big_a * big_e - big_b * big_d
    scale = np.abs(big_a * big_e) + np.abs(big_b * big_d) + 1.0
    regular = np.abs(delta) > _DEGENERATE_TOL * scale
    safe = np.where(regular, delta, 1.0)
    x = (big_e * g - big_b * h) / safe
    y = (big_a * h - big_d * g) / safe
    ax, ay = geometry.a1
    candidate = np.stack([x + ax, y + ay, a], axis=-1)
    return (candidate, (big_a, big_b, big_d, big_e, g, h), regular,
            np.abs(delta) < _POLISH_TOL * scale)


def _solve(rho, geometry):
    """:meth:`ThreeRPR.solve` of checked legs, shape (n, 3); ``geometry`` a
    :class:`ThreeRPR` or a :class:`_BasePerRow` of n rows."""
    n = rho.shape[0]
    moving = isinstance(geometry, _BasePerRow)
    if moving:
        coeffs = _moving_base_coefficients(geometry.points, rho,
                                           (geometry.d1, geometry.d3, geometry.beta))
    else:
        coeffs = _equation7_coefficients(rho[:, 0], rho[:, 1], rho[:, 2], geometry)
    alpha = _real_roots(coeffs)
    poses = np.full((n, MAX_SOLUTIONS, 3), np.nan)
    rows, cols = np.nonzero(np.isfinite(alpha))
    if rows.size == 0:
        return np.zeros(n, dtype=np.uint8), poses
    a = alpha[rows, cols]
    r = rho[rows]
    # From here on one entry per root: root k is of row rows[k].
    if moving:
        # One compiled pass: numpy's would copy every root's base points and
        # take a dozen temporaries the size of the roots.
        candidate, terms, regular, rough = _moving_base_linear(
            geometry.points, rho, rows, a,
            (geometry.d1, geometry.d3, geometry.beta, geometry.d1**2, geometry.d3**2))
    else:
        candidate, terms, regular, rough = _linear_poses(a, r, geometry)
    big_a, big_b, big_d, big_e, g, h = terms
    if not np.all(regular):
        candidate[~regular] = _degenerate_poses(
            r[~regular], a[~regular], rows[~regular], big_a[~regular], big_b[~regular],
            big_d[~regular], big_e[~regular], g[~regular], h[~regular],
            _take(geometry, rows[~regular]))
    # Near a degenerate orientation the linear formula loses digits, and the
    # circle construction is only a first guess: polish those poses with
    # Newton (safe there, a degenerate orientation is not a singular one), and
    # keep a polished pose only if it fits the legs better and, for a regular
    # root, stays close (next to a fold, Newton could wander off).
    if np.any(rough):
        before = candidate[rough]
        rough_geometry = _take(geometry, rows[rough])
        after = _newton(before, r[rough], rough_geometry, 3)

        def fit(p):
            return np.max(np.abs(_residuals(p, r[rough], rough_geometry)), axis=-1)

        moved = np.max(np.abs(after - before), axis=-1)
        keep = (fit(after) < fit(before)) & ((moved < 1e-3 * geometry.scale) | ~regular[rough])
        candidate[np.flatnonzero(rough)[keep]] = after[keep]
    # A double root of the sextic at a degenerate orientation whose line of
    # B1 misses leg 1's circle is no pose at all (its B1 is complex): the
    # candidate built for it misses the legs by far more than rounding.
    limit = _FAKE_RESIDUAL * geometry.scale**2
    if moving:
        fake = _moving_base_fake(geometry.points, rho, rows, candidate,
                                 (geometry.d1, geometry.d3, geometry.beta), limit)
    else:
        fake = np.max(np.abs(_residuals(candidate, r, geometry)), axis=-1) > limit
    poses[rows, cols] = candidate
    poses[rows[fake], cols[fake]] = np.nan
    if np.any(fake):
        alpha[rows[fake], cols[fake]] = np.nan
        first = np.argsort(np.isnan(alpha), axis=1, kind="stable")
        poses = np.take_along_axis(poses, first[..., None], axis=1)
        alpha = np.take_along_axis(alpha, first, axis=1)
    poses[..., 2] = wrap_angle(poses[..., 2])
    return np.isfinite(alpha).sum(axis=1).astype(np.uint8), poses


def _residuals(pose, rho, geometry):
    return np.stack(_leg_residuals(_rows(pose, geometry), np.moveaxis(rho, -1, 0)), axis=-1)


def _degenerate_poses(rho, alpha, row, big_a, big_b, big_d, big_e, g, h, geometry):
    """Poses at (near) degenerate orientations, where legs 2 and 3 give
    nearly parallel lines for B1: the two intersections of leg 2's line with
    leg 1's circle are the candidates.  An isolated root takes the one that
    fits leg 3's line better.  The two roots of a close pair (a double root at
    the degenerate orientation, split by rounding) take one candidate each,
    matched so that the pair fits leg 3 best, so they never collapse on one
    pose."""
    norm2 = big_a**2 + big_b**2
    foot = g / norm2
    px, py = big_a * foot, big_b * foot
    half = np.sqrt(np.maximum(rho[:, 0] ** 2 - foot**2 * norm2, 0.0) / norm2)
    plus = np.stack([px - big_b * half, py + big_a * half], axis=-1)
    minus = np.stack([px + big_b * half, py - big_a * half], axis=-1)
    misfit_plus = np.abs(big_d * plus[:, 0] + big_e * plus[:, 1] - h)
    misfit_minus = np.abs(big_d * minus[:, 0] + big_e * minus[:, 1] - h)
    take_plus = misfit_plus <= misfit_minus
    order = np.lexsort((alpha, row))
    first, second = order[:-1], order[1:]
    paired = (row[first] == row[second]) & (np.abs(alpha[second] - alpha[first]) < _PAIR_GAP)
    first, second = first[paired], second[paired]
    straight = misfit_plus[first] + misfit_minus[second]
    crossed = misfit_minus[first] + misfit_plus[second]
    take_plus[first] = straight <= crossed
    take_plus[second] = ~take_plus[first]
    chosen = np.where(take_plus[:, None], plus, minus)
    ax, ay = geometry.a1
    return np.stack([chosen[:, 0] + ax, chosen[:, 1] + ay, alpha], axis=-1)


def _direct_kinematics(rho, geometry):
    """:meth:`ThreeRPR.direct_kinematics` of checked legs, shape (3,)."""
    count, poses = _solve(rho[None, :], geometry)
    return poses[0, : count[0]]


def _degenerate_orientations(geometry):
    """:meth:`ThreeRPR.degenerate_orientations`: the roots of ``AE - BD``,
    a first-order trigonometric polynomial in alpha."""
    n = 16
    alpha = 2 * np.pi * np.arange(n) / n
    big_a, big_b, _, big_d, big_e, _ = _linear_terms(alpha, geometry)
    spectrum = np.fft.rfft(big_a * big_e - big_b * big_d) / n
    # AE - BD has harmonics 0 and 1 only: c0 + c1 cos + s1 sin.
    c0, c1, s1 = spectrum[0].real, 2 * spectrum[1].real, -2 * spectrum[1].imag
    amplitude = math.hypot(c1, s1)
    if amplitude <= abs(c0):
        return np.array([])
    phase = math.atan2(s1, c1)
    offset = math.acos(-c0 / amplitude)
    return np.sort(wrap_angle(np.array([phase + offset, phase - offset])))

