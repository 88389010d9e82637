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
3-RPR's sextic, solved by the 3-RPR's batch solver with base points per
joint vector (:func:`~.rpr3.solve_with_bases`), so at most six solutions.
That reduction (:class:`_MovingBaseRPR`) is shared with the 3-PRR
(:mod:`.prr3`), whose base points are its slider joints.

Parallel singularities are ``det Jx = 0``; the margin normalises ``Jx`` as
the 3-RPR's does.  A serial singularity (a leg stretched or folded, ``u_i``
parallel to ``dC_i/dth_i``) is no obstacle to moving in joint space and is
not treated as one.  As the five-bar's, the pose alone does not fix the
elbows, so :meth:`ThreeRRR.margin` needs the joints.
"""

import dataclasses
from dataclasses import dataclass
import functools
import math

import numba
from numba import types
from numba.core.types.function_type import CompileResultWAP
from numba.extending import register_jitable
import numpy as np

from ..exceptions import InvalidInputError
from .base import (STEP_KERNEL_SIGNATURE, Mechanism, finite_vectors, positive_length,
                   register_mechanism)
from .rpr3 import (
    MAX_SOLUTIONS,
    ThreeRPR,
    _adjugate_product,
    _corrected,
    _leg_residuals,
    _rows_margin,
    _row_terms,
    beta_from_sides,
    solve_with_bases,
)

__all__ = ["ThreeRRR", "DEFAULT_THREE_RRR"]

# Newton steps that polish the direct kinematics' poses, at most (fewer once
# the legs fit within _POLISH_FIT [scale**2], rounding's reach), and how far
# [scale] a polished pose may move in any case (far beyond the roots' error,
# far below the gap between two regular solutions); it may move farther
# while it stays nearer its start than every other solution of its joints.
_POLISH_STEPS = 6
_POLISH_FIT = 1e-13
_POLISH_REACH = 1e-4


class _MovingBaseRPR(Mechanism):
    """A 3-RPR whose base points move with the joints and whose legs all have
    one length: with its joints fixed, the 3-RRR (base points its elbows)
    and the 3-PRR (base points its slider joints) are such 3-RPRs.

    The direct kinematics, margin, predictor, corrector and residuals are the
    3-RPR's with the moving base points ``C_i``; a subclass gives them by

    * ``_base_parameters(parameters, q1, q2, q3)``: the 3-RPR parameters
      ``(c1x, c1y, c2x, c2y, c3x, c3y, d1, d3, beta)`` of its joints (a
      ``register_jitable`` function, as a staticmethod);
    * ``_directions(base)``: ``dC_i/dq_i`` as rows ``(x1, y1, x2, y2, x3,
      y3)`` (shape (6, ...)) from the 3-RPR parameters ``base`` of the
      joints: ``u_i . dC_i/dq_i`` is the diagonal of ``-Jq / 2``;
    * ``_change(joints_from, joints_to)``: the joints' change;
    * ``distal``: the legs' length; ``parameters``: its geometry as a tuple;
    * ``_compiled_step`` and ``_step_kernel``: its step compiled by numba;
    * ``_moving_points``: what the margin's error message calls the ``C_i``.

    Subclasses are frozen dataclasses with the fields ``a1, a2, a3, d1, d3,
    beta``.
    """

    joint_names = ("q1", "q2", "q3")
    pose_names = ("x", "y", "alpha")
    angular = (False, False, True)
    mode_coordinate = 2
    max_solutions = MAX_SOLUTIONS
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

    def base_points(self, joints):
        """The moving base points ``C_i`` of joints ``(..., 3)``.

        Returns
        -------
        ndarray, shape (..., 3, 2)
            [length unit].
        """
        joints = finite_vectors(joints, "joints", 3)
        c1x, c1y, c2x, c2y, c3x, c3y, *_ = self._base_parameters(
            self.parameters, joints[..., 0], joints[..., 1], joints[..., 2])
        return np.stack([np.stack([c1x, c1y], -1), np.stack([c2x, c2y], -1),
                         np.stack([c3x, c3y], -1)], -2)

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
            ``(th1, th2, th3)`` [rad], finite.

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
        legs = np.full(joints.shape, self.distal)
        bases = self.base_points(joints)
        count, poses = solve_with_bases(legs, bases, self.platform)
        # Where two roots of the sextic are close the root finder leaves
        # their poses off the legs by up to about 1e-5 [length unit**2], even
        # when both are regular (two assembly modes at nearly one alpha); the
        # 3-RRR, whose base points move with its joints, meets such joints
        # far more often than the 3-RPR.  Newton on the pose equations
        # restores full precision; a polished pose is kept only if it fits
        # better and stayed close (or nearer its start than any other
        # solution), so that Newton never trades one solution for another.
        _polish(poses, count, bases.reshape(-1, 6).T, (self.d1, self.d3, self.beta), self.distal,
                self.scale)
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
            pose alone does not fix the elbows.

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
        poses, joints = np.broadcast_arrays(np.asarray(poses, dtype=float),
                                            np.asarray(joints, dtype=float))
        bases = _coordinates(self._moving_parameters(joints))
        return _moving_margin(poses.reshape(-1, 3), bases, (self.d1, self.d3, self.beta),
                              self.scale).reshape(poses.shape[:-1])[()]

    def aspect(self, poses, joints=None):
        """``sign(margin)``: +1 or -1, 0 exactly on a singularity, int8, shape (...)."""
        return np.sign(self.margin(poses, joints)).astype(np.int8)

    def predict(self, poses, joints_from, joints_to):
        """Euler step ``Jx dx = -Jq dq`` of poses ``(..., 3)`` for a change of
        joints (the change as ``_change`` takes it: the short way round for
        angles)."""
        poses = np.asarray(poses, dtype=float)
        joints_from = np.asarray(joints_from, dtype=float)
        change = self._change(joints_from, np.asarray(joints_to, dtype=float))
        poses, joints_from, change = np.broadcast_arrays(poses, joints_from, change)
        base = self._moving_parameters(joints_from)
        return _moving_euler(poses.reshape(-1, 3), _coordinates(base),
                             self._directions(base).reshape(6, -1), change.reshape(-1, 3),
                             (self.d1, self.d3, self.beta)).reshape(poses.shape)

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
        poses, joints = np.broadcast_arrays(np.asarray(poses, dtype=float),
                                            np.asarray(joints, dtype=float))
        # The joints stay: their base points are computed once.
        bases = _coordinates(self._moving_parameters(joints))
        return _moving_newton(poses.reshape(-1, 3), bases, (self.d1, self.d3, self.beta),
                              self.distal, int(iterations)).reshape(poses.shape)

    def residual(self, poses, joints):
        """Constraint residuals ``F_i = |B_i - C_i|**2 - distal**2``.

        Returns
        -------
        ndarray, shape (..., 3)
            One per leg [length unit**2].
        """
        rows = self._rows(poses, joints)
        l2 = self.distal
        return np.stack(np.broadcast_arrays(*_leg_residuals(rows, (l2, l2, l2))), axis=-1)

    def step(self, pose, joints_from, joints_to):
        x, y, alpha = (float(v) for v in pose)
        ok, x, y, alpha, margin = self._compiled_step(
            self.parameters, self.scale, x, y, alpha, *(float(v) for v in joints_from),
            *(float(v) for v in joints_to))
        return ((x, y, alpha), margin) if ok else None

    @functools.cached_property
    def step_kernel(self):
        # Its address taken once: passing the dispatcher itself would look it
        # up, under numba's compiler lock, at every call.
        compiled = CompileResultWAP(self._step_kernel.overloads[STEP_KERNEL_SIGNATURE.args])
        # Typed once: numba would otherwise infer its type at every call.
        compiled._numba_type_ = types.FunctionType(STEP_KERNEL_SIGNATURE)
        return compiled, np.array([*self.parameters, self.scale])

    def _moving_parameters(self, joints):
        """The 3-RPR parameters of joints ``(..., 3)`` (``_base_parameters``),
        broadcast to their shape."""
        joints = np.asarray(joints, dtype=float)
        return self._base_parameters(self.parameters, joints[..., 0], joints[..., 1],
                                     joints[..., 2])

    def _rows(self, poses, joints):
        poses = np.asarray(poses, dtype=float)
        return _row_terms(poses[..., 0], poses[..., 1], poses[..., 2],
                          self._moving_parameters(joints))


@register_jitable
def _row_parameters(bases, r, platform):
    """The 3-RPR parameters of column ``r`` of base coordinates (6, n),
    rows ``(c1x, c1y, c2x, c2y, c3x, c3y)``, and a platform ``(d1, d3, beta)``."""
    return (bases[0, r], bases[1, r], bases[2, r], bases[3, r], bases[4, r], bases[5, r],
            *platform)


@register_jitable
def _newton_step(rows, legs, x, y, alpha):
    """One Newton step of the pose ``(x, y, alpha)`` of rows ``rows`` onto
    ``legs``; a singular system leaves it, as the 3-RPR's ``_solve_rows``."""
    e1, e2, e3 = _leg_residuals(rows, legs)
    (dx, dy, da), det = _adjugate_product(rows, e1, e2, e3)
    inv = 1.0 / det if det != 0.0 else 0.0
    return x - 0.5 * dx * inv, y - 0.5 * dy * inv, alpha - 0.5 * da * inv


@register_jitable
def _misfit(rows, legs):
    """The largest leg residual of a pose's rows [length unit**2]."""
    e1, e2, e3 = _leg_residuals(rows, legs)
    return max(abs(e1), abs(e2), abs(e3))


@numba.njit(cache=True, nogil=True)
def _polish(poses, count, bases, platform, distal, scale):
    """:meth:`_MovingBaseRPR.solve`'s polish, in place: Newton steps of each
    pose ``poses[r, :count[r]]`` (shape (n, 6, 3)) on the 3-RPR of base
    coordinates ``bases[:, r]`` (shape (6, n)), platform ``(d1, d3, beta)`` and
    legs ``distal``, kept if it fits the legs better and did not move to
    another solution (the constants above)."""
    legs = (distal, distal, distal)
    for r in range(poses.shape[0]):
        parameters = _row_parameters(bases, r, platform)
        for s in range(count[r]):
            x, y, alpha = poses[r, s, 0], poses[r, s, 1], poses[r, s, 2]
            rows = _row_terms(x, y, alpha, parameters)
            misfit = polished = _misfit(rows, legs)
            px, py, palpha = x, y, alpha
            for _ in range(_POLISH_STEPS):
                if polished < _POLISH_FIT * scale * scale:
                    break
                px, py, palpha = _newton_step(rows, legs, px, py, palpha)
                rows = _row_terms(px, py, palpha, parameters)
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


def _coordinates(base):
    """The base coordinates of 3-RPR parameters ``(c1x, c1y, ..., c3y,
    ...)`` whose coordinates are arrays, as rows, shape (6, n): stacked
    whole rows, far cheaper than interleaved points."""
    return np.array(base[:6]).reshape(6, -1)


@numba.njit(cache=True, nogil=True)
def _moving_euler(poses, bases, directions, change, platform):
    """:meth:`_MovingBaseRPR.predict` of poses (n, 3) on the 3-RPRs of base
    coordinates ``bases`` (6, n), moving along ``directions`` (6, n) by
    ``change`` (n, 3); ``platform`` is ``(d1, d3, beta)``."""
    out = np.empty_like(poses)
    for r in range(poses.shape[0]):
        w, q = directions[:, r], change[r]
        rows = _row_terms(poses[r, 0], poses[r, 1], poses[r, 2],
                          _row_parameters(bases, r, platform))
        u1x, u1y, u2x, u2y, _, u3x, u3y, _ = rows
        (dx, dy, da), det = _adjugate_product(rows, (u1x * w[0] + u1y * w[1]) * q[0],
                                              (u2x * w[2] + u2y * w[3]) * q[1],
                                              (u3x * w[4] + u3y * w[5]) * q[2])
        # A singular system leaves the pose, as the 3-RPR's _solve_rows does.
        inv = 1.0 / det if det != 0.0 else 0.0
        out[r, 0], out[r, 1] = poses[r, 0] + dx * inv, poses[r, 1] + dy * inv
        out[r, 2] = poses[r, 2] + da * inv
    return out


@numba.njit(cache=True, nogil=True)
def _moving_margin(poses, bases, platform, scale):
    """:meth:`_MovingBaseRPR.margin` of poses (n, 3) on the 3-RPRs of base
    coordinates ``bases`` (6, n) and platform ``(d1, d3, beta)``, shape (n,)."""
    out = np.empty(poses.shape[0])
    for r in range(poses.shape[0]):
        out[r] = _rows_margin(_row_terms(poses[r, 0], poses[r, 1], poses[r, 2],
                                         _row_parameters(bases, r, platform)), scale)
    return out


@numba.njit(cache=True, nogil=True)
def _moving_newton(poses, bases, platform, distal, iterations):
    """:meth:`_MovingBaseRPR.correct` of poses (n, 3) on the 3-RPRs of base
    coordinates ``bases`` (6, n), platform ``(d1, d3, beta)`` and legs
    ``distal``: ``iterations`` Newton steps each."""
    legs = (distal, distal, distal)
    out = np.empty_like(poses)
    for r in range(poses.shape[0]):
        parameters = _row_parameters(bases, r, platform)
        x, y, alpha = poses[r, 0], poses[r, 1], poses[r, 2]
        for _ in range(iterations):
            x, y, alpha = _newton_step(_row_terms(x, y, alpha, parameters), legs, x, y, alpha)
        out[r, 0], out[r, 1], out[r, 2] = x, y, alpha
    return out


@register_jitable
def _pose_gap(x, y, alpha, x2, y2, alpha2, scale):
    """Distance of two poses, the orientations' short way round at ``scale``."""
    turn = alpha - alpha2
    turn -= 2 * math.pi * math.floor(turn / (2 * math.pi) + 0.5)
    return math.sqrt((x - x2) ** 2 + (y - y2) ** 2 + (turn * scale) ** 2)


# The constraint equations are the 3-RPR's with the elbows as base points:
# the 3-RPR's row arithmetic serves numpy batches and, compiled by numba,
# the floats of the sequential continuation.

@register_jitable
def _elbow_parameters(parameters, t1, t2, t3):
    """The 3-RPR parameters whose base points are the elbows of ``(t1, t2, t3)``."""
    a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta, l1, _ = parameters
    return (a1x + l1 * np.cos(t1), a1y + l1 * np.sin(t1), a2x + l1 * np.cos(t2),
            a2y + l1 * np.sin(t2), a3x + l1 * np.cos(t3), a3y + l1 * np.sin(t3), d1, d3, beta)


@register_jitable
def _joint_rates(rows, parameters, base):
    """``u_i . dC_i/dth_i``, the diagonal of ``-Jq / 2``, from the elbows
    ``base`` (:func:`_elbow_parameters`): ``dC_i/dth_i`` is ``C_i - A_i``
    turned a quarter, which spares the joints' sines and cosines."""
    u1x, u1y, u2x, u2y, _, u3x, u3y, _ = rows
    a1x, a1y, a2x, a2y, a3x, a3y = parameters[:6]
    c1x, c1y, c2x, c2y, c3x, c3y = base[:6]
    return ((c1x - a1x) * u1y - (c1y - a1y) * u1x, (c2x - a2x) * u2y - (c2y - a2y) * u2x,
            (c3x - a3x) * u3y - (c3y - a3y) * u3x)


@register_jitable
def _turn_difference(change):
    """Joint changes taken the short way round: in [-pi, pi]."""
    return change - 2 * np.pi * np.floor(change / (2 * np.pi) + 0.5)


@numba.njit(cache=True)
def _compiled_step(parameters, scale, x, y, alpha, a1, a2, a3, b1, b2, b3):
    """One predictor-corrector step from joints ``(a1, a2, a3)`` to
    ``(b1, b2, b3)``: ``(converged, x, y, alpha, margin)``."""
    l1, l2 = parameters[9], parameters[10]
    base = _elbow_parameters(parameters, a1, a2, a3)
    rows = _row_terms(x, y, alpha, base)
    v1, v2, v3 = _joint_rates(rows, parameters, base)
    q1, q2, q3 = _turn_difference(b1 - a1), _turn_difference(b2 - a2), _turn_difference(b3 - a3)
    (dx, dy, da), det = _adjugate_product(rows, v1 * q1, v2 * q2, v3 * q3)
    if det == 0.0:
        return False, x, y, alpha, 0.0
    px, py, palpha = x + dx / det, y + dy / det, alpha + da / det
    # The corrector's move is measured against the predictor's, or against
    # the elbows' move if that is longer: where a leg is stretched or folded
    # (a serial singularity, no obstacle) its joint moves the platform only
    # to second order, and the predictor's move alone would refuse every
    # step across it.
    predicted = max(math.sqrt((dx / det) ** 2 + (dy / det) ** 2 + (da / det * scale) ** 2),
                    l1 * max(abs(q1), abs(q2), abs(q3)))
    return _corrected(_elbow_parameters(parameters, b1, b2, b3), (l2, l2, l2), scale, px, py,
                      palpha, predicted)


@numba.njit(STEP_KERNEL_SIGNATURE, cache=True)
def _step_kernel(parameters, pose, joints_from, joints_to):
    """:func:`_compiled_step` as :data:`~.base.STEP_KERNEL_SIGNATURE` takes
    it; ``parameters`` are :attr:`ThreeRRR.parameters`, then the scale."""
    p = parameters
    ok, x, y, alpha, margin = _compiled_step(
        (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10]), p[11],
        pose[0], pose[1], pose[2], joints_from[0], joints_from[1], joints_from[2],
        joints_to[0], joints_to[1], joints_to[2])
    if not ok:
        return np.nan
    pose[0], pose[1], pose[2] = x, y, alpha
    return margin


@register_mechanism("3-RRR")
@dataclass(frozen=True)
class ThreeRRR(_MovingBaseRPR):
    """The planar 3-RRR parallel manipulator.

    Joints are the actuated base angles ``(th1, th2, th3)`` [rad]; poses are
    ``(x, y, alpha)`` [length unit, length unit, rad] as the 3-RPR's, and
    ``alpha`` chooses the assembly mode of a request.  Batches follow
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

    @functools.cached_property
    def parameters(self):
        """``(a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta, l1, l2)``: the geometry
        as the constraint equations (and their compiled form) take it."""
        return (*self.a1, *self.a2, *self.a3, self.d1, self.d3, self.beta, self.l1, self.l2)

    @property
    def distal(self):
        """The legs' length of the 3-RPR it reduces to: ``l2``."""
        return self.l2

    _base_parameters = staticmethod(_elbow_parameters)
    _compiled_step = staticmethod(_compiled_step)
    _step_kernel = staticmethod(_step_kernel)

    def _directions(self, base):
        # dC_i/dth_i is C_i - A_i turned a quarter.
        (a1x, a1y), (a2x, a2y), (a3x, a3y) = self.a1, self.a2, self.a3
        c1x, c1y, c2x, c2y, c3x, c3y = base[:6]
        return np.array([a1y - c1y, c1x - a1x, a2y - c2y, c2x - a2x, a3y - c3y, c3x - a3x])

    def _change(self, joints_from, joints_to):
        return _turn_difference(joints_to - joints_from)

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
