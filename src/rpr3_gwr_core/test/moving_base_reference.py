"""An independent reference for the mechanisms that are 3-RPRs whose base
points move with their joints (the 3-RRR: its elbows; the 3-PRR: its slider
joints), written from their definitions and sharing nothing with the
package: the platform points, the residuals ``|B_i - C_i|**2 - l**2``, the
normalised ``det Jx``, a direct kinematics through the torus of poses at a
fixed first joint, and a continuation of its own.

At a fixed first joint, B1 lies on the circle of radius ``l`` around C1
(angle phi) and alpha is free: the poses form the torus (phi, alpha).  Each
torus point fixes B2 and B3, and the mechanism's closed form (``joint_of``)
gives the other two joints (0, 1 or 2 values, the two ``side`` choices).
The solutions of a joint vector are the torus points mapped onto it.
"""

import math

import numpy as np
import pytest

__all__ = ["MovingBaseReference", "wrap"]


def wrap(angle):
    return np.arctan2(np.sin(angle), np.cos(angle))


class MovingBaseReference:
    """The reference of one mechanism.

    Parameters
    ----------
    bases : callable
        ``C_i`` of joints (..., 3), shape (..., 3, 2).
    joint_of : callable
        ``joint_of(b, i, side)``: joint i whose ``C_i`` lies at ``leg`` from
        the platform points ``b`` (..., 2), on one ``side`` (+1 or -1); NaN
        where there is none.
    leg : float
        The distal links' length.
    d1, d3, beta : float
        The platform.
    angular : bool
        Whether joints are angles (their differences are wrapped).
    """

    def __init__(self, bases, joint_of, leg, d1, d3, beta, angular):
        self.bases, self.joint_of, self.leg = bases, joint_of, leg
        self.d1, self.d3, self.beta = d1, d3, beta
        self.scale = max(d1, d3, math.sqrt(d1**2 + d3**2 - 2 * d1 * d3 * math.cos(beta)))
        self.angular = angular

    def difference(self, a, b):
        """``a - b`` of joints, wrapped for angles."""
        return wrap(a - b) if self.angular else a - b

    def platform(self, pose):
        """B1, B2, B3 of poses (..., 3), shape (..., 3, 2)."""
        pose = np.asarray(pose, dtype=float)
        x, y, alpha = pose[..., 0], pose[..., 1], pose[..., 2]
        b1 = np.stack([x, y], -1)
        b2 = b1 + self.d1 * np.stack([np.cos(alpha), np.sin(alpha)], -1)
        b3 = b1 + self.d3 * np.stack([np.cos(alpha + self.beta), np.sin(alpha + self.beta)], -1)
        return np.stack([b1, b2, b3], -2)

    def residual(self, pose, joints):
        return np.sum((self.platform(pose) - self.bases(joints)) ** 2, -1) - self.leg**2

    def margin(self, pose, joints):
        """det of the rows (u_i, (B_i - B1) x u_i / scale), each row normalised."""
        b = self.platform(pose)
        u, r = b - self.bases(joints), b - b[..., :1, :]
        w = (r[..., 0] * u[..., 1] - r[..., 1] * u[..., 0]) / self.scale
        rows = np.concatenate([u, w[..., None]], -1)
        return np.linalg.det(rows / np.linalg.norm(rows, axis=-1, keepdims=True))

    def torus_map(self, q1, phi, alpha, side2, side3):
        """``(q2, q3, pose)`` of torus points (phi, alpha) at fixed ``q1``."""
        phi, alpha = np.broadcast_arrays(np.asarray(phi, float), np.asarray(alpha, float))
        c1 = self.bases(np.array([q1, 0.0, 0.0]))[0]
        pose = np.stack([c1[0] + self.leg * np.cos(phi), c1[1] + self.leg * np.sin(phi), alpha],
                        -1)
        b = self.platform(pose)
        return (self.joint_of(b[..., 1, :], 1, side2), self.joint_of(b[..., 2, :], 2, side3),
                pose)

    def torus_preimages(self, joints, window, n=720):
        """Every pose of ``joints``: the torus points mapped onto them, from
        the local minima (below ``window``) of the mismatch on an n x n scan
        refined by Newton, sorted by alpha."""
        q1, q2, q3 = joints
        grid = 2 * math.pi * np.arange(n) / n - math.pi
        phi, alpha = np.meshgrid(grid, grid, indexing="ij")
        found = []
        for side2 in (1, -1):
            for side3 in (1, -1):
                def mismatch(p, a, side2=side2, side3=side3):
                    g2, g3, _ = self.torus_map(q1, p, a, side2, side3)
                    return np.stack([self.difference(g2, q2), self.difference(g3, q3)], -1)

                with np.errstate(invalid="ignore"):
                    size = np.max(np.abs(mismatch(phi, alpha)), -1)
                    size = np.where(np.isnan(size), np.inf, size)
                    local = size < window
                    for di in (-1, 0, 1):
                        for dj in (-1, 0, 1):
                            local &= size <= np.roll(size, (di, dj), axis=(0, 1))
                    p, a = phi[local], alpha[local]
                    h = 1e-7
                    for _ in range(60):
                        g = mismatch(p, a)
                        jp = (mismatch(p + h, a) - mismatch(p - h, a)) / (2 * h)
                        ja = (mismatch(p, a + h) - mismatch(p, a - h)) / (2 * h)
                        det = jp[:, 0] * ja[:, 1] - ja[:, 0] * jp[:, 1]
                        dp = (ja[:, 1] * g[:, 0] - ja[:, 0] * g[:, 1]) / det
                        da = (jp[:, 0] * g[:, 1] - jp[:, 1] * g[:, 0]) / det
                        shrink = np.maximum(1.0, np.hypot(dp, da) / 0.1)
                        p, a = p - dp / shrink, a - da / shrink
                    converged = np.max(np.abs(mismatch(p, a)), -1) < 1e-9
                for pose in self.torus_map(q1, p[converged], a[converged], side2, side3)[2]:
                    pose = np.array([pose[0], pose[1], wrap(pose[2])])
                    if all(np.max(np.abs(pose - other)) > 1e-6 for other in found):
                        found.append(pose)
        return np.array(sorted(found, key=lambda pose: pose[2])).reshape(-1, 3)

    def slice_lattice(self, q1, n):
        """The configuration space at fixed ``q1`` on an n x n lattice of the
        torus (phi, alpha), one sheet per pair of sides (+1 +1, +1 -1, -1
        +1, -1 -1): the joints, shape (4, n, n, 3), NaN where a sheet has no
        point, the poses (4, n, n, 3), the signed margins (4, n, n), and
        the pairs of points of one aspect where two sheets meet (a leg's
        two sides, where its circles touch within a lattice step: a fold of
        the torus map, which a motion crosses with the joint turning back),
        as flat index arrays for :func:`~torus_components.torus_components`."""
        angles = 2 * math.pi * (np.arange(n) + 0.5) / n - math.pi
        phi, alpha = np.meshgrid(angles, angles, indexing="ij")
        sides = ((1, 1), (1, -1), (-1, 1), (-1, -1))
        joints = np.empty((4, n, n, 3))
        poses = np.empty((4, n, n, 3))
        for k, (side2, side3) in enumerate(sides):
            with np.errstate(invalid="ignore"):
                q2, q3, poses[k] = self.torus_map(q1, phi, alpha, side2, side3)
            joints[k] = np.stack([np.full_like(q2, q1), q2, q3], -1)
        defined = np.isfinite(joints).all(-1)
        margins = np.full((4, n, n), np.nan)
        margins[defined] = self.margin(poses[defined], joints[defined])
        index = np.arange(4 * n * n).reshape(4, n, n)
        joins = []
        # Sheets k and k ^ 2 differ in leg 2's side, k and k ^ 1 in leg 3's.
        for leg, flip in ((1, 2), (2, 1)):
            for k in (k for k in range(4) if k < k ^ flip):
                undefined = ~np.isfinite(joints[k, ..., leg])
                near_fold = np.zeros((n, n), dtype=bool)
                for axis in (0, 1):
                    for shift in (-1, 1):
                        near_fold |= np.roll(undefined, shift, axis=axis)
                with np.errstate(invalid="ignore"):
                    meet = near_fold & (np.sign(margins[k]) == np.sign(margins[k ^ flip]))
                joins.append((index[k][meet], index[k ^ flip][meet]))
        return joints, poses, margins, joins

    def follow(self, pose, joints, steps=400):
        """Own continuation along a polyline of joints: Newton with a
        finite-difference Jacobian from the previous pose at each dense
        sample; returns ``(joints, pose, move)`` at the samples and the poses
        at the vertices."""
        def newton(p, q):
            for _ in range(20):
                f = self.residual(p, q)
                jac = np.stack([(self.residual(p + e, q) - self.residual(p - e, q)) / 2e-7
                                for e in 1e-7 * np.eye(3)], -1)
                p = p - np.linalg.solve(jac, f)
                if np.max(np.abs(f)) < 1e-11 * self.scale**2:
                    break
            return p

        followed, vertices = [], [pose]
        for q0, q1 in zip(joints[:-1], joints[1:]):
            change = self.difference(q1, q0)
            for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
                q = q0 + s * change
                new = newton(pose, q)
                followed.append((q, new, np.max(np.abs(new - pose))))
                pose = new
            vertices.append(pose)
        return followed, vertices

    # --- checks both mechanisms' tests make ---------------------------------------------

    def check_torus_points(self, mechanism, q1, n=90):
        """Joints made from a dense torus sample at ``q1``: each has the pose
        it was made from among its solutions, and every solution fits the
        legs; returns how many joint vectors had each count."""
        grid = 2 * math.pi * (np.arange(n) + 0.5) / n - math.pi
        phi, alpha = (v.ravel() for v in np.meshgrid(grid, grid, indexing="ij"))
        seen = np.zeros(7, int)
        for side2 in (1, -1):
            for side3 in (1, -1):
                with np.errstate(invalid="ignore"):
                    q2, q3, made = self.torus_map(q1, phi, alpha, side2, side3)
                ok = np.isfinite(q2) & np.isfinite(q3)
                joints = np.stack([np.full(ok.sum(), q1), q2[ok], q3[ok]], -1)
                made = np.concatenate([made[ok, :2], wrap(made[ok, 2:])], -1)
                count, poses = mechanism.solve(joints)
                seen += np.bincount(count, minlength=7)
                residual = np.abs(self.residual(poses, joints[:, None, :]))
                assert np.nanmax(residual) < 1e-9 * self.scale**2
                distance = np.max(np.abs(poses - made[:, None, :]), -1)
                nearest = np.nanmin(np.where(np.isnan(distance), np.inf, distance), -1)
                regular = np.abs(self.margin(made, joints)) > 1e-3
                assert np.max(nearest[regular]) < 1e-6
        return seen

    def check_step_follows_each_solution(self, mechanism, q0, step):
        """Each solution of ``q0``, stepped 40 times by ``step`` along a fixed
        direction, fits the legs, keeps its margin's sign and ends on a
        solution."""
        q0 = np.asarray(q0, dtype=float)
        count, poses = mechanism.solve(q0[None])
        direction = np.array([0.3, -0.5, 0.4])
        for pose in poses[0, : count[0]]:
            q, sign = q0, np.sign(self.margin(pose, q0))
            for _ in range(40):
                target = q + step * direction
                result = mechanism.step(pose, q, target)
                assert result is not None
                pose, margin = np.array(result[0]), result[1]
                assert np.max(np.abs(self.residual(pose, target))) < 1e-9 * self.scale**2
                assert margin == pytest.approx(self.margin(pose, target), abs=1e-10)
                assert np.sign(margin) == sign
                q = target
            count_end, poses_end = mechanism.solve(q[None])
            assert np.min(np.max(np.abs(poses_end[0, : count_end[0]] - pose), -1)) < 1e-8
