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

from .._jit import entry, leaf

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
    call from a cold start (``g`` in [1e-8, 0.49]). A departure's ODE calls it some 530-610 times
    (docs/solver.md, Versions, 1.18.2 and 1.18.3)."""
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


def _open_cavity_speed(stokes, pi):
    """``dU/d ln X = -1/(St (1 + sigma))`` while the cavity is open (module docstring), as a
    function of ``ln X`` and ``U``; each call starts ``cavity_fraction`` from the root of the one
    before (an ODE solver's calls lie close together: 3.1 evaluations of ``f`` a call instead of
    3.7 from a cold start, over three departures St 10-100)."""
    last = [0.0]

    def speed(lnx, u):
        x = math.exp(lnx)
        last[0] = cavity_fraction(pi * x * x / (6.0 * u), last[0])
        return -1.0 / (stokes * (1.0 + last[0]))

    return speed


# How the departure's ODE is solved (SciPy's solve_ivp). The eighth-order DOP853 takes 29 steps
# and 533 evaluations where RK45 took 95 and 608 at the same tolerance (SciPy 1.17.1;
# departure(1e-3, 0.5, 3.0, 10.0, 1e-4)): with the root compiled, a departure and its speed_at
# took 0.67-0.96x RK45's time over five departures (St 5-300, Pi 1e-6 to 1e-2), as accurate (the
# closing state and speed_at within 5.1e-9 of DOP853 at rtol 1e-13, RK45 within 3.9e-9;
# docs/solver.md, Versions, 1.18.3).
_ODE = dict(method="DOP853", rtol=1e-10, atol=1e-14)


def _cavity_closes(pi):
    """The event where the cavity closes (``3U/X^2 = Pi``, crossed upwards in ``ln X``), terminal,
    for SciPy's ``solve_ivp`` on ``(U, ...)``."""
    def closes(lnx, y):
        return pi * math.exp(2.0 * lnx) - 3.0 * y[0]

    closes.terminal = True
    closes.direction = 1.0
    return closes


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
    if pi <= 0.0:
        return math.inf, u_from, math.inf, np.array([[x_from], [u_from], [t_from]])
    if 3.0 * u_from <= pi * x_from * x_from:  # no cavity: nothing to integrate
        return x_from, u_from, t_from, np.array([[x_from], [u_from], [t_from]])

    speed = _open_cavity_speed(stokes, pi)

    def rhs(lnx, y):
        return [speed(lnx, y[0]), math.exp(lnx) / y[0]]

    closes = _cavity_closes(pi)
    ln0 = math.log(x_from)
    ln1 = 0.5 * math.log(3.0 * u_from / pi) + 1.0  # U only falls: the cavity closes before
    from scipy.integrate import solve_ivp  # here: a run without this piece never imports it
    sol = solve_ivp(rhs, (ln0, ln1), [u_from, t_from], events=closes, dense_output=True, **_ODE)
    if sol.status != 1 or not sol.t_events[0].size:
        raise RuntimeError(f"the cavity of the rigid departure did not close: {sol.message}")
    ln_c = float(sol.t_events[0][0])
    u_c, t_c = (float(v) for v in sol.y_events[0][0])
    grid = np.linspace(ln0, ln_c, samples)
    u, t = sol.sol(grid)
    return math.exp(ln_c), u_c, t_c, np.vstack([np.exp(grid), u, t])


def speed_at(x_from, u_from, stokes, pi, x_target):
    """Separation speed of the rigid departure with a floor from ``(x_from, u_from > 0)`` when it
    passes ``x_target >= x_from`` (0 if it comes to rest before): the ODE while the cavity is open
    (module docstring), the classic ``U = U_c - ln(x/X_c)/St`` after it closes."""
    if x_target <= x_from:
        return u_from
    if pi <= 0.0:
        return u_from  # no suction at all
    if 3.0 * u_from > pi * x_from * x_from:  # a cavity is open: integrate while it is
        speed = _open_cavity_speed(stokes, pi)

        def rhs(lnx, y):
            return [speed(lnx, y[0])]

        closes = _cavity_closes(pi)
        from scipy.integrate import solve_ivp  # here: a run without this piece never imports it
        sol = solve_ivp(rhs, (math.log(x_from), math.log(x_target)), [u_from], events=closes,
                        **_ODE)
        if not sol.t_events[0].size:  # still open at x_target
            return float(sol.y[0, -1])
        x_from, u_from = math.exp(float(sol.t_events[0][0])), float(sol.y_events[0][0][0])
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
