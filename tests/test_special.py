"""solver/special.py: the elliptic integrals and the exponential integral against closed forms,
tabulated values and scipy.special (an independent implementation: Cephes' polynomial
approximations and specfun's series), which the solver used before 1.15.1."""

import math

import numpy as np
import pytest
from scipy import special as reference

from solver import special

ULP = np.finfo(float).eps
# Against 40-digit values (mpmath, 12000 arguments over [0, 1], near both ends to 1e-300):
# ellipke and ellipkm1 within 2.8 units of the last place, scipy.special within 1.5; over 20
# random samples like the one below the two differed by 3.5 units at most: 6 leaves margin for
# another platform's sqrt and division.
ELLIPTIC_RTOL = 6 * ULP
# exp(-z) Ei(z) against 40-digit values (4300 arguments in [-40, 40]): within 7 units, scipy
# within 10.2, away from the root of Ei at 0.3725, where both are accurate to a unit of 1
# absolute (gamma + ln z + the series, three terms of order 1, cancel there).
EI_RTOL, EI_ATOL = 20 * ULP, 2 * ULP


def _parameters():
    rng = np.random.default_rng(5)
    return np.concatenate([
        rng.random(20000),
        1.0 - 10.0 ** -rng.uniform(0.0, 16.0, 2000),  # near the pole of K
        10.0 ** -rng.uniform(0.0, 300.0, 2000),  # near 0
        [0.0, 0.5, np.nextafter(0.5, 1.0), np.nextafter(1.0, 0.0), 5e-324]])


def test_complete_elliptic_integrals_agree_with_scipy():
    m = _parameters()
    k, e = special.ellipke(m)
    finite = m < 1.0
    np.testing.assert_allclose(k[finite], reference.ellipk(m[finite]), rtol=ELLIPTIC_RTOL, atol=0)
    np.testing.assert_allclose(e, reference.ellipe(m), rtol=ELLIPTIC_RTOL, atol=0)
    # K(1 - p) with p small: the complementary form keeps every digit of p
    p = m[m > 0.0]
    np.testing.assert_allclose(special.ellipkm1(p), reference.ellipkm1(p), rtol=ELLIPTIC_RTOL,
                               atol=0)
    # 1 - m given separately where it is known without cancellation (the elastic kernel's use)
    k_p, e_p = special.ellipke(1.0 - p, p)
    np.testing.assert_allclose(k_p, reference.ellipkm1(p), rtol=ELLIPTIC_RTOL, atol=0)
    np.testing.assert_allclose(e_p, reference.ellipe(1.0 - p), rtol=ELLIPTIC_RTOL, atol=0)


def test_one_value_takes_the_scalar_path_with_the_arrays_answer():
    """A float (and a 0-d array) goes through ``_ellipke_scalar``, the same operations in the
    same order as one element of an array, so the same answer to the bit; every value of a
    batch agrees with it to the unit of the last place the batch's extra AGM steps can move
    (the batch iterates until its slowest element has converged); NaN outside [0, 1]."""
    m = _parameters()[::7]
    batch_k, batch_e = special.ellipke(m)
    for i, mi in enumerate(m):
        k, e = special.ellipke(float(mi))
        one_k, one_e = special.ellipke(np.array([mi]))
        assert (k, e) == (one_k[0], one_e[0]), mi
        assert special.ellipke(np.float64(mi)) == (k, e)
        assert abs(k - batch_k[i]) <= ULP * abs(k) and abs(e - batch_e[i]) <= ULP * abs(e), mi
        if mi > 0.0:
            assert special.ellipkm1(float(mi)) == special.ellipkm1(np.array([mi]))[0], mi
    assert all(math.isnan(v) for x in (-0.5, 1.5, math.nan) for v in special.ellipke(x))
    assert special.ellipkm1(0.0) == math.inf


def test_complete_elliptic_integrals_closed_forms():
    k_half = math.gamma(0.25) ** 2 / (4.0 * math.sqrt(math.pi))  # K(1/2)
    e_half = (0.5 * math.pi + k_half**2) / (2.0 * k_half)  # Legendre's relation at m = 1/2
    k, e = special.ellipke(np.array([0.0, 0.5, 1.0]))
    assert k[0] == pytest.approx(0.5 * math.pi, rel=ULP)
    assert e[0] == pytest.approx(0.5 * math.pi, rel=ULP)
    assert k[1] == pytest.approx(k_half, rel=2 * ULP)  # 1.5 units off, measured
    assert e[1] == pytest.approx(e_half, rel=2 * ULP)
    assert k[2] == math.inf and e[2] == 1.0
    assert special.ellipkm1(0.0) == math.inf
    assert special.ellipkm1(1.0) == pytest.approx(0.5 * math.pi, rel=ULP)
    # scalars in, scalars out; outside [0, 1]: NaN (the model never asks there)
    for m in (0.3, 0.7):  # either branch of E
        assert all(np.ndim(v) == 0 for v in special.ellipke(m))
        assert np.ndim(special.ellipkm1(m)) == 0
        assert special.ellipke(m)[1] == pytest.approx(float(reference.ellipe(m)),
                                                      rel=ELLIPTIC_RTOL)
    assert special.ellipke(np.full((2, 3), 0.7))[1].shape == (2, 3)
    assert np.all(np.isnan(special.ellipke([-0.1, 1.1, np.nan])[1]))
    assert np.all(np.isnan(special.ellipkm1([-0.1, 1.1, np.nan])))
    # 1 - m given separately: broadcast against m, NaN outside [0, 1]
    k, e = special.ellipke([0.3, 0.9], p=[0.7, 0.1])
    np.testing.assert_allclose(k, reference.ellipk([0.3, 0.9]), rtol=ELLIPTIC_RTOL)
    assert special.ellipke(np.full((2, 3), 0.7), np.full(3, 0.3))[1].shape == (2, 3)
    assert all(math.isnan(v) for v in (*special.ellipke(0.3, p=1.5), *special.ellipke(0.7, p=-0.1)))


def test_scaled_exponential_integral_agrees_with_scipy():
    rng = np.random.default_rng(6)
    z = np.concatenate([rng.uniform(-40.0, 40.0, 20000), rng.uniform(-1.5, 1.5, 4000),
                        -(10.0 ** -rng.uniform(0.0, 300.0, 500)),
                        10.0 ** -rng.uniform(0.0, 300.0, 500),
                        [-40.0, -1.0, np.nextafter(-1.0, 0.0), 40.0, 0.3725]])
    np.testing.assert_allclose(special.scaled_ei(z), np.exp(-z) * reference.expi(z),
                               rtol=EI_RTOL, atol=EI_ATOL)


def test_scaled_exponential_integral_tabulated_values_and_branches():
    # Ei(1) and E1(1) (Abramowitz & Stegun, table 5.1), to the last place
    assert special.scaled_ei(1.0) * math.e == pytest.approx(1.8951178163559367555, rel=2 * ULP)
    assert -special.scaled_ei(-1.0) / math.e == pytest.approx(0.21938393439552027368, rel=4 * ULP)
    # where two expansions meet they agree (the asymptotic one's first omitted term is 7e-17
    # relative at |z| = 40; the series and continued fraction within their 7 units each)
    for z in (40.0, -40.0):
        inner = special.scaled_ei(z)
        outer = special.scaled_ei(np.nextafter(z, 2.0 * z))
        assert outer == pytest.approx(inner, rel=16 * ULP)
    assert special.scaled_ei(np.nextafter(-1.0, -2.0)) == pytest.approx(special.scaled_ei(-1.0),
                                                                        rel=16 * ULP)
    # beyond 40 the asymptotic series, without overflow (40-digit values; 1/z at 1e300)
    big = special.scaled_ei(np.array([1e3, -1e3, 1e300]))
    np.testing.assert_allclose(big, [1.0010020060241207e-3, -0.9990019940238807e-3, 1e-300],
                               rtol=2 * ULP)
    assert special.scaled_ei(0.0) == -math.inf and math.isnan(special.scaled_ei(math.nan))
