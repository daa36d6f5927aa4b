"""The step's interpolant: the polynomial through the newest accepted states, the BDF's dense
output of order ``k`` (``k + 1`` states, the newest first, at the times ``t``).

What the time loop (stepper.py) and the collision's observables (collision.py: ``_peak``) read
inside a step: a column's extremum over the step (``extremum_in_step``), the time a column falls
through 0 (``stop_in_step``), the integral of a rate over the step (``dissipated_in_step``); and
the parts those are made of: the Lagrange basis with its slopes (``lagrange_basis``), a
combination of rows by its weights (``combine``), the Newton form of one column's polynomial
(``divided_differences``, ``newton_form``). No piece of physics: every copy of the loop
(integration/kinds.py) shares this module.
"""

import math

import numpy as np

from .._jit import entry, leaf

# Gauss-Legendre's three points on [-1, 1] and their weights: exact for polynomials of degree 5,
# the highest order's interpolant (``dissipated_in_step``)
GAUSS3 = ((-math.sqrt(0.6), 5.0 / 9.0), (0.0, 8.0 / 9.0), (math.sqrt(0.6), 5.0 / 9.0))
BISECTIONS = 50  # halvings of a step's interval to locate a cell's extremum in it (2^-50)


@leaf
def lagrange_basis(t, k, x, values, slopes):
    """The Lagrange basis through the ``k + 1`` newest times ``t[:k + 1]`` at ``x``: its values
    into ``values[:k + 1]`` and its slopes into ``slopes[:k + 1]`` (each slope a sum of products,
    also at the nodes themselves)."""
    for j in range(k + 1):
        lj = 1.0
        dj = 0.0
        for m in range(k + 1):
            if m == j:
                continue
            lj *= (x - t[m]) / (t[j] - t[m])
            term = 1.0 / (t[j] - t[m])
            for i in range(k + 1):
                if i != j and i != m:
                    term *= (x - t[i]) / (t[j] - t[i])
            dj += term
        values[j] = lj
        slopes[j] = dj


@leaf
def combine(weights, k, rows, col):
    """``sum_j weights[j] rows[j, col]`` over the ``k + 1`` newest rows."""
    out = 0.0
    for j in range(k + 1):
        out += weights[j] * rows[j, col]
    return out


@leaf
def divided_differences(t, k, rows, col, coef):
    """The Newton form of the polynomial through ``(t[j], rows[j, col])``, ``j = 0..k``: its
    coefficients (divided differences) into ``coef[:k + 1]``, so that it reads ``coef[0] +
    coef[1] (x - t[0]) + coef[2] (x - t[0]) (x - t[1]) + ...`` (``newton_form``)."""
    for j in range(k + 1):
        coef[j] = rows[j, col]
    for level in range(1, k + 1):
        for j in range(k, level - 1, -1):
            coef[j] = (coef[j] - coef[j - 1]) / (t[j] - t[j - level])


@leaf
def newton_form(t, k, coef, x):
    """The value and the slope at ``x`` of ``divided_differences``' polynomial, by Horner's
    scheme on its Newton form with the derivative alongside: ``O(k)`` operations, against
    ``lagrange_basis``'s ``O(k^3)``."""
    value = coef[k]
    slope = 0.0
    for j in range(k - 1, -1, -1):
        slope = slope * (x - t[j]) + value
        value = value * (x - t[j]) + coef[j]
    return value, slope


@entry
@leaf
def extremum_in_step(t, rows, cells, k, sign, basis):
    """The extremum of ``rows[:, :cells]`` (the newest states first, times ``t``) over its
    columns and over the last step (``t[1]`` to ``t[0]``), on the step's own interpolant: the
    polynomial through the ``k + 1`` newest states (the BDF's dense output, order ``k``). The
    smallest value where ``sign`` is 1, the largest where it is -1. A column that falls at the
    step's start and rises at its end (times ``sign``) has its extremum inside, located by
    bisection on the slope (the column's polynomial in Newton form, ``newton_form``: through
    ``lagrange_basis`` at every halving, this search took 21 % of a classic collision's CPU time
    at the standard preset). Returns the extremum (inf times ``sign`` if no column has one
    inside the step) and its time. Such a series, an extremum over the cells, is not smooth in time
    where the cell that holds it changes (the dimple's rim moves), so a parabola through three
    rows of it misreads it by the step's cube: at order 5 on the fast preset, ``h_m`` jumped by
    0.7 % between neighbouring St 5 % apart, and the central gap at the peak pressure read 2 %
    off."""
    values, coef, at_start, at_end = basis[0], basis[1], basis[2], basis[3]
    lagrange_basis(t, k, t[1], values, at_start)
    lagrange_basis(t, k, t[0], values, at_end)
    best, t_best = np.inf, t[0]
    for i in range(cells):
        if not (sign * combine(at_start, k, rows, i) < 0.0 < sign * combine(at_end, k, rows, i)):
            continue
        divided_differences(t, k, rows, i, coef)
        lo, hi = t[1], t[0]
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo + hi)
            if sign * newton_form(t, k, coef, mid)[1] < 0.0:
                lo = mid
            else:
                hi = mid
        t_i = 0.5 * (lo + hi)
        value = sign * newton_form(t, k, coef, t_i)[0]
        if value < best:
            best, t_best = value, t_i
    return sign * best, t_best


@leaf
def dissipated_in_step(t, r, k, basis):
    """The energy dissipated over the last step above order 2: the integral of the polynomial
    through the ``k + 1`` newest dissipation rates ``r`` (at the times ``t``, the history's), by
    Gauss-Legendre's three points (exact to degree 5), so the energy balance is closed to the
    step's order; at orders 1 and 2 the loop keeps the trapezoidal rule."""
    half = 0.5 * (t[0] - t[1])
    mid = 0.5 * (t[0] + t[1])
    total = 0.0
    for x, weight in GAUSS3:
        lagrange_basis(t, k, mid + x * half, basis[0], basis[1])
        rate = 0.0
        for j in range(k + 1):
            rate += basis[0, j] * r[j]
        total += weight * rate
    return total * half


@leaf
def stop_in_step(t, y, col, k, basis):
    """The time inside the last step where column ``col`` of the states ``y`` (positive at the
    step's start, not at its end) falls through 0 on the step's interpolant, by bisection; the
    basis there in ``basis[0]``."""
    lo, hi = t[1], t[0]
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        lagrange_basis(t, k, mid, basis[0], basis[1])
        if combine(basis[0], k, y, col) > 0.0:
            lo = mid
        else:
            hi = mid
    t_stop = 0.5 * (lo + hi)
    lagrange_basis(t, k, t_stop, basis[0], basis[1])
    return t_stop
