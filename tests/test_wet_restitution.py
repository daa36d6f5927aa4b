"""The wet coefficient of restitution e_wet: the rigid departure from the release state, stick,
the reference separation x_ref, continuity at the stick-or-rebound threshold, the fast path."""

import math

import numpy as np
import pytest
from scipy import integrate, optimize

from solver import collide
from solver.master import MasterCurve
from solver.model import rigid


def _departure_by_ode(stokes, x_from, v_from, x_ref):
    """Integrate the rigid lubrication ODE dX/dT = -V, dV/dT = -V/(St X) (docs/model.md, "Rigid
    solution") from the release state outwards until X = x_ref; the separation speed there."""
    def rhs(t, y):
        return [-y[1], -y[1] / (stokes * y[0])]

    def reach(t, y):
        return y[0] - x_ref
    reach.terminal, reach.direction = True, 1.0
    # V -> 0 exponentially slowly near x_e; x_ref is reached in finite time when x_e > x_ref
    sol = integrate.solve_ivp(rhs, (0.0, 1e6), [x_from, v_from], events=reach, rtol=1e-11,
                              atol=1e-13, method="DOP853")
    assert sol.t_events[0].size, "the departure never reaches x_ref"
    return -sol.y_events[0][0][1]


@pytest.mark.parametrize("stokes, eps, x_ref_x0", [(10.0, 0.01, 1.0), (12.0, 0.03, 1.0),
                                                   (12.0, 0.03, 3.0), (30.0, 1e-4, 1.0)])
def test_e_wet_matches_direct_integration_of_the_departure(stokes, eps, x_ref_x0):
    c = collide(stokes, eps, accuracy="fast", x_ref_x0=x_ref_x0)
    assert c.ok and c.model == "ehd" and c.e_wet > 0.0
    coupled = c.series["phase"] == 1
    x_c, v_c = c.series["X"][coupled], c.series["V"][coupled]
    x_ref = x_ref_x0 * c.x0_over_x1
    # the departure starts from the release state, or from the last coupled row inside x_ref
    # when the deformation relaxed only beyond it (collision._wet_restitution)
    j = len(x_c) - 1 if x_c[-1] <= x_ref else np.nonzero((x_c <= x_ref) & (v_c < 0))[0][-1]
    x1, v1 = x_c[j], v_c[j]
    speed = _departure_by_ode(stokes, x1, v1, x_ref)
    st_ref = rigid.impact_stokes(stokes, c.x0_over_x1, x_ref)
    # same state, same ODE: only the ODE solver's tolerance (rtol 1e-11) separates the two
    assert c.e_wet == pytest.approx(speed * stokes / st_ref, rel=1e-8)
    assert c.St_ref == pytest.approx(st_ref, rel=1e-14)


def test_release_beyond_x_ref_agrees_with_the_rigid_departure_from_release():
    # eps = 0.01 releases at X = 9.0 > x0 = 6.3: e_wet from the last row inside x0 and the rigid
    # law run back from the release state differ by the deformation left between them,
    # O(release = 3e-3) of the speed at fast accuracy
    c = collide(10.0, 0.01, accuracy="fast")
    coupled = c.series["phase"] == 1
    x1, v1 = c.series["X"][coupled][-1], c.series["V"][coupled][-1]
    assert x1 > c.x0_over_x1
    back = rigid.restitution(x1, v1, c.physics, c.x0_over_x1)
    assert c.e_wet == pytest.approx(back, rel=3e-3)


def test_e_wet_is_zero_exactly_when_the_spheres_stick():
    rigid_scene = collide(2.0, 1e-6, accuracy="fast")  # never deforms: creeps to rest
    assert rigid_scene.model == "rigid" and rigid_scene.e_wet == 0.0
    stuck = collide(6.0, 0.01, accuracy="fast")  # rebounds inside x0 but stays there
    assert stuck.model == "ehd" and stuck.v_r > 0.0 and not stuck.escaped
    assert stuck.e_wet == 0.0
    assert rigid.departure_speed(2.0, 0.3, 10.0, 5.0) == 0.0  # still approaching at release


def test_x_ref_is_consistent_with_the_rigid_approach():
    # the approach from x_ref at St_ref arrives at x0 with speed v0 (St there): integrate it
    stokes, x0, x_ref = 12.0, 20.0, 70.0
    st_ref = rigid.impact_stokes(stokes, x0, x_ref)
    assert rigid.stokes_at_start(st_ref, x0, x_ref) == pytest.approx(stokes, rel=1e-15)
    v_ref = st_ref / stokes  # approach speed at x_ref in units of v0

    def at_x0(t, y):
        return y[0] - x0

    at_x0.terminal = True  # past x0 the march would crawl into x = 0 (26 s instead of 5 ms)
    sol = integrate.solve_ivp(lambda t, y: [-y[1], -y[1] / (stokes * y[0])], (0.0, 1e3),
                              [x_ref, v_ref], events=at_x0, rtol=1e-12, atol=1e-14,
                              method="DOP853")
    assert sol.y_events[0][0][1] == pytest.approx(1.0, rel=1e-9)
    # and e_wet at x_ref follows from e_wet at x0: St_ref e(x_ref) = St e(x0) - ln(x_ref/x0)
    # (a scene that releases inside x0, so both use the rigid departure from the same state)
    c0 = collide(30.0, 1e-4, accuracy="fast")
    c3 = collide(30.0, 1e-4, accuracy="fast", x_ref_x0=3.0)
    assert c0.tau_release == c3.tau_release
    assert c3.St_ref * c3.e_wet == pytest.approx(c0.St * c0.e_wet - math.log(3.0), rel=1e-12)
    with pytest.raises(ValueError, match="x_ref_x0"):
        collide(12.0, 0.03, accuracy="fast", x_ref_x0=0.5)
    with pytest.raises(ValueError, match="comes to rest before x0"):
        rigid.stokes_at_start(1.0, x0, x_ref)


def test_e_wet_is_continuous_across_the_threshold():
    # e_wet = ln(x_e/x0)/St leaves 0 where ln(x_e/x0) crosses 0, with ln x_e continuous in St
    eps = 0.01

    def ln_xe_x0(st):
        return collide(st, eps, accuracy="fast").ln_x_e_x0

    st_c = optimize.brentq(ln_xe_x0, 7.0, 8.0, xtol=1e-6)
    below, above = collide(st_c - 1e-3, eps, accuracy="fast"), collide(st_c + 1e-3, eps,
                                                                         accuracy="fast")
    assert below.e_wet == 0.0 and 0.0 < above.e_wet
    # slope d(ln x_e)/dSt is O(1) here (ln x_e/x0 goes -0.53 -> 0.18 from St 7 to 8), so
    # 1e-3 in St moves e_wet by ~1e-3 / St ~ 1e-4: no jump at St_c
    assert above.e_wet < 5e-4


@pytest.fixture(scope="module")
def curve():
    return MasterCurve.build("fast", s_min=5.0, s_max=40.0, per_decade=16)


def test_fast_path_carries_e_wet(curve):
    fast = curve.collide(20.0, 1e-4)
    direct = collide(20.0, 1e-4, accuracy="fast", save_profiles=False)
    assert fast.model == "master"
    assert fast.e_wet == pytest.approx(rigid.restitution_from_rest(
        fast.ln_x_e_x1, fast.physics, fast.x0_over_x1), rel=1e-14)
    # e_wet = ln(x_e/x0)/St: the curve's ln x_e error (<= 1e-3 relative, tests/test_master.py)
    # over ln(x_e/x0) of a few units
    assert fast.e_wet == pytest.approx(direct.e_wet, abs=2e-3)
    assert curve.collide(2.0, 1e-6).e_wet == 0.0  # off the curve: solved directly (rigid)
    assert np.isfinite(curve.collide(20.0, 1e-4, x_ref_x0=2.0).e_wet)
