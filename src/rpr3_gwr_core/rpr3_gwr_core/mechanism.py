"""The 3-RPR's constraint equations in scalar form, for sequential continuation.

Following the platform along a leg path step by step cannot be vectorised;
these few dozen :mod:`math` operations per step cost far less than the same
on one-element numpy arrays.  They mirror ``kinematics._rows`` and
``kinematics._solve_rows``.
"""

import math

import numpy as np

__all__ = ["Mechanism"]

_NEWTON_STEPS = 6
_RESIDUAL_TOL = 1e-9


class Mechanism:
    """Scalar constraint equations of one geometry.

    Parameters
    ----------
    geometry : Geometry
    """

    def __init__(self, geometry):
        self.a = (geometry.a1, geometry.a2, geometry.a3)
        self.d1, self.d3, self.beta = geometry.d1, geometry.d3, geometry.beta
        self.scale = geometry.scale

    def rows(self, x, y, alpha):
        """Entries of ``Jx / 2`` at a pose (see ``kinematics._rows``)."""
        (a1x, a1y), (a2x, a2y), (a3x, a3y) = self.a
        c, s = math.cos(alpha), math.sin(alpha)
        c3, s3 = math.cos(alpha + self.beta), math.sin(alpha + self.beta)
        u1x, u1y = x - a1x, y - a1y
        u2x, u2y = x + self.d1 * c - a2x, y + self.d1 * s - a2y
        u3x, u3y = x + self.d3 * c3 - a3x, y + self.d3 * s3 - a3y
        w2 = self.d1 * (c * u2y - s * u2x)
        w3 = self.d3 * (c3 * u3y - s3 * u3x)
        return u1x, u1y, u2x, u2y, w2, u3x, u3y, w3

    @staticmethod
    def solve(rows, r1, r2, r3):
        """``(Jx / 2)^-1 r``, or None on a singular Jacobian."""
        a, b, c, d, e, f, g, h = rows
        det = a * (d * h - e * g) + b * (e * f - c * h)
        if det == 0.0:
            return None
        return (((d * h - e * g) * r1 - b * h * r2 + b * e * r3) / det,
                ((e * f - c * h) * r1 + a * h * r2 - a * e * r3) / det,
                ((c * g - d * f) * r1 + (b * f - a * g) * r2 + (a * d - b * c) * r3) / det)

    def step(self, x, y, alpha, rho_from, rho_to):
        """One predictor-corrector step from a pose at legs ``rho_from`` to
        legs ``rho_to``; ``((x, y, alpha), margin)``, or None when the
        corrector does not converge."""
        r1, r2, r3 = (float(v) for v in rho_from)
        t1, t2, t3 = (float(v) for v in rho_to)
        delta = self.solve(self.rows(x, y, alpha), r1 * (t1 - r1), r2 * (t2 - r2), r3 * (t3 - r3))
        if delta is None:
            return None
        x, y, alpha = x + delta[0], y + delta[1], alpha + delta[2]
        tol = _RESIDUAL_TOL * self.scale**2
        for _ in range(_NEWTON_STEPS):
            rows = self.rows(x, y, alpha)
            u1x, u1y, u2x, u2y, _, u3x, u3y, _ = rows
            f1 = u1x * u1x + u1y * u1y - t1 * t1
            f2 = u2x * u2x + u2y * u2y - t2 * t2
            f3 = u3x * u3x + u3y * u3y - t3 * t3
            if max(abs(f1), abs(f2), abs(f3)) < tol:
                return (x, y, alpha), self.margin(rows)
            delta = self.solve(rows, f1, f2, f3)
            if delta is None:
                return None
            x, y, alpha = x - 0.5 * delta[0], y - 0.5 * delta[1], alpha - 0.5 * delta[2]
        return None

    def margin(self, rows):
        """Normalised det(Jx) (``kinematics.singularity_margin``) from rows."""
        a, b, c, d, e, f, g, h = rows
        det = (a * (d * h - e * g) + b * (e * f - c * h)) / self.scale
        norm = (math.hypot(a, b) * math.sqrt(c * c + d * d + (e / self.scale) ** 2)
                * math.sqrt(f * f + g * g + (h / self.scale) ** 2))
        return det / norm if norm > 0 else 0.0


    def follow(self, pose, rho_from, rho_to, substeps=1, max_halvings=8):
        """Carry a pose from ``rho_from`` to ``rho_to`` in ``substeps`` equal
        steps, halving a step where the corrector fails.

        Returns
        -------
        ((x, y, alpha), margin, extreme) or None
            The final pose and its margin, and the margin of smallest
            magnitude met on the way, or of the other sign if det(Jx)
            changed sign (so ``sign(extreme) != sign(margin at the start)``
            tells a crossed singularity); None when the platform cannot
            follow.
        """
        x, y, alpha = (float(v) for v in pose)
        rho_from, rho_to = np.asarray(rho_from, float), np.asarray(rho_to, float)
        done, h, smallest = 0.0, 1.0 / substeps, 1.0 / substeps / 2**max_halvings
        margin = extreme = self.margin(self.rows(x, y, alpha))
        while done < 1.0:
            h = min(h, 1.0 - done)
            out = self.step(x, y, alpha, rho_from + (rho_to - rho_from) * done,
                            rho_from + (rho_to - rho_from) * (done + h))
            if out is None:
                if h < smallest:
                    return None
                h /= 2
                continue
            (x, y, alpha), margin = out
            if (margin > 0) != (extreme > 0) or abs(margin) < abs(extreme):
                extreme = margin
            done += h
        return (x, y, alpha), margin, extreme
