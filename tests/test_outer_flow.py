"""The exact Stokes resistance (solver/model/outer_flow.py) against its limits and itself.

Units (docs/model.md, "Outer flow"): ``a`` reduced radius (wall: the sphere's radius), ``x`` the
gap between the surfaces, ``v`` the relative velocity, ``R = F / (6 pi mu a v)``.
"""

import math

import numpy as np
import pytest

from solver.model import outer_flow as of


def _brenner_direct(alpha, n_terms):
    # Brenner (1961) eq. (2.19) written as printed (no rescaling), a fixed number of terms;
    # only usable where nothing overflows or cancels (moderate alpha)
    n = np.arange(1, min(n_terms, int(300 / alpha)) + 1, dtype=float)  # sinh(m alpha) < 1e300
    m = 2 * n + 1
    bracket = ((2 * np.sinh(m * alpha) + m * np.sinh(2 * alpha))
               / (4 * np.sinh((n + 0.5) * alpha) ** 2 - m ** 2 * np.sinh(alpha) ** 2) - 1)
    return 4 / 3 * np.sinh(alpha) * np.sum(n * (n + 1) / ((2 * n - 1) * (2 * n + 3)) * bracket)


@pytest.mark.parametrize("alpha", [0.5, 1.0, 1.5, 2.0, 2.5, 3.0])
def test_wall_series_is_brenners_formula(alpha):
    # the rescaled evaluation against the formula as printed, 400 terms (terms ~ exp(-2 n alpha):
    # below 1e-300 by then); 1e-13 relative: round-off of ~10 operations per term
    gap = math.cosh(alpha) - 1.0
    assert of.wall_resistance(gap) == pytest.approx(_brenner_direct(alpha, 400), rel=1e-13)


@pytest.mark.parametrize("gap", [1e-4, 1e-2, 0.3, 3.0, 100.0])
def test_wall_closed_form_matches_the_general_linear_system(gap):
    # independent algebra: the 4x4 no-slip system of pair_forces with a huge second sphere (the
    # wall is its limit, radius ratio 1e9: the wall's curvature changes R by O(1e-9 (1 + gap)))
    # against Brenner's closed-form sum
    f1, _ = of.pair_forces(gap, 1e9, 1.0, 0.0)
    assert -f1 == pytest.approx(of.wall_resistance(gap), rel=1e-8 * (1 + gap))


@pytest.mark.parametrize("gap", [1e-6, 1e-3, 1.0, 1e3])
def test_series_converged(gap):
    # N terms against 2N terms (the stopping rule's claim): the sum with tol = 1e-12 and with
    # tol = 1e-15 (more terms) agree to 1e-10, plus the round-off of a sum of that size
    # (a few ulp of R: 1e-15 R, i.e. 1e-9 at x = 1e-6 a where R = 1e6)
    for resistance in (of.wall_resistance, of.equal_spheres_resistance):
        r = resistance(gap, tol=1e-12)
        assert abs(r - resistance(gap, tol=1e-15)) < 1e-10 + 1e-15 * r


def test_series_tail_bound_holds_with_doubled_terms():
    # the stopping rule itself: the sum it stops at (tol = 1e-10) against the same terms summed
    # to n = 60 / alpha + 100, where they are below exp(-120) of the first: the difference is
    # the tail the rule claims to be < 1e-10, plus round-off (a few ulp of R, 1e-15 R)
    for gap in (1e-5, 1e-2, 1.0):
        alpha = of.alpha_wall(gap)
        got = of.wall_resistance(gap, tol=1e-10)
        full = _brenner_series_rescaled(alpha, int(60 / alpha) + 100)
        assert abs(got - full) < 1e-10 + 1e-15 * got


def _brenner_series_rescaled(alpha, n_terms):
    calls = []

    def fake_sum(terms, n_guess, tol):
        calls.append(1)
        return float(np.sum(terms(np.arange(1, n_terms + 1, dtype=float))))

    real = of._sum_series
    of._sum_series = fake_sum
    try:
        gap = 2.0 * math.sinh(0.5 * alpha) ** 2
        return of.wall_resistance(gap)
    finally:
        of._sum_series = real


@pytest.mark.parametrize("gap", [1e-5, 1e-4, 1e-3, 1e-2])
def test_wall_small_gap_limit_cox_brenner(gap):
    # Cox & Brenner (1967): lambda = a/x + (1/5) ln(a/x) + 0.971 + O(x ln x). Tolerance: 5e-4 for
    # the published constant's three decimals, plus the next term O((x/a) ln(a/x)), whose
    # coefficient Cox & Brenner do not give: bounded here by the leading logarithm's 1/5 (the
    # next term comes from the same O(x/a) correction of the gap shape; the series shows
    # 0.05-0.08 for x <= 1e-2 a, so a wrong 1/5 or a wrong constant fails)
    x = gap
    asymptote = 1.0 / x + 0.2 * math.log(1.0 / x) + 0.971
    assert abs(of.wall_resistance(gap) - asymptote) <= 5e-4 + 0.2 * x * math.log(1.0 / x)


def test_wall_regular_part_limit_is_cox_brenners_constant():
    # lambda - a/x - (1/5) ln(a/x) at x = 1e-6 a: 0.971 (Cox & Brenner 1967) to its three
    # decimals; the O(x ln x) term is ~1e-6 there
    assert of.wall_outer_regular(1e-6) == pytest.approx(0.971, abs=5e-4)


@pytest.mark.parametrize("resistance, coefficient", [(of.wall_resistance, 0.2),
                                                     (of.equal_spheres_resistance, 0.45)])
def test_logarithm_of_the_small_gap_limit(resistance, coefficient):
    # the coefficient of ln(a/x): wall 1/5 (Cox & Brenner 1967); equal spheres 9/20 in these
    # units (Jeffrey & Onishi 1984, g2 = 9/40 for X11 and -X12 each, in the single-sphere scale:
    # F/(6 pi mu a_s u) with u = v/2, a_s = 2a, is R). From R - a/x at x = 1e-5 and 1e-6: the
    # constant cancels and what is left is O(x ln x) ~ 1e-4 / ln(10) of the slope
    x1, x2 = 1e-5, 1e-6
    slope = ((resistance(x2) - 1 / x2) - (resistance(x1) - 1 / x1)) / math.log(x1 / x2)
    assert slope == pytest.approx(coefficient, abs=1e-4)


def test_wall_large_distance_first_reflections():
    # eps = a/h, h the centre's distance to the wall (h = a + x). First wall reflection (Lorentz
    # 1907): lambda = 1 + (9/8) eps; repeated, the same reflection gives (81/64) eps^2; the next
    # term is eps^3 (Faxen's; lambda = 1 / (1 - (9/8) eps + (1/2) eps^3 + O(eps^4)), Happel &
    # Brenner 1965 ch. 7: its eps^3 coefficient is (9/8)^3 - 1/2 = 0.924). Tolerances: that
    # eps^3 term, 0.924 + O(eps) with eps <= 1/30, bounded by 1.0 eps^3
    for h in (30.0, 100.0, 1000.0):
        eps = 1.0 / h
        lam = of.wall_resistance(h - 1.0)
        assert abs(lam - (1 + 9 / 8 * eps)) <= 81 / 64 * eps ** 2 + 1.0 * eps ** 3
        assert abs(lam - (1 + 9 / 8 * eps + 81 / 64 * eps ** 2)) <= 1.0 * eps ** 3


def test_wall_large_distance_faxen_term():
    # the eps^3 coefficient itself, (lambda - 1 - 9/8 eps - 81/64 eps^2) / eps^3 -> 0.924 with an
    # O(eps) remainder (eps^4 term of the reflection series, coefficient O(1)): at eps = 1e-3
    eps = 1e-3
    coefficient = (of.wall_resistance(1 / eps - 1) - 1 - 9 / 8 * eps - 81 / 64 * eps ** 2) / eps ** 3
    assert coefficient == pytest.approx((9 / 8) ** 3 - 0.5, abs=5 * eps)


def test_equal_spheres_lubrication_limit():
    # leading term: two spheres of radius a_s approaching at relative velocity v feel
    # F = 6 pi mu (a_s/2)^2 v / x (reduced radius a = a_s/2), i.e. R = a/x; in the single-sphere
    # convention (each sphere at u = v/2) F / (6 pi mu a_s u) = a_s / (2x), and per relative
    # velocity and sphere radius F / (6 pi mu a_s v) = a_s / (4 x) (the brief's 1/4)
    for x in (1e-6, 1e-4):
        r = of.equal_spheres_resistance(x)
        # R x -> 1 with the correction (9/20) x ln(a/x) + O(x)
        assert r * x == pytest.approx(1.0, abs=0.45 * x * math.log(1 / x) + 2 * x)
    a_s, x_phys, v = 1.0, 1e-5, 1.0
    a = a_s / 2
    force_over_6pimu = of.equal_spheres_resistance(x_phys / a) * a * v
    assert force_over_6pimu / (a_s * v) == pytest.approx(a_s / (4 * x_phys), rel=1e-3)


def test_equal_spheres_large_distance():
    # eps = a_s/d (d centre distance): the other sphere's Stokeslet on the axis, velocity
    # (3/2) eps u against the motion, so R = 1 + (3/2) eps + (9/4) eps^2 (the reflection
    # repeated); next term eps^3: (3/2)^3 from the third reflection and an O(1) Faxen and
    # dipole part, so bounded by 4.5 eps^3
    for d_over_as in (10.0, 100.0, 1000.0):
        eps = 1 / d_over_as
        gap = (d_over_as - 2.0) * 2.0  # x / a with a = a_s / 2
        r = of.equal_spheres_resistance(gap)
        assert abs(r - (1 + 1.5 * eps + 2.25 * eps ** 2)) <= 4.5 * eps ** 3


@pytest.mark.parametrize("gap", [1e-4, 1e-2, 1.0, 50.0])
def test_equal_spheres_closed_form_matches_the_linear_system(gap):
    # the 2x2 odd solution against the full 4x4 system with u1 = +1, u2 = -1 (each towards the
    # other at unit speed); 1e-9: the 4x4 solve loses ~log10(1/alpha^2) digits at small gaps
    f1, f2 = of.pair_forces(gap, 1.0, 1.0, -1.0)
    r = of.equal_spheres_resistance(gap)
    assert -f1 == pytest.approx(r, rel=1e-9)
    assert f2 == pytest.approx(r, rel=1e-9)


def test_pair_isolated_spheres_and_reflection():
    # far apart each sphere has its Stokes drag -u; sphere 2 at rest is pushed by sphere 1's
    # Stokeslet, (3/2)(a1/d) u1 (first reflection), with an O((a/d)^3) remainder
    for ratio in (1.0, 3.0):
        a1, a2 = 1.0, ratio
        d = 2000.0
        a = a1 * a2 / (a1 + a2)
        gap = (d - a1 - a2) / a
        f1, f2 = of.pair_forces(gap, ratio, 1.0, 0.0)
        # f1: -1 - (3/2 a2/d)(3/2 a1/d) (second reflection) + O(d^-3)
        assert f1 == pytest.approx(-1.0 - 2.25 * a1 * a2 / d ** 2, abs=10 / d ** 3)
        # f2 = F2 / (6 pi mu a2): the velocity of the Stokeslet (3/2)(a1/d) u1
        assert f2 == pytest.approx(1.5 * a1 / d, abs=10 / d ** 3)


@pytest.mark.parametrize("ratio", [0.5, 2.0, 4.0])
def test_pair_unequal_lubrication(ratio):
    # unequal spheres, sphere 2 at rest: F1 = 6 pi mu a^2 u1 / x (a reduced radius) + the
    # logarithm g2 ln(a_avg / x) with Jeffrey & Onishi's (1984) g2 = l (1 + 7 l + l^2) /
    # (5 (1 + l)^3), l = a2/a1, in F / (6 pi mu a1 u1). The slope of F1/(6 pi mu a1 u1) - a^2/(a1 x)
    # between x = 1e-3 a and 1e-4 a is g2 up to the O(x ln x) term (~1e-3 / ln 10)
    lam = ratio
    a1, a2 = 1.0, ratio
    a = a1 * a2 / (a1 + a2)
    g2 = lam * (1 + 7 * lam + lam ** 2) / (5 * (1 + lam) ** 3)

    def outer(gap):
        f1, _ = of.pair_forces(gap, ratio, 1.0, 0.0)
        return -f1 - a / (a1 * gap)

    slope = (outer(1e-4) - outer(1e-3)) / math.log(10.0)
    assert slope == pytest.approx(g2, abs=5e-3)


def test_outer_corrections_finite_and_smooth_to_contact():
    # the join to the lubrication region: R - a/x grows like c ln(a/x) (finite for every x > 0),
    # R - a/x - c ln(a/x) tends to a constant. Down to x = 1e-6 a: finite, monotone in x on a
    # geometric grid, and smooth: second differences in ln x below 1e-6 (round-off is
    # ~1e-14 a/x = 1e-8 at the smallest gap; the function's own curvature there is O(x))
    x = np.geomspace(1e-6, 1e-1, 26)
    for regular, log_c in ((of.wall_outer_regular, of.WALL_LOG),
                           (of.equal_spheres_outer_regular, of.EQUAL_LOG)):
        g = np.array([regular(v) for v in x])
        assert np.all(np.isfinite(g))
        assert np.all(np.diff(g) > 0)
        curvature = np.diff(g, 2)
        assert np.all(np.abs(curvature[:10]) < 1e-6 + 10 * x[2:12])
    w = np.array([of.wall_outer(v) for v in x])
    assert np.all(np.isfinite(w))
    assert w == pytest.approx(np.array([of.wall_outer_regular(v) for v in x])
                              + 0.2 * np.log(1 / x), rel=1e-14, abs=1e-14)


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf])
def test_bad_gap_refused(bad):
    with pytest.raises(ValueError, match="gap"):
        of.wall_resistance(bad)
    with pytest.raises(ValueError, match="gap"):
        of.equal_spheres_resistance(bad)


# ---- two free spheres of any radii and masses: their relative motion (pair_resistance) --------

@pytest.mark.parametrize("gap", [1e-3, 0.05, 1.0, 20.0])
def test_pair_of_equal_spheres_is_the_equal_spheres_result(gap):
    # equal radii and masses: the zero-momentum motion is the symmetric one; 1e-9: pair_forces'
    # 4x4 solve (module docstring); the image chain and the sinh series both to ~1e-12 of C
    assert of.pair_resistance(gap, 1.0, 1.0) == pytest.approx(of.equal_spheres_resistance(gap),
                                                              rel=1e-9)
    assert of.pair_added_mass(gap, 1.0, 1.0) == pytest.approx(of.equal_spheres_added_mass(gap),
                                                              rel=1e-11)


@pytest.mark.parametrize("gap", [1e-3, 0.1, 2.0])
def test_pair_tends_to_the_wall(gap):
    # a2/a1 = 1e4, m2/m1 = 1e12: sphere 2 is a wall at rest up to O(a1/a2) = 1e-4 (its
    # curvature over the gap's extent) -> 1e-3 relative bounds it with margin; the pair's C is
    # per rho_f V1 / (2 m), twice the wall's per rho_f V1 / m1
    assert of.pair_resistance(gap, 1e4, 1e12) == pytest.approx(of.wall_resistance(gap), rel=1e-3)
    assert of.pair_added_mass(gap, 1e4, 1e12) == pytest.approx(2.0 * of.wall_added_mass(gap),
                                                               rel=1e-3)


@pytest.mark.parametrize("ratio, masses", [(0.5, 0.3), (2.0, 1.0), (4.0, 20.0)])
def test_pair_small_gap_limit_jeffrey_onishi(ratio, masses):
    # near contact R = a/x + g ln(a/x) + O(1): the film's forces on the two spheres are equal and
    # opposite to that order, so whatever the masses R is the single sphere's with the other at
    # rest, g = (1 + 7 l + l^2) / (5 (1 + l)^2) (Jeffrey & Onishi's g2 in the reduced radius).
    # x R/a -> 1 with the O(x ln x) remainder (2e-3 at 1e-4), and the slope of R - a/x against
    # ln(a/x) between 1e-3 and 1e-4 is g up to the O(x ln x) term (as the test above: 5e-3)
    lam = ratio
    g = (1 + 7 * lam + lam ** 2) / (5 * (1 + lam) ** 2)
    assert of.pair_log(lam) == pytest.approx(g, rel=1e-15)
    assert 1e-4 * of.pair_resistance(1e-4, lam, masses) == pytest.approx(1.0, abs=2e-3)
    slope = (of.pair_resistance(1e-4, lam, masses) - 1e4
             - of.pair_resistance(1e-3, lam, masses) + 1e3) / math.log(10.0)
    assert slope == pytest.approx(g, abs=5e-3)


@pytest.mark.parametrize("ratio, masses", [(0.5, 0.3), (3.0, 5.0)])
def test_pair_far_field_reflections(ratio, masses):
    # far apart, by reflections (each sphere in the other's Stokeslet, (3/2)(a_j/d) u_j, and that
    # reflected back): f1 = -(u1 (1 + k) - (3/2)(a2/d) u2), f2 = -(u2 (1 + k) - (3/2)(a1/d) u1),
    # k = (9/4) a1 a2 / d^2, so with u1 = m/m1 = s1, u2 = -m/m2 = -s2:
    # R a = (s1^2 + l s2^2)(1 + k) + 3 (l/d) s1 s2 + O(d^-3) (Faxen terms and the third
    # reflection). The remainder must fall like d^-3: its ratio between d and 2d is 8 (within
    # [6, 10]: the next order's share)
    lam = ratio
    a = lam / (1 + lam)
    s1, s2 = masses / (1 + masses), 1 / (1 + masses)

    def remainder(d):
        k = 2.25 * lam / d ** 2
        expected = ((s1 ** 2 + lam * s2 ** 2) * (1 + k) + 3 * lam / d * s1 * s2) / a
        return of.pair_resistance((d - 1 - lam) / a, lam, masses) - expected

    r1, r2 = remainder(60.0), remainder(120.0)
    assert abs(r1) < 20.0 / 60.0 ** 3
    assert 6.0 < r1 / r2 < 10.0
    # the added mass far away: the isolated spheres' (1/2 each, weighted by V_i u_i^2)
    c = (s1 ** 2 + lam ** 3 * s2 ** 2)  # 4 T / (rho V1 v^2), T = sum rho V_i u_i^2 / 4
    assert of.pair_added_mass(1e6, lam, masses) == pytest.approx(c, rel=1e-9)


def test_pair_bad_ratios_refused():
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="radius_ratio must be a finite number > 0"):
            of.pair_resistance(0.1, bad, 1.0)
        with pytest.raises(ValueError, match="mass_ratio must be a finite number > 0"):
            of.pair_added_mass(0.1, 1.0, bad)
