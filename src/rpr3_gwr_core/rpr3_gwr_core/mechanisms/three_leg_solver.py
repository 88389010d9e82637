"""The three-leg solver that the 3-RPR, the 3-RRR and the 3-PRR share.

A platform triangle ``B1 B2 B3`` held by three legs of given lengths to
three base points ``A1..A3``: with the joints fixed each of these
mechanisms is such a 3-RPR (the 3-RRR's base points are its elbows, the
3-PRR's its slider joints).  Conventions (paper section 4.1): the pose is
``(x, y, alpha)`` [length unit, length unit, rad] with ``B1 = (x, y)``,
``B2 = B1 + d1 (cos alpha, sin alpha)`` and
``B3 = B1 + d3 (cos(alpha + beta), sin(alpha + beta))``; the legs are
``rho_i = |B_i - A_i|``, the constraint equations
``F_i = |B_i - A_i|**2 - rho_i**2 = 0``, and ``Jx / 2`` has the rows
``(u_i, w_i)`` with ``u_i = B_i - A_i`` and ``w_i = u_i . dB_i/dalpha``.

The row arithmetic is written once, as code that runs on numpy arrays
for batches and, compiled by numba (:func:`row_terms`,
:func:`adjugate_product`, :func:`leg_residuals`, :func:`rows_margin`,
:func:`corrected`), on floats inside each mechanism's kernels.  Those take
the 3-RPR's ``parameters``, the tuple
``(a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta)`` [length unit, rad].
The batch functions take a ``geometry``: a
:class:`~rpr3_gwr_core.mechanisms.rpr3.ThreeRPR`, whose attributes
``a1..a3``, ``d1``, ``d3``, ``beta``, ``scale`` and ``parameters`` they read.

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
(:func:`solve_with_bases`), for the mechanisms whose base points move with
their joints (:mod:`.moving_base`).
"""

import functools
import math

import numba
from numba.extending import register_jitable
import numpy as np

from ..exceptions import InvalidInputError
from .trig_roots import sampled_roots

__all__ = [
    "MAX_SOLUTIONS",
    "wrap_angle",
    "checked_legs",
    "row_terms",
    "adjugate_product",
    "leg_residuals",
    "rows_margin",
    "corrected",
    "pose_rows",
    "solve_rows",
    "singularity_margin",
    "newton",
    "residuals",
    "solve_legs",
    "solve_with_bases",
    "degenerate_orientations",
]

# The sextic's degree: at most six real roots, six poses per joint vector.
MAX_SOLUTIONS = 6

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
    """Angles wrapped to (-pi, pi].

    Parameters
    ----------
    angle : array_like
        [rad], any shape.

    Returns
    -------
    ndarray
        [rad], the shape of ``angle``.
    """
    return np.pi - np.remainder(np.pi - np.asarray(angle, dtype=float), 2 * np.pi)


def checked_legs(rho):
    """Leg lengths as a float array, refused unless finite and non-negative.

    Parameters
    ----------
    rho : array_like, shape (..., 3)
        [length unit].

    Returns
    -------
    ndarray, shape (..., 3)

    Raises
    ------
    InvalidInputError
        If ``rho`` is not numbers, its last axis is not of 3, or a length is
        NaN, infinite or negative.
    """
    try:
        rho = np.asarray(rho, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"rho must be numbers, got {rho!r}") from None
    if rho.shape[-1:] != (3,):
        raise InvalidInputError(f"rho has 3 components, got shape {rho.shape}")
    if not np.all(np.isfinite(rho)):
        raise InvalidInputError("rho contains NaN or infinity")
    if np.any(rho < 0):
        raise InvalidInputError("leg lengths rho must be non-negative")
    return rho


# The constraint equations are written once, as arithmetic that runs on numpy
# arrays for batches (the field, continuity) and, compiled by numba, on floats
# for the sequential continuation of one pose (validator, driver), where
# numpy's per-call cost would dominate.

def pose_rows(pose, geometry):
    """The entries of ``Jx / 2`` of many poses (:func:`row_terms` on arrays).

    Parameters
    ----------
    pose : ndarray, shape (..., 3)
        ``(x, y, alpha)`` [length unit, length unit, rad].
    geometry : ThreeRPR
        Read for its ``parameters``.

    Returns
    -------
    tuple of 8 ndarray, each of shape (...)
        ``(u1x, u1y, u2x, u2y, w2, u3x, u3y, w3)`` [length unit, length
        unit**2 for the ``w_i``].
    """
    return row_terms(pose[..., 0], pose[..., 1], pose[..., 2], geometry.parameters)


@register_jitable
def row_terms(x, y, alpha, parameters):
    """The entries of ``Jx / 2`` of one pose, compiled into kernels or on arrays.

    Parameters
    ----------
    x, y, alpha : float or ndarray
        The pose [length unit, length unit, rad], arrays of one shape.
    parameters : tuple of 9 float
        ``(a1x, a1y, a2x, a2y, a3x, a3y, d1, d3, beta)`` [length unit, rad].

    Returns
    -------
    tuple of 8 float or ndarray
        ``(u1x, u1y, u2x, u2y, w2, u3x, u3y, w3)``: the legs
        ``u_i = B_i - A_i`` [length unit] and ``w_i = u_i . dB_i/dalpha``
        [length unit**2] (``w_1 = 0`` because B1 is the platform's
        reference point).
    """
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
def adjugate_product(rows, r1, r2, r3):
    """``det(Jx / 2) (Jx / 2)^-1 r`` and ``det(Jx / 2)``, by the adjugate.

    Parameters
    ----------
    rows : tuple of 8 float or ndarray
        The entries of ``Jx / 2`` (:func:`row_terms`).
    r1, r2, r3 : float or ndarray
        The right-hand side, one per leg, of the rows' shape.

    Returns
    -------
    product : tuple of 3 float or ndarray
        ``(dx, dy, dalpha)`` times the determinant.
    det : float or ndarray
        ``det(Jx / 2)``; the solution is ``product / det`` where it is not 0.
    """
    a, b, c, d, e, f, g, h = rows
    return (((d * h - e * g) * r1 - b * h * r2 + b * e * r3,
             (e * f - c * h) * r1 + a * h * r2 - a * e * r3,
             (c * g - d * f) * r1 + (b * f - a * g) * r2 + (a * d - b * c) * r3),
            _det_rows(*rows))


def solve_rows(rows, r1, r2, r3):
    """``(Jx / 2)^-1 r`` of many poses by the adjugate of their rows.

    Parameters
    ----------
    rows : tuple of 8 ndarray, each of shape (...)
        The entries of ``Jx / 2`` (:func:`pose_rows`).
    r1, r2, r3 : ndarray, shape (...)
        The right-hand side, one per leg.

    Returns
    -------
    ndarray, shape (..., 3)
        ``(dx, dy, dalpha)``; 0 where the system is singular.
    """
    (dx, dy, da), det = adjugate_product(rows, r1, r2, r3)
    inv = np.where(det != 0, 1.0 / np.where(det != 0, det, 1.0), 0.0)
    return np.stack([dx * inv, dy * inv, da * inv], axis=-1)


@register_jitable
def leg_residuals(rows, rho):
    """The constraint residuals ``|B_i - A_i|**2 - rho_i**2`` of a pose.

    Parameters
    ----------
    rows : tuple of 8 float or ndarray
        The entries of ``Jx / 2`` (:func:`row_terms`).
    rho : sequence of 3 float or ndarray
        The legs' lengths [length unit].

    Returns
    -------
    tuple of 3 float or ndarray
        One per leg [length unit**2].
    """
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


def singularity_margin(pose, geometry):
    """Signed, normalised distance of many poses from a parallel singularity.

    Each row of ``Jx / 2``, its orientation column over ``geometry.scale``,
    is divided by its norm before the determinant (Hadamard's bound).

    Parameters
    ----------
    pose : ndarray, shape (..., 3)
        ``(x, y, alpha)`` [length unit, length unit, rad].
    geometry : ThreeRPR

    Returns
    -------
    ndarray, shape (...)
        In [-1, 1], 0 on a singularity and where a leg has zero length.
    """
    rows = pose_rows(pose, geometry)
    norms = _row_norms(rows, geometry.scale)
    with np.errstate(invalid="ignore", divide="ignore"):
        margin = _normalised_det(rows, norms, geometry.scale)
    return np.where((norms[0] > 0) & (norms[1] > 0) & (norms[2] > 0), margin, 0.0)


def newton(pose, rho, geometry, iterations):
    """Newton steps of many poses onto their legs.

    Parameters
    ----------
    pose : ndarray, shape (..., 3)
        Initial guesses ``(x, y, alpha)`` [length unit, length unit, rad].
    rho : ndarray, shape (..., 3)
        The legs' lengths [length unit].
    geometry : ThreeRPR
    iterations : int

    Returns
    -------
    ndarray, shape (..., 3)
        The corrected poses (alpha not wrapped); a singular system leaves a
        pose.
    """
    legs = np.moveaxis(rho, -1, 0)
    for _ in range(iterations):
        rows = pose_rows(pose, geometry)
        pose = pose - 0.5 * solve_rows(rows, *leg_residuals(rows, legs))
    return pose


# The scalar continuation step: converged when every leg's residual is below
# _RESIDUAL_TOL * scale**2, after at most _NEWTON_STEPS corrector steps, and
# refused when the corrector moved the pose more than _JUMP_RATIO times the
# predictor's move plus _JUMP_FLOOR * scale (the residual tolerance's reach).
_NEWTON_STEPS = 6
_RESIDUAL_TOL = 1e-9
_JUMP_RATIO = 0.5
_JUMP_FLOOR = 1e-7


@register_jitable
def rows_margin(rows, scale):
    """:func:`singularity_margin` of one pose, from its rows.

    Parameters
    ----------
    rows : tuple of 8 float
        The entries of ``Jx / 2`` (:func:`row_terms`).
    scale : float
        The length [length unit] that divides the orientation column.

    Returns
    -------
    float
        In [-1, 1]; 0 where a row is zero.
    """
    norms = _row_norms(rows, scale)
    if norms[0] > 0 and norms[1] > 0 and norms[2] > 0:
        return _normalised_det(rows, norms, scale)
    return 0.0


@register_jitable
def corrected(parameters, legs, scale, px, py, palpha, predicted):
    """The corrector of a continuation step: Newton from a predicted pose
    onto the legs, refused where it moved too far for the prediction.

    Parameters
    ----------
    parameters : tuple of 9 float
        The base points and platform (:func:`row_terms`).
    legs : tuple of 3 float
        The legs' lengths to meet [length unit].
    scale : float
        The length [length unit] of the tolerances and of the orientation.
    px, py, palpha : float
        The predicted pose [length unit, length unit, rad].
    predicted : float
        How far the predictor moved [length unit, the orientation times
        ``scale``].

    Returns
    -------
    tuple of (bool, float, float, float, float)
        ``(converged, x, y, alpha, margin)``: the corrected pose and its
        :func:`rows_margin`; margin 0 where not converged.
    """
    x, y, alpha = px, py, palpha
    tol = _RESIDUAL_TOL * scale * scale
    for _ in range(_NEWTON_STEPS):
        rows = row_terms(x, y, alpha, parameters)
        e1, e2, e3 = leg_residuals(rows, legs)
        if max(abs(e1), abs(e2), abs(e3)) < tol:
            moved = math.sqrt((x - px) ** 2 + (y - py) ** 2 + ((alpha - palpha) * scale) ** 2)
            # The predictor is first order, so on the followed branch the
            # correction is of second order in the step: one as long as the
            # prediction itself landed on another solution of these legs.
            if moved > _JUMP_RATIO * predicted + _JUMP_FLOOR * scale:
                return False, x, y, alpha, 0.0
            return True, x, y, alpha, rows_margin(rows, scale)
        (dx, dy, da), det = adjugate_product(rows, e1, e2, e3)
        if det == 0.0:
            return False, x, y, alpha, 0.0
        x, y, alpha = x - 0.5 * dx / det, y - 0.5 * dy / det, alpha - 0.5 * da / det
    return False, x, y, alpha, 0.0


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
    """The linear formula of :func:`solve_legs` for base points per row, root by
    root: the arithmetic of :func:`_linear_terms` and :func:`solve_legs`, in
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
    """Which poses miss their legs by more than ``limit``, as :func:`solve_legs`
    judges them from :func:`residuals` (a NaN residual is no miss), for
    base points per row: pose k is of row ``rows[k]``, ``platform`` is
    ``(d1, d3, beta)``."""
    d1, d3, beta = platform
    fake = np.empty(poses.shape[0], dtype=np.bool_)
    for k in range(poses.shape[0]):
        row = rows[k]
        parameters = (points[row, 0, 0], points[row, 0, 1], points[row, 1, 0],
                      points[row, 1, 1], points[row, 2, 0], points[row, 2, 1], d1, d3, beta)
        e1, e2, e3 = leg_residuals(row_terms(poses[k, 0], poses[k, 1], poses[k, 2], parameters),
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
    answers the attributes the batch solver reads of a
    :class:`~.rpr3.ThreeRPR`
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

    :func:`solve_legs` (same sextic, root finder and ordering) for
    mechanisms that reduce to a 3-RPR whose base points move with their
    joints (:mod:`.moving_base`: the 3-RRR's elbows, the 3-PRR's slider
    joints).

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
        As :func:`solve_legs`'s.

    Raises
    ------
    InvalidInputError
        If the shapes do not match, or a value is not finite (or a leg
        negative).
    """
    rho = checked_legs(rho)
    bases = np.ascontiguousarray(bases, dtype=float)
    if rho.ndim != 2 or bases.shape != (rho.shape[0], 3, 2):
        raise InvalidInputError(
            f"rho must have shape (n, 3) and bases (n, 3, 2), got {rho.shape}, {bases.shape}")
    if not np.all(np.isfinite(bases)):
        raise InvalidInputError("base points contain NaN or infinity")
    return solve_legs(rho, _BasePerRow(bases, platform))


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


def solve_legs(rho, geometry):
    """All real direct-kinematic solutions of many leg vectors.

    Parameters
    ----------
    rho : ndarray, shape (n, 3)
        Leg lengths [length unit], as :func:`checked_legs` gives them.
    geometry : ThreeRPR
        The base points and platform (or, from :func:`solve_with_bases`,
        base points per row).

    Returns
    -------
    count : ndarray of uint8, shape (n,)
        The number of solutions of each row, at most :data:`MAX_SOLUTIONS`.
    poses : ndarray, shape (n, 6, 3)
        ``(x, y, alpha)`` [length unit, length unit, rad], sorted by alpha
        in (-pi, pi], NaN beyond ``count``.
    """
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
        after = newton(before, r[rough], rough_geometry, 3)

        def fit(p):
            return np.max(np.abs(residuals(p, r[rough], rough_geometry)), axis=-1)

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
        fake = np.max(np.abs(residuals(candidate, r, geometry)), axis=-1) > limit
    poses[rows, cols] = candidate
    poses[rows[fake], cols[fake]] = np.nan
    if np.any(fake):
        alpha[rows[fake], cols[fake]] = np.nan
        first = np.argsort(np.isnan(alpha), axis=1, kind="stable")
        poses = np.take_along_axis(poses, first[..., None], axis=1)
        alpha = np.take_along_axis(alpha, first, axis=1)
    poses[..., 2] = wrap_angle(poses[..., 2])
    return np.isfinite(alpha).sum(axis=1).astype(np.uint8), poses


def residuals(pose, rho, geometry):
    """The constraint residuals of many poses (:func:`leg_residuals`).

    Parameters
    ----------
    pose : ndarray, shape (..., 3)
        ``(x, y, alpha)`` [length unit, length unit, rad].
    rho : ndarray, shape (..., 3)
        The legs' lengths [length unit].
    geometry : ThreeRPR

    Returns
    -------
    ndarray, shape (..., 3)
        One per leg [length unit**2].
    """
    return np.stack(leg_residuals(pose_rows(pose, geometry), np.moveaxis(rho, -1, 0)), axis=-1)


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


def degenerate_orientations(geometry):
    """The orientations where equation (7)'s linear formula for (x, y)
    degenerates: the roots of ``AE - BD``, a first-order trigonometric
    polynomial in alpha.

    Parameters
    ----------
    geometry : ThreeRPR

    Returns
    -------
    ndarray, shape (0,) or (2,)
        [rad] in (-pi, pi], sorted.
    """
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
