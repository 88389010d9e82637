"""The geometry of a planar 3-RPR manipulator as an immutable value.

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
"""

from dataclasses import dataclass
import math
import numbers

import numpy as np

from .exceptions import InvalidInputError

__all__ = ["Geometry", "PAPER_GEOMETRY", "beta_from_sides"]


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


@dataclass(frozen=True)
class Geometry:
    """Base points and platform of a 3-RPR manipulator.

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

    def __post_init__(self):
        for name in ("a1", "a2", "a3"):
            try:
                point = tuple(_real(v) for v in getattr(self, name))
            except (TypeError, ValueError):
                raise InvalidInputError(f"{name} must be two numbers, got {getattr(self, name)!r}") from None
            if len(point) != 2 or not all(math.isfinite(v) for v in point):
                raise InvalidInputError(f"{name} must be two finite numbers, got {point}")
            object.__setattr__(self, name, point)
        for name in ("d1", "d3", "beta"):
            try:
                value = _real(getattr(self, name))
            except (TypeError, ValueError):
                raise InvalidInputError(f"{name} must be a number, got {getattr(self, name)!r}") from None
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

    @property
    def scale(self):
        """Characteristic length (longest platform side) used to make the
        orientation column of the Jacobian commensurable with positions."""
        return max(self.d1, self.d2, self.d3)

    def to_dict(self):
        """Plain-data form, for JSON and cache keys."""
        return {"a1": list(self.a1), "a2": list(self.a2), "a3": list(self.a3),
                "d1": self.d1, "d3": self.d3, "beta": self.beta}

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(a1=tuple(data["a1"]), a2=tuple(data["a2"]), a3=tuple(data["a3"]),
                       d1=data["d1"], d3=data["d3"], beta=data["beta"])
        except (KeyError, TypeError) as exc:
            raise InvalidInputError(f"malformed geometry: {exc}") from exc


PAPER_GEOMETRY = Geometry()
