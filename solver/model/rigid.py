"""Rigid-sphere lubrication (W = 0): the exact solution and the small-deformation estimate.

Dimensionless, scale ``x1`` (docs/model.md, "Rigid solution"). With no deformation the
film pressure is
``P = 3 V / H^2``, the force ``Int P R dR = 3 V / X`` and the motion

    V = V1 + ln(X / X1) / St,
    T - T1 = St X1 exp(-St V1) [Ei(St V1) - Ei(St V1 + ln(X / X1))]

from any state ``(T1, X1, V1)`` (``Ei`` the exponential integral); the spheres come to rest at
``X1 exp(-St V1)`` after infinite time. Inserting the rigid pressure into the elastic integral
gives the leading deflection ``W(R) = 3 V X^(-3/2) I(R / sqrt(X))``, so
``W(0) / X = (3 pi^2 / (4 sqrt 2)) V X^(-5/2)``: the hand-over criterion.

Exact for the classic film only (``Physics.classic``): a pressure floor or a pressure-dependent
viscosity changes the rigid film's pressure and force. ``exact_for`` is the test every caller
makes before using these shortcuts.
"""

from __future__ import annotations

import math

import numpy as np
from ..integration.events import RELAXED
from ..physics import parse_table
from . import contact
from ..special import scaled_ei

__all__ = [
    "I0",
    "HANDOVER_COEFF",
    "velocity",
    "elapsed_time",
    "rest_separation",
    "departure_speed",
    "departure_speed_from_rest",
    "restitution",
    "restitution_from_rest",
    "impact_stokes",
    "stokes_at_start",
    "handover_separation",
    "deformation_ratio",
    "exact_for",
    "departs_rigidly",
    "law_slopes",
    "law_onset_separation",
    "release_event",
    "approach_peaks",
    "start_deformation_ratio",
    "eps_for_start_deformation",
    "log_peak_deformation_ratio",
]

I0 = math.pi**2 / (4.0 * math.sqrt(2.0))  # I(0), the maximum of the deformation integral
HANDOVER_COEFF = 3.0 * I0  # W(0)/X = HANDOVER_COEFF * V * X**-2.5 along the rigid path


def velocity(x, x_from, v_from, stokes):
    """Approach velocity ``V = V1 + ln(X/X1)/St`` on the rigid path through ``(X1, V1)``."""
    return v_from + np.log(np.asarray(x, dtype=float) / x_from) / stokes


def elapsed_time(x, x_from, v_from, stokes):
    """Time ``T - T1`` to move rigidly from ``X1`` (velocity ``V1``) to ``X`` (docs/model.md, "Rigid solution")."""
    a = stokes * v_from
    u = np.log(np.asarray(x, dtype=float) / x_from)
    at_both = scaled_ei(np.append(a + u, a))  # exp(-z) Ei(z) at X and at X1, in one call
    return stokes * x_from * (at_both[-1] - np.exp(u) * at_both[:-1].reshape(u.shape))


def rest_separation(x_from, v_from, stokes):
    """Where rigid motion from ``(X1, V1)`` ends: ``ln X_e = ln X1 - St V1`` (returns the log)."""
    return math.log(x_from) - stokes * v_from


def departure_speed_from_rest(ln_x_e, stokes, x_ref):
    """Separation speed ``-V`` (units v0) at which rigid motion that would come to rest at
    ``x_e`` (``ln_x_e``; ``x_e > X`` for a departure) passes ``x_ref`` outwards:
    ``ln(x_e / x_ref) / St`` (from ``V = ln(X / x_e) / St``), 0 when it never gets there
    (``x_e <= x_ref``: the spheres stick)."""
    return max(0.0, (ln_x_e - math.log(x_ref)) / stokes)


def departure_speed(x_from, v_from, stokes, x_ref):
    """Separation speed ``-V`` (units v0) with which rigid motion from ``(X1, V1)`` passes
    ``x_ref`` outwards: ``-V1 - ln(x_ref / X1) / St``, 0 when it never gets there (it comes to
    rest at ``x_e = X1 exp(-St V1) <= x_ref``, which includes ``V1 >= 0``)."""
    return departure_speed_from_rest(rest_separation(x_from, v_from, stokes), stokes, x_ref)


def impact_stokes(stokes, x_start, x_ref):
    """The Stokes number of the approach at ``x_ref >= x_start``: ``St V(x_ref)`` with the rigid
    approach ``V(x_ref) = 1 + ln(x_ref / x_start) / St`` that arrives at ``x_start`` with speed 1,
    i.e. ``St_ref = St + ln(x_ref / x_start)`` (the approach loses ``ln(x_ref/x0)/St`` of v0
    between the two; exact for the classic film, deformation being negligible there)."""
    if x_ref < x_start:
        raise ValueError(f"x_ref = {x_ref:g} x1 lies inside the start x0 = {x_start:g} x1: the "
                         "reference separation must be x_ref >= x0")
    return stokes + math.log(x_ref / x_start)


def stokes_at_start(stokes_ref, x_start, x_ref):
    """Inverse of ``impact_stokes``: the Stokes number at ``x_start`` of an approach whose Stokes
    number at ``x_ref >= x_start`` is ``stokes_ref``; ``St = St_ref - ln(x_ref / x_start)``, which
    must be > 0 (else the rigid approach stops before it reaches ``x_start``)."""
    stokes = stokes_ref - math.log(x_ref / x_start)
    if not stokes > 0.0:
        raise ValueError(f"St_ref = {stokes_ref:g} at x_ref/x0 = {x_ref / x_start:g}: the rigid "
                         "approach comes to rest before x0 (St_ref <= ln(x_ref/x0))")
    return stokes


def restitution(x_from, v_from, physics, x_ref):
    """The wet coefficient of restitution seen at ``x_ref`` (``>= x0``): the departure speed at
    ``x_ref`` from the release state ``(X1, V1)`` over the approach speed there,
    ``e_wet = ln(x_e / x_ref) / St_ref`` (``St_ref = impact_stokes``; 0 when the spheres stick).

    The one place where the departure after the coupled phase is modelled: exact for a film
    without a floor (``departs_rigidly``; a pressure-dependent liquid is released only where its
    law no longer matters, ``release_event``). A film with a pressure floor (cavitation) departs
    differently (model/cavitation.py)."""
    if not departs_rigidly(physics):
        raise NotImplementedError(f"no departure model for non-classic physics {physics}")
    return restitution_of_speed(departure_speed(x_from, v_from, physics.St, x_ref), physics, x_ref)


def restitution_from_rest(ln_x_e, physics, x_ref):
    """``restitution`` from the rest separation alone (the master curve's ``ln_x_e_x1``): the
    same closed form, ``x_e`` fixing the whole rigid departure."""
    if not departs_rigidly(physics):
        raise NotImplementedError(f"no departure model for non-classic physics {physics}")
    return restitution_of_speed(departure_speed_from_rest(ln_x_e, physics.St, x_ref), physics,
                                x_ref)


def restitution_of_speed(speed, physics, x_ref):
    """A separation speed at ``x_ref`` (units v0) over the approach speed there,
    ``St_ref / St`` (``impact_stokes``): the restitution every departure model reports."""
    return speed / (impact_stokes(physics.St, physics.x_start, x_ref) / physics.St)


def film_pressure(s, x, v):
    """The classic rigid film's pressure ``3 V/(X + s)^2`` at ``s = R^2/2`` (the coupled phase's
    start on the classic approach)."""
    return 3.0 * v / (x + s) ** 2


def deformation_ratio(x, v):
    """Leading-order central deformation over separation, ``W(0)/X``, for the rigid pressure."""
    return HANDOVER_COEFF * v * np.asarray(x, dtype=float) ** -2.5


def exact_for(physics) -> bool:
    """Whether the rigid solution, the hand-over and the release of this module are exact for
    ``physics`` (a ``solver.Physics``): only for the classic film."""
    return physics.classic


def departs_rigidly(physics) -> bool:
    """Whether the departure after ``release_event`` is this module's closed form: for every
    film without a cavitation floor (the event waits until a pressure-dependent liquid's law no
    longer matters)."""
    return physics.cavitation == "off"


def law_slopes(physics):
    """How strongly the liquid's laws change the film per unit pressure, in compression and in
    tension: ``d ln(rho/mu) / dP`` at ``P = 0`` in magnitude (``beta`` and ``c1``; 0 for the
    classic film). In tension the viscosity counts only where its law is read there; the
    density's compressibility ``c1`` fades there (model/liquid.py), so ``c1`` bounds it."""
    viscous = physics.beta if physics.viscosity_law in ("barus", "roelands") else 0.0
    if physics.viscosity_law == "table":  # its steepest segment
        points = parse_table(physics.viscosity_table)
        viscous = max(abs(math.log(b[1] / a[1]) / (b[0] - a[0]))
                      for a, b in zip(points, points[1:]))
    dense = physics.dh_c1 if physics.density_law != "constant" else 0.0
    tension = (viscous if physics.viscosity_in_tension == "law" else 0.0) + dense
    return viscous + dense, tension


def release_event(release, stokes, physics=None):
    """The coupled phase's terminal event (integration/events.py): the deformation has relaxed
    below ``release`` (max|W|/X) and the rigid motion can only relax it further, separating or past
    the rigid deformation peak ``V < 0.4/St`` (``W(0)/X ~ V X^-2.5`` falls once ``St V < 0.4``).
    With a pressure-dependent liquid (``physics``), also its law changes the rigid film by less
    than ``release`` (``law_slopes`` times ``|3V/X^2|``). From there this module's departure
    ``X_e = X exp(-St V)`` is exact (to ``release``)."""
    slopes = law_slopes(physics) if physics is not None else (0.0, 0.0)
    return RELAXED, np.array([release, 0.4 / stokes, slopes[0], slopes[1], release])


def law_onset_separation(x_start, stokes, slope, tol):
    """First separation on the rigid path from ``(x_start, 1)`` where the liquid's law changes the
    film by ``tol``: ``slope * P(0) = tol`` with the axis pressure ``P(0) = 3V/X^2``
    (``law_slopes``). Up to there the classic rigid approach is exact to ``tol``. Returns
    ``None`` when the path never gets there (``slope = 0``: the classic film)."""
    if slope <= 0.0:
        return None
    return _rigid_onset(x_start, stokes, math.log(3.0 * slope / tol) - 2.0 * math.log(x_start),
                        2.0)


def _rigid_onset(x_start, stokes, log_c, power):
    """First separation on the rigid path from ``(x_start, 1)`` where ``c V X^-power`` reaches 1
    (``log_c = ln c - power ln X0``): with ``u = ln(X0/X)`` and ``V = 1 - u/St``, the root of
    ``f(u) = log_c + ln(1 - u/St) + power u`` below its peak at ``u = St - 1/power``, found in logs
    (``exp(power u)`` overflows at large St). ``x_start`` when it is reached at the start,
    ``None`` when the path never gets there (the law's onset, ``law_onset_separation``, and the
    hand-over, ``handover_separation``).

    Newton's iteration from ``u = 0``: ``f`` rises and is concave up to its peak, so each tangent
    lies above ``f`` and every iterate stays below the root, rising to it (quadratically; linearly
    only for a root at the peak itself), to the last bit. Written here, not scipy.optimize's
    root finders: every collision hands over through this root, and importing scipy.optimize
    cost each ``ehd run`` 0.2 s (benchmarks/startup.md)."""

    def log_ratio(u):
        return log_c + math.log1p(-u / stokes) + power * u

    if log_ratio(0.0) >= 0.0:
        return x_start
    u_peak = stokes - 1.0 / power
    if u_peak <= 0.0 or log_ratio(u_peak) < 0.0:
        return None
    u = 0.0
    for _ in range(200):  # quadratic: about 6 iterations; a root at the peak halves per iteration
        slope = power - 1.0 / (stokes - u)
        if not slope > 0.0:  # at the peak: the root is there
            break
        u_next = min(u - log_ratio(u) / slope, u_peak)
        if not u_next > u:  # no more progress: the last bit
            break
        u = u_next
    return x_start * math.exp(-u)


def contact_onset_separation(x_start, stokes, roughness):
    """Where the rigid approach from ``(x_start, 1)`` must hand over before the asperities touch
    (model/contact.py): ``contact.CONTACT_MARGIN`` times the roughness, where the rigid gap (at least
    ``X``) is still clear of them; ``x_start`` when that lies beyond the start, ``None`` without
    roughness or when the spheres come to rest (at ``x_start exp(-St)``) before it."""
    if roughness <= 0.0:
        return None
    x_c = contact.CONTACT_MARGIN * roughness
    if x_c >= x_start:
        return x_start
    if math.log(x_start / x_c) >= stokes:
        return None
    return x_c


def approach_peaks(x_start, stokes, x_end):
    """Largest force, central deformation and pressure on the rigid approach from ``(x_start, 1)``
    down to ``x_end`` (0: all the way), with the time ``T`` of each.

    With ``u = ln(X0/X)`` and ``V = 1 - u/St``: the force ``3V/X`` (its third in the unit
    ``6 pi mu a^2 v0 / x1``) peaks at ``u = St - 1``, ``W(0) = 3 I0 V X^-1.5`` at ``u = St - 2/3``,
    the axis pressure ``P(0) = 3V/X^2`` at ``u = St - 1/2``; each is clipped to the path (the start
    when St is small). Returns a dict of ``peak_force``, ``w0_max``, ``p_max`` and ``t_*`` times.
    """
    u_end = math.log(x_start / x_end) if x_end > 0 else math.inf

    def at(u_peak):
        x = x_start * math.exp(-min(max(u_peak, 0.0), u_end))
        v = float(velocity(x, x_start, 1.0, stokes))
        return x, v, float(elapsed_time(x, x_start, 1.0, stokes))

    x_f, v_f, t_f = at(stokes - 1.0)
    x_w, v_w, t_w = at(stokes - 2.0 / 3.0)
    x_p, v_p, t_p = at(stokes - 0.5)
    return {"peak_force": v_f / x_f, "t_peak_force": t_f,
            "w0_max": 3.0 * v_w * x_w**-1.5 * I0, "t_max_deformation": t_w,
            "p_max": 3.0 * v_p / (x_p * x_p), "t_p_max": t_p, "x_p_max": x_p}


def handover_separation(x_start, stokes, threshold):
    """First separation on the rigid path from ``(x_start, 1)`` where ``W(0)/X`` reaches ``threshold``.

    Returns ``None`` when the rigid path never deforms that much (the scene is rigid only).
    With ``u = ln(X0/X)``, ``W(0)/X = c (1 - u/St) X0^-2.5 exp(2.5 u)`` peaks at ``u = St - 0.4``.
    """
    return _rigid_onset(x_start, stokes, math.log(HANDOVER_COEFF) - 2.5 * math.log(x_start)
                        - math.log(threshold), 2.5)


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
