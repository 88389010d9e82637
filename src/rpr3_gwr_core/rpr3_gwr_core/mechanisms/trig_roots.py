"""Real roots of trigonometric polynomials, proven simple by sampling.

A trigonometric polynomial of degree K,
``f(phi) = a_0 + sum_k a_k cos(k phi) + b_k sin(k phi)``, has the derivative
bounds ``|f^(m)| <= M_m = sum_k k**m hypot(a_k, b_k)``.  Sampled at
``phi_i = i h`` with ``h = 2 pi / N``, an interval between two samples holds

* no root when both samples have one sign and both exceed ``M_2 h**2 / 8``
  (f stays above its chord minus that much), or when the tangent at each
  end, minus the same, keeps that sign up to the middle;
* exactly one root, a simple one, when the samples differ in sign and ``f'``
  provably keeps its sign (the chord test on ``f'`` with ``M_3``).

An interval that passes neither is halved, and its halves tested alike, a
few times over.  A row whose every interval passes is *certified*: its real
roots are exactly the sign changes, each polished by safeguarded Newton to
full precision.  Rows where roots come close to merging (a double root, or
a complex pair near the real axis) fail the tests and are left to a
complete root finder.  The tests carry a safety factor: f provably stays a
quarter of the bound away from zero, so a certified row has no complex
root within about 1e-4 of the real axis, and a complete finder counts the
same roots there, whatever its tolerance for nearly real ones.
"""

import functools
import math

import numba
import numpy as np

__all__ = ["sampled_roots"]

# The sampling tests are strict by this factor, which buries the rounding
# of the sampled values and keeps certified rows away from the borderline
# cases a complete root finder may decide either way.
_SAFETY = 1.25
# Newton's last step: below this [rad] the next one would be under rounding.
_LAST_STEP = 1e-9
_MAX_ITERATIONS = 100
# Intervals are halved at most this often: a piece h / 2**8 wide still
# failing holds roots within about that of merging.
_MAX_DEPTH = 8


def sampled_roots(coeffs, samples, max_roots):
    """Real roots of trigonometric polynomials whose sampling proves them simple.

    Parameters
    ----------
    coeffs : ndarray, shape (n, 2 K + 1)
        ``(a_0, a_1, b_1, ..., a_K, b_K)`` of each polynomial.
    samples : int
        N, the number of samples ``phi_i = 2 pi i / N`` over a period.
    max_roots : int
        Root slots per row (at most ``2 K``).

    Returns
    -------
    certified : ndarray of bool, shape (n,)
        Rows whose real roots are all found and simple (module doc).
    roots : ndarray, shape (n, max_roots)
        Roots of certified rows [rad], sorted in (-pi, pi]; NaN elsewhere
        and beyond the row's number of roots.
    """
    coeffs = np.ascontiguousarray(coeffs, dtype=float)
    certified = np.zeros(len(coeffs), dtype=np.bool_)
    roots = np.full((len(coeffs), max_roots), np.nan)
    _certify_rows(coeffs, _sampling(int(samples), coeffs.shape[1]), certified, roots)
    return certified, roots


@functools.lru_cache(maxsize=8)
def _sampling(samples, size):
    """:func:`_sampling_tables`, built once per sampling and shared, read-only."""
    tables = _sampling_tables(samples, size)
    for table in tables:
        table.flags.writeable = False
    return tables


@numba.njit(cache=True, nogil=True)
def _sampling_tables(samples, size):
    """What the sampling of rows of ``size`` coefficients at ``samples``
    points computes for every row alike: ``(basis, slope_basis, middles)``.

    ``basis[m, i]`` and ``slope_basis[i, m]`` are the m-th basis function and
    its derivative at ``phi_i``; ``middles[i, node]`` the cosine and sine of
    the middle of a piece of interval i: node 1 is the interval, nodes
    ``2 n`` and ``2 n + 1`` the halves of node n, down to ``_MAX_DEPTH``
    halvings, each middle the very float :func:`_row_roots` computes.
    """
    h = 2.0 * math.pi / samples
    basis = np.empty((size, samples))
    slope_basis = np.zeros((samples, size))
    for i in range(samples):
        basis[0, i] = 1.0
        for k in range(1, (size - 1) // 2 + 1):
            basis[2 * k - 1, i] = math.cos(k * i * h)
            basis[2 * k, i] = math.sin(k * i * h)
            slope_basis[i, 2 * k - 1] = -k * basis[2 * k, i]
            slope_basis[i, 2 * k] = k * basis[2 * k - 1, i]
    nodes = 2**_MAX_DEPTH
    middles = np.empty((samples, nodes, 2))
    ends = np.empty((nodes, 2))
    for i in range(samples):
        ends[1, 0], ends[1, 1] = i * h, (i + 1) * h
        for node in range(1, nodes):
            a, b = ends[node, 0], ends[node, 1]
            middle = 0.5 * (a + b)
            middles[i, node, 0], middles[i, node, 1] = math.cos(middle), math.sin(middle)
            if 2 * node < nodes:
                ends[2 * node, 0], ends[2 * node, 1] = a, middle
                ends[2 * node + 1, 0], ends[2 * node + 1, 1] = middle, b
    return basis, slope_basis, middles


# The helpers below are inlined into the loops over rows: a call that takes
# an array counts its references, atomically, which cost as much as the
# arithmetic.

@numba.njit(cache=True, nogil=True, inline="always")
def _evaluate(row, c1, s1):
    """``(f(phi), f'(phi))`` of one row of coefficients, from ``cos phi`` and
    ``sin phi``."""
    ck, sk = 1.0, 0.0
    value, slope = row[0], 0.0
    for k in range(1, (row.size + 1) // 2):
        ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
        a, b = row[2 * k - 1], row[2 * k]
        value += a * ck + b * sk
        slope += k * (b * ck - a * sk)
    return value, slope


@numba.njit(cache=True, nogil=True, inline="always")
def _polish(row, lo, hi, f_lo, f_hi):
    """The one root of ``row`` in ``[lo, hi]``, where f changes sign from
    ``f_lo`` to ``f_hi``."""
    phi = lo + (hi - lo) * f_lo / (f_lo - f_hi)
    for _ in range(_MAX_ITERATIONS):
        value, slope = _evaluate(row, math.cos(phi), math.sin(phi))
        if value == 0.0:
            return phi
        step = value / slope
        # Converged: the step is below rounding of the bracket's ends, so it
        # is taken even if it lands a hair outside.
        if abs(step) < _LAST_STEP:
            return phi - step
        if (value > 0.0) == (f_lo > 0.0):
            lo = phi
        else:
            hi = phi
        phi -= step
        # Newton may leave the bracket from a poor start; bisect then.
        if not min(lo, hi) < phi < max(lo, hi):
            phi = 0.5 * (lo + hi)
    return phi


@numba.njit(cache=True, nogil=True)
def _apart(f_a, f_b, slope_a, slope_b, width, bound):
    """Whether g, of which ``f_a, f_b`` are the values and ``slope_a,
    slope_b`` the slopes at the ends of a piece, provably stays farther than
    ``(_SAFETY - 1) bound width**2 / 8`` from zero on it, ``bound`` bounding
    ``|g''|``: by the chord, or by the tangent at each end up to the middle."""
    if f_a * f_b <= 0.0:
        return False
    curvature = bound * width * width / 8.0
    least = min(abs(f_a), abs(f_b))
    if least > _SAFETY * curvature:
        return True
    sign = 1.0 if f_a > 0.0 else -1.0
    return (least > (_SAFETY - 1.0) * curvature
            and sign * (f_a + 0.5 * width * slope_a) > _SAFETY * curvature
            and sign * (f_b - 0.5 * width * slope_b) > _SAFETY * curvature)


@numba.njit(cache=True, nogil=True)
def _row_roots(row, values, sampling, found, stack):
    """The roots of ``row``, sampled as ``values`` (``values[-1]`` repeating
    ``values[0]``), written to ``found``: their number, or -1 if the row is
    not certified.  An interval that the chord test does not settle is
    halved until every piece passes a test of the module doc; -1 if a piece
    still fails at ``_MAX_DEPTH``."""
    _, slope_basis, middles = sampling
    samples = values.size - 1
    h = 2.0 * math.pi / samples
    degree = (row.size - 1) // 2
    bound2, bound3 = 0.0, 0.0
    for k in range(1, degree + 1):
        amplitude = math.hypot(row[2 * k - 1], row[2 * k])
        bound2 += k * k * amplitude
        bound3 += k * k * k * amplitude
    band = _SAFETY * bound2 * h * h / 8
    count = 0
    for i in range(samples):
        f_a, f_b = values[i], values[i + 1]
        # Most pieces pass the chord test, which needs no slopes.
        if f_a * f_b > 0.0 and min(abs(f_a), abs(f_b)) > band:
            continue
        j = (i + 1) % samples
        slope_a, slope_b = 0.0, 0.0
        for m in range(row.size):
            slope_a += row[m] * slope_basis[i, m]
            slope_b += row[m] * slope_basis[j, m]
        a, b = i * h, (i + 1) * h
        node = 1
        pending = 0
        while True:
            width = b - a
            if not _apart(f_a, f_b, slope_a, slope_b, width, bound2):
                # The slopes' own chord test (their slopes unknown) shows f monotone.
                if f_a * f_b < 0.0 and _apart(slope_a, slope_b, 0.0, 0.0, width, bound3):
                    if count == found.size:
                        return -1
                    found[count] = _polish(row, a, b, f_a, f_b)
                    count += 1
                elif node >= middles.shape[1]:
                    return -1
                else:
                    # Go on with the left half; the right one waits on the stack.
                    middle = 0.5 * (a + b)
                    f_middle, slope_middle = _evaluate(row, middles[i, node, 0],
                                                       middles[i, node, 1])
                    stack[pending] = (middle, b, f_middle, f_b, slope_middle, slope_b,
                                      float(2 * node + 1))
                    pending += 1
                    b, f_b, slope_b, node = middle, f_middle, slope_middle, 2 * node
                    continue
            if pending == 0:
                break
            pending -= 1
            a, b = stack[pending, 0], stack[pending, 1]
            f_a, f_b = stack[pending, 2], stack[pending, 3]
            slope_a, slope_b, node = stack[pending, 4], stack[pending, 5], int(stack[pending, 6])
    return count


@numba.njit(cache=True, nogil=True)
def _certify_rows(coeffs, sampling, certified, roots):
    basis = sampling[0]
    samples = basis.shape[1]
    values = np.empty(samples + 1)
    found = np.empty(roots.shape[1])
    # Depth-first halving keeps at most one right half pending per level.
    stack = np.empty((_MAX_DEPTH, 7))
    for r in range(coeffs.shape[0]):
        row = coeffs[r]
        # Summed term by term, each sample in the order of a dot product
        # with its basis row, but vectorised across the samples.
        values[:] = 0.0
        for m in range(row.size):
            for i in range(samples):
                values[i] += row[m] * basis[m, i]
        values[samples] = values[0]
        count = _row_roots(row, values, sampling, found, stack)
        if count < 0:
            continue
        for m in range(count):
            root = math.pi - ((math.pi - found[m]) % (2.0 * math.pi))
            # Sorted by insertion: a handful of roots.
            k = m
            while k > 0 and roots[r, k - 1] > root:
                roots[r, k] = roots[r, k - 1]
                k -= 1
            roots[r, k] = root
        certified[r] = True
