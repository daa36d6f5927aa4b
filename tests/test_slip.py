"""Slip at the surfaces (solver/model/slip.py; docs/model.md, "Slip"): the closed forms against
each other and their limits, the film's faces against the rigid slip film under refinement, the
rigid phases against the motion integrated numerically, and collisions: the classic limit, the
energy balance and convergence."""

import math

import numpy as np
import pytest
from scipy import integrate

from solver import Physics, collide
from solver.model import slip
from solver.model.film import face_flux


@pytest.mark.parametrize("u", [1e-6, 0.3, 1.0, slip.FAR * (1 - 1e-9), slip.FAR, 10.0, 1e3, 1e9])
def test_the_force_is_the_potentials_derivative(u):
    """``X dG/dX = f*`` (the motion ``dV/dX = f*/(St X)`` integrates to ``G``), on both sides of
    the switch between the closed forms and their series: a central difference of relative step
    1e-5 is good to ~1e-9 relative (its truncation (1e-5)^2, its round-off 1e-16/1e-5 of G)."""
    c = 6.0
    x = u * c
    h = 1e-5 * x
    slope = (slip.potential(x + h, c) - slip.potential(x - h, c)) / (2.0 * h)
    assert float(slope * x) == pytest.approx(float(slip.force_factor(x, c)), rel=1e-8, abs=1e-12)


def test_the_closed_forms_have_their_limits():
    """Without slip (X/c -> inf) the classic film: ``f* = 1 - c/(3X) + c^2/(6X^2) ...``, ``G - ln(X/c) -> 1``,
    ``P -> 3V/H^2``; at contact (X/c -> 0) ``f* ~ 2 (X/c) (ln(c/X) - 1)`` and ``G -> -1/2``;
    continuous where the series takes over (to 1e-14, a few ulps of the values ~1-3)."""
    c = 1.0
    for u in (1e4, 1e6):
        assert float(slip.force_factor(u, c)) == pytest.approx(1.0 - 1.0 / (3.0 * u),
                                                                  abs=1.0 / (3.0 * u * u))
        assert float(slip.potential(u, c)) - math.log(u) == pytest.approx(1.0, abs=2.0 / u)
        assert float(slip.rigid_pressure(0.0, u, 1.0, c)) == pytest.approx(3.0 / u**2,
                                                                             rel=1.0 / u)
    u = 1e-8
    assert float(slip.force_factor(u, c)) == pytest.approx(2 * u * (math.log(1 / u) - 1),
                                                           rel=1e-6)
    assert float(slip.potential(0.0, c)) == -0.5
    for f in (slip.force_factor, slip.potential):
        assert float(f(slip.FAR * (1 - 1e-15), c)) == pytest.approx(float(f(slip.FAR, c)),
                                                                     rel=1e-14)
    z = 1.0 / slip.FAR  # the pressure's series/closed-form switch at c/H = 1/FAR
    h = c / z
    assert float(slip.rigid_pressure(0.0, h * (1 + 1e-15), 1.0, c)) == pytest.approx(
        float(slip.rigid_pressure(0.0, h, 1.0, c)), rel=1e-14)


def test_the_rigid_pressure_integrates_to_the_force():
    """``Int P ds = 3 (V/X) f*`` (the force's unit holds 1/3): the closed forms of the pressure and
    of the force are one solution (quadrature to 1e-10)."""
    for x, c in ((0.5, 6.0), (3.0, 0.6), (40.0, 600.0)):
        total = integrate.quad(lambda s: float(slip.rigid_pressure(s, x, 1.0, c)), 0.0, np.inf,
                               epsabs=0.0, epsrel=1e-12, limit=400)[0]
        assert total == pytest.approx(3.0 / x * float(slip.force_factor(x, c)), rel=1e-10)


def _discrete_axis_pressure(c, nodes, x=1.0, v=1.0, s_last=1e4):
    """The axis pressure of the film's faces (model/film.py, ``face_flux``) for the rigid slip
    film: the flux through a face is ``-V s_f`` (``dH/dT = -V`` everywhere, none through the
    axis), each face's drop follows from its conductance, summed inwards from the outer node held
    at the closed form. The nodes cluster at the axis, ``s = s_last (k/n)^2`` (a smooth map, so
    halving every cell is refining it)."""
    phys = Physics(St=10.0, eps=1e-4, slip_length=c / 6.0).as_array()
    s = s_last * (np.arange(nodes) / (nodes - 1.0)) ** 2
    s_face = 0.5 * (s[1:] + s[:-1])
    h = x + s
    p = float(slip.rigid_pressure(s[-1], x, v, c))
    for f in range(s.size - 2, -1, -1):
        unit = face_flux(s[f], s[f + 1], s_face[f], 0.0, 1.0, h[f], h[f + 1], phys)[0]
        p -= -v * s_face[f] / unit  # the face's flux per unit drop
    return p


def test_the_faces_converge_to_the_rigid_slip_film_at_second_order():
    """``flux_factor`` is exact for a uniform gap and in both limits of slip, second order
    between: the axis pressure's error falls by 4 +- 15 % each time every cell halves (the
    observed order 2 from three grids), at a slip gap c = 6 comparable with the film's width;
    without slip the faces are exact (round-off over 400 faces, 1e-12)."""
    exact = float(slip.rigid_pressure(0.0, 1.0, 1.0, 6.0))
    errors = [abs(_discrete_axis_pressure(6.0, n) - exact) for n in (401, 801, 1601)]
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(3.4 < r < 4.6 for r in ratios), (errors, ratios)
    assert _discrete_axis_pressure(1e-300, 401) == pytest.approx(
        float(slip.rigid_pressure(0.0, 1.0, 1.0, 1e-300)), rel=1e-12)


def test_the_rigid_approach_is_the_motion_integrated():
    """The closed-form speed and the quadrature time of ``slip.approach`` against the motion
    ``dX/dT = -V, dV/dT = -(V/X) f*/St`` integrated by an explicit Runge-Kutta pair at
    rtol 1e-11 (agreement to 1e-8)."""
    x0, stokes, c = 40.0, 5.0, 6.0
    path = slip.approach(x0, stokes, c, switch=1e-3)
    assert path.event == "handover"
    assert float(slip.deformation_ratio(path.x[-1], path.v[-1], c)) == pytest.approx(1e-3,
                                                                                  rel=1e-8)

    def motion(t, y):
        return [-y[1], -y[1] / y[0] * float(slip.force_factor(y[0], c)) / stokes]

    sol = integrate.solve_ivp(motion, (0.0, path.t[-1]), [x0, 1.0], method="DOP853",
                              rtol=1e-11, atol=1e-14, dense_output=True)
    x_num, v_num = sol.sol(path.t)
    np.testing.assert_allclose(x_num, path.x, rtol=1e-8)
    np.testing.assert_allclose(v_num, path.v, rtol=1e-8)


def test_a_slow_approach_rests_where_the_potential_says():
    """At small St the rigid slip film stops the spheres: ``G(X_e/c) = G(X0/c) - St``."""
    x0, stokes, c = 40.0, 0.5, 6.0
    path = slip.approach(x0, stokes, c, switch=1e-3)
    assert path.event == "rest" and path.v[-1] == pytest.approx(0.0, abs=1e-12)
    assert float(slip.potential(path.x[-1], c)) == pytest.approx(
        float(slip.potential(x0, c)) - stokes, rel=1e-12)


def test_an_approach_that_rests_reaches_its_rest_only_after_infinite_time():
    """The approach's last sample at its rest has speed 0 and time inf. In rounding the speed
    there came out just above 0, and the quadrature of ``dX/|V|`` towards it met a speed of
    exactly 0: ``collide`` raised ZeroDivisionError at every preset (St 2, eps 1e-6, slip
    length 3, found by a hostile scan); it is a rigid collision that rests, ``x_e`` where the
    potential says."""
    physics = Physics(St=2.0, eps=1e-6, slip_length=3.0)
    c = slip.mobility_gap(physics)
    path = slip.approach(physics.x_start, physics.St, c, switch=1e-3)
    assert path.event == "rest" and path.v[-1] == 0.0 and path.t[-1] == math.inf
    assert np.all(np.isfinite(path.t[:-1])) and np.all(np.diff(path.t[:-1]) > 0)
    result = collide(physics, accuracy="fast")
    assert result.status == "ok" and result.model == "rigid" and result.e_wet == 0.0
    assert result.ln_x_e_x1 == pytest.approx(
        slip.rest_separation(physics.x_start, 1.0, physics.St, c), rel=1e-12)


def test_a_film_drained_to_round_off_says_why_the_solve_failed():
    """A slip length of tens of ``x1`` drains the film to round-off and the steps underflow
    (docs/model.md, "Slip"); the failure's message names that cause, which no accuracy mends,
    instead of only the step's underflow."""
    result = collide(Physics(St=10.0, eps=1e-4, slip_length=30.0), accuracy="fast")
    assert result.status == "step_underflow"
    assert "drained to round-off" in result.message and math.isnan(result.e_wet)


def test_the_rigid_departure_comes_to_rest_or_hands_back():
    """A slow departure is sampled to 0.99 of the way to its rest (in ln X); a fast one hands
    back to the classic departure 30 e-folds out, where the two rest separations agree to
    ``c/X ~ 1e-13`` (1e-9 allowed for the fixed-point solve of ``rest_separation``)."""
    x, v, stokes, c = 2.0, -0.3, 10.0, 6.0
    path = slip.departure(x, v, 0.0, stokes, c)
    ln_rest = slip.rest_separation(x, v, stokes, c)
    assert path.event == "rest" and path.x[-1] < math.exp(ln_rest)
    assert np.all(np.diff(path.t) > 0) and np.all(path.v < 0)
    far = slip.departure(x, -30.0, 0.0, stokes, c)  # rest beyond e^30 x: hands back
    assert far.event == "far" and far.x[-1] == pytest.approx(x * math.exp(30.0), rel=1e-12)
    # far out the slip path is the classic one: ln X_e - ln X = St |V| to O(c/X)
    assert slip.rest_separation(far.x[-1], far.v[-1], stokes, c) == pytest.approx(
        math.log(far.x[-1]) - stokes * far.v[-1], abs=1e-9)


def test_slip_refuses_a_cavitation_floor():
    with pytest.raises(ValueError, match="slip"):
        Physics(St=10.0, eps=1e-4, slip_length=1.0, Pi=1.0)


def test_a_vanishing_slip_is_the_classic_collision():
    """slip 1e-7 x1 moves the film by ~c/H ~ 6e-7 where it matters: e and v_r within 1e-5 of the
    classic film's (fast's hand-over error is 6.4e-3, so both share their numerical error and the
    difference is the physics'); slip 0 is the classic film itself (``Physics.classic``)."""
    classic = collide(Physics(St=20.0, eps=1e-3), accuracy="fast")
    slipping = collide(Physics(St=20.0, eps=1e-3, slip_length=1e-7), accuracy="fast")
    assert slipping.status == "ok" and slipping.model == "ehd"
    assert slipping.e_wet == pytest.approx(classic.e_wet, abs=1e-5)
    assert slipping.v_r == pytest.approx(classic.v_r, abs=1e-5)


def test_slip_lets_the_spheres_rebound_more_and_closes_the_energy():
    """Slip lowers the film's resistance, so less of the energy is lost to it: ``e`` grows with
    the slip length; the energy balance closes to the standard preset's rtol scale (the classic
    film's energy_error at St 10, eps 1e-4 is 1.5e-4; slip's face weighting adds 2nd-order terms,
    hence 1e-3); and e converges: fast and fine within 0.01, standard between them to 0.004."""
    e = []
    for slip_length in (0.3, 1.0, 3.0):
        r = collide(Physics(St=10.0, eps=1e-4, slip_length=slip_length))
        assert r.status == "ok" and abs(r.energy_error) < 1e-3
        e.append(r.e_wet)
    assert e[0] < e[1] < e[2]
    by_preset = [collide(Physics(St=10.0, eps=1e-4, slip_length=1.0), accuracy=a).e_wet
                 for a in ("fast", "standard", "fine")]
    assert abs(by_preset[0] - by_preset[2]) < 0.01
    assert abs(by_preset[1] - by_preset[2]) < 0.004


def test_slip_on_rough_surfaces_rebounds_as_its_departure_says():
    """With roughness the slip departure must not read as resting on the asperities: at slip 3
    x1 the smooth film rebounds with e 0.37 (docs/model.md, "Slip"); roughness 0.5 x1, below its
    closest approach, keeps a rebound, and e is the slip departure's reading of the coupled
    phase's end (not 0, which is what a departure handing on a state at rest gave)."""
    r = collide(Physics(St=10.0, eps=1e-4, slip_length=3.0, roughness=0.5, e_dry=0.9),
                accuracy="fast")
    assert r.status == "ok" and r.e_wet > 0.1
    assert r.series["phase"][-1] == 2 and np.all(np.diff(r.series["X"][r.series["phase"] == 2]) > 0)
