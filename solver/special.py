"""The special functions of the model, in numpy from their definitions.

- ``ellipke(m)``: ``K(m)`` and ``E(m)``, the complete elliptic integrals of the first and second
  kind (parameter ``m``, as scipy.special's ``ellipk`` and ``ellipe``), and ``ellipkm1(p)``:
  ``K(1 - p)`` close to its logarithmic singularity (as scipy.special's), the elastic kernel's
  (model/elasticity.py).
- ``scaled_ei(z)``: ``exp(-z) Ei(z)`` (``Ei`` the exponential integral), the rigid film's time
  (model/rigid.py).

Written here, not imported from scipy.special: importing scipy.special costs about 0.1 s of every
run (it brings scipy's array-API layer): a sixth of a warm ``ehd run`` of solver 1.15.0
(benchmarks/startup.md).
Each agrees with scipy.special to a few units of the last place (tests/test_special.py).

Elliptic integrals by Gauss's arithmetic-geometric mean (DLMF 19.8.1, 19.8.6): with ``a_0 = 1``,
``b_0 = sqrt(1 - m)``, ``c_0 = sqrt(m)``, ``a_{n+1} = (a_n + b_n)/2``, ``b_{n+1} = sqrt(a_n b_n)``,
``c_{n+1} = c_n^2 / (4 a_{n+1})`` (``= (a_n - b_n)/2`` without its cancellation) and ``M`` their
common limit,

    K(m) = pi / (2 M),    K(m) - E(m) = K(m) S(m),    S(m) = sum_{n>=0} 2^(n-1) c_n^2.

``E = K (1 - S)`` loses no digits for ``m <= 1/2`` (``S <= 0.28``); above, Legendre's relation
(DLMF 19.7.1) with ``p = 1 - m`` gives ``E(m) = M(1, sqrt m) + K(m) S(p)``, a sum of positive
terms, so ``E`` is accurate up to ``E(1) = 1``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ellipkm1", "ellipke", "scaled_ei"]

_MAX_AGM = 64  # the AGM converges quadratically: 13 steps reach 1e-300 (sqrt p = 1e-150)
# c_n / a_n below this: a_n - b_n = 2 c_(n+1) ~ c_n^2 / (2 a_n) is below a_n's last place
_CONVERGED = 2.0**-27


def _agm(b, c):
    """``M(1, b)`` and ``sum_{n>=1} 2^(n-1) c_n^2`` for ``b = b_0``, ``c = c_0``
    (``b^2 + c^2 = 1``, both in [0, 1]), elementwise; ``M(1, 0) = 0`` (then the sum is not
    used: it is where K has its pole)."""
    zero = b == 0.0
    b = np.where(zero, 1.0, b)
    c = np.where(zero, 0.0, c)
    a = np.ones_like(b)
    tail = np.zeros_like(b)
    weight = 0.5
    for _ in range(_MAX_AGM):
        a_next = 0.5 * (a + b)
        b = np.sqrt(a * b, out=b)
        c *= c
        c /= 4.0 * a_next
        a = a_next
        weight *= 2.0
        tail += weight * (c * c)
        if not np.any(c > _CONVERGED * a):
            return np.where(zero, 0.0, a), tail
    raise FloatingPointError("arithmetic-geometric mean did not converge")


def _agm_scalar(b, c):
    """``_agm`` for one pair of floats, the same operations in the same order (so the same
    result to the bit: tests/test_special.py), without numpy's cost per call: a quadrature that
    calls the elastic kernel point by point (the paper figures' small-deformation integral)
    took 0.1 ms a call through arrays."""
    if b == 0.0:
        return 0.0, 0.0
    a, tail, weight = 1.0, 0.0, 0.5
    for _ in range(_MAX_AGM):
        a_next = 0.5 * (a + b)
        b = math.sqrt(a * b)
        c = c * c / (4.0 * a_next)
        a = a_next
        weight *= 2.0
        tail += weight * (c * c)
        if not c > _CONVERGED * a:
            return a, tail
    raise FloatingPointError("arithmetic-geometric mean did not converge")


def _ellipke_scalar(m, p):
    """``ellipke`` for one ``m`` and its ``p = 1 - m`` (floats), through ``_agm_scalar``."""
    if not (0.0 <= m <= 1.0 and 0.0 <= p <= 1.0):
        return np.float64(math.nan), np.float64(math.nan)
    mean_m, tail_m = _agm_scalar(math.sqrt(p), math.sqrt(m))
    k_m = 0.5 * math.pi / mean_m if mean_m else math.inf
    e_m = k_m * (1.0 - 0.5 * m - tail_m) if mean_m else math.inf
    if m > 0.5:
        mean_p, tail_p = _agm_scalar(math.sqrt(m), math.sqrt(p))
        e_m = 1.0 if p == 0.0 else mean_p + k_m * (0.5 * p + tail_p)
    return np.float64(k_m), np.float64(e_m)


def ellipkm1(p):
    """``K(1 - p)`` for ``0 <= p <= 1`` (``inf`` at ``p = 0``; NaN outside [0, 1]): ``ellipke``'s
    ``K`` with ``1 - p`` given as ``p``."""
    return ellipke(1.0 - np.asarray(p, dtype=float), p)[0]


def ellipke(m, p=None):
    """``K(m)`` and ``E(m)`` for ``0 <= m <= 1`` (``K(1) = inf``, ``E(1) = 1``; NaN outside
    [0, 1]); ``p``: ``1 - m`` where the caller knows it without the cancellation of ``1 - m``
    (broadcast against ``m``; NaN where it is outside [0, 1]; taken as it is, not checked against
    ``m``)."""
    if np.ndim(m) == 0 and np.ndim(p) == 0:  # one value (p None too): no arrays
        m = float(m)
        return _ellipke_scalar(m, 1.0 - m if p is None else float(p))
    m = np.asarray(m, dtype=float)
    if p is None:
        p = 1.0 - m
    else:
        m, p = np.broadcast_arrays(m, np.asarray(p, dtype=float))
    shape = m.shape
    m, p = m.ravel(), p.ravel()
    inside = (m >= 0.0) & (m <= 1.0) & (p >= 0.0) & (p <= 1.0)
    m = np.where(inside, m, 0.0)
    p = np.where(inside, p, 1.0)
    mean_m, tail_m = _agm(np.sqrt(p), np.sqrt(m))  # K(m) = pi / (2 mean_m), S(m) = m/2 + tail_m
    with np.errstate(divide="ignore", invalid="ignore"):
        k_m = 0.5 * math.pi / mean_m
        e_m = k_m * (1.0 - 0.5 * m - tail_m)
        high = m > 0.5
        if high.any():  # Legendre: E(m) = M(1, sqrt m) + K(m) S(p)
            mean_p, tail_p = _agm(np.sqrt(m[high]), np.sqrt(p[high]))
            e_m[high] = np.where(p[high] == 0.0, 1.0,
                                 mean_p + k_m[high] * (0.5 * p[high] + tail_p))
    k_m[~inside] = np.nan
    e_m[~inside] = np.nan
    return k_m.reshape(shape)[()], e_m.reshape(shape)[()]


_EULER_GAMMA = 0.5772156649015329
_ASYMPTOTIC = 40.0  # |z| beyond: the asymptotic series (its smallest term, at k = 40, is 7e-17)
_SERIES_ROWS = 4096  # arguments per block of _series's terms (memory bounded whatever the input)
_K = np.arange(1.0, 2.0 * _ASYMPTOTIC + 62.0)  # the series' k, as many as |z| = 40 needs


def scaled_ei(z):
    """``exp(-z) Ei(z)`` for real ``z`` (``Ei`` the exponential integral, ``-inf`` at 0), without
    overflow:

    - ``0 < z <= 40``: the power series ``Ei(z) = gamma + ln z + sum_k z^k / (k k!)`` (DLMF 6.6.1;
      positive terms);
    - ``-1 <= z < 0``: ``Ei(z) = -E1(-z)``, ``E1(x) = -gamma - ln x - sum_k (-x)^k / (k k!)``
      (DLMF 6.6.2; at most a factor e^2 lost to the alternating terms);
    - ``-40 <= z < -1``: ``exp(x) E1(x) = 1/(x+1- 1/(x+3- 4/(x+5- ...)))`` (the even part of
      DLMF 6.9.1), evaluated from a deep enough term back;
    - ``|z| > 40``: the asymptotic series ``(1/z) sum_k k!/z^k`` (DLMF 6.12.2; terms fall until
      ``k ~ |z|``)."""
    z = np.asarray(z, dtype=float)
    if z.size and 0.0 < z.min() and z.max() <= _ASYMPTOTIC:  # the common case: one branch
        return _series(z.ravel()).reshape(z.shape)[()]
    out = np.full(z.shape, -np.inf)
    out[np.isnan(z)] = np.nan
    series = ((z > 0.0) & (z <= _ASYMPTOTIC)) | ((z < 0.0) & (z >= -1.0))
    fraction = (z < -1.0) & (z >= -_ASYMPTOTIC)
    asymptotic = np.abs(z) > _ASYMPTOTIC
    for where, part in ((series, _series), (fraction, _fraction), (asymptotic, _asymptotic)):
        if where.any():
            out[where] = part(z[where])
    return out[()]


def _series(z):
    """``exp(-z) Ei(z)``, ``Ei(z) = gamma + ln|z| + sum_k z^k / (k k!)``, for ``0 < |z| <= 40``:
    ``2|z| + 60`` terms (from ``k = 2|z|`` on, each term is under the sum and under half the one
    before: 60 more leave less than ``2^-60`` of the sum), 20 where every ``|z| < 1`` (the 20th
    term is below ``1/(20 20!) = 2e-20`` times ``|z|``, and the sum is at least ``3|z|/4``)."""
    largest = np.max(np.abs(z))
    k = _K[:20] if largest < 1.0 else _K[:int(2.0 * largest) + 61]
    total = _by_blocks(z, lambda block: (np.cumprod(block / k, axis=1) / k).sum(axis=1))
    return np.exp(-z) * (_EULER_GAMMA + np.log(np.abs(z)) + total)  # z^k / k! / k summed


def _by_blocks(z, row_sums):
    """``row_sums`` of the column ``z[:, None]``, ``_SERIES_ROWS`` arguments at a time (a
    block's terms at most 4096 x 141 numbers, whatever the input's size)."""
    if z.size <= _SERIES_ROWS:
        return row_sums(z[:, None])
    total = np.empty_like(z)
    for start in range(0, z.size, _SERIES_ROWS):
        total[start:start + _SERIES_ROWS] = row_sums(z[start:start + _SERIES_ROWS, None])
    return total


def _fraction(z):
    """``exp(-z) Ei(z) = -exp(x) E1(x)`` for ``x = -z`` in [1, 40] from the continued fraction,
    ``120 / sqrt(x)`` terms deep (against 40-digit values, the last place is reached with 95 terms
    at ``x = 1``, 51 at 2, 23 at 5, 9 at 20)."""
    x = -z
    tail = np.zeros_like(x)
    for k in range(int(math.ceil(120.0 / math.sqrt(np.min(x)))), 0, -1):
        tail = k * k / (x + 2.0 * k + 1.0 - tail)
    return -1.0 / (x + 1.0 - tail)


def _asymptotic(z):
    """``exp(-z) Ei(z)`` for ``|z| > 40``: ``(1/z) sum_{k<=40} k!/z^k``, stopped where its terms
    are smallest (they fall while ``k < |z|``): the first omitted one is below ``41!/40^41``,
    7e-17 of the sum."""
    k = _K[:40]
    return (1.0 + _by_blocks(z, lambda block: np.cumprod(k / block, axis=1).sum(axis=1))) / z
