"""The planar five-bar (5R) as a :class:`Mechanism`.

Conventions: base joints ``A1 = (0, 0)`` and ``A2 = (d, 0)``; the actuated
angles ``(th1, th2)`` [rad] turn the proximal links of length ``l1`` to the
elbows ``C_i = A_i + l1 (cos th_i, sin th_i)``; the distal links of length
``l2`` meet at the end effector ``P = (x, y)``.  The constraint equations
are ``F_i = |P - C_i|**2 - l2**2 = 0``; with ``u_i = P - C_i``

    Jx = dF/dP = 2 (u1; u2),    Jq = dF/dq = diag(-2 u_i . dC_i/dth_i).

The direct kinematics intersects the circles of radius ``l2`` around the
elbows: with ``dist = |C2 - C1|``, ``e = (C2 - C1) / dist``, ``n`` the
vector ``e`` turned by +90 degrees, ``M = (C1 + C2) / 2`` and
``h = sqrt(l2**2 - dist**2 / 4)`` the solutions are ``M + h n`` then
``M - h n``, none when ``dist > 2 l2``.  On a solution
``cross(u1, u2) = +-dist h``, so the parallel singularities (``det Jx = 0``)
are the fold ``dist = 2 l2`` (C1, P and C2 aligned, the two solutions merge)
and the joints where the elbows coincide (``dist = 0``), whose direct
kinematics is the whole circle of radius ``l2`` around them, every pose of
it singular; ``M + h n`` has the positive aspect, ``M - h n`` the negative.

Unlike the 3-RPR's, the five-bar's pose ``(x, y)`` does not fix its passive
joints: each elbow may sit on either side of the line from its base to P.
Its margin therefore needs the joints as well as the pose
(:meth:`FiveBar.margin`).
"""

from dataclasses import dataclass
import functools
import math

import numba
from numba.extending import register_jitable
import numpy as np

from ..exceptions import InvalidInputError, SingularityError
from .base import (PREDICT_KERNEL_SIGNATURE, STEP_KERNEL_SIGNATURE, Mechanism, finite_vectors,
                   first_class, positive_length, register_mechanism, revolute_leg_angles)

__all__ = ["FiveBar", "DEFAULT_FIVE_BAR", "COINCIDENT_ELBOWS"]

# Elbows closer than this [scale] count as coinciding: the direct kinematics
# is then refused, as the circle of singular poses it is near.  Both
# solutions of such joints have a margin below dist / l2, at most
# 1e-6 (l1 + l2) / l2: for the usual proportions (l1 and l2 alike) three
# orders below the planner's smallest accepted margin (1e-3), so nothing
# usable is lost.  And the coincidence point given to six decimals (rounded
# by up to 5e-7 rad, which parts the elbows by up to about 7e-7 l1) still
# counts as coinciding, not as two near-singular poses.
COINCIDENT_ELBOWS = 1e-6

# The scalar continuation step, as the 3-RPR's: converged when both residuals
# are below _RESIDUAL_TOL * scale**2 after at most _NEWTON_STEPS corrector
# steps, refused when the corrector moved the pose more than _JUMP_RATIO
# times the predictor's move plus _JUMP_FLOOR * scale (the predictor is
# first order, so a longer correction landed on the other solution).
_NEWTON_STEPS = 6
_RESIDUAL_TOL = 1e-9
_JUMP_RATIO = 0.5
_JUMP_FLOOR = 1e-7


@register_mechanism("5R")
@dataclass(frozen=True)
class FiveBar(Mechanism):
    """The planar five-bar mechanism (5R).

    Joints are the actuated angles ``(th1, th2)`` [rad] of the proximal
    links at ``A1 = (0, 0)`` and ``A2 = (d, 0)``; poses are the end
    effector ``(x, y)`` [m] (the point P where the distal links meet), and
    ``y`` chooses the assembly mode of a request.  A pose has up to 4
    working modes (:meth:`inverse_kinematics`), one elbow branch per leg:
    sign +1 where the elbow angle (``elbow{i}`` of :meth:`body_outline`,
    the direction of ``C_i P`` relative to ``A_i C_i``) lies in
    ``[0, pi]``, -1 where it lies in ``(-pi, 0)``.  Batches follow
    :class:`~rpr3_gwr_core.mechanisms.base.Mechanism`: joints and poses
    ``(..., 2)``; :meth:`solve` takes joints ``(n, 2)`` and gives counts
    ``(n,)`` (uint8) and poses ``(n, 2, 2)``, ``M + h n`` (aspect +1)
    before ``M - h n`` (aspect -1), NaN beyond the count (module doc).

    Attributes
    ----------
    d : float
        Distance A1 A2 between the base joints [m].
    l1 : float
        Proximal links A_i C_i [m].
    l2 : float
        Distal links C_i P [m].

    Raises
    ------
    InvalidInputError
        If a length is not a finite positive number.
    """

    d: float = 0.118
    l1: float = 0.09
    l2: float = 0.118

    joint_names = ("th1", "th2")
    angular_joints = (True, True)
    pose_names = ("x", "y")
    angular = (False, False)
    mode_coordinate = 1
    leg_branches = 2
    max_solutions = 2

    def __post_init__(self):
        for name in ("d", "l1", "l2"):
            object.__setattr__(self, name, positive_length(getattr(self, name), name))

    @property
    def scale(self):
        """``l1 + l2``, the reach of a leg [m]: no pose coordinate is an angle,
        so it only sets the continuation's and the roadmap's tolerances."""
        return self.l1 + self.l2

    @property
    def parameters(self):
        """``(d, l1, l2)``: the geometry as the constraint equations take it."""
        return (self.d, self.l1, self.l2)

    def to_dict(self):
        """Plain-data form, for JSON, messages and cache keys."""
        return {"kind": self.kind, "d": self.d, "l1": self.l1, "l2": self.l2}

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(d=data["d"], l1=data["l1"], l2=data["l2"])
        except (KeyError, TypeError) as exc:
            raise InvalidInputError(f"malformed five-bar: {exc}") from exc

    def elbow_distance(self, joints):
        """``|C2 - C1|`` of joints ``(..., 2)`` [m], shape (...)."""
        joints = finite_vectors(joints, "joints", 2)
        return np.hypot(*_elbow_gap(joints[..., 0], joints[..., 1], self.parameters))

    # The Mechanism interface, served by the functions below.

    def check_joints(self, joints):
        """Refuse joints the five-bar cannot be planned from.

        Parameters
        ----------
        joints : array_like, shape (..., 2)

        Raises
        ------
        InvalidInputError
            If a joint is not a finite number or the shape is not (..., 2).
        SingularityError
            If the elbows coincide (closer than ``COINCIDENT_ELBOWS * scale``).
        """
        joints = finite_vectors(joints, "joints", 2)
        dist = self.elbow_distance(joints)
        if np.any(dist < COINCIDENT_ELBOWS * self.scale):
            k = int(np.argmin(dist.ravel()))
            at = tuple(joints.reshape(-1, 2)[k].tolist())
            raise SingularityError(
                f"the elbows C1 and C2 coincide at (th1, th2) = {at} (|C2 - C1| = "
                f"{float(dist.ravel()[k]):.1e} m): the direct kinematics is a whole circle of "
                f"singular poses, of radius l2 = {self.l2:g} m around them")

    def body_outline(self, poses, joints):
        """Proximal links ``A_i C_i`` and distal links ``C_i P``, and the
        passive angles: ``elbow{i}`` the distal link's direction relative to
        the proximal one, ``end`` that of ``C2 P`` relative to ``C1 P``
        (:meth:`Mechanism.body_outline`)."""
        th = np.asarray(joints)
        end = np.asarray(poses)[..., :2]
        base = np.broadcast_to(np.array([[0.0, 0.0], [self.d, 0.0]]), th.shape + (2,))
        elbow = base + self.l1 * np.stack([np.cos(th), np.sin(th)], axis=-1)
        distal = np.arctan2(end[..., None, 1] - elbow[..., 1], end[..., None, 0] - elbow[..., 0])
        links = []
        for i in range(2):
            links.append((f"proximal{i + 1}", i, (f"A{i + 1}", f"C{i + 1}"), base[..., i, :],
                          elbow[..., i, :], False))
            links.append((f"distal{i + 1}", i, (f"C{i + 1}", "P"), elbow[..., i, :], end, False))
        relative = np.concatenate([distal - th, distal[..., 1:] - distal[..., :1]], axis=-1)
        relative = np.arctan2(np.sin(relative), np.cos(relative))
        passive = [("elbow1", relative[..., 0]), ("elbow2", relative[..., 1]),
                   ("end", relative[..., 2])]
        return links, [], passive

    def leg_joints(self, poses):
        """Each leg's angle at end points on both of its branches
        (:meth:`Mechanism.leg_joints`).

        Parameters
        ----------
        poses : array_like, shape (..., 2)
            ``(x, y)`` of P [m], finite.

        Returns
        -------
        ndarray, shape (..., 2, 2)
            ``th_i`` [rad] in (-pi, pi]; NaN where a leg cannot reach P.
        """
        poses = finite_vectors(poses, "poses", 2)
        bases = np.array([[0.0, 0.0], [self.d, 0.0]])
        return revolute_leg_angles(bases, poses[..., None, :], self.l1, self.l2)

    def solve(self, joints):
        joints = finite_vectors(joints, "joints", 2)
        if joints.ndim != 2:
            raise InvalidInputError(f"joints must have shape (n, 2), got {joints.shape}")
        return _solve(joints, self)

    def margin(self, poses, joints=None):
        """Signed, normalised distance from a parallel singularity:
        ``cross(u1 / |u1|, u2 / |u2|)``, the normalised ``det Jx``.

        Parameters
        ----------
        poses : array_like, shape (..., 2)
        joints : array_like, shape (..., 2)
            The joints of the poses (broadcast against them).  Required: the
            pose alone does not fix the elbows.

        Returns
        -------
        ndarray, shape (...)
            In [-1, 1], 0 on a singularity (and where a leg has zero length),
            its sign the aspect; a NumPy scalar for one pose.

        Raises
        ------
        TypeError
            Without ``joints``.
        """
        if joints is None:
            raise TypeError(
                "the five-bar's margin needs the joints as well as the poses: a pose (x, y) "
                "does not fix the elbows C1, C2 (each may sit on either side of the line "
                "from its base to the end effector), so the sign of det Jx is not a "
                "function of the pose; call margin(poses, joints)")
        poses, joints = np.asarray(poses, dtype=float), np.asarray(joints, dtype=float)
        u1x, u1y, u2x, u2y, _, _ = _rows(poses[..., 0], poses[..., 1], joints[..., 0],
                                         joints[..., 1], self.parameters)
        return _margin_rows(u1x, u1y, u2x, u2y)[()]

    def aspect(self, poses, joints=None):
        """``sign(margin)``: +1 or -1, 0 exactly on a singularity, int8, shape (...)."""
        return np.sign(self.margin(poses, joints)).astype(np.int8)

    def predict(self, poses, joints_from, joints_to):
        poses, joints_from, joints_to = (np.asarray(a, dtype=float)
                                         for a in (poses, joints_from, joints_to))
        u1x, u1y, u2x, u2y, w1, w2 = _rows(poses[..., 0], poses[..., 1], joints_from[..., 0],
                                           joints_from[..., 1], self.parameters)
        dq = joints_to - joints_from
        # Jx dx = -Jq dq, both sides halved: (u1; u2) dx = (w1 dq1, w2 dq2).
        return poses + _solve_rows(u1x, u1y, u2x, u2y, w1 * dq[..., 0], w2 * dq[..., 1])

    def correct(self, poses, joints, iterations):
        poses, joints = np.asarray(poses, dtype=float), np.asarray(joints, dtype=float)
        for _ in range(iterations):
            u1x, u1y, u2x, u2y, _, _ = _rows(poses[..., 0], poses[..., 1], joints[..., 0],
                                             joints[..., 1], self.parameters)
            f1, f2 = _leg_residuals(u1x, u1y, u2x, u2y, self.l2)
            # dF/dP = 2 (u1; u2): the Newton step is half the rows' solution.
            poses = poses - 0.5 * _solve_rows(u1x, u1y, u2x, u2y, f1, f2)
        return poses

    def residual(self, poses, joints):
        poses, joints = np.asarray(poses, dtype=float), np.asarray(joints, dtype=float)
        u1x, u1y, u2x, u2y, _, _ = _rows(poses[..., 0], poses[..., 1], joints[..., 0],
                                         joints[..., 1], self.parameters)
        return np.stack(np.broadcast_arrays(*_leg_residuals(u1x, u1y, u2x, u2y, self.l2)),
                        axis=-1)

    def step(self, pose, joints_from, joints_to):
        x, y = (float(v) for v in pose)
        ok, x, y, margin = _compiled_step(self.parameters, self.scale, x, y,
                                          *(float(v) for v in joints_from),
                                          *(float(v) for v in joints_to))
        return ((x, y), margin) if ok else None

    @functools.cached_property
    def step_kernel(self):
        return (first_class(_step_kernel, STEP_KERNEL_SIGNATURE),
                np.array([*self.parameters, self.scale]))

    @functools.cached_property
    def predict_kernel(self):
        return first_class(_predict_kernel, PREDICT_KERNEL_SIGNATURE), np.array(self.parameters)


# A commercial five-bar's proportions, so that the roadmap meets what a real
# one does: d < 2 l1, so its elbows can coincide, and 81.5 % of its joint
# torus is assembled.
DEFAULT_FIVE_BAR = FiveBar(d=0.118, l1=0.09, l2=0.118)


# The constraint equations are written once, as arithmetic that runs on numpy
# arrays for batches (the field, continuity) and, compiled by numba, on floats
# for the sequential continuation (validator, driver), where numpy's per-call
# cost would dominate.

@register_jitable
def _elbow_gap(th1, th2, parameters):
    """``C2 - C1``, as one expression so that every caller agrees on it."""
    d, l1, _ = parameters
    return d + l1 * (np.cos(th2) - np.cos(th1)), l1 * (np.sin(th2) - np.sin(th1))


@register_jitable
def _rows(x, y, th1, th2, parameters):
    """Entries of ``Jx / 2`` (the legs ``u_i = P - C_i``) and of ``-Jq / 2``
    (``w_i = u_i . dC_i/dth_i``)."""
    d, l1, _ = parameters
    c1, s1, c2, s2 = np.cos(th1), np.sin(th1), np.cos(th2), np.sin(th2)
    u1x, u1y = x - l1 * c1, y - l1 * s1
    u2x, u2y = x - d - l1 * c2, y - l1 * s2
    return u1x, u1y, u2x, u2y, l1 * (c1 * u1y - s1 * u1x), l1 * (c2 * u2y - s2 * u2x)


@register_jitable
def _leg_residuals(u1x, u1y, u2x, u2y, l2):
    return u1x * u1x + u1y * u1y - l2 * l2, u2x * u2x + u2y * u2y - l2 * l2


def _solve_rows(u1x, u1y, u2x, u2y, r1, r2):
    """``(u1; u2)^-1 r``, shape (..., 2); a singular system gives 0."""
    det = u1x * u2y - u1y * u2x
    inv = np.where(det != 0, 1.0 / np.where(det != 0, det, 1.0), 0.0)
    return np.stack(np.broadcast_arrays((u2y * r1 - u1y * r2) * inv,
                                        (u1x * r2 - u2x * r1) * inv), axis=-1)


def _margin_rows(u1x, u1y, u2x, u2y):
    # Each leg normalised before the cross product, so that tiny legs do not
    # underflow the product of the norms.
    n1, n2 = np.hypot(u1x, u1y), np.hypot(u2x, u2y)
    ok = (n1 > 0) & (n2 > 0)
    n1, n2 = np.where(ok, n1, 1.0), np.where(ok, n2, 1.0)
    return np.where(ok, (u1x / n1) * (u2y / n2) - (u1y / n1) * (u2x / n2), 0.0)


def _solve(joints, mechanism):
    n = joints.shape[0]
    _, l1, l2 = mechanism.parameters
    th1, th2 = joints[:, 0], joints[:, 1]
    gx, gy = _elbow_gap(th1, th2, mechanism.parameters)
    dist = np.hypot(gx, gy)
    real = (dist <= 2 * l2) & (dist >= COINCIDENT_ELBOWS * mechanism.scale)
    safe = np.where(real, dist, 1.0)
    # n = e turned by +90 degrees, scaled by h; h as a product of the two
    # factors keeps its digits next to the fold, where dist is close to 2 l2.
    half = 0.5 * np.where(real, dist, 0.0)
    h = np.sqrt((l2 - half) * (l2 + half))
    hx, hy = -gy / safe * h, gx / safe * h
    mx = 0.5 * (l1 * np.cos(th1) + mechanism.d + l1 * np.cos(th2))
    my = 0.5 * (l1 * np.sin(th1) + l1 * np.sin(th2))
    poses = np.full((n, 2, 2), np.nan)
    poses[real, 0, 0], poses[real, 0, 1] = (mx + hx)[real], (my + hy)[real]
    poses[real, 1, 0], poses[real, 1, 1] = (mx - hx)[real], (my - hy)[real]
    return np.where(real, 2, 0).astype(np.uint8), poses


@numba.njit(cache=True)
def _compiled_step(parameters, scale, x, y, a1, a2, b1, b2):
    """One predictor-corrector step from joints ``(a1, a2)`` to ``(b1, b2)``:
    ``(converged, x, y, margin)``."""
    l2 = parameters[2]
    u1x, u1y, u2x, u2y, w1, w2 = _rows(x, y, a1, a2, parameters)
    det = u1x * u2y - u1y * u2x
    if det == 0.0:
        return False, x, y, 0.0
    r1, r2 = w1 * (b1 - a1), w2 * (b2 - a2)
    px, py = x + (u2y * r1 - u1y * r2) / det, y + (u1x * r2 - u2x * r1) / det
    predicted = math.hypot(px - x, py - y)
    x, y = px, py
    tol = _RESIDUAL_TOL * scale * scale
    for _ in range(_NEWTON_STEPS):
        u1x, u1y, u2x, u2y, _, _ = _rows(x, y, b1, b2, parameters)
        f1, f2 = _leg_residuals(u1x, u1y, u2x, u2y, l2)
        if max(abs(f1), abs(f2)) < tol:
            if math.hypot(x - px, y - py) > _JUMP_RATIO * predicted + _JUMP_FLOOR * scale:
                return False, x, y, 0.0
            n1, n2 = math.hypot(u1x, u1y), math.hypot(u2x, u2y)
            if n1 == 0.0 or n2 == 0.0:
                return True, x, y, 0.0
            return True, x, y, (u1x / n1) * (u2y / n2) - (u1y / n1) * (u2x / n2)
        det = u1x * u2y - u1y * u2x
        if det == 0.0:
            return False, x, y, 0.0
        x -= 0.5 * (u2y * f1 - u1y * f2) / det
        y -= 0.5 * (u1x * f2 - u2x * f1) / det
    return False, x, y, 0.0


@numba.njit(STEP_KERNEL_SIGNATURE, cache=True)
def _step_kernel(parameters, pose, joints_from, joints_to):
    """:func:`_compiled_step` as :data:`~.base.STEP_KERNEL_SIGNATURE` takes
    it; ``parameters`` are :attr:`FiveBar.parameters`, then the scale."""
    p = parameters
    ok, x, y, margin = _compiled_step((p[0], p[1], p[2]), p[3], pose[0], pose[1],
                                      joints_from[0], joints_from[1], joints_to[0],
                                      joints_to[1])
    if not ok:
        return np.nan
    pose[0], pose[1] = x, y
    return margin


@numba.njit(cache=True, nogil=True)
def _predict_kernel(parameters, poses, joints_from, joints_to, out):
    """:meth:`FiveBar.predict` of the solutions of one joint vector, as
    :data:`~.base.PREDICT_KERNEL_SIGNATURE` takes it; ``parameters`` are
    :attr:`FiveBar.parameters`."""
    geometry = (parameters[0], parameters[1], parameters[2])
    a1, a2 = joints_from[0], joints_from[1]
    dq1, dq2 = joints_to[0] - a1, joints_to[1] - a2
    for r in range(poses.shape[0]):
        u1x, u1y, u2x, u2y, w1, w2 = _rows(poses[r, 0], poses[r, 1], a1, a2, geometry)
        r1, r2 = w1 * dq1, w2 * dq2
        det = u1x * u2y - u1y * u2x
        # A singular system leaves the pose, as _solve_rows does.
        inv = 1.0 / det if det != 0.0 else 0.0
        out[r, 0] = poses[r, 0] + (u2y * r1 - u1y * r2) * inv
        out[r, 1] = poses[r, 1] + (u1x * r2 - u2x * r1) * inv
