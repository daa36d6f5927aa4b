"""The rigid Barus film (solver/model/piezoviscous.py): closed forms against quadrature of the
pressure profile, the classic limit, and the rigid approach against direct integration."""

import math

import numpy as np
import pytest
from scipy import integrate

from solver.model import piezoviscous as pz
from solver.model import rigid

EPS = np.finfo(float).eps


def _load_by_quadrature(x, v, beta, in_tension="ambient"):
    """``Int_0^inf P ds`` of the closed-form profile, by adaptive quadrature."""
    val, _ = integrate.quad(lambda s: float(pz.rigid_pressure(s, x, v, beta, in_tension)), 0.0,
                            math.inf, epsabs=0.0, epsrel=1e-13, limit=200)
    return val


def _axis_by_quadrature(x, v, beta, in_tension="ambient", epsrel=1e-13):
    """``W(0) = (pi/2) Int_0^inf P dR``; split at R = 1 so the log singularity of the axis
    pressure at the glass gap sits at an endpoint of a finite interval."""
    def p(r):
        return float(pz.rigid_pressure(0.5 * r * r, x, v, beta, in_tension))

    a, _ = integrate.quad(p, 0.0, 1.0, epsabs=0.0, epsrel=epsrel, limit=200)
    b, _ = integrate.quad(p, 1.0, math.inf, epsabs=0.0, epsrel=1e-13, limit=200)
    return 0.5 * math.pi * (a + b)


# ---- closed forms ---------------------------------------------------------------------------
@pytest.mark.parametrize("x, v, beta, in_tension, expected", [
    (5.0, 1.0, 2.0, "ambient", 0.626653), (3.0, 1.0, 2.5, "ambient", 1.233686),
    (2.0, 0.5, 1.0, "ambient", 0.805765), (10.0, 1.0, 5.0, "ambient", 0.307990),
    (1.0, -1.0, 2.0, "law", -1.925280), (0.5, -1.0, 5.0, "law", -1.823480),
    (2.0, -0.3, 1.0, "law", -0.434483)])
def test_issue_check_values(x, v, beta, in_tension, expected):
    # issue 11's values, quoted to 6 decimals: rounding leaves at most 5e-7
    assert pz.rigid_force(x, v, beta, in_tension) == pytest.approx(expected, abs=1e-6)


@pytest.mark.parametrize("x, v, beta, in_tension", [
    (5.0, 1.0, 2.0, "ambient"), (3.0, 1.0, 2.5, "ambient"), (1.3, 0.5, 1.0, "ambient"),
    (10.0, 1.0, 5.0, "ambient"), (4.0, 2.0, 0.01, "ambient"), (1.0, -1.0, 2.0, "law"),
    (0.5, -1.0, 5.0, "law"), (2.0, -0.3, 1.0, "law"), (0.2, -2.0, 10.0, "law"),
    (1.0, -1.0, 2.0, "ambient")])
def test_load_matches_quadrature_of_the_profile(x, v, beta, in_tension):
    # quad at epsrel 1e-13 on a smooth profile; the closed form is good to a few round-offs
    assert pz.rigid_force(x, v, beta, in_tension) == pytest.approx(
        _load_by_quadrature(x, v, beta, in_tension), rel=1e-11)


def test_separating_film_keeps_ambient_viscosity_by_default():
    # "ambient": the tensile film is the classic one exactly (same formula, no law)
    assert pz.rigid_force(1.5, -0.7, 3.0) == pytest.approx(-3 * 0.7 / 1.5, rel=4 * EPS)
    s = np.linspace(0.0, 10.0, 11)
    np.testing.assert_allclose(pz.rigid_pressure(s, 1.5, -0.7, 3.0), -2.1 / (1.5 + s) ** 2,
                               rtol=4 * EPS)


@pytest.mark.parametrize("x, v, beta, in_tension", [(5.0, 1.0, 2.0, "ambient"),
                                                     (1.3, 0.5, 1.0, "ambient"),
                                                     (0.5, -1.0, 5.0, "law")])
def test_pressure_solves_the_film_equation(x, v, beta, in_tension):
    # (1/6) s H^3 exp(-beta P) dP/ds = -V s (the film equation integrated once, flux 0 on the
    # axis); central differences with step 1e-4 s: truncation ~1e-8, round-off ~EPS/1e-4 ~1e-12
    s = np.array([0.1, 0.7, 2.0, 9.0])
    ds = 1e-4 * s
    dp = (pz.rigid_pressure(s + ds, x, v, beta, in_tension)
          - pz.rigid_pressure(s - ds, x, v, beta, in_tension)) / (2 * ds)
    p = pz.rigid_pressure(s, x, v, beta, in_tension)
    h = x + s
    flux = s * h**3 * np.exp(-beta * p) * dp / 6.0
    np.testing.assert_allclose(flux, -v * s, rtol=1e-7)
    # and the reduced pressure is the isoviscous film: q = 3V/H^2 to round-off
    np.testing.assert_allclose(-np.expm1(-beta * p) / beta, 3 * v / h**2, rtol=1e-13)


def test_beta_to_zero_is_the_classic_film_to_round_off():
    x, v = 2.0, 1.0
    for beta in (0.0, 1e-300, 1e-200):
        assert pz.rigid_force(x, v, beta) == 3 * v / x
        assert pz.rigid_force(x, -v, beta, "law") == -3 * v / x
        assert pz.axis_deflection(x, v, beta) == pytest.approx(3 * rigid.I0 * v * x**-1.5,
                                                               rel=2 * EPS)
    for beta in (1e-12, 1e-8, 1e-4):
        z = 3 * beta * v / x**2
        # S = 1 + z/6 + z^2/15 + ... and G = 1 + 5z/16 + ...: the first correction, exactly;
        # what is left is z^2 plus a few round-offs
        assert pz.rigid_force(x, v, beta) / (3 * v / x) - 1 == pytest.approx(
            z / 6, abs=z * z + 4 * EPS)
        assert pz.rigid_force(x, -v, beta, "law") / (-3 * v / x) - 1 == pytest.approx(
            -z / 6, abs=z * z + 4 * EPS)
        assert pz.axis_deflection(x, v, beta) / (3 * rigid.I0 * v * x**-1.5) - 1 == \
            pytest.approx(5 * z / 16, abs=z * z + 4 * EPS)
        s = np.array([0.0, 1.0, 100.0])
        np.testing.assert_allclose(pz.rigid_pressure(s, x, v, beta), 3 * v / (x + s) ** 2,
                                   rtol=z + 4 * EPS)


@pytest.mark.parametrize("z", [pz._SERIES_BELOW, -pz._SERIES_BELOW, pz._CLOSE_TO_GLASS])
def test_load_factor_is_continuous_where_its_form_changes(z):
    # series / artanh form / log1p form: each good to a few round-offs on its own side
    below, above = pz.load_factor([z * (1 - 1e-13), z * (1 + 1e-13)])
    assert below == pytest.approx(above, rel=1e-13)


def test_glass_gap():
    v, beta = 0.8, 2.5
    k = pz.glass_gap(v, beta)
    assert k == pytest.approx(math.sqrt(3 * beta * v), rel=EPS)
    # the load stays finite there: (1/beta)[2k ln 2k - 2k ln k] = 2 ln2 k / beta
    assert pz.rigid_force(k, v, beta) == pytest.approx(2 * math.log(2) * k / beta, rel=4 * EPS)
    assert pz.rigid_force(k * (1 + 1e-9), v, beta) == pytest.approx(
        2 * math.log(2) * k / beta, rel=1e-6)  # slope ~ ln(x - k): ~2e-8 from the limit
    assert pz.rigid_force(k * (1 - 1e-9), v, beta) == math.inf
    assert pz.rigid_force(0.0, v, beta) == math.inf
    assert pz.rigid_pressure(0.0, k, v, beta) == math.inf  # log singular on the axis only
    assert np.isfinite(pz.rigid_pressure(1e-6, k, v, beta))
    assert pz.glass_gap(-1.0, beta) == 0.0


# ---- central deflection ---------------------------------------------------------------------
def test_axis_deflection_classic_is_the_hand_over_coefficient():
    # rigid.py's W(0) = 3 I0 V X^-1.5 is (pi/2) Int P dR of P = 3V/(X + R^2/2)^2
    x, v = 3.0, 0.7
    assert _axis_by_quadrature(x, v, 0.0) == pytest.approx(3 * rigid.I0 * v * x**-1.5,
                                                           rel=1e-12)
    assert pz.axis_deflection(x, v, 0.0) / x == pytest.approx(
        float(rigid.deformation_ratio(x, v)), rel=4 * EPS)  # = HANDOVER_COEFF V X^-2.5
    assert rigid.HANDOVER_COEFF == pytest.approx(3 * math.pi**2 / (4 * math.sqrt(2)), rel=EPS)


@pytest.mark.parametrize("x, v, beta, in_tension", [
    (5.0, 1.0, 2.0, "ambient"), (1.3, 0.5, 1.0, "ambient"), (10.0, 1.0, 5.0, "ambient"),
    (0.5, -1.0, 5.0, "law"), (2.0, -0.3, 1.0, "law"), (2.0, -0.3, 1.0, "ambient")])
def test_axis_deflection_matches_quadrature(x, v, beta, in_tension):
    # quad at epsrel 1e-13 (smooth integrand); closed form good to round-off
    assert pz.axis_deflection(x, v, beta, in_tension) == pytest.approx(
        _axis_by_quadrature(x, v, beta, in_tension), rel=1e-11)


def test_axis_deflection_is_finite_at_the_glass_gap():
    v, beta = 1.0, 2.0
    k = pz.glass_gap(v, beta)
    # (pi^2/(sqrt 2 beta)) sqrt(k) (2 - sqrt 2); quad with the log singularity at an endpoint:
    # QAGS extrapolates it to about 1e-11 (measured 1.3e-11; it cannot do 1e-11 reliably)
    closed = math.pi**2 / (math.sqrt(2) * beta) * math.sqrt(k) * (2 - math.sqrt(2))
    assert pz.axis_deflection(k, v, beta) == pytest.approx(closed, rel=8 * EPS)
    assert pz.axis_deflection(k, v, beta) == pytest.approx(
        _axis_by_quadrature(k, v, beta, epsrel=1e-10), rel=1e-9)


def test_bad_tension_choice_is_refused():
    with pytest.raises(ValueError, match="in_tension"):
        pz.rigid_force(1.0, 1.0, 1.0, "compression")


# ---- the rigid approach ---------------------------------------------------------------------
X0 = 1e-6**-0.4  # eps = 1e-6


@pytest.mark.parametrize("beta", [0.0, 1e-9])
@pytest.mark.parametrize("stokes, switch", [(10.0, 0.01), (30.0, 0.001), (2.0, 0.01)])
def test_approach_classic_limit(beta, stokes, switch):
    # beta = 1e-9 changes the film by z/6 ~ 1e-9 X^-2 (X >~ 2 here); the integration is at
    # rtol 1e-12, so 1e-8 covers both (measured: 1e-12 at most)
    r = pz.approach(X0, 1.0, 0.0, stokes, beta, switch)
    x_s = rigid.handover_separation(X0, stokes, switch)
    if x_s is None:
        assert r.event == "rest" and r.v_end == 0.0 and r.t_end == math.inf
        assert r.x_end == pytest.approx(math.exp(rigid.rest_separation(X0, 1.0, stokes)),
                                        rel=1e-8)
        head = rigid.approach_peaks(X0, stokes, 0.0)
    else:
        assert r.event == "handover"
        assert r.x_end == pytest.approx(x_s, rel=1e-8)
        head = rigid.approach_peaks(X0, stokes, x_s)
    inner = r.x[1:-1]  # the path, against the closed forms
    np.testing.assert_allclose(r.v[1:-1], rigid.velocity(inner, X0, 1.0, stokes), rtol=1e-8)
    np.testing.assert_allclose(r.t[1:-1], rigid.elapsed_time(inner, X0, 1.0, stokes),
                               rtol=1e-8)
    np.testing.assert_allclose(r.force, r.v / r.x, rtol=1e-8)
    for key, value in head.items():
        assert r.peaks[key] == pytest.approx(value, rel=1e-8), key


@pytest.mark.parametrize("fraction, event", [(0.999, "handover"), (1.001, "rest")])
def test_approach_finds_a_hand_over_close_to_the_deformation_peak(fraction, event):
    # a threshold just below the path's largest W(0)/X is crossed and recrossed within one step;
    # the peak event finds it (docs/model.md "Small deformation": the peak
    # 3 pi^2 eps exp(2.5 St - 1)/(10 sqrt 2 St)); tolerance as in the classic-limit test
    stokes = 5.0
    peak = 3 * math.pi**2 * 1e-6 * math.exp(2.5 * stokes - 1) / (10 * math.sqrt(2) * stokes)
    for beta in (0.0, 1e-9):
        r = pz.approach(X0, 1.0, 0.0, stokes, beta, fraction * peak)
        assert r.event == event
        if event == "handover":
            assert r.x_end == pytest.approx(
                rigid.handover_separation(X0, stokes, fraction * peak), rel=1e-8)


def _time_integration(x0, v0, stokes, beta, t):
    """The motion in time with the issue's closed-form load, independent of the module."""
    def load(x, v):
        k = math.sqrt(3 * beta * v)
        return ((x - k) * math.log(x - k) + (x + k) * math.log(x + k) - 2 * x * math.log(x)) / beta

    sol = integrate.solve_ivp(lambda _, y: [-y[1], -load(y[0], y[1]) / (3 * stokes)],
                              (0.0, t[-1]), [x0, v0], method="DOP853", rtol=1e-12, atol=1e-14,
                              dense_output=True)
    return sol.sol(t)


@pytest.mark.parametrize("x0, stokes, switch, event", [(10.0, 5.0, 0.05, "handover"),
                                                       (10.0, 20.0, 1.0, "glass"),
                                                       (30.0, 3.0, 1.0, "rest")])
def test_approach_matches_time_integration_at_beta_5(x0, stokes, switch, event):
    beta = 5.0
    r = pz.approach(x0, 1.0, 0.0, stokes, beta, switch)
    assert r.event == event
    n = np.isfinite(r.t).sum()
    x, v = _time_integration(x0, 1.0, stokes, beta, r.t[:n])
    # both at rtol 1e-12; differences measured ~1e-11 over the path
    np.testing.assert_allclose(r.x[:n], x, rtol=1e-9)
    np.testing.assert_allclose(r.v[:n], v, rtol=1e-9)
    if event == "handover":
        assert r.w0[-1] / r.x[-1] == pytest.approx(switch, rel=1e-10)  # root-found to ~1e-15
    if event == "glass":
        # the axis viscosity exp(beta P(0)) has reached e: X = GLASS_MARGIN k
        assert beta * r.p_axis[-1] == pytest.approx(pz.GLASS_LOG_VISCOSITY, rel=1e-10)
        assert r.x_end == pytest.approx(pz.GLASS_MARGIN * pz.glass_gap(r.v_end, beta), rel=1e-10)
    if event == "rest":
        assert r.v_end == 0.0 and r.t_end == math.inf
    assert np.all(np.diff(r.t[:n]) > 0) and np.all(np.diff(r.v) < 0)


def test_approach_peaks_bound_the_path():
    # the peaks are located by events on the log-derivatives; a dense path may not exceed them
    # (beyond round-off) and comes within its sampling of them: u spacing 1.5e-3 leaves a
    # quadratic 1e-6 at most (measured 3e-7), and its time is off by up to one spacing (1e-4)
    r = pz.approach(30.0, 1.0, 0.0, 3.0, 5.0, 1.0)
    dense = pz.approach(30.0, 1.0, 0.0, 3.0, 5.0, 1.0, samples=2001)
    for key, path in (("peak_force", dense.force), ("w0_max", dense.w0),
                      ("p_max", dense.p_axis)):
        assert path.max() <= r.peaks[key] * (1 + 1e-12)
        assert path.max() == pytest.approx(r.peaks[key], rel=1e-5)
        i = int(np.argmax(path))
        t_key = {"peak_force": "t_peak_force", "w0_max": "t_max_deformation",
                 "p_max": "t_p_max"}[key]
        assert r.peaks[t_key] == pytest.approx(dense.t[i], rel=1e-3)


def test_approach_ending_at_its_start():
    # hand-over at the start as rigid.handover_separation returns x_start; glass likewise
    r = pz.approach(10.0, 1.0, 2.0, 5.0, 5.0, 1e-3)
    assert (r.event, r.x_end, r.v_end, r.t_end, r.x.size) == ("handover", 10.0, 1.0, 2.0, 1)
    r = pz.approach(4.0, 1.0, 0.0, 5.0, 5.0, 10.0)  # k = 3.87 > 4 / GLASS_MARGIN
    assert r.event == "glass" and r.x.size == 1


def test_energy_along_the_rigid_path():
    # V0^2 - V^2 = Int D dT with the dissipation rate of the Barus film,
    # D = (2/(3 St)) Int s H^3 (dP/ds)^2 / (6 mu_bar) ds = (2/(3 St)) Int 6 V^2 s/(H (H^2 - k^2)) ds
    # (dP/ds = -6 V mu_bar / H^3, mu_bar = H^2/(H^2 - k^2)); dT = X/V du. Simpson on 201 points
    # uniform in u (spacing 2e-3): error ~h^4 ~ 1e-11, measured 5e-13
    stokes, beta = 5.0, 5.0
    r = pz.approach(10.0, 1.0, 0.0, stokes, beta, 0.05, samples=201)

    def rate_over_v(x, v):  # D / V
        k2 = 3 * beta * v
        val, _ = integrate.quad(lambda s: 6 * v * s / ((x + s) * ((x + s) ** 2 - k2)), 0.0,
                                math.inf, epsabs=0.0, epsrel=1e-12)
        return 2.0 / (3.0 * stokes) * val

    u = np.log(r.x[0] / r.x)
    dissipated = integrate.simpson([rate_over_v(x, v) * x for x, v in zip(r.x, r.v)], x=u)
    assert dissipated == pytest.approx(1.0 - r.v_end**2, rel=1e-8)


def test_exact_for():
    from solver import Physics

    assert pz.exact_for(Physics(St=5.0, eps=1e-3))
    assert pz.exact_for(Physics(St=5.0, eps=1e-3, beta=2.0))
    assert pz.exact_for(Physics(St=5.0, eps=1e-3, beta=2.0, viscosity_in_tension="law",
                                Pi=1e-3))
    assert not pz.exact_for(Physics(St=5.0, eps=1e-3, beta=2.0, viscosity_law="roelands"))
    assert not pz.exact_for(Physics(St=5.0, eps=1e-3, beta=2.0, density_law="dowson-higginson"))


def test_scalar_load_factor_is_the_array_one():
    from solver.model.piezoviscous import _load_factor_scalar, load_factor

    for z in (-3.0, -0.06, -0.05, -1e-3, 0.0, 1e-3, 0.05, 0.051, 0.3, 0.5, 0.51, 0.9, 1.0):
        assert _load_factor_scalar(z) == pytest.approx(float(load_factor(z)), rel=1e-15, abs=0)
