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

__all__ = ["cavity_fraction", "separation_force", "departure", "speed_at", "restitution",
           "exact_for"]

_SERIES_FROM = 10.0  # sigma above which f is summed as a series (the closed form cancels)


def _f(sigma):
    """``f(sigma)`` of the module docstring; for large ``sigma`` (``e = 1/sigma``) the series
    ``sum_{n>=2} (-1)^n e^n (1/2 - 1/(n+1))`` = ``e^2/6 - e^3/4 + 3 e^4/10 - ...``, which avoids the
    cancellation of two terms near 1."""
    if sigma <= 0.0:
        return 0.5
    if sigma <= _SERIES_FROM:
        return (1.0 + 2.0 * sigma) / (2.0 * (1.0 + sigma)) - sigma * math.log1p(1.0 / sigma)
    e = 1.0 / sigma
    total, power = 0.0, e
    for n in range(2, 40):  # e <= 0.1: 40 terms reach 1e-38 relative
        power *= e
        total += (-1) ** n * power * (0.5 - 1.0 / (n + 1))
    return total


def cavity_fraction(g):
    """``sigma = s_c / X`` solving ``f(sigma) = g`` (module docstring): 0 for ``g >= 1/2`` (no
    cavity), ``inf`` for ``g = 0`` (no floor: the whole film cavitates)."""
    if g >= 0.5:
        return 0.0
    if g <= 0.0:
        return math.inf
    # f ~ 1/(6 sigma^2) for large sigma brackets the root from above
    hi = max(2.0, 2.0 / math.sqrt(6.0 * g))
    from scipy import optimize  # here: a run without this piece never imports it (0.2 s)
    return optimize.brentq(lambda z: _f(z) - g, 0.0, hi, xtol=1e-15, rtol=1e-14)


def separation_force(x, u, pi):
    """``Int P ds`` of rigid spheres at gap ``x`` separating at ``u > 0`` with the floor ``-pi``:
    ``-3u/(x (1 + sigma))``."""
    sigma = cavity_fraction(pi * x * x / (6.0 * u))
    return 0.0 if math.isinf(sigma) else -3.0 * u / (x * (1.0 + sigma))


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

    def rhs(lnx, y):
        x = math.exp(lnx)
        sigma = cavity_fraction(pi * x * x / (6.0 * y[0]))
        return [-1.0 / (stokes * (1.0 + sigma)), x / y[0]]

    def closes(lnx, y):
        return pi * math.exp(2.0 * lnx) - 3.0 * y[0]

    closes.terminal = True
    closes.direction = 1.0
    ln0 = math.log(x_from)
    ln1 = 0.5 * math.log(3.0 * u_from / pi) + 1.0  # U only falls: the cavity closes before
    from scipy.integrate import solve_ivp  # here: a run without this piece never imports it
    sol = solve_ivp(rhs, (ln0, ln1), [u_from, t_from], events=closes, rtol=1e-10, atol=1e-14,
                    dense_output=True)
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
        def rhs(lnx, y):
            x = math.exp(lnx)
            return [-1.0 / (stokes * (1.0 + cavity_fraction(pi * x * x / (6.0 * y[0]))))]

        def closes(lnx, y):
            return pi * math.exp(2.0 * lnx) - 3.0 * y[0]

        closes.terminal = True
        closes.direction = 1.0
        from scipy.integrate import solve_ivp  # here: a run without this piece never imports it
        sol = solve_ivp(rhs, (math.log(x_from), math.log(x_target)), [u_from], events=closes,
                        rtol=1e-10, atol=1e-14)
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
