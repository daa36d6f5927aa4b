"""Slip at the surfaces: a gas film's first-order (Maxwell-Navier) slip, or a liquid's on a
slippery surface (docs/model.md, "Slip").

Each surface lets the fluid slide over it with the slip length ``l`` (``u_wall = l du/dz``; for a
gas ``l`` is the mean free path times ``(2 - sigma_v)/sigma_v``, Maxwell 1879). Poiseuille flow
between two such walls carries ``(h^3 + 6 l h^2)/(12 mu) dp/dr`` per unit width, so the film's
mobility is the classic one times ``1 + c/H`` with ``c = 6 l/x1``: the one change to the film
equations (``flux_factor``, which model/film.py's faces read).

The rigid film (``W = 0``, ``H = X + s``) keeps closed forms (Hocking 1973; Vinogradova 1995 for
two slipping surfaces): the pressure ``P = (6 V/H^2) phi(c/H)``, ``phi(z) = (z - ln(1+z))/z^2``;
the force ``V/X f*(c/X)`` with ``f*(c/X) = (2X/c) [(1 + X/c) ln(1 + c/X) - 1]`` (1 without slip,
``(X/3l) ln(6l/X)`` at large slip); and the motion ``dV/dX = f*/(St X)``, whose integral is
``V = V1 + (G(X/c) - G(X1/c))/St`` with

    G(u) = (1+u)^2 ln(1+u) - (2u + u^2) ln u - u - 1/2,

which tends to ``ln u + 1`` far out (the classic ``ln X / St``) and to ``G(0) = -1/2`` at contact:
the spheres touch after a finite loss of speed. The rigid approach and departure are these
(``approach``, ``departure``), exact for an isoviscous film (``exact_for``).

Everything is dimensionless in the scales of docs/model.md ("Scales"), the slip length ``l`` in
``x1`` (``Physics.slip_length``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._jit import hook, jit, leaf
from ..physics import SLIP
from .kind import SLIP_CODE, asks_slip

__all__ = ["flux_factor", "mobility_gap", "force_factor", "potential", "velocity",
           "elapsed_time", "rest_separation", "rigid_pressure", "axis_deflection",
           "deformation_ratio", "exact_for", "departs_exact", "RigidSlipPath", "approach",
           "departure"]

SERIES_TERMS = 30  # terms of the far-out series below: their ratio is <= 1/4, 4^-30 ~ 1e-18
FAR = 4.0  # X/c (or c/H) beyond which a closed form loses digits and its series is summed


# ---- the film: the one change to the equations ------------------------------------------------
@hook
def slips(phys):
    """Whether the surfaces slip; never in a copy of the loop without slip's code (model/kind.py),
    whose branches numba prunes."""
    if SLIP_CODE:
        return asks_slip(phys)
    return False


@leaf
def flux_factor(h_lo, h_hi, phys):
    """How much more a face carries with slip, ``1 + (c/2)(1/H_lo + 1/H_hi)`` (``c = 6 l``),
    and its derivatives in ``H_lo`` and ``H_hi``; ``(1, 0, 0)`` without slip.

    The mobility ``H^3 + c H^2`` is ``H^3 (1 + c/H)``; the face integrates ``1/H^3`` exactly
    (model/film.py, ``flux_law``) and this factor the rest: exact for a uniform gap and in both
    limits of a linear one (``c << H``, to first order in ``c``, and ``c >> H``, where the face's
    exact conductance is ``(c/2)(1/H_lo + 1/H_hi)`` times the classic one), second order between.

    Returns
    -------
    g, dg_dh_lo, dg_dh_hi : float
    """
    half_c = 3.0 * phys[SLIP]
    if half_c == 0.0:
        return 1.0, 0.0, 0.0
    return (1.0 + half_c * (1.0 / h_lo + 1.0 / h_hi), -half_c / (h_lo * h_lo),
            -half_c / (h_hi * h_hi))


def mobility_gap(physics) -> float:
    """``c = 6 l/x1``: the gap below which slip carries more of the flow than the shear."""
    return 6.0 * physics.slip_length


# ---- the rigid film's closed forms ------------------------------------------------------------
def _series(w, coefficients):
    total = np.zeros_like(w)
    for coefficient in coefficients[::-1]:
        total = total * w + coefficient
    return total


_N = np.arange(SERIES_TERMS)
# (1 + u) ln(1 + 1/u) - 1 = w sum (-1)^n w^n / ((n + 1)(n + 2)), w = 1/u
_FORCE_SERIES = (-1.0) ** _N / ((_N + 1.0) * (_N + 2.0))
# G(u) - ln(1 + u) + 1/2 = sum (-1)^n (n + 3)/((n + 1)(n + 2)) w^n
_POTENTIAL_SERIES = (-1.0) ** _N * (_N + 3.0) / ((_N + 1.0) * (_N + 2.0))
# (z - ln(1 + z))/z^2 = sum (-1)^n z^n/(n + 2)
_PRESSURE_SERIES = (-1.0) ** _N / (_N + 2.0)


def force_factor(x, c):
    """``f*(c/X)``: the rigid film's force over the classic ``V/X`` (module docstring)."""
    u = np.asarray(x, dtype=float) / c
    far = u >= FAR
    w = 1.0 / np.where(far, u, FAR)
    near = np.where(far, 1.0, u)
    with np.errstate(divide="ignore", invalid="ignore"):
        direct = np.where(near > 0.0, 2.0 * near * ((1.0 + near) * np.log1p(1.0 / near) - 1.0),
                          0.0)
    return np.where(far, 2.0 * _series(w, _FORCE_SERIES), direct)


def potential(x, c):
    """``G(X/c)``, whose difference over ``St`` is the rigid film's change of speed (module
    docstring)."""
    u = np.asarray(x, dtype=float) / c
    far = u >= FAR
    w = 1.0 / np.where(far, u, FAR)
    near = np.where(far, 1.0, u)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_near = np.where(near > 0.0, np.log(near), 0.0)
    direct = ((1.0 + near) ** 2 * np.log1p(near) - (2.0 * near + near * near) * log_near
              - near - 0.5)
    return np.where(far, np.log1p(np.where(far, u, 0.0)) + _series(w, _POTENTIAL_SERIES) - 0.5,
                    direct)


def velocity(x, x_from, v_from, stokes, c):
    """Speed on the rigid slip path through ``(X1, V1)`` (``V > 0`` approach)."""
    return v_from + (potential(x, c) - potential(x_from, c)) / stokes


def _log_potential_gap(ln_x, c):
    # G(X/c) - ln(X/c) for X/c >= FAR, from ln X (X itself may overflow)
    w = math.exp(math.log(c) - ln_x)
    return math.log1p(w) + float(_series(np.array(w), _POTENTIAL_SERIES)) - 0.5


def rest_separation(x_from, v_from, stokes, c):
    """``ln X`` where the rigid slip path from ``(X1, V1)`` comes to rest: ``G(X_e/c) = G(X1/c) -
    St V1`` (``V1 < 0``: a departure, ``X_e > X1``); ``-inf`` when an approach reaches contact
    first (``G`` is ``-1/2`` there)."""
    target = float(potential(x_from, c)) - stokes * v_from
    if target <= -0.5:
        return -math.inf
    if target >= float(potential(FAR * c, c)):  # far out: ln X = ln c + target - (G - ln u)
        ln_x = math.log(c) + target - 1.0
        for _ in range(60):
            step = math.log(c) + target - _log_potential_gap(ln_x, c) - ln_x
            ln_x += step
            if abs(step) < 1e-15 * max(1.0, abs(ln_x)):
                break
        return ln_x
    from scipy import optimize  # here: a run without this piece never imports it (0.2 s)
    return math.log(optimize.brentq(lambda x: float(potential(x, c)) - target, 0.0, FAR * c,
                                    xtol=1e-300, rtol=1e-15))


def elapsed_time(x, x_from, v_from, stokes, c):
    """Time ``T - T1`` to move on the rigid slip path from ``X1`` to each ``X`` (quadrature of
    ``dX/|V|``; ``inf`` at the rest separation, which the path approaches logarithmically)."""
    from scipy.integrate import quad  # here: a run without this piece never imports it

    x = np.atleast_1d(np.asarray(x, dtype=float))
    out = np.empty_like(x)
    sign = 1.0 if v_from > 0.0 else -1.0

    def speed(ln_xi):  # in ln X: dT = X d(ln X)/|V|
        xi = math.exp(ln_xi)
        return xi / abs(float(velocity(xi, x_from, v_from, stokes, c)))

    t, ln_last = 0.0, math.log(x_from)
    for k, xk in enumerate(x):
        if float(velocity(xk, x_from, v_from, stokes, c)) * sign <= 0.0:
            out[k:] = math.inf
            break
        t += abs(quad(speed, ln_last, math.log(xk), epsabs=0.0, epsrel=1e-11, limit=200)[0])
        out[k] = t
        ln_last = math.log(xk)
    return out


def rigid_pressure(s, x, v, c):
    """The rigid slip film's pressure ``P(s) = (6 V/H^2) phi(c/H)``, ``H = X + s``."""
    h = x + np.asarray(s, dtype=float)
    z = c / h
    small = z < 1.0 / FAR
    zs = np.where(small, z, 0.0)
    zl = np.where(small, 1.0, z)
    phi = np.where(small, _series(zs, _PRESSURE_SERIES), (zl - np.log1p(zl)) / (zl * zl))
    return 6.0 * v * phi / (h * h)


def axis_deflection(x, v, c):
    """``W(0)`` of the rigid slip pressure: ``(pi/2) Int_0^inf P dR`` (the kernel is ``pi/2``
    on the axis, docs/model.md, "Elasticity"); ``3 I0 V X^-1.5`` without slip."""
    def integrand(t):  # R = sqrt(2 X) t/(1 - t), t in [0, 1)
        r = math.sqrt(2.0 * x) * t / (1.0 - t)
        return float(rigid_pressure(0.5 * r * r, x, v, c)) * math.sqrt(2.0 * x) / (1.0 - t) ** 2
    from scipy.integrate import quad  # here: a run without this piece never imports it
    return 0.5 * math.pi * quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-10, limit=200)[0]


def deformation_ratio(x, v, c):
    """``W(0)/X`` of the rigid slip film: the hand-over criterion."""
    return axis_deflection(x, v, c) / x


def exact_for(physics) -> bool:
    """Whether ``approach`` is the exact rigid approach of ``physics``: slip in an isoviscous
    film (the approach film is in compression: no cavitation floor acts)."""
    return physics.slip_length > 0.0 and physics.isoviscous


def departs_exact(physics) -> bool:
    """Whether ``departure`` is the exact rigid departure after the release: slip without a
    cavitation floor (a pressure-dependent liquid is released only where its law no longer
    matters, model/rigid.py, ``release_event``)."""
    return physics.slip_length > 0.0 and physics.cavitation == "off"


# ---- the rigid phases -------------------------------------------------------------------------
@dataclass(frozen=True)
class RigidSlipPath:
    """A rigid slip path sampled from its start: ``t, x, v`` (``v > 0`` approach), its force
    ``V/X f*`` (the series column ``F``), axis pressure and ``W(0)``; ``event`` is what ended it
    (``"handover"``: ``W(0)/X`` reached the switch, ``"stop"``: the given ``x_stop``, ``"rest"``,
    or ``"far"``: a departure's samples end)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    force: np.ndarray
    p_axis: np.ndarray
    w0: np.ndarray
    event: str


def _path(t_from, x_from, v_from, stokes, c, xs, event, ends_at_rest=False):
    v = velocity(xs, x_from, v_from, stokes, c)
    if ends_at_rest:
        # the last sample is the rest, which the path reaches only as t -> inf: in rounding its
        # speed there can come out just above 0, and the quadrature towards it then met a speed
        # of exactly 0 (ZeroDivisionError at St 2, eps 1e-6, slip length 3)
        v[-1] = 0.0
        t = t_from + np.append(elapsed_time(xs[:-1], x_from, v_from, stokes, c), math.inf)
    else:
        t = t_from + elapsed_time(xs, x_from, v_from, stokes, c)
    p_axis = rigid_pressure(0.0, xs, v, c)
    w0 = np.array([axis_deflection(xi, vi, c) for xi, vi in zip(xs, v)])
    return RigidSlipPath(t, xs, v, v / xs * force_factor(xs, c), p_axis, w0, event)


def approach(x_start, stokes, c, switch, x_stop=0.0, samples=60) -> RigidSlipPath:
    """The rigid slip approach from ``(x_start, V = 1, T = 0)`` until ``W(0)/X`` reaches
    ``switch`` (the hand-over), ``x_stop``, or rest; sampled uniformly in ``ln X``, the end
    included (``t = inf`` at a rest)."""
    from scipy import optimize  # here: a run without this piece never imports it (0.2 s)
    ln_rest = rest_separation(x_start, 1.0, stokes, c)
    ln_lo = max(ln_rest, math.log(x_stop) if x_stop > 0.0 else -math.inf)

    def over(ln_x):
        x = math.exp(ln_x)
        return deformation_ratio(x, float(velocity(x, x_start, 1.0, stokes, c)), c) - switch

    ln_x, event = math.log(x_start), "handover"
    if over(ln_x) < 0.0:  # step in ln X until the switch, the stop or the rest is passed
        while True:
            nxt = ln_x - 0.05
            if nxt <= ln_lo:
                if over(ln_lo) >= 0.0:
                    ln_x = optimize.brentq(over, ln_lo, ln_x, xtol=1e-13)
                else:
                    ln_x, event = ln_lo, ("rest" if ln_lo == ln_rest else "stop")
                break
            if over(nxt) >= 0.0:
                ln_x = optimize.brentq(over, nxt, ln_x, xtol=1e-13)
                break
            ln_x = nxt
    xs = x_start * np.exp(np.linspace(0.0, ln_x - math.log(x_start), samples))
    return _path(0.0, x_start, 1.0, stokes, c, xs, event, ends_at_rest=event == "rest")


def departure(x_from, v_from, t_from, stokes, c, samples=41) -> RigidSlipPath:
    """The rigid slip departure from the release ``(X1, V1 < 0)`` out to 0.99 of the way to rest
    in ``ln X``, at most 30 e-folds (beyond, ``c/X`` is below ``e^-30`` of its value at the
    release and the classic departure is exact to that order): ``event`` ``"rest"`` or
    ``"far"``."""
    ln_rest = rest_separation(x_from, v_from, stokes, c)
    span = 0.99 * (ln_rest - math.log(x_from))
    event = "far" if span > 30.0 else "rest"
    xs = x_from * np.exp(np.linspace(0.0, min(span, 30.0), samples))
    return _path(t_from, x_from, v_from, stokes, c, xs, event)
