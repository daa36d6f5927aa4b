"""The JFO film's refill departure (solver/model/refill.py, docs/model.md "The refill departure
(JFO)"): its closed forms, its ODE against SciPy's, its mass balance, and the collision that
uses it against the coupled phase run until the film is full again."""

import dataclasses
import functools
import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from solver import Physics, collide, pieces
from solver.model import cavitation, refill, rigid


@pytest.mark.parametrize("x, q", [(1.0, 0.3), (2.0, 19.0), (1.0, 9.999), (1.0, 10.001),
                                  (0.5, 40.0), (3.0, 1e-6)])
def test_outer_integral_is_the_integral_it_names(x, q):
    """I = Int_q^inf ds/(s (X+s)^3), closed form below sig = q/X = 10, series above: against
    quadrature (its own error estimate 1e-13 relative and below)."""
    exact, _ = quad(lambda s: 1.0 / (s * (x + s) ** 3), q, np.inf, epsabs=0.0, epsrel=1e-13,
                    limit=200)
    assert refill.outer_integral(x, q) == pytest.approx(exact, rel=1e-11)


@pytest.mark.parametrize("x, u, pi", [(1.0, 1.0, 1e-3), (5.0, 0.3, 1e-4), (0.2, 0.8, 1e-2)])
def test_at_the_reynolds_edge_the_front_stalls_and_the_force_is_the_reynolds_one(x, u, pi):
    """With the front on the Reynolds cavity's edge s_c (model/cavitation.py), s0 = s_c (no flux
    at the edge: the Reynolds condition) and the force is -U/(X + s_c), a third of
    cavitation.separation_force. The root is correct to about 1e-8 relative in sigma
    (cavitation._TOLERANCE, squared by Newton's last step), so s0 within 1e-7."""
    s_c = cavitation.cavity_fraction(pi * x * x / (6.0 * u)) * x
    assert refill.front_source(x, u, s_c, pi) == pytest.approx(s_c, rel=1e-7)
    force = refill.force(np.array([x]), np.array([u]), np.array([s_c]), pi)[0]
    assert force == pytest.approx(cavitation.separation_force(x, u, pi) / 3.0, rel=1e-7)


def test_outside_the_reynolds_edge_the_front_refills_and_inside_it_would_grow():
    x, u, pi = 1.0, 1.0, 1e-3
    s_c = cavitation.cavity_fraction(pi * x * x / (6.0 * u)) * x
    assert refill.front_source(x, u, 1.2 * s_c, pi) < 1.2 * s_c
    assert refill.front_source(x, u, 0.8 * s_c, pi) > 0.8 * s_c


# a release state: gap, speed, St, Pi, and cells (outer faces, fractions) whose front lies
# outside the Reynolds edge (s_c = 17.8 at X 2, U 0.5, Pi 1e-3)
RELEASE = (2.0, 0.5, 10.0, 1e-3)
FACES = np.array([1.0, 3.0, 6.0, 10.0, 15.0, 21.0, 28.0, 36.0])
THETAS = np.array([0.2, 0.25, 0.35, 0.45, 0.55, 0.7, 0.8, 0.9])


@functools.lru_cache(maxsize=None)
def _scipy_departure():
    """The same ODE (module docstring of refill.py) by SciPy's DOP853 at rtol 1e-13, cell by
    cell, each cell's run ended by the front reaching its inner face."""
    x_rel, u0, stokes, pi = RELEASE
    faces, thetas = refill._cavity(FACES, THETAS, x_rel, u0, pi)  # the front in its cell
    state, lnx, t = np.array([u0, 0.0, faces[-1]]), math.log(x_rel), 0.0
    for cell in range(faces.size - 1, -1, -1):
        theta, inner = thetas[cell], faces[cell - 1] if cell else 0.0

        def rhs(lnx_, y):
            x = math.exp(lnx_)
            u, _, q = y
            s0 = refill.front_source(x, u, q, pi)
            return [-x * (x + 2 * q - s0) / (stokes * (x + q) ** 2), x / u,
                    x * (s0 - q) / (x + q - theta * (x_rel + q))]

        # the axis is reached as q -> 0 with dq/d lnX ~ 1/ln(1/q): end the last cell just short
        target = inner if cell else 1e-12 * faces[0]
        event = lambda lnx_, y: y[2] - target  # noqa: E731
        event.terminal, event.direction = True, -1
        sol = solve_ivp(rhs, (lnx, lnx + 50.0), state, method="DOP853", rtol=1e-13, atol=1e-15,
                        events=event)
        lnx, state = sol.t_events[0][0], sol.y_events[0][0]
        state[2] = inner
    return math.exp(lnx), state[0], state[1]


def test_the_compiled_departure_is_scipys_dop853_at_rtol_1e_13():
    """Its closing state (the front at the axis) within 1e-8 relative of SciPy's: the compiled
    ODE runs at rtol 1e-10; the error over a departure of 8 face events and some 100 steps is a
    few times that (measured here: 2.5e-10)."""
    x_rel, u0, stokes, pi = RELEASE
    code, x_c, u_c, t_c, path = refill.departure(x_rel, u0, 0.0, stokes, pi, FACES, THETAS)
    assert code == refill.CLOSED
    x_ref, u_ref, t_ref = _scipy_departure()
    assert x_c == pytest.approx(x_ref, rel=1e-8)
    assert u_c == pytest.approx(u_ref, rel=1e-8)
    assert t_c == pytest.approx(t_ref, rel=1e-8)
    # the path starts at the release with the front on the last cell's face (it is fuller than
    # the one inside it: the front lies within it) and ends on the axis
    assert path[0, 0] == x_rel and path[3, -1] == 0.0
    assert FACES[-2] < path[3, 0] <= FACES[-1]
    assert np.all(np.diff(path[3]) <= 0.0) and np.all(np.diff(path[0]) > 0.0)


def test_the_front_starts_where_the_outermost_cells_liquid_puts_it():
    """The outermost cell (fuller than the one inside it) is full beyond the front and holds the
    inner cell's fraction inside it: the same liquid, Int theta (X_rel + s) ds, to rounding."""
    x_rel, u0, _, pi = RELEASE
    faces, thetas = refill._cavity(FACES, THETAS, x_rel, u0, pi)
    a, b, front = FACES[-2], FACES[-1], faces[-1]
    gap = lambda lo, hi: x_rel * (hi - lo) + 0.5 * (hi * hi - lo * lo)  # noqa: E731
    assert a < front < b and thetas[-1] == THETAS[-2]
    assert thetas[-1] * gap(a, front) + gap(front, b) == pytest.approx(THETAS[-1] * gap(a, b),
                                                                        rel=1e-12)
    assert np.array_equal(faces[:-1], FACES[:-1]) and np.array_equal(thetas[:-1], THETAS[:-1])


def test_the_void_changes_at_u_s0_along_the_path():
    """The cavity's void, Int_0^q (H - c) ds, changes at dV/dT = U q + (H_q - c(q)) dq/dT = U s0
    (the jump condition: the front's liquid is the film's flux). Its change up to the last
    sample before the closing against the trapezoidal integral of U s0 over the samples: the
    rule's error falls as they double (U s0 kinks at each face: measured 1.1e-3, 4.0e-4, 1.6e-4
    of the change at 200, 400, 800 samples), and it closes on the axis with no void left."""
    x_rel, u0, stokes, pi = RELEASE
    misfit = []
    for samples in (200, 800):
        _, _, _, _, path = refill.departure(x_rel, u0, 0.0, stokes, pi, FACES, THETAS,
                                            samples=samples)
        void = refill.void_volume(*path[[0, 3]], x_rel, u0, pi, FACES, THETAS)
        assert void[-1] == 0.0
        x, u, t, q = path[:, :-1]
        rate = u * np.array([refill.front_source(*v, pi) for v in zip(x, u, q)])
        change = np.trapezoid(rate, t) if hasattr(np, "trapezoid") else np.trapz(rate, t)
        misfit.append(abs(change / (void[-2] - void[0]) - 1.0))
    assert misfit[1] < 5e-4 and misfit[1] < misfit[0] / 4.0, misfit


def test_speed_at_is_the_departures_speed():
    """speed_at stops on x_target: the departure's speed there, on the path's samples (both
    at rtol 1e-10, separate runs: 1e-8)."""
    x_rel, u0, stokes, pi = RELEASE
    _, x_c, u_c, _, path = refill.departure(x_rel, u0, 0.0, stokes, pi, FACES, THETAS)
    for k in (5, 20, 38):
        assert refill.speed_at(x_rel, u0, stokes, pi, FACES, THETAS, path[0, k]) == \
            pytest.approx(path[1, k], rel=1e-8)
    beyond = 3.0 * x_c  # after the refill: the classic U = U_c - ln(x/X_c)/St
    assert refill.speed_at(x_rel, u0, stokes, pi, FACES, THETAS, beyond) == \
        pytest.approx(u_c - math.log(3.0) / stokes, rel=1e-8)


def test_a_front_inside_the_reynolds_edge_would_grow_and_a_full_film_has_no_refill():
    x_rel, u0, stokes, pi = RELEASE
    code, *_ = refill.departure(x_rel, u0, 0.0, stokes, pi, FACES[:3], THETAS[:3])
    assert code == refill.GROWS
    code, x, u, t, path = refill.departure(x_rel, u0, 0.0, stokes, pi, FACES, np.ones(8))
    assert (code, x, u, t, path.shape) == (refill.CLOSED, x_rel, u0, 0.0, (4, 1))
    with pytest.raises(ValueError, match="at least 2 samples"):
        refill.departure(x_rel, u0, 0.0, stokes, pi, FACES, THETAS, samples=1)


# --- the collision ----------------------------------------------------------------------------

SCENES = [dict(St=10.0, eps=1e-4, Pi=1e-3), dict(St=10.0, eps=1e-2, Pi=1e-4),
          dict(St=30.0, eps=1e-6, Pi=1e-4)]


def _coupled_until_full(physics, monkeypatch):
    """The collision as before solver 1.19.0: the coupled phase until the film is full again."""
    with monkeypatch.context() as m:
        m.setattr(refill, "exact_for", lambda physics: False)
        return collide(physics)


@pytest.mark.parametrize("fields", SCENES, ids=lambda f: f"St{f['St']:g}-eps{f['eps']:g}-Pi{f['Pi']:g}")
def test_the_refill_departure_agrees_with_the_coupled_phase_run_until_full(fields, monkeypatch):
    """The refill departure against the coupled phase run on until the film is full again, at
    the standard preset. Bounds from the 90-scene comparison (docs/model.md): e_wet within
    1.5e-3, ln x_e within 1.3e-3, the largest void within 4 %; these scenes 1e-4, 2e-4 and 1 %
    (measured). The collision ends its coupled phase earlier, and its departure holds the
    cavity until the front reaches the axis."""
    physics = Physics(cavitation="jfo", **fields)
    refilled = collide(physics)
    full = _coupled_until_full(physics, monkeypatch)
    assert refilled.ok and full.ok
    assert refilled.tau_release < full.tau_release
    assert refilled.e_wet == pytest.approx(full.e_wet, rel=1.5e-3)
    assert refilled.ln_x_e_x1 == pytest.approx(full.ln_x_e_x1, rel=1.3e-3)
    assert refilled.void_volume_max == pytest.approx(full.void_volume_max, rel=0.04)
    series = refilled.series
    departing = (series["phase"] == 2) & (series["cavity_radius"] > 0.0)
    assert departing.any()
    radius = series["cavity_radius"][series["phase"] == 2]
    assert np.all(np.diff(radius[radius > 0.0]) <= 0.0)  # the front only refills
    assert np.all(series["P_min"][departing] == -physics.Pi)


def test_where_the_refill_would_grow_the_coupled_phase_runs_on(monkeypatch):
    """A departure that answers GROWS (or STOPPED) hands the collision back to the coupled phase
    until the film is full again: the result is that of the plan without the refill departure,
    to the bit."""
    physics = Physics(cavitation="jfo", **SCENES[0])
    real = refill.departure

    def grows(*args, **kwargs):
        code, x, u, t, path = real(*args, **kwargs)
        return refill.GROWS, x, u, t, None

    with monkeypatch.context() as m:
        m.setattr(refill, "departure", grows)
        ran_on = collide(physics)
    full = _coupled_until_full(physics, monkeypatch)
    for name in ("e_wet", "ln_x_e_x1", "v_r", "void_volume_max", "tau_release", "steps"):
        assert getattr(ran_on, name) == getattr(full, name), name


def test_spheres_that_stop_with_the_cavity_open_run_the_coupled_phase_on(monkeypatch):
    """St 3, eps 1e-2, Pi 1e-4 (standard): where the coupled phase would end (released at X 7.2
    with U 0.14), the spheres would stop at X 17 with the cavity still open (the refill
    departure answers STOPPED; measured). The time loop asks ``refill.closes`` there and runs on
    until the film is full, in the same solve (no second one: ``collision.run_on`` is not
    called), so the collision is the coupled phase run until full, to the bit."""
    import solver.collision as collision

    physics = Physics(St=3.0, eps=1e-2, Pi=1e-4, cavitation="jfo")
    reruns = []
    real = collision.run_on
    with monkeypatch.context() as m:
        m.setattr(collision, "run_on", lambda plan: reruns.append(plan) or real(plan))
        ran_on = collide(physics)
    assert reruns == []
    coupled = ran_on.series["phase"] == 1
    assert ran_on.series["cavity_radius"][coupled][-1] == 0.0  # full at the coupled phase's end
    full = _coupled_until_full(physics, monkeypatch)
    for name in ("e_wet", "ln_x_e_x1", "v_r", "void_volume_max", "tau_release", "steps"):
        assert getattr(ran_on, name) == getattr(full, name), name


def test_closes_is_the_departures_first_pass():
    """``refill.closes`` (what the time loop asks) answers as ``departure`` does: CLOSED for the
    test's release state, and not where the front starts inside the Reynolds edge (GROWS)."""
    x_rel, u0, stokes, pi = RELEASE
    assert refill.closes(x_rel, u0, 0.0, stokes, pi, FACES, THETAS)
    assert not refill.closes(x_rel, u0, 0.0, stokes, pi, FACES[:3], THETAS[:3])
    assert refill.closes(x_rel, u0, 0.0, stokes, pi, FACES, np.ones(8))


def test_a_speed_at_x_ref_the_refill_cannot_give_is_the_classic_departures(monkeypatch):
    """Where speed_at answers None (its run to x_ref grew or stopped, while the departure's
    closed), e_wet is the classic departure's from the release, as before the refill departure:
    one line of physics instead of an exception."""
    physics = Physics(cavitation="jfo", **SCENES[0])
    with monkeypatch.context() as m:
        m.setattr(refill, "speed_at", lambda *args: None)
        result = collide(physics)
    coupled = result.series["phase"] == 1
    x, v = result.series["X"][coupled][-1], result.series["V"][coupled][-1]
    x_ref = result.x_ref_x0 * physics.x_start
    classic = rigid.restitution_of_speed(rigid.departure_speed(x, v, physics.St, x_ref), physics,
                                         x_ref)
    assert x < x_ref and result.e_wet == classic


def test_a_compressible_liquid_keeps_the_coupled_phase_until_full():
    """Its cells hold rho theta H, which the refill departure does not: its plan runs on."""
    from solver.integration.events import RELAXED_APART, RELAXED_FULL
    from solver.shortcuts import plan

    assert plan(Physics(cavitation="jfo", **SCENES[0])).end_event == RELAXED_APART
    compressible = Physics(cavitation="jfo", density_law="dowson-higginson", dh_c1=0.6,
                           dh_c2=1.7, **SCENES[0])
    assert plan(compressible).end_event == RELAXED_FULL
    assert plan(dataclasses.replace(compressible, cavitation="reynolds")).departure == "floor"
    assert pieces.RUN_ON == "run on"
