"""The rigid film with a cavitation floor ``P >= -Pi`` (Reynolds condition): closed forms and the
departure of separating rigid spheres (docs/model.md, "Cavitation").

Rigid spheres separating at speed ``U = -V > 0`` (``H = X + s``, ``dH/dT = U``) with the Reynolds
(Swift-Stieber) condition: a cavity ``0 <= s <= s_c`` at ``P = -Pi``, and outside it the film
equation with ``P(s_c) = -Pi``, ``dP/ds(s_c) = 0``, ``P -> 0`` far away. Integrating
``(1/6)(s H^3 P')' = U`` gives ``dP/ds = 6U (1 - s_c/s)/(X + s)^3``; ``P(s_c) = -Pi`` fixes the
cavity through ``sigma = s_c / X``:

    f(sigma) = (1 + 2 sigma)/(2 (1 + sigma)) - sigma ln(1 + 1/sigma) = g,   g = Pi X^2 / (6 U),

``f`` falling from 1/2 (``sigma = 0``) to 0 (``sigma -> inf``); no cavity when ``g >= 1/2``, i.e.
``3U/X^2 <= Pi`` (the rigid axis tension ``3U/X^2`` has not reached the floor). The film force is
``Int P ds = -3U/(X + s_c)``: the cavity shifts the effective gap by ``s_c``, and the suction stays
finite as ``X -> 0`` (``-> -3 sqrt(U Pi)``).

So the rigid departure is a scalar ODE, ``dU/d ln X = -1/(St (1 + sigma))`` (force unit
``6 pi mu a^2 v0 / x1``: ``F = -U/(X + s_c)``, ``dV/dT = -F/St``), integrated until the cavity
closes; from there the classic closed form ``X_e = X exp(St U)`` holds. Exact for the Reynolds
condition, which has no memory of the cavity; a mass-conserving (JFO) film does, so it integrates
the coupled problem until its film is full again instead.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import entry, jit, leaf
from .dopri import (A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65,
                    B1, B3, B4, B5, B6, C2, C3, C4, C5, E1, E3, E4, E5, E6, E7,
                    after_acceptance, after_rejection, illinois, trial)

__all__ = ["cavity_fraction", "separation_force", "departure", "speed_at", "restitution",
           "exact_for"]

_SERIES_FROM = 10.0  # sigma above which f is summed as a series (the closed form cancels)


def _f(sigma):
    """``f(sigma)`` of the module docstring (``_f_and_slope``)."""
    return _f_and_slope(sigma)[0]


@leaf
def _f_and_slope(sigma):
    """``f(sigma)`` of the module docstring and its slope in ``ln sigma``, ``sigma f'(sigma) =
    sigma/(2 (1 + sigma)^2) + sigma/(1 + sigma) - sigma ln(1 + 1/sigma)`` (< 0), in one pass
    (``cavity_fraction`` needs both at each iterate). For large ``sigma`` (``e = 1/sigma``) both
    from the series ``f = sum_{n>=2} (-1)^n e^n (1/2 - 1/(n+1))`` = ``e^2/6 - e^3/4 + 3 e^4/10 -
    ...`` (``sigma f' = -sum n (...)``), which avoids the cancellation of the closed form's terms
    near 1."""
    if sigma <= 0.0:
        return 0.5, 0.0
    if sigma <= _SERIES_FROM:
        log_term = sigma * math.log1p(1.0 / sigma)
        return ((1.0 + 2.0 * sigma) / (2.0 * (1.0 + sigma)) - log_term,
                0.5 * sigma / (1.0 + sigma) ** 2 + sigma / (1.0 + sigma) - log_term)
    e = 1.0 / sigma
    total, slope, power = 0.0, 0.0, e
    for n in range(2, 40):  # e <= 0.1: the terms fall 10x each, 40 reach 1e-38 relative
        power *= e
        term = (-1) ** n * power * (0.5 - 1.0 / (n + 1))
        total += term
        slope -= n * term
        if abs(term) < 1e-18 * abs(total):  # the rest is below the rounding of the sum
            break
    return total, slope


# ``cavity_fraction`` returns after a Newton step in ``ln sigma`` below _TOLERANCE (relative in
# sigma): Newton converges quadratically, and ``|F''/(2 F')|`` of ``F(ln sigma) = f - g`` is about
# 1 for large sigma (``f ~ sigma^-2/6``) and 1/2 for small, so the root is then correct to about
# the step squared, below the rounding of ``f`` (its closed form loses up to 1e-13 of itself near
# sigma = 10, where smaller steps dithered on that noise). Measured against SciPy's brentq at
# rtol 1e-14, which it replaced: 8e-14 relative at most over g in [1e-14, 0.4999999]. It stops
# too at a bracket narrower than _BRACKET, and after _MAX_ITERATIONS; where Newton would leave the
# bracket, the bracket halves instead.
_TOLERANCE = 1e-8
_BRACKET = 1e-13
_MAX_ITERATIONS = 200


def cavity_fraction(g, start=0.0):
    """``sigma = s_c / X`` solving ``f(sigma) = g`` (module docstring): 0 for ``g >= 1/2`` (no
    cavity), ``inf`` for ``g = 0`` (no floor: the whole film cavitates). ``start`` (> 0), a
    guess of ``sigma``, saves iterations (the departure's ODE passes the last call's root).

    Newton's method in ``ln sigma`` (``f`` falls over decades of ``sigma``: ``1/(6 sigma^2)`` for
    large ``sigma``, ``1/2 + sigma ln sigma`` for small), kept inside the bracket ``f(lo) > g >
    f(hi)`` by bisection where it would leave it, until a step below ``_TOLERANCE`` (above: why
    that is enough). Compiled (``_root``), 0.3 us a call from Python, where the same arithmetic
    in Python took 5.5 us and SciPy's ``brentq`` before it 42 us; 3.7 evaluations of ``f`` a
    call from a cold start (``g`` in [1e-8, 0.49]). The departure's compiled ODE calls ``_root``
    itself (``_slope``)."""
    return _root(float(g), float(start))


@entry
@leaf
def _root(g, start):
    """``cavity_fraction`` of the floats ``g`` and ``start``, compiled."""
    if g >= 0.5:
        return 0.0
    if g <= 0.0:
        return math.inf
    lo, hi = 0.0, max(2.0, 2.0 / math.sqrt(6.0 * g))  # f ~ 1/(6 sigma^2) brackets from above
    # start: the large-sigma root 1/sqrt(6 g), or the small-sigma root of 1/2 + sigma ln sigma
    sigma = 1.0 / math.sqrt(6.0 * g) if g < 0.05 else (0.5 - g) / max(1.0, -math.log(0.5 - g))
    if lo < start < hi:
        sigma = start
    for _ in range(_MAX_ITERATIONS):
        value, slope = _f_and_slope(sigma)
        value -= g
        if value > 0.0:
            lo = sigma
        elif value < 0.0:
            hi = sigma
        else:
            return sigma
        step = value / slope  # Newton in ln sigma
        if abs(step) <= _TOLERANCE:
            return sigma * math.exp(-step)
        if hi - lo <= _BRACKET * hi:
            return 0.5 * (lo + hi)
        new = sigma * math.exp(-step) if abs(step) < 700.0 else 0.5 * (lo + hi)
        sigma = new if lo < new < hi else 0.5 * (lo + hi)
    return sigma


def separation_force(x, u, pi):
    """``Int P ds`` of rigid spheres at gap ``x`` separating at ``u > 0`` with the floor ``-pi``:
    ``-3u/(x (1 + sigma))``."""
    sigma = cavity_fraction(pi * x * x / (6.0 * u))
    return 0.0 if math.isinf(sigma) else -3.0 * u / (x * (1.0 + sigma))


# --- the departure's ODE, compiled ------------------------------------------------------------
# Solved by Dormand and Prince's explicit Runge-Kutta pair of orders 5 and 4 (model/dopri.py),
# with the classic step control, in ``ln X``, compiled with the cavity's root (``_root``): SciPy's
# ``solve_ivp`` spent 1.4-4.0 ms of Python work on a departure and its ``speed_at`` (29 DOP853
# steps, 533 calls of a Python right-hand side), 4-16 % of a standard-preset collision; now
# 0.13-0.32 ms. How close: docs/solver.md, Versions, 1.18.5; tests/test_cavitation.py against
# ``solve_ivp`` at rtol 1e-13.
RTOL, ATOL = 1e-10, 1e-14  # on (U, T)
_MAX_STEPS = 100_000
_EVENT_ITERATIONS = 100


@leaf
def _slope(lnx, u, stokes, pi, sigma):
    """The departure's right-hand side at ``ln X``, ``U``: ``dU/d ln X = -1/(St (1 + sigma))``
    while the cavity is open (``sigma`` = 0 once it has closed), ``dT/d ln X = X/U``; and the
    cavity's ``sigma``, found from ``sigma`` (the last call's: an ODE's calls lie close
    together, 3.1 evaluations of ``f`` a call instead of 3.7 from a cold start)."""
    x = math.exp(lnx)
    sigma = _root(pi * x * x / (6.0 * u), sigma)
    return -1.0 / (stokes * (1.0 + sigma)), x / u, sigma


@leaf
def _rk_step(lnx, u, t, h, k1u, k1t, stokes, pi, sigma):
    """One Dormand-Prince step of ``h`` from ``(ln X, U, T)`` whose slopes are ``k1u, k1t``:
    the fifth-order state, its error estimate, the slopes there (the next step's first stage)
    and the last root."""
    k2u, k2t, sigma = _slope(lnx + C2 * h, u + h * A21 * k1u, stokes, pi, sigma)
    k3u, k3t, sigma = _slope(lnx + C3 * h, u + h * (A31 * k1u + A32 * k2u), stokes, pi, sigma)
    k4u, k4t, sigma = _slope(lnx + C4 * h, u + h * (A41 * k1u + A42 * k2u + A43 * k3u),
                             stokes, pi, sigma)
    k5u, k5t, sigma = _slope(lnx + C5 * h, u + h * (A51 * k1u + A52 * k2u + A53 * k3u
                                                     + A54 * k4u), stokes, pi, sigma)
    k6u, k6t, sigma = _slope(lnx + h, u + h * (A61 * k1u + A62 * k2u + A63 * k3u + A64 * k4u
                                               + A65 * k5u), stokes, pi, sigma)
    u_new = u + h * (B1 * k1u + B3 * k3u + B4 * k4u + B5 * k5u + B6 * k6u)
    t_new = t + h * (B1 * k1t + B3 * k3t + B4 * k4t + B5 * k5t + B6 * k6t)
    k7u, k7t, sigma = _slope(lnx + h, u_new, stokes, pi, sigma)
    err_u = h * (E1 * k1u + E3 * k3u + E4 * k4u + E5 * k5u + E6 * k6u + E7 * k7u)
    err_t = h * (E1 * k1t + E3 * k3t + E4 * k4t + E5 * k5t + E6 * k6t + E7 * k7t)
    return u_new, t_new, err_u, err_t, k7u, k7t, sigma


@leaf
def _closing(lnx, u, pi):
    """Where the cavity closes: ``Pi X^2 - 3U`` crosses 0 upwards (``3U/X^2 = Pi``)."""
    return pi * math.exp(2.0 * lnx) - 3.0 * u


@leaf
def _step_to_closing(lnx, u, t, h, u_hi, t_hi, k1u, k1t, stokes, pi, sigma):
    """The step ``s`` in ``(0, h]`` from ``(ln X, U, T)`` whose end is where the cavity closes
    (``_closing`` below 0 at the start, not below at the step ``h``'s end ``u_hi, t_hi``), by the
    Illinois variant of the false position on ``s`` (each value a step of ``s`` itself, so the
    state there is as accurate as a step's), to the rounding of ``ln X``; returns ``s`` and the
    state there."""
    lo, hi, side = 0.0, h, 0
    f_lo, f_hi = _closing(lnx, u, pi), _closing(lnx + h, u_hi, pi)
    for _ in range(_EVENT_ITERATIONS):
        if hi - lo <= 4e-16 * max(1.0, abs(lnx)):
            break
        s = trial(lo, hi, f_lo, f_hi)
        u_s, t_s, _, _, _, _, _ = _rk_step(lnx, u, t, s, k1u, k1t, stokes, pi, sigma)
        lo, hi, f_lo, f_hi, side = illinois(lo, hi, f_lo, f_hi, side, s,
                                            _closing(lnx + s, u_s, pi))
        if side == 1:
            u_hi, t_hi = u_s, t_s
    return hi, u_hi, t_hi


@entry
@jit
def _integrate(ln_from, ln_to, u, t, stokes, pi, rtol, atol, samples, path):
    """The departure from ``(ln X, U, T) = (ln_from, u, t)`` towards ``ln_to``, until the cavity
    closes (``_closing``); steps end on each of ``samples`` (ascending, in ``[ln_from, ln_to]``)
    and ``path[:, k]`` takes ``U, T`` there. Returns ``(ln X, U, T)`` where it stopped, whether
    the cavity closed there (or the spheres stopped, below), and the number of samples passed;
    ``ln X`` is NaN after ``_MAX_STEPS`` steps.

    The step is controlled on ``U`` and on ``T``, whose error is measured against its own
    increment too: as ``U`` falls to the rounding, ``dT/d ln X = X/U`` grows without bound, and
    measured against ``T`` alone its error forced steps below the rounding of ``ln X``."""
    lnx, k, closed = ln_from, 0, False
    k1u, k1t, sigma = _slope(lnx, u, stokes, pi, 0.0)
    h = _first_step(lnx, u, k1u, ln_to - ln_from, stokes, pi, sigma, rtol, atol)
    for _ in range(_MAX_STEPS):
        if lnx >= ln_to:
            return lnx, u, t, closed, k
        end = samples[k] if k < samples.size else ln_to
        if end <= lnx:  # a sample at the start, or repeated
            path[0, k], path[1, k] = u, t
            k += 1
            continue
        landing = h >= end - lnx
        step = end - lnx if landing else h
        if not landing and lnx + step == lnx:
            # steps below the rounding of ln X: U has fallen to the rounding of its scale (a
            # start at U ~ 1e-12 falls towards 0 while the cavity, open until 3U/X^2 = Pi, stays
            # open): the spheres have stopped here, and the cavity closes where they stand
            return lnx, u, t, True, k
        u_new, t_new, err_u, err_t, k7u, k7t, sigma_new = _rk_step(lnx, u, t, step, k1u, k1t,
                                                                   stokes, pi, sigma)
        scale_u = atol + rtol * max(abs(u), abs(u_new))
        scale_t = atol + rtol * max(abs(t), abs(t_new), abs(t_new - t))
        error = math.sqrt(0.5 * ((err_u / scale_u) ** 2 + (err_t / scale_t) ** 2))
        if not error <= 1.0:  # NaN too (a trial stage past U = 0)
            h = after_rejection(step, error)
            continue
        if _closing(lnx, u, pi) < 0.0 <= _closing(lnx + step, u_new, pi):
            s, u, t = _step_to_closing(lnx, u, t, step, u_new, t_new, k1u, k1t, stokes, pi,
                                       sigma)
            return lnx + s, u, t, True, k
        lnx = end if landing else lnx + step
        u, t, k1u, k1t, sigma = u_new, t_new, k7u, k7t, sigma_new
        if landing and k < samples.size:
            path[0, k], path[1, k] = u, t
            k += 1
        grown = after_acceptance(step, error)
        h = max(h, grown) if landing else grown  # a landing step is no measure of the step
    return math.nan, u, t, closed, k


@leaf
def _first_step(lnx, u, k1u, span, stokes, pi, sigma, rtol, atol):
    """The first step in ``ln X`` (Hairer, Norsett and Wanner, Solving Ordinary Differential
    Equations I, sec. II.4), in the error's scale of ``U``: a trial ``h0``, 1 % of ``U`` over its
    slope; then ``h1``, where ``h1^5`` times the larger of the slope and its change over an Euler
    step of ``h0`` is 0.01; the smaller of ``100 h0`` and ``h1``, within ``span``."""
    scale = atol + rtol * abs(u)
    d0, d1 = abs(u) / scale, abs(k1u) / scale
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, span)
    k2u, _, _ = _slope(lnx + h0, u + h0 * k1u, stokes, pi, sigma)
    d2 = abs(k2u - k1u) / scale / h0
    h1 = max(1e-6, h0 * 1e-3) if max(d1, d2) <= 1e-15 else (0.01 / max(d1, d2)) ** 0.2
    return min(100.0 * h0, h1, span)


def departure(x_from, u_from, t_from, stokes, pi, samples=40):
    """Rigid departure with a floor from ``(X, U) = (x_from, u_from)``, ``u_from > 0`` at time
    ``t_from``, until the cavity closes (module docstring).

    Returns
    -------
    x_c, u_c, t_c : float
        The state where the cavity closes (``3U/X^2 = Pi``); the classic closed form holds from
        there. ``x_c = inf`` when ``pi = 0`` (no suction at all: the spheres never stop).
    path : (3, samples) array
        ``X, U, T`` along the way (for time series).
    """
    if samples < 2:
        raise ValueError(f"the departure's path takes at least 2 samples (got {samples})")
    if pi <= 0.0:
        return math.inf, u_from, math.inf, np.array([[x_from], [u_from], [t_from]])
    if 3.0 * u_from <= pi * x_from * x_from:  # no cavity: nothing to integrate
        return x_from, u_from, t_from, np.array([[x_from], [u_from], [t_from]])
    ln0 = math.log(x_from)
    ln1 = 0.5 * math.log(3.0 * u_from / pi) + 1.0  # U only falls: the cavity closes before
    ln_c, u_c, t_c, closed, _ = _integrate(ln0, ln1, float(u_from), float(t_from), float(stokes),
                                           float(pi), RTOL, ATOL, np.empty(0), np.empty((2, 0)))
    if not closed:
        raise RuntimeError(f"the cavity of the rigid departure did not close in "
                           f"{_MAX_STEPS} steps (U = {u_c:.6g})")
    grid = np.linspace(ln0, ln_c, samples)
    path = np.empty((3, samples))
    path[0] = np.exp(grid)
    path[1:, 0] = u_from, t_from
    path[1:, -1] = u_c, t_c
    # the samples between, on a second pass whose steps end on them (the first's steps do not)
    inner = path[1:, 1:-1]
    ln_end, _, _, _, passed = _integrate(ln0, ln_c, float(u_from), float(t_from), float(stokes),
                                         float(pi), RTOL, ATOL, grid[1:-1].copy(), inner)
    # samples the second pass did not reach lie between its closing and the first's (a
    # departure shorter than the passes' difference, ~RTOL): the closing state
    if passed < samples - 2 and not abs(ln_end - ln_c) <= 1e-8 * max(1.0, abs(ln_c)):
        raise RuntimeError("the rigid departure's samples were not all reached")
    inner[0, passed:], inner[1, passed:] = u_c, t_c
    path[1:, 1:-1] = inner
    return math.exp(ln_c), u_c, t_c, path


def speed_at(x_from, u_from, stokes, pi, x_target):
    """Separation speed of the rigid departure with a floor from ``(x_from, u_from > 0)`` when it
    passes ``x_target >= x_from`` (0 if it comes to rest before): the ODE while the cavity is open
    (module docstring), the classic ``U = U_c - ln(x/X_c)/St`` after it closes."""
    if x_target <= x_from:
        return u_from
    if pi <= 0.0:
        return u_from  # no suction at all
    if 3.0 * u_from > pi * x_from * x_from:  # a cavity is open: integrate while it is
        ln_end, u_end, _, closed, _ = _integrate(
            math.log(x_from), math.log(x_target), float(u_from), 0.0, float(stokes), float(pi),
            RTOL, ATOL, np.empty(0), np.empty((2, 0)))
        if math.isnan(ln_end):
            raise RuntimeError("the rigid departure with a floor took too many steps")
        if not closed:  # still open at x_target
            return u_end
        x_from, u_from = math.exp(ln_end), u_end
    return max(0.0, u_from - math.log(x_target / x_from) / stokes)


def restitution(x_from, v_from, physics, x_ref):
    """``e_wet`` at ``x_ref`` (``>= x0``) with the Reynolds floor: the departure speed there
    (``speed_at``) over the approach speed there, ``1 + ln(x_ref/x0)/St`` (the approach is in
    compression, where the floor never acts: the classic rigid approach, rigid.impact_stokes).
    A state still approaching (``v_from >= 0``) creeps to rest: 0."""
    from .rigid import restitution_of_speed

    if v_from >= 0.0:
        return 0.0
    return restitution_of_speed(speed_at(x_from, -v_from, physics.St, physics.Pi, x_ref),
                                physics, x_ref)


def exact_for(physics) -> bool:
    """Whether ``departure`` is the exact departure of ``physics`` (a ``solver.Physics``): the
    Reynolds condition, which has no memory, and any model at ``Pi = 0``, where the film pulls
    with no force at all (nothing refills, the spheres never stop). A JFO cavity with ``Pi > 0``
    has a memory: its coupled phase goes on until the film is full again."""
    return physics.cavitation == "reynolds" or (physics.cavitation == "jfo" and physics.Pi == 0.0)
