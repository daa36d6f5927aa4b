"""Rigid-sphere lubrication (W = 0): the exact solution and the small-deformation estimate.

Dimensionless, scale ``x1`` (physics.md). With no deformation the film pressure is
``P = 3 V / H^2``, the force ``Int P R dR = 3 V / X`` and the motion

    V = V1 + ln(X / X1) / St,
    T - T1 = St X1 exp(-St V1) [Ei(St V1) - Ei(St V1 + ln(X / X1))]

from any state ``(T1, X1, V1)`` (``Ei`` the exponential integral); the spheres come to rest at
``X1 exp(-St V1)`` after infinite time. Inserting the rigid pressure into the elastic integral
gives the leading deflection ``W(R) = 3 V X^(-3/2) I(R / sqrt(X))``, so
``W(0) / X = (3 pi^2 / (4 sqrt 2)) V X^(-5/2)``: the hand-over criterion.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, special

__all__ = [
    "I0",
    "HANDOVER_COEFF",
    "velocity",
    "elapsed_time",
    "rest_separation",
    "handover_separation",
    "deformation_ratio",
    "start_deformation_ratio",
    "eps_for_start_deformation",
    "log_peak_deformation_ratio",
]

I0 = math.pi**2 / (4.0 * math.sqrt(2.0))  # I(0), the maximum of the deformation integral
HANDOVER_COEFF = 3.0 * I0  # W(0)/X = HANDOVER_COEFF * V * X**-2.5 along the rigid path


def _scaled_ei(z):
    """``exp(-z) Ei(z)`` without overflow: for ``|z| > 40`` the asymptotic series
    ``(1/z) sum_k k!/z^k`` (terms fall until k ~ |z|; truncation error ~ exp(-|z|))."""
    z = np.asarray(z, dtype=float)
    out = np.empty_like(z)
    mid = np.abs(z) <= 40.0
    out[mid] = np.exp(-z[mid]) * special.expi(z[mid])
    zl = z[~mid]
    if zl.size:
        term = np.ones_like(zl)
        total = np.ones_like(zl)
        for k in range(1, 30):
            term = term * k / zl
            total += term
        out[~mid] = total / zl
    return out


def velocity(x, x_from, v_from, stokes):
    """Approach velocity ``V = V1 + ln(X/X1)/St`` on the rigid path through ``(X1, V1)``."""
    return v_from + np.log(np.asarray(x, dtype=float) / x_from) / stokes


def elapsed_time(x, x_from, v_from, stokes):
    """Time ``T - T1`` to move rigidly from ``X1`` (velocity ``V1``) to ``X`` (physics.md)."""
    a = stokes * v_from
    u = np.log(np.asarray(x, dtype=float) / x_from)
    return stokes * x_from * (_scaled_ei(np.full_like(u, a)) - np.exp(u) * _scaled_ei(a + u))


def rest_separation(x_from, v_from, stokes):
    """Where rigid motion from ``(X1, V1)`` ends: ``ln X_e = ln X1 - St V1`` (returns the log)."""
    return math.log(x_from) - stokes * v_from


def deformation_ratio(x, v):
    """Leading-order central deformation over separation, ``W(0)/X``, for the rigid pressure."""
    return HANDOVER_COEFF * v * np.asarray(x, dtype=float) ** -2.5


def handover_separation(x_start, stokes, threshold):
    """First separation on the rigid path from ``(x_start, 1)`` where ``W(0)/X`` reaches ``threshold``.

    Returns ``None`` when the rigid path never deforms that much (the scene is rigid only).
    With ``u = ln(X0/X)``, ``W(0)/X = c (1 - u/St) X0^-2.5 exp(2.5 u)`` peaks at ``u = St - 0.4``.
    """

    log_c = math.log(HANDOVER_COEFF) - 2.5 * math.log(x_start) - math.log(threshold)

    def log_ratio(u):  # ln(W(0)/X / threshold), in logs: exp(2.5 u) overflows at large St
        return log_c + math.log1p(-u / stokes) + 2.5 * u

    if log_ratio(0.0) >= 0.0:
        return x_start
    u_peak = stokes - 0.4
    if u_peak <= 0.0 or log_ratio(u_peak) < 0.0:
        return None
    u = optimize.brentq(log_ratio, 0.0, u_peak, xtol=1e-14, rtol=1e-14)
    return x_start * math.exp(-u)


# ---- closed forms of the hand-over criterion (used by the scene checks and reports) ------------
def start_deformation_ratio(eps):
    """``W(0)/X`` at the start ``(X0, V = 1)``: ``X0 = eps^(-2/5)`` makes it ``3 I0 eps``."""
    return HANDOVER_COEFF * eps


def eps_for_start_deformation(ratio):
    """The ``eps`` at which the start deformation ``W(0)/X`` equals ``ratio`` (inverse of
    ``start_deformation_ratio``)."""
    return ratio / HANDOVER_COEFF


def log_peak_deformation_ratio(x_start, stokes):
    """``ln max W(0)/X`` along the rigid path from ``(x_start, V = 1)`` until it comes to rest.

    With ``u = ln(X0/X)`` the ratio is ``c (1 - u/St) X0^-2.5 exp(2.5 u)`` (``c`` =
    ``HANDOVER_COEFF``), largest at ``u = St - 0.4`` when ``St > 0.4`` (there
    ``c X0^-2.5 (0.4/St) exp(2.5 St - 1)``), else at the start. In logs: ``exp(2.5 St)``
    overflows a float for large St.
    """
    log_start = math.log(HANDOVER_COEFF) - 2.5 * math.log(x_start)
    if stokes <= 0.4:
        return log_start
    return log_start + math.log(0.4 / stokes) + 2.5 * stokes - 1.0
