"""The liquid's laws (solver/model/liquid.py) against closed forms, quadrature and high precision.

The face's pressure difference ``Int rho/mu dP`` is the one new discretised term of a
pressure-dependent film: exact for Barus at constant density (its exponential fit is the closed
form), free of the cancellation that ruins the reduced pressure as an unknown, and second order
for the other laws.
"""

import math
from decimal import Decimal, getcontext

import numpy as np
import pytest
from scipy import integrate

from solver import Physics
from solver.model import liquid
from solver.model.liquid import (compression_energy, density, kink_departure,
                                 kirchhoff_difference, log_viscosity, pressure_of_kirchhoff,
                                 viscosity_ratio, volume_difference)


def _phys(**kw):
    return Physics(St=1.0, eps=1e-4, **kw).as_array()


def _quad_difference(a, b, phys):
    """``Int_a^b rho/mu dP`` by adaptive quadrature (split at the kink P = 0)."""
    def f(p):
        return density(p, phys)[0] * math.exp(-log_viscosity(p, phys)[0])
    points = [0.0] if a < 0.0 < b or b < 0.0 < a else None
    return integrate.quad(f, a, b, points=points, epsabs=0.0, epsrel=1e-13, limit=200)[0]


def test_barus_difference_has_no_cancellation_in_a_glassy_film():
    """At ``beta P ~ 30`` the reduced pressure ``(1 - exp(-beta P))/beta`` keeps ~1 % of its
    digits in a face difference; the kernel's ``exp(-beta P_lo) (-expm1(-beta dP))/beta`` keeps
    them all: checked against the same closed form in 50-digit decimal arithmetic."""
    getcontext().prec = 50
    beta = 5.0
    phys = _phys(beta=beta)
    for p_lo in (0.2, 3.0, 6.0, 8.0):
        # beta dp from 5e-9 to 5, the ends' ratio taken from beta dp = 1e-2 (2e-3, 4e-3: where
        # the ratio of the ends' mobilities is the least accurate, a relative 1e-16 / (beta dp))
        for dp in (1e-9, 1e-6, 1e-3, 2e-3, 4e-3, 1.0):
            got = kirchhoff_difference(p_lo, p_lo + dp, phys)[0]
            b, lo, hi = Decimal(beta), Decimal(p_lo), Decimal(p_lo) + Decimal(dp)
            exact = float(((-b * lo).exp() - (-b * hi).exp()) / b)
            # 1e-13: a few ulps through expm1 and exp (relative); the plain difference of reduced
            # pressures is off by ~1e-16 / (exp(-beta P) dP) relative: 1 at P = 8, dP = 1e-6
            assert got == pytest.approx(exact, rel=1e-13)
    naive = (1 - math.exp(-beta * 8.000001)) / beta - (1 - math.exp(-beta * 8.0)) / beta
    exact = kirchhoff_difference(8.0, 8.000001, phys)[0]
    assert abs(naive / exact - 1.0) > 1e-3  # what the reduced pressure as an unknown loses


@pytest.mark.parametrize("law", [
    dict(beta=4.0, viscosity_law="roelands", roelands_Z=0.6, roelands_PR=0.4),
    dict(density_law="dowson-higginson", dh_c1=0.3, dh_c2=0.85),
    dict(beta=4.0, density_law="dowson-higginson", dh_c1=0.6, dh_c2=1.7),
])
def test_difference_is_second_order_for_the_other_laws(law):
    """The exponential fit of ``ln(mu/rho)`` across a face is exact where the log is linear (Barus
    at constant density) and second order where it curves: the error of one interval falls 8x
    when it halves (cubic per interval, so second order over a fixed span)."""
    phys = _phys(**law)
    errors = []
    for width in (0.1, 0.05, 0.025, 0.0125):
        a = 0.8
        errors.append(abs(kirchhoff_difference(a, a + width, phys)[0]
                          - _quad_difference(a, a + width, phys)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # local order 3 (cubic error per interval); 2.7: allows the next term at the widest interval
    assert np.all(orders > 2.7), orders


def test_barus_difference_is_exact_and_splits_at_the_kink():
    phys = _phys(beta=2.5)
    for a, b in ((0.1, 3.0), (3.0, 0.1), (-2.0, 1.5), (1.5, -2.0), (-1.0, -0.3)):
        # 1e-12: the closed form against quadrature to 1e-13 (relative)
        assert kirchhoff_difference(a, b, phys)[0] == pytest.approx(_quad_difference(a, b, phys),
                                                                   rel=1e-12)
    # in tension the liquid keeps mu0 (viscosity_in_tension = "ambient"): the plain difference
    assert kirchhoff_difference(-1.0, -0.3, phys)[0] == 0.7
    tension = _phys(beta=2.5, viscosity_in_tension="law")
    assert kirchhoff_difference(-1.0, -0.3, tension)[0] == pytest.approx(
        (math.exp(2.5) - math.exp(0.75)) / 2.5, rel=1e-13)


def test_the_series_and_the_ends_ratio_agree_where_they_meet():
    """``_fitted`` takes a series below ``_SERIES_SPREAD`` of ``g`` across the face and the ratio
    of the ends' mobilities above it: value and both derivatives continuous there, the face
    either way round."""
    beta, p_lo = 5.0, 2.0
    phys = _phys(beta=beta)
    width = liquid._SERIES_SPREAD / beta
    for flip in (False, True):
        def face(dp):
            ends = (p_lo + dp, p_lo) if flip else (p_lo, p_lo + dp)
            return kirchhoff_difference(*ends, phys)
        # 5e-9: the two points are 2e-9 apart (relative), each number's slope in the spread is of
        # order 1; the branches themselves agree to 1e-14 (the series' truncation 2e-16, the
        # ratio's rounding 1e-16 / 1e-2)
        for got, want in zip(face(width * (1 + 1e-9)), face(width * (1 - 1e-9))):
            assert got == pytest.approx(want, rel=5e-9)


@pytest.mark.parametrize("law", [
    dict(beta=5.0), dict(beta=5.0, viscosity_in_tension="law"),
    dict(beta=4.0, viscosity_law="roelands", roelands_Z=0.6, roelands_PR=0.4),
    dict(beta=2.0, density_law="dowson-higginson", dh_c1=0.6, dh_c2=1.7),
    dict(viscosity_law="table", viscosity_table="0:1, 0.5:3, 1:20, 2:400"),
])
def test_the_value_alone_is_the_value_with_its_slopes(law):
    """The residual and the error norm take ``kirchhoff_between`` without its derivatives, the
    Jacobian with them: the same value to the bit, on either side of the series' spread, across
    the kinks and at glassy ends."""
    phys = _phys(**law)
    for a, b in ((0.3, 0.3001), (0.3, 0.31), (0.3, 2.0), (-1.0, 1.5), (0.2, 1.7), (150.0, 151.0),
                 (2.0, -0.5), (0.0, 0.7)):
        at_a, at_b = liquid.mobility(a, phys), liquid.mobility(b, phys)
        full = liquid.kirchhoff_between(a, at_a, b, at_b, phys, True)
        alone = liquid.kirchhoff_between(a, at_a, b, at_b, phys, False)
        assert alone[0] == full[0] and full == kirchhoff_difference(a, b, phys)


def test_a_glassy_face_passes_nothing_and_stays_finite():
    """Both ends' mobilities below ``exp(-745)`` (a glassy lens's ``beta P``): the interval's
    difference is 0 with finite derivatives, not ``0/0``; one end glassy: the closed form's
    other end alone."""
    beta = 5.0
    phys = _phys(beta=beta)
    assert kirchhoff_difference(200.0, 210.0, phys) == (0.0, 0.0, 0.0)
    value, d_lo, d_hi = kirchhoff_difference(100.0, 300.0, phys)
    assert value == pytest.approx(math.exp(-500.0) / beta, rel=1e-13)
    assert d_lo == pytest.approx(-math.exp(-500.0), rel=1e-13)
    assert abs(d_hi) <= 1e-13 * abs(d_lo)  # exp(-1500): 0, but for the rounding of two terms


def test_small_beta_is_the_classic_film():
    """``beta -> 0``: the difference tends to ``dP`` (relative change ``~beta P``), and at
    ``beta = 0`` it is ``dP`` bit for bit."""
    for beta in (1e-6, 1e-9, 1e-12):
        phys = _phys(beta=beta)
        got = kirchhoff_difference(0.5, 2.0, phys)[0]
        # the relative change is beta times the mean pressure (1.25), to first order
        assert abs(got / 1.5 - 1.0) == pytest.approx(1.25 * beta, rel=1e-3)
    assert kirchhoff_difference(0.5, 2.0, _phys())[0] == 1.5


def test_roelands_slope_at_zero_is_beta():
    phys = _phys(beta=3.0, viscosity_law="roelands", roelands_Z=0.6, roelands_PR=0.4)
    g, slope = log_viscosity(1e-9, phys)
    assert slope == pytest.approx(3.0, rel=1e-8)  # (1 + P/P_R)^(Z-1) at P = 1e-9
    # grows more slowly than Barus above p_R (Z < 1)
    assert log_viscosity(2.0, phys)[0] < 3.0 * 2.0
    assert viscosity_ratio(2.0, _phys(beta=3.0)) == pytest.approx(math.exp(6.0), rel=1e-14)


def test_energy_terms_match_their_integrals():
    phys = _phys(density_law="dowson-higginson", dh_c1=0.6, dh_c2=1.7)

    def rho(p):
        return density(p, phys)[0]

    def drho(p):
        return density(p, phys)[1]

    for p in (0.01, 0.5, 3.0, 20.0, -0.003, -0.02, -1.0):
        e = integrate.quad(lambda x: x * drho(x) / rho(x) ** 2, 0.0, p, epsrel=1e-13)[0]
        # 1e-9: closed form against quadrature (1e-13), relative; the closed forms' log1p and
        # the subtractions lose up to ~1e-10 at small |p| (the value is ~c1 p^2/2)
        assert compression_energy(p, phys) == pytest.approx(e, rel=1e-9)
        vol = integrate.quad(lambda x: 1.0 / rho(x), 0.0, p, epsrel=1e-13)[0]
        assert volume_difference(0.0, p, phys) == pytest.approx(vol, rel=1e-12)
    # in tension the compressibility c1 fades over 0.01: density and slope continuous at 0, the
    # expansion bounded by c1 * 0.01
    assert density(1e-12, phys)[0] - density(-1e-12, phys)[0] == pytest.approx(2 * 0.6e-12,
                                                                               rel=1e-3)
    assert density(-1e-12, phys)[1] == pytest.approx(density(1e-12, phys)[1], rel=1e-9)
    assert density(-5.0, phys)[0] == pytest.approx(1.0 - 0.6 * 0.01, rel=1e-15)
    # Dowson-Higginson tends to 1 + c1/c2 at infinite pressure
    assert density(1e12, phys)[0] == pytest.approx(1.0 + 0.6 / 1.7, rel=1e-9)


def test_table_is_exact_where_its_log_is_linear_and_barus_as_a_table_is_barus():
    """A measured table: ``ln(mu/mu0)`` linear between its points, so the face difference, split
    at the points, is exact; a table of the Barus law is the Barus law."""
    table = _phys(viscosity_table="0:1, 0.5:3, 1.5:400, 3:2000")
    points = [(0.0, 0.0), (0.5, math.log(3.0)), (1.5, math.log(400.0)), (3.0, math.log(2000.0))]

    def exact(a, b):  # piecewise Int exp(-g) dP with g linear on each segment
        total = 0.0
        for (p0, g0), (p1, g1) in zip(points, points[1:]):
            lo, hi = max(a, p0), min(b, p1)
            if hi > lo:
                slope = (g1 - g0) / (p1 - p0)
                g_lo, g_hi = g0 + slope * (lo - p0), g0 + slope * (hi - p0)
                total += (math.exp(-g_lo) - math.exp(-g_hi)) / slope
        return total

    for a, b in ((0.1, 0.4), (0.2, 2.9), (0.7, 1.2), (1.0, 2.0)):
        # 1e-13: a few ulps through expm1 per piece (relative)
        assert kirchhoff_difference(a, b, table)[0] == pytest.approx(exact(a, b), rel=1e-13)
        assert kirchhoff_difference(b, a, table)[0] == -kirchhoff_difference(a, b, table)[0]
    # beyond the last point: the last slope
    assert log_viscosity(4.0, table)[0] == pytest.approx(
        math.log(2000.0) + math.log(2000.0 / 400.0) / 1.5, rel=1e-14)
    barus, as_table = _phys(beta=3.0), _phys(viscosity_table=f"0:1, 10:{math.exp(30.0)!r}")
    for a, b in ((0.2, 1.0), (-1.0, 2.0), (3.0, 3.1)):
        assert kirchhoff_difference(a, b, as_table)[0] == pytest.approx(
            kirchhoff_difference(a, b, barus)[0], rel=1e-13)


def test_the_pressure_of_a_kirchhoff_pressure_inverts_the_transform():
    """``pressure_of_kirchhoff`` (the start of a coupled phase on the classic approach): for
    Barus the closed form ``P = -ln(1 - beta K)/beta``, and False beyond the ceiling ``1/beta``
    (a glass gap); for Roelands and a table, the pressure whose Kirchhoff pressure is ``K``."""
    beta = 3.0
    k = np.array([0.0, 1e-6, 0.05, 0.2, 0.33, 0.999 * (1.0 / beta)])
    out = np.empty_like(k)
    assert pressure_of_kirchhoff(k, _phys(beta=beta), out)
    # bisection to a few ulps of P, and the fitted integral exact for Barus: 1e-12 relative,
    # the closed form's own rounding near the ceiling (1 - beta K ~ 1e-3) included
    np.testing.assert_allclose(out, -np.log1p(-beta * k) / beta, rtol=1e-12, atol=1e-300)
    # (K reaches 1/beta itself in rounding, at P ~ 12: beyond it there is no pressure)
    assert not pressure_of_kirchhoff(np.array([0.1, 1.001 / beta]), _phys(beta=beta), out[:2])
    for phys in (_phys(beta=2.0, viscosity_law="roelands"),
                 _phys(viscosity_table="0:1, 0.5:3, 1.5:400, 3:2000")):
        k = np.array([0.01, 0.1, 0.2, 0.3])  # below the table's ceiling, 0.37
        out = np.empty_like(k)
        assert pressure_of_kirchhoff(k, phys, out)
        back = np.array([kirchhoff_difference(0.0, p, phys)[0] for p in out])
        # K rises with P at 1/mu <= 1: an ulp of P moves K by at most an ulp of its own size
        np.testing.assert_allclose(back, k, rtol=1e-13)
        assert np.all(out >= k)  # mu >= mu0 in compression: P >= K


def test_kink_departure_is_the_slope_jump_times_the_range():
    """``kink_departure``: the jump of ``d ln(mu/rho)/dP`` at a kink inside the range times the
    range, in closed form for each law's kink (the slopes are read a 1e-9 of the range to either
    side: each law's slope changes by less than 1e-8 relative there, hence rel=1e-7)."""
    barus = _phys(beta=2.0)
    assert kink_departure(-0.02, 0.03, barus) == pytest.approx(2.0 * 0.05, rel=1e-7)
    assert kink_departure(0.01, 0.03, barus) == 0.0  # no kink inside
    assert kink_departure(-0.03, 0.0, barus) == 0.0  # 0 at the end is not inside
    # the law read in tension too is smooth at 0: no departure (to the slopes' rounding)
    assert kink_departure(-0.02, 0.03, _phys(beta=2.0, viscosity_in_tension="law")) < 1e-15
    # Roelands' slope at 0 is beta (test_roelands_slope_at_zero_is_beta)
    assert kink_departure(-0.1, 0.1, _phys(beta=2.0, viscosity_law="roelands")) == \
        pytest.approx(2.0 * 0.2, rel=1e-7)
    # Dowson-Higginson's density and its slope are continuous at 0: what is left is the slope's
    # own change between the two points 4e-10 apart where it is read, at most the tension side's
    # curvature c1 / TENSION_WIDTH = 30 (x 2 for margin): 2 * 30 * 4e-10 * 0.2 = 4.8e-9, far below
    # any preset's rtol (fine: 1e-5)
    dh = _phys(density_law="dowson-higginson")
    assert kink_departure(-0.1, 0.1, dh) < 2 * 30.0 * (2e-9 * 0.2) * 0.2
    # a table: the largest slope jump among its points inside the range
    table = _phys(viscosity_table="0:1, 0.5:3, 1.5:400, 3:2000")
    s0, s1, s2 = (math.log(3.0) / 0.5, math.log(400.0 / 3.0) / 1.0,
                  math.log(2000.0 / 400.0) / 1.5)
    assert kink_departure(0.2, 1.0, table) == pytest.approx(abs(s1 - s0) * 0.8, rel=1e-7)
    assert kink_departure(-0.1, 2.0, table) == pytest.approx(
        max(s0, abs(s1 - s0), abs(s2 - s1)) * 2.1, rel=1e-7)


@pytest.mark.parametrize("text, words", [
    ("1:2, 2:3", ["start with the point 0:1"]), ("0:1", ["at least one more point"]),
    ("0:1, 2:5, 1:9", ["must increase"]), ("0:1, 1:-2", ["ratio > 0"]),
    ("0:1, 1;2", ["not a point"]), ("0:1, x:2", ["not a point"])])
def test_bad_tables_are_named(text, words):
    with pytest.raises(ValueError) as err:
        Physics(St=1.0, eps=1e-4, viscosity_table=text)
    assert all(w in str(err.value) for w in words), str(err.value)


def test_a_law_read_in_tension_stays_finite():
    """``viscosity_in_tension = "law"`` thins the liquid by ``exp(beta P)``: held at ``exp(300)``
    (a Newton iterate at P = -16, beta = 45 overflowed to inf), with a zero slope there."""
    phys = _phys(beta=45.0, viscosity_in_tension="law")
    value, d_lo, d_hi = kirchhoff_difference(-30.0, -20.0, phys)
    assert value == pytest.approx(10.0 * math.exp(300.0), rel=1e-12)  # the held mobility
    assert math.isfinite(d_lo) and math.isfinite(d_hi)
    # below the limit the law itself
    assert kirchhoff_difference(-2.0, -1.0, phys)[0] == pytest.approx(
        (math.exp(90.0) - math.exp(45.0)) / 45.0, rel=1e-12)
