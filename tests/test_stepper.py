"""The time loop's parts (solver/integration/stepper.py, and the step's interpolant in
solver/integration/dense.py), each against what it must be exactly.

The whole loop is tested through collisions (closed forms, energy, convergence: test_collision.py,
test_convergence.py); here each part on its own, where a wrong coefficient or a swapped index
would otherwise show only as more steps.
"""

import numpy as np
import pytest

from solver.integration import dense, stepper


@pytest.mark.parametrize("dt, dt_prev", [(0.1, 0.1), (0.13, 0.05), (0.02, 0.3)])
def test_bdf2_is_exact_for_quadratics(dt, dt_prev):
    """Variable-step BDF2 ``y1 - a1 y0 - a2 y_1 = b dt y'(t1)`` holds exactly for every
    polynomial of degree 2 (its order), whatever the two step sizes."""
    t_prev, t0 = 0.7, 0.7 + dt_prev
    t1 = t0 + dt
    a1, a2, b = stepper._bdf2(dt, t0, t_prev, 2)
    for c0, c1, c2 in [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.3, -2.0, 5.0)]:
        f = lambda t: c0 + c1 * t + c2 * t * t  # noqa: E731
        df = c1 + 2.0 * c2 * t1
        # 1e-12: a few roundings of O(1) terms, relative to the largest term
        assert f(t1) - a1 * f(t0) - a2 * f(t_prev) == pytest.approx(b * dt * df, abs=1e-12)
    assert stepper._bdf2(dt, t0, t_prev, 1) == (1.0, 0.0, 1.0)  # implicit Euler to start


# accepted times, newest first, unevenly spaced (the loop's history: stepper.History)
TIMES = np.array([0.9, 0.72, 0.5, 0.41, 0.2, 0.0])


def _rows(f, t):
    return np.array([f(ti) for ti in t])


def test_predictor_extrapolates_polynomials_exactly():
    """Through three states the predictor is the quadratic, through two the line; its error
    factor is ``dt / (t_new - t_oldest)``."""
    t, dt = TIMES[3:], 0.15  # 0.41, 0.2, 0.0
    quad = lambda t: np.array([1.0 + 2.0 * t - 3.0 * t * t, -t * t])  # noqa: E731
    out = np.empty(2)
    fac = stepper._predict(dt, t, 2, _rows(quad, t), out)
    np.testing.assert_allclose(out, quad(t[0] + dt), rtol=0, atol=1e-13)  # round-off, O(1) terms
    assert fac == pytest.approx(dt / (t[0] + dt - t[2]), rel=1e-15)
    line = lambda t: np.array([2.0 - t, 3.0 * t])  # noqa: E731
    fac = stepper._predict(dt, t, 1, _rows(line, t), out)
    np.testing.assert_allclose(out, line(t[0] + dt), rtol=0, atol=1e-13)
    assert fac == pytest.approx(dt / (t[0] + dt - t[1]), rel=1e-15)
    assert stepper._predict(dt, t, 0, _rows(line, t), out) == 0.0
    np.testing.assert_array_equal(out, line(t[0]))


@pytest.mark.parametrize("degree", [3, 4, 5])
def test_higher_degree_predictor_is_exact_for_its_polynomials(degree):
    """Through ``d + 1`` states the predictor of degree ``d`` reproduces every polynomial of that
    degree at the new time (and not one of degree ``d + 1``: the points it uses are the newest
    ``d + 1``); its error factor is ``dt / (t_new - t_d)``."""
    dt = 0.11
    poly = lambda t: np.array([(t - 0.3) ** degree, 1.0 - t ** (degree - 1)])  # noqa: E731
    out = np.empty(2)
    fac = stepper._predict(dt, TIMES, degree, _rows(poly, TIMES), out)
    # 1e-12: Lagrange weights of size up to ~30 times O(1) values, a few roundings each
    np.testing.assert_allclose(out, poly(TIMES[0] + dt), rtol=0, atol=1e-12)
    assert fac == pytest.approx(dt / (TIMES[0] + dt - TIMES[degree]), rel=1e-15)
    higher = lambda t: np.array([t ** (degree + 1), 0.0])  # noqa: E731
    stepper._predict(dt, TIMES, degree, _rows(higher, TIMES), out)
    assert abs(out[0] - higher(TIMES[0] + dt)[0]) > 1e-6


@pytest.mark.parametrize("order", [1, 2, 3, 4, 5])
def test_bdf_of_order_k_is_exact_for_polynomials_of_degree_k(order):
    """The variable-step BDF of order ``k`` (``_coefficients``) holds exactly for every polynomial
    of degree ``k`` on uneven steps, and its coefficients sum to 1 (a constant is kept). Orders 1
    and 2 are ``_bdf2``'s closed form; the general formula agrees with it (checked at 2 by
    computing the Lagrange form here)."""
    dt = 0.13
    t_new = TIMES[0] + dt
    a = np.zeros(stepper.SLOTS)
    b = stepper._coefficients(dt, TIMES, order, a)
    assert a[:order].sum() == pytest.approx(1.0, abs=1e-12)
    for shift in (0.0, 0.37):
        f = lambda t: (t - shift) ** order  # noqa: E731
        df = order * (t_new - shift) ** (order - 1)
        history = sum(a[j] * f(TIMES[j]) for j in range(order))
        # 1e-11: coefficients up to ~20 times O(1) values, a few roundings each
        assert f(t_new) - history == pytest.approx(b * dt * df, abs=1e-11)
    if order == 2:  # the closed form is the Lagrange form
        d_new = 1 / (t_new - TIMES[0]) + 1 / (t_new - TIMES[1])
        assert b == pytest.approx(1 / (d_new * dt), rel=1e-14)


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_basis_values_and_slopes_are_the_lagrange_polynomials(k):
    """``dense.lagrange_basis`` at a point, at a node and between nodes: the values reproduce
    every polynomial of degree ``k`` through the ``k + 1`` newest times, and the slopes its
    derivative."""
    values, slopes = np.empty(stepper.SLOTS), np.empty(stepper.SLOTS)
    f = lambda t: (t - 0.21) ** k + 0.5 * t  # noqa: E731
    df = lambda t: k * (t - 0.21) ** (k - 1) + 0.5  # noqa: E731
    for x in (TIMES[0], TIMES[1], 0.5 * (TIMES[0] + TIMES[1]), TIMES[0] + 0.07):
        dense.lagrange_basis(TIMES, k, x, values, slopes)
        # 1e-12: weights of size up to ~30 times O(1) values, a few roundings each
        assert values[:k + 1] @ f(TIMES[:k + 1]) == pytest.approx(f(x), abs=1e-12)
        assert slopes[:k + 1] @ f(TIMES[:k + 1]) == pytest.approx(df(x), abs=1e-10)


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_newton_form_is_the_interpolant_and_its_derivative(k):
    """``dense.divided_differences`` and ``dense.newton_form``, the value and slope
    ``dense.extremum_in_step`` reads: the polynomial of degree ``k`` through the ``k + 1`` newest
    times and its derivative, the same as ``dense.lagrange_basis`` gives, at the step's ends and
    inside it."""
    f = lambda t: (t - 0.21) ** k + 0.5 * t  # noqa: E731
    df = lambda t: k * (t - 0.21) ** (k - 1) + 0.5  # noqa: E731
    rows = np.array([[f(t), -3.0 * f(t)] for t in TIMES])
    coef, values, slopes = (np.empty(stepper.SLOTS) for _ in range(3))
    for x in (TIMES[0], TIMES[1], 0.5 * (TIMES[0] + TIMES[1]), TIMES[0] + 0.07):
        dense.lagrange_basis(TIMES, k, x, values, slopes)
        for col, scale in ((0, 1.0), (1, -3.0)):
            dense.divided_differences(TIMES, k, rows, col, coef)
            value, slope = dense.newton_form(TIMES, k, coef, x)
            # 1e-12 and 1e-10, as the Lagrange basis' test above: differences of O(1) values
            # over time differences of 0.1-1, a few roundings each
            assert value == pytest.approx(scale * f(x), abs=1e-12)
            assert value == pytest.approx(values[:k + 1] @ rows[:k + 1, col], abs=1e-12)
            assert slope == pytest.approx(scale * df(x), abs=1e-10)
            assert slope == pytest.approx(slopes[:k + 1] @ rows[:k + 1, col], abs=1e-10)


@pytest.mark.parametrize("k", [3, 4, 5])
def test_extremum_in_step_finds_each_columns_interior_extremum(k):
    """``dense.extremum_in_step``: over columns whose values are polynomials of degree ``k`` in
    time, the smallest interior minimum of the last step (``TIMES[1]`` to ``TIMES[0]``) and its
    time, to the bisection's resolution; a column monotone over the step has none; the largest
    value with ``sign`` -1."""
    t_lo, t_hi = TIMES[1], TIMES[0]
    centres = (t_lo + 0.3 * (t_hi - t_lo), t_lo + 0.8 * (t_hi - t_lo), t_hi + 0.5)
    depths = (0.2, 0.1, -5.0)  # the third column falls all through the step: no interior minimum

    def column(t, c, d):
        return (t - c) ** 2 * (1.0 + (t - c) ** (k - 2)) + d if k > 2 else (t - c) ** 2 + d

    rows = np.array([[column(t, c, d) for c, d in zip(centres, depths)] for t in TIMES])
    basis = np.zeros((4, stepper.SLOTS))
    value, when = dense.extremum_in_step(TIMES, rows, 3, k, 1.0, basis)
    # the columns are (t - c)^2 (1 + (t - c)^(k-2)) + d: a minimum d at c; the second column's
    # 0.1 is the smaller interior one (the third's -5 lies beyond the step)
    assert value == pytest.approx(0.1, abs=1e-12)
    assert when == pytest.approx(centres[1], abs=1e-9)  # 2^-50 of the step, and the root's
    value, _ = dense.extremum_in_step(TIMES, -rows, 3, k, -1.0, basis)
    assert value == pytest.approx(-0.1, abs=1e-12)
    value, _ = dense.extremum_in_step(TIMES, rows[:, 2:], 1, k, 1.0, basis)
    assert value == np.inf


@pytest.mark.parametrize("k", [3, 4, 5])
def test_dissipated_in_step_integrates_its_polynomial_exactly(k):
    """``dense.dissipated_in_step``: the integral over the last step of the polynomial through the
    ``k + 1`` newest dissipation rates, exact for degree ``k`` (Gauss-Legendre's three points
    are exact to degree 5)."""
    rate = lambda t: 1.0 + (t - 0.1) ** k  # noqa: E731
    antiderivative = lambda t: t + (t - 0.1) ** (k + 1) / (k + 1)  # noqa: E731
    got = dense.dissipated_in_step(TIMES.copy(), rate(TIMES), k, np.zeros((4, stepper.SLOTS)))
    # 1e-13: a few roundings of O(1) values over a step of 0.1
    assert got == pytest.approx(antiderivative(TIMES[0]) - antiderivative(TIMES[1]), abs=1e-13)


def test_step_factor_bounds_growth_and_keeps_the_lu():
    """Growth at most 2x (BDF2 zero-stability needs < 2.41x), shrink at most 5x, and a proposed
    growth under 1.2x keeps the step (and so the factorised matrix); above order 2 the growth
    is held to ``GROWTH`` and the step follows the order's error ``~ dt^(k+1)``."""
    assert stepper._step_factor(0.0, 2) == 2.0
    assert stepper._step_factor(1e-9, 2) == 2.0
    assert stepper._step_factor(1e3, 2) == 0.2
    assert stepper._step_factor(0.55, 2) == 1.0  # 0.9 * 0.55^(-1/3) = 1.096: kept
    err = 0.2
    assert stepper._step_factor(err, 2) == pytest.approx(0.9 * err ** (-1.0 / 3.0), rel=1e-15)
    assert stepper._step_factor(err, 1) == stepper._step_factor(err, 2)  # BDF1 starts BDF2
    for k in (3, 4, 5):
        assert stepper._step_factor(1e-9, k) == stepper.GROWTH[k] < 2.0
        assert stepper._step_factor(0.9, k) == pytest.approx(0.9 * 0.9 ** (-1.0 / (k + 1)),
                                                             rel=1e-15)


def test_norm_counts_small_pressures_as_absolute():
    """A pressure far below the largest one is measured against ``PRESSURE_SCALE`` of it (plus
    the absolute scale), a gap below ``GAP_SCALE`` against that; X and V against 1 and 0.1."""
    p = np.array([10.0, 1e-6])
    h = np.array([1.0, 1e-4])
    zero = np.zeros(2)
    rtol = 1e-3
    dp = np.array([0.0, 1e-3])
    expected = 1e-3 / (1e-6 + stepper.PRESSURE_SCALE * 10.0) / rtol
    assert stepper._norm(dp, 0.0, 0.0, zero, p, 0.0, 0.0, h, rtol, 0.0) == pytest.approx(
        expected, rel=1e-14)
    dh = np.array([0.0, 1e-5])
    assert stepper._norm(zero, 0.0, 0.0, dh, p, 0.0, 0.0, h, rtol, 0.0) == pytest.approx(
        1e-5 / (1e-4 + stepper.GAP_SCALE) / rtol, rel=1e-14)
    assert stepper._norm(zero, 0.5, 0.0, zero, p, 1.0, 0.0, h, 1.0, 0.0) == pytest.approx(0.25)
    assert stepper._norm(zero, 0.0, 0.05, zero, p, 0.0, 0.0, h, 1.0, 0.0) == pytest.approx(0.5)


def test_counters_are_named_in_the_order_the_loop_returns_them():
    assert [stepper.STEPS, stepper.REJECTED, stepper.NEWTON, stepper.LU, stepper.JACOBIANS,
            stepper.LOWRANK, stepper.HIGHER_ORDER] == list(range(len(stepper.COUNTERS)))
    from solver import Physics, collide

    for order in (2, 5):
        c = collide(Physics(St=10.0, eps=1e-2), accuracy="fast", max_order=order,
                    save_profiles=False)
        # every attempt runs Newton at least once and every accepted step is an attempt
        assert c.newton_iterations >= c.steps + c.rejected_steps > 0
        assert 0 < c.lu_factorizations <= c.newton_iterations
        if order == 2:  # BDF2
            assert c.higher_order_steps == 0
        else:  # the first steps are at orders 1 and 2, before the order may rise
            assert 0 < c.higher_order_steps < c.steps
