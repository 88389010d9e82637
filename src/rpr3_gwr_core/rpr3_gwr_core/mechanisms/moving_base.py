"""The 3-RPR whose base points move with its joints: the reduction that
the 3-RRR (:mod:`.rrr3`) and the 3-PRR (:mod:`.prr3`) share.

With its joints fixed, a mechanism whose three legs of one length
``distal`` join moving base points ``C_i`` to the 3-RPR's platform points
``B_i`` is a 3-RPR whose base points are the ``C_i``: the 3-RRR's elbows,
``C_i = A_i + l1 (cos q_i, sin q_i)``, the 3-PRR's slider joints,
``C_i = A_i + q_i e_i``.  Its direct kinematics is the three-leg solver's
sextic with base points per joint vector
(:func:`~.three_leg_solver.solve_with_bases`), so at most six solutions;
with ``u_i = B_i - C_i`` the constraint equations
``F_i = |B_i - C_i|**2 - distal**2 = 0`` give

    Jx / 2 = rows (u_i, (B_i - B1) x u_i),    -Jq / 2 = diag(u_i . dC_i/dq_i).

One set of compiled kernels serves both mechanisms, told by the
mechanism's :attr:`MovingBaseRPR.parameters` whether the joints turn or
slide the base points.  The margin normalises ``Jx`` as the 3-RPR's does;
a serial singularity (``u_i`` parallel to ``dC_i/dq_i``) is no obstacle to
moving in joint space and is not treated as one.
"""

import dataclasses
import functools
import math

import numba
from numba.extending import register_jitable
import numpy as np

from ..exceptions import InvalidInputError
from .base import (PREDICT_KERNEL_SIGNATURE, STEP_KERNEL_SIGNATURE, Mechanism, finite_vectors,
                   first_class)
from .rpr3 import ThreeRPR
from .three_leg_solver import (
    MAX_SOLUTIONS,
    adjugate_product,
    corrected,
    leg_residuals,
    row_terms,
    rows_margin,
    solve_with_bases,
)

__all__ = ["MovingBaseRPR"]

# Newton steps that polish the direct kinematics' poses, at most (fewer once
# the legs fit within _POLISH_FIT [scale**2], rounding's reach), and how far
# [scale] a polished pose may move in any case (far beyond the roots' error,
# far below the gap between two regular solutions); it may move farther
# while it stays nearer its start than every other solution of its joints.
_POLISH_STEPS = 6
_POLISH_FIT = 1e-13
_POLISH_REACH = 1e-4


class MovingBaseRPR(Mechanism):
    """A 3-RPR whose base points move with the joints and whose legs all have
    one length: with its joints fixed, the 3-RRR (base points its elbows)
    and the 3-PRR (base points its slider joints) are such 3-RPRs.

    The direct kinematics, margin, predictor, corrector and residuals are the
    3-RPR's with the moving base points ``C_i``, compiled once for every such
    mechanism: the kernels below read how the ``C_i`` follow the joints from
    :attr:`parameters`.  A subclass gives

    * ``_actuation``: the tail ``(revolute, reach, e1x, e1y, e2x, e2y, e3x,
      e3y)`` of :attr:`parameters`;
    * ``distal``: the legs' length;
    * ``_moving_points``: what the margin's error message calls the ``C_i``;
    * ``_legs_reaching``: each leg's joint, on both branches, whose ``C_i``
      lies at ``distal`` from given platform points (the inverse kinematics).

    Subclasses are frozen dataclasses with the fields ``a1, a2, a3, d1, d3,
    beta``.
    """

    joint_names = ("q1", "q2", "q3")
    pose_names = ("x", "y", "alpha")
    angular = (False, False, True)
    mode_coordinate = 2
    leg_branches = 2
    max_solutions = MAX_SOLUTIONS
    angle_parameters = ("beta",)
    _moving_points = "base points C_i"
    _POINTS = ("a1", "a2", "a3")

    def _check_platform(self):
        """Check and convert the base points and platform as the 3-RPR of the
        same ones does, so that both accept and refuse the same values."""
        platform = ThreeRPR(a1=self.a1, a2=self.a2, a3=self.a3, d1=self.d1, d3=self.d3,
                            beta=self.beta)
        for name in ("a1", "a2", "a3", "d1", "d3", "beta"):
            object.__setattr__(self, name, getattr(platform, name))

    def to_dict(self):
        """Plain-data form, for JSON, messages and cache keys: the kind and
        every field, points as lists."""
        return {"kind": self.kind, **{
            f.name: list(getattr(self, f.name)) if f.name in self._POINTS
            else getattr(self, f.name) for f in dataclasses.fields(self)}}

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(**{f.name: tuple(data[f.name]) if f.name in cls._POINTS
                          else data[f.name] for f in dataclasses.fields(cls)})
        except (KeyError, TypeError) as exc:
            raise InvalidInputError(f"malformed {cls.kind}: {exc}") from exc

    @functools.cached_property
    def platform(self):
        """The 3-RPR of the same base points and platform: with the joints
        fixed the mechanism is it with the C_i as base points."""
        return ThreeRPR(a1=self.a1, a2=self.a2, a3=self.a3, d1=self.d1, d3=self.d3,
                        beta=self.beta)

    @functools.cached_property
    def scale(self):
        """Longest platform side [length unit], as the 3-RPR's: it makes the
        orientation column of ``Jx`` commensurable with positions."""
        return self.platform.scale

    @functools.cached_property
    def parameters(self):
        """``(a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta, distal, scale,
        revolute, reach, e1x, e1y, e2x, e2y, e3x, e3y)``: the geometry as the
        compiled kernels (and, as an array, :attr:`step_kernel`) take it.

        ``revolute`` is 1.0 where each joint turns a proximal link of length
        ``reach``, ``C_i = A_i + reach (cos q_i, sin q_i)`` (the ``e_i``
        unused), and 0.0 where it slides ``C_i = A_i + q_i e_i`` along the
        unit vector ``e_i`` (``reach`` 1): ``reach`` bounds how far [length
        unit] a ``C_i`` moves per unit of its joint.
        """
        return (*self.a1, *self.a2, *self.a3, self.d1, self.d3, self.beta, self.distal,
                self.scale, *self._actuation)

    def base_points(self, joints):
        """The moving base points ``C_i`` of joints ``(..., 3)``.

        Returns
        -------
        ndarray, shape (..., 3, 2)
            [length unit].
        """
        joints = finite_vectors(joints, "joints", 3)
        (rows,) = _rows(joints.shape, joints)
        return _moving_bases(rows, self.parameters).reshape(joints.shape[:-1] + (3, 2))

    def leg_joints(self, poses):
        """Each leg's joint at poses on both of its branches
        (:meth:`Mechanism.leg_joints`): the joints whose ``C_i`` lies at
        ``distal`` from the platform point ``B_i``.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            ``(x, y, alpha)`` [length unit, length unit, rad], finite.

        Returns
        -------
        ndarray, shape (..., 3, 2)
            [joint unit]; NaN where a leg cannot reach its platform point.
        """
        return self._legs_reaching(self.platform.platform_points(poses))

    def body_outline(self, poses, joints):
        """Proximal links ``A_i C_i`` (the 3-PRR's slid part of its rail),
        distal links ``C_i B_i``, the platform triangle, and the passive
        angles: ``elbow{i}`` the distal link's direction relative to
        ``A_i C_i``, ``platform{i}`` relative to the platform
        (:meth:`Mechanism.body_outline`)."""
        points = self.platform.platform_points(poses)
        moving = self.base_points(joints)
        base = np.broadcast_to(self.platform.base, moving.shape)
        distal = np.arctan2(points[..., 1] - moving[..., 1], points[..., 0] - moving[..., 0])
        proximal = np.arctan2(moving[..., 1] - base[..., 1], moving[..., 0] - base[..., 0])
        elbow, relative = distal - proximal, distal - np.asarray(poses)[..., 2:3]
        links = []
        for i in range(3):
            links.append((f"proximal{i + 1}", i, (f"A{i + 1}", f"C{i + 1}"), base[..., i, :],
                          moving[..., i, :], False))
            links.append((f"distal{i + 1}", i, (f"C{i + 1}", f"B{i + 1}"), moving[..., i, :],
                          points[..., i, :], False))
        passive = [(f"{name}{i + 1}", np.arctan2(np.sin(a[..., i]), np.cos(a[..., i])))
                   for name, a in (("elbow", elbow), ("platform", relative)) for i in range(3)]
        return links, [("platform", ("B1", "B2", "B3"), points)], passive

    def check_joints(self, joints):
        """Refuse joints that are not finite numbers of shape (..., 3).

        Raises
        ------
        InvalidInputError
        """
        finite_vectors(joints, "joints", 3)

    def solve(self, joints):
        """All real direct-kinematic solutions of many joint vectors.

        Parameters
        ----------
        joints : array_like, shape (n, 3)
            ``(q1, q2, q3)`` [joint unit], finite.

        Returns
        -------
        count : ndarray of uint8, shape (n,)
        poses : ndarray, shape (n, 6, 3)
            ``(x, y, alpha)`` [length unit, length unit, rad], sorted by alpha
            in (-pi, pi], NaN beyond ``count``.
        """
        joints = finite_vectors(joints, "joints", 3)
        if joints.ndim != 2:
            raise InvalidInputError(f"joints must have shape (n, 3), got {joints.shape}")
        (rows,) = _rows(joints.shape, joints)
        bases = _moving_bases(rows, self.parameters)
        count, poses = solve_with_bases(np.full(joints.shape, self.distal), bases, self.platform)
        # Where two roots of the sextic are close the root finder leaves
        # their poses off the legs by up to about 1e-5 [length unit**2], even
        # when both are regular (two assembly modes at nearly one alpha); the
        # 3-RRR, whose base points move with its joints, meets such joints
        # far more often than the 3-RPR.  Newton on the pose equations
        # restores full precision; a polished pose is kept only if it fits
        # better and stayed close (or nearer its start than any other
        # solution), so that Newton never trades one solution for another.
        _polish(poses, count, bases, self.parameters)
        return count, poses

    def margin(self, poses, joints=None):
        """Signed, normalised distance from a parallel singularity.

        Each row ``(u_i, (B_i - B1) x u_i / scale)`` of ``Jx / 2`` (the
        orientation column over :attr:`scale`) is divided by its norm before
        the determinant (Hadamard's bound), as the 3-RPR's margin.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
        joints : array_like, shape (..., 3)
            The joints of the poses (broadcast against them).  Required: the
            pose alone does not fix the base points ``C_i``.

        Returns
        -------
        ndarray, shape (...)
            In [-1, 1], 0 on a singularity (and where a distal link has zero
            length), its sign the aspect; a NumPy scalar for one pose.

        Raises
        ------
        TypeError
            Without ``joints``.
        """
        if joints is None:
            raise TypeError(
                f"the {self.kind}'s margin needs the joints as well as the poses: a pose "
                f"does not fix the {self._moving_points}, so the sign of det Jx is not a "
                "function of the pose; call margin(poses, joints)")
        shape, (poses, joints) = _batch(poses, joints)
        return _moving_margin(poses, joints, self.parameters).reshape(shape[:-1])[()]

    def aspect(self, poses, joints=None):
        """``sign(margin)``: +1 or -1, 0 exactly on a singularity, int8, shape (...)."""
        return np.sign(self.margin(poses, joints)).astype(np.int8)

    def predict(self, poses, joints_from, joints_to):
        """Euler step ``Jx dx = -Jq dq`` of poses ``(..., 3)`` for a change of
        joints (a revolute joint's the short way round)."""
        shape, rows = _batch(poses, joints_from, joints_to)
        return _moving_euler(*rows, self.parameters).reshape(shape)

    def correct(self, poses, joints, iterations):
        """Newton steps on the constraint equations at fixed joints.

        Parameters
        ----------
        poses : ndarray, shape (..., 3)
            Initial guesses; not modified.
        joints : ndarray, shape (..., 3)
        iterations : int

        Returns
        -------
        ndarray, shape (..., 3)
            Corrected poses (alpha is not wrapped).
        """
        shape, (poses, joints) = _batch(poses, joints)
        return _moving_newton(poses, joints, self.parameters, int(iterations)).reshape(shape)

    def residual(self, poses, joints):
        """Constraint residuals ``F_i = |B_i - C_i|**2 - distal**2``.

        Returns
        -------
        ndarray, shape (..., 3)
            One per leg [length unit**2].
        """
        shape, (poses, joints) = _batch(poses, joints)
        return _moving_residuals(poses, joints, self.parameters).reshape(shape)

    def step(self, pose, joints_from, joints_to):
        x, y, alpha = (float(v) for v in pose)
        ok, x, y, alpha, margin = _compiled_step(
            self.parameters, x, y, alpha, *(float(v) for v in joints_from),
            *(float(v) for v in joints_to))
        return ((x, y, alpha), margin) if ok else None

    @functools.cached_property
    def step_kernel(self):
        return first_class(_step_kernel, STEP_KERNEL_SIGNATURE), np.array(self.parameters)

    @functools.cached_property
    def predict_kernel(self):
        return first_class(_predict_kernel, PREDICT_KERNEL_SIGNATURE), np.array(self.parameters)


def _batch(*arrays):
    """Arrays of shape (..., 3) broadcast together: their shape, and each as
    rows (:func:`_rows`)."""
    arrays = [np.asarray(a, dtype=float) for a in arrays]
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    return shape, _rows(shape, *arrays)


def _rows(shape, *arrays):
    """Each float array broadcast to ``shape`` (..., 3), as rows (n, 3) that
    are C-contiguous and writeable: the one layout the kernels are compiled
    for.  An array already so is not copied."""
    out = []
    for a in arrays:
        if a.shape != shape:
            a = np.broadcast_to(a, shape)
        out.append(np.require(a.reshape(-1, 3), requirements="CW"))
    return out


# The kernels: the 3-RPR's row arithmetic on the moving base points, one row
# of a batch (or the one pose of a step) at a time, so that no temporary
# scales with the batch.  ``geometry`` is :attr:`MovingBaseRPR.parameters`;
# a batch kernel types ``base`` with ``geometry[:9]`` before its loop, and
# :func:`_row_rpr` replaces it at the first row.

@register_jitable
def _geometry_tuple(p):
    """:attr:`MovingBaseRPR.parameters` from their array, as the kernels take them."""
    return (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11], p[12],
            p[13], p[14], p[15], p[16], p[17], p[18])


@register_jitable
def _moving_rpr(geometry, q1, q2, q3):
    """The 3-RPR parameters ``(c1x, c1y, c2x, c2y, c3x, c3y, d1, d3, beta)``
    of joints ``(q1, q2, q3)``: its base points are the ``C_i``."""
    (a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta, _, _, revolute, reach,
     e1x, e1y, e2x, e2y, e3x, e3y) = geometry
    if revolute:
        return (a1x + reach * np.cos(q1), a1y + reach * np.sin(q1), a2x + reach * np.cos(q2),
                a2y + reach * np.sin(q2), a3x + reach * np.cos(q3), a3y + reach * np.sin(q3),
                d1, d3, beta)
    return (a1x + q1 * e1x, a1y + q1 * e1y, a2x + q2 * e2x, a2y + q2 * e2y, a3x + q3 * e3x,
            a3y + q3 * e3y, d1, d3, beta)


@register_jitable
def _row_rpr(geometry, joints, r, previous):
    """:func:`_moving_rpr` of row ``r`` of joints (n, 3), or ``previous``,
    that of row ``r - 1``, when the row repeats it: a batch's rows come
    grouped by joints (a cell's solutions one after the other), and the
    base points cost most of a row's sines and cosines."""
    if r > 0 and joints[r, 0] == joints[r - 1, 0] and joints[r, 1] == joints[r - 1, 1] \
            and joints[r, 2] == joints[r - 1, 2]:
        return previous
    return _moving_rpr(geometry, joints[r, 0], joints[r, 1], joints[r, 2])


@register_jitable
def _joint_rates(geometry, rows, base):
    """``u_i . dC_i/dq_i``, the diagonal of ``-Jq / 2``, from the rows of
    ``Jx / 2`` and the 3-RPR parameters ``base`` (:func:`_moving_rpr`) of the
    joints."""
    a1x, a1y, a2x, a2y, a3x, a3y = geometry[:6]
    e1x, e1y, e2x, e2y, e3x, e3y = geometry[13:]
    if geometry[11]:
        # dC_i/dq_i is C_i - A_i turned a quarter, which spares the joints'
        # sines and cosines.
        c1x, c1y, c2x, c2y, c3x, c3y = base[:6]
        e1x, e1y, e2x, e2y = a1y - c1y, c1x - a1x, a2y - c2y, c2x - a2x
        e3x, e3y = a3y - c3y, c3x - a3x
    u1x, u1y, u2x, u2y, _, u3x, u3y, _ = rows
    return u1x * e1x + u1y * e1y, u2x * e2x + u2y * e2y, u3x * e3x + u3y * e3y


@register_jitable
def _joint_change(geometry, start, end):
    """The change of a joint from ``start`` to ``end``: a revolute joint's
    the short way round, in [-pi, pi]."""
    change = end - start
    if geometry[11]:
        return change - 2 * np.pi * np.floor(change / (2 * np.pi) + 0.5)
    return change


@register_jitable
def _newton_step(rows, legs, x, y, alpha):
    """One Newton step of the pose ``(x, y, alpha)`` of rows ``rows`` onto
    ``legs``; a singular system leaves it, as the 3-RPR's ``solve_rows``."""
    e1, e2, e3 = leg_residuals(rows, legs)
    (dx, dy, da), det = adjugate_product(rows, e1, e2, e3)
    inv = 1.0 / det if det != 0.0 else 0.0
    return x - 0.5 * dx * inv, y - 0.5 * dy * inv, alpha - 0.5 * da * inv


@register_jitable
def _misfit(rows, legs):
    """The largest leg residual of a pose's rows [length unit**2]."""
    e1, e2, e3 = leg_residuals(rows, legs)
    return max(abs(e1), abs(e2), abs(e3))


@numba.njit(cache=True, nogil=True)
def _moving_bases(joints, geometry):
    """:meth:`MovingBaseRPR.base_points` of joints (n, 3), shape (n, 3, 2)."""
    out = np.empty((joints.shape[0], 3, 2))
    for r in range(joints.shape[0]):
        base = _moving_rpr(geometry, joints[r, 0], joints[r, 1], joints[r, 2])
        for k in range(6):
            out[r, k // 2, k % 2] = base[k]
    return out


@numba.njit(cache=True, nogil=True)
def _polish(poses, count, bases, geometry):
    """:meth:`MovingBaseRPR.solve`'s polish, in place: Newton steps of each
    pose ``poses[r, :count[r]]`` (shape (n, 6, 3)) on the 3-RPR of base
    points ``bases[r]`` (shape (n, 3, 2)), kept if it fits the legs better
    and did not move to another solution (the constants above)."""
    d1, d3, beta, distal, scale = geometry[6:11]
    legs = (distal, distal, distal)
    for r in range(poses.shape[0]):
        parameters = (bases[r, 0, 0], bases[r, 0, 1], bases[r, 1, 0], bases[r, 1, 1],
                      bases[r, 2, 0], bases[r, 2, 1], d1, d3, beta)
        for s in range(count[r]):
            x, y, alpha = poses[r, s, 0], poses[r, s, 1], poses[r, s, 2]
            rows = row_terms(x, y, alpha, parameters)
            misfit = polished = _misfit(rows, legs)
            px, py, palpha = x, y, alpha
            for _ in range(_POLISH_STEPS):
                if polished < _POLISH_FIT * scale * scale:
                    break
                px, py, palpha = _newton_step(rows, legs, px, py, palpha)
                rows = row_terms(px, py, palpha, parameters)
                polished = _misfit(rows, legs)
            if not polished < misfit:
                continue
            moved = _pose_gap(px, py, palpha, x, y, alpha, scale)
            if moved >= _POLISH_REACH * scale and _another_within(
                    poses[r], count[r], s, px, py, palpha, moved, scale):
                continue
            poses[r, s, 0], poses[r, s, 1] = px, py
            poses[r, s, 2] = math.pi - (math.pi - palpha) % (2 * math.pi)


@register_jitable
def _another_within(poses, count, slot, x, y, alpha, reach, scale):
    """Whether a solution of ``poses[:count]`` other than ``slot`` lies
    within ``reach`` of the pose ``(x, y, alpha)``."""
    for t in range(count):
        if t != slot and _pose_gap(x, y, alpha, poses[t, 0], poses[t, 1], poses[t, 2],
                                   scale) <= reach:
            return True
    return False


@register_jitable
def _pose_gap(x, y, alpha, x2, y2, alpha2, scale):
    """Distance of two poses, the orientations' short way round at ``scale``."""
    turn = alpha - alpha2
    turn -= 2 * math.pi * math.floor(turn / (2 * math.pi) + 0.5)
    return math.sqrt((x - x2) ** 2 + (y - y2) ** 2 + (turn * scale) ** 2)


@register_jitable
def _euler(geometry, base, x, y, alpha, changes):
    """The Euler step of the pose ``(x, y, alpha)`` for the joint changes
    ``changes`` (:func:`_joint_change`), its 3-RPR parameters ``base``
    (:func:`_moving_rpr` of the joints it starts from)."""
    rows = row_terms(x, y, alpha, base)
    v1, v2, v3 = _joint_rates(geometry, rows, base)
    (dx, dy, da), det = adjugate_product(rows, v1 * changes[0], v2 * changes[1],
                                          v3 * changes[2])
    # A singular system leaves the pose, as the 3-RPR's solve_rows does.
    inv = 1.0 / det if det != 0.0 else 0.0
    return x + dx * inv, y + dy * inv, alpha + da * inv


@register_jitable
def _joint_changes(geometry, start, end):
    """:func:`_joint_change` of each of three joints (arrays of shape (3,))."""
    return (_joint_change(geometry, start[0], end[0]), _joint_change(geometry, start[1], end[1]),
            _joint_change(geometry, start[2], end[2]))


@numba.njit(cache=True, nogil=True)
def _moving_euler(poses, joints_from, joints_to, geometry):
    """:meth:`MovingBaseRPR.predict` of poses (n, 3) from joints (n, 3) to
    joints (n, 3)."""
    out = np.empty_like(poses)
    base = geometry[:9]
    for r in range(poses.shape[0]):
        base = _row_rpr(geometry, joints_from, r, base)
        out[r, 0], out[r, 1], out[r, 2] = _euler(
            geometry, base, poses[r, 0], poses[r, 1], poses[r, 2],
            _joint_changes(geometry, joints_from[r], joints_to[r]))
    return out


@numba.njit(cache=True, nogil=True)
def _predict_kernel(parameters, poses, joints_from, joints_to, out):
    """:func:`_moving_euler` of the solutions of one joint vector, as
    :data:`~.base.PREDICT_KERNEL_SIGNATURE` takes it; ``parameters`` are
    :attr:`MovingBaseRPR.parameters`."""
    geometry = _geometry_tuple(parameters)
    base = _moving_rpr(geometry, joints_from[0], joints_from[1], joints_from[2])
    changes = _joint_changes(geometry, joints_from, joints_to)
    for r in range(poses.shape[0]):
        out[r, 0], out[r, 1], out[r, 2] = _euler(geometry, base, poses[r, 0], poses[r, 1],
                                                 poses[r, 2], changes)


@numba.njit(cache=True, nogil=True)
def _moving_margin(poses, joints, geometry):
    """:meth:`MovingBaseRPR.margin` of poses (n, 3) at joints (n, 3), shape (n,)."""
    out = np.empty(poses.shape[0])
    base = geometry[:9]
    for r in range(poses.shape[0]):
        base = _row_rpr(geometry, joints, r, base)
        out[r] = rows_margin(row_terms(poses[r, 0], poses[r, 1], poses[r, 2], base),
                              geometry[10])
    return out


@numba.njit(cache=True, nogil=True)
def _moving_newton(poses, joints, geometry, iterations):
    """:meth:`MovingBaseRPR.correct` of poses (n, 3) at joints (n, 3):
    ``iterations`` Newton steps each."""
    distal = geometry[9]
    legs = (distal, distal, distal)
    out = np.empty_like(poses)
    base = geometry[:9]
    for r in range(poses.shape[0]):
        base = _row_rpr(geometry, joints, r, base)
        x, y, alpha = poses[r, 0], poses[r, 1], poses[r, 2]
        for _ in range(iterations):
            x, y, alpha = _newton_step(row_terms(x, y, alpha, base), legs, x, y, alpha)
        out[r, 0], out[r, 1], out[r, 2] = x, y, alpha
    return out


@numba.njit(cache=True, nogil=True)
def _moving_residuals(poses, joints, geometry):
    """:meth:`MovingBaseRPR.residual` of poses (n, 3) at joints (n, 3), shape (n, 3)."""
    distal = geometry[9]
    out = np.empty_like(poses)
    base = geometry[:9]
    for r in range(poses.shape[0]):
        base = _row_rpr(geometry, joints, r, base)
        out[r, 0], out[r, 1], out[r, 2] = leg_residuals(
            row_terms(poses[r, 0], poses[r, 1], poses[r, 2], base), (distal, distal, distal))
    return out


@numba.njit(cache=True)
def _compiled_step(geometry, x, y, alpha, a1, a2, a3, b1, b2, b3):
    """One predictor-corrector step from joints ``(a1, a2, a3)`` to
    ``(b1, b2, b3)``: ``(converged, x, y, alpha, margin)``."""
    distal, scale, reach = geometry[9], geometry[10], geometry[12]
    base = _moving_rpr(geometry, a1, a2, a3)
    rows = row_terms(x, y, alpha, base)
    v1, v2, v3 = _joint_rates(geometry, rows, base)
    q1, q2, q3 = (_joint_change(geometry, a1, b1), _joint_change(geometry, a2, b2),
                  _joint_change(geometry, a3, b3))
    (dx, dy, da), det = adjugate_product(rows, v1 * q1, v2 * q2, v3 * q3)
    if det == 0.0:
        return False, x, y, alpha, 0.0
    px, py, palpha = x + dx / det, y + dy / det, alpha + da / det
    # The corrector's move is measured against the predictor's, or against
    # the base points' move if that is longer: where a leg is stretched or
    # folded, or perpendicular to its slider (a serial singularity, no
    # obstacle), its joint moves the platform only to second order, and the
    # predictor's move alone would refuse every step across it.
    predicted = max(math.sqrt((dx / det) ** 2 + (dy / det) ** 2 + (da / det * scale) ** 2),
                    reach * max(abs(q1), abs(q2), abs(q3)))
    return corrected(_moving_rpr(geometry, b1, b2, b3), (distal, distal, distal), scale, px,
                      py, palpha, predicted)


@numba.njit(STEP_KERNEL_SIGNATURE, cache=True)
def _step_kernel(parameters, pose, joints_from, joints_to):
    """:func:`_compiled_step` as :data:`~.base.STEP_KERNEL_SIGNATURE` takes
    it; ``parameters`` are :attr:`MovingBaseRPR.parameters`."""
    ok, x, y, alpha, margin = _compiled_step(
        _geometry_tuple(parameters), pose[0], pose[1], pose[2], joints_from[0],
        joints_from[1], joints_from[2], joints_to[0], joints_to[1], joints_to[2])
    if not ok:
        return np.nan
    pose[0], pose[1], pose[2] = x, y, alpha
    return margin
