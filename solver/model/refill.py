"""The rigid departure of a mass-conserving (JFO) film whose cavity is still open at the release:
the cavity refills from its outer edge, and the spheres move as the film it leaves pulls them
(docs/model.md, "Cavitation": "The refill departure (JFO)").

At the release the surfaces are rigid again (``H = X + s``, ``s = R^2/2``) and separate at
``U = -V > 0``. Then:

- **One cavity, from the axis.** A full film between the axis and a cavity would have to rise
  from its axis to ``-Pi`` at the cavity while the opening gap draws liquid in, so its axis
  would lie below the floor: any cell inside the outermost cavitated one cavitates at once, with
  the liquid it holds. The cavity is ``[0, q]``.
- **Frozen content.** Inside the cavity the pressure is flat, so no liquid moves: each cell
  keeps the content it had at the release, ``c = theta (X_rel + s)`` (its fraction ``theta`` of
  the rigid gap there; the film's cells hold ``theta H`` with ``H`` within the release's
  ``max|W| < release X`` of the rigid gap).
- **The full film outside, in closed form.** ``(1/6)(s H^3 P')' = U`` with ``P(q) = -Pi`` and
  ``P -> 0`` far away gives ``s H^3 P' = 6U (s - s0)``, with

      s0 = (3U/H_q^2 - Pi) / (6U I),   I = Int_q^inf ds / (s (X + s)^3)
         = X^-3 [ln(1 + 1/sig) - 1/(1 + sig) - 1/(2 (1 + sig)^2)],   sig = q/X,

  and the force ``Int P ds / 3 = -U (X + 2q - s0) / (X + q)^2``, the unit of
  model/cavitation.py's ``-U/(X + s_c)``, to which it reduces at ``s0 = q``.
- **The front** (the jump condition): the liquid the film brings, ``U (q - s0)`` per unit of
  ``s``, fills the void ``H_q - c(q)`` it reaches, ``dq/dT = U (s0 - q) / (H_q - c(q))``. The
  cavity refills while ``s0 < q``; ``s0 = q`` is the Reynolds condition (model/cavitation.py),
  where the front stalls; ``s0 > q`` would make it grow again, with cells cavitating full: a
  history this departure does not follow (``GROWS``; and ``STOPPED`` where the spheres stop with
  the cavity open: the coupled phase then runs on until the film is full again, as it did
  before solver 1.19.0).

So the departure is an ODE in ``(U, T, q)`` over ``ln X``: ``dU/d ln X = X F/(St U)``, ``dT/d ln X
= X/U``, ``dq/d ln X = X (dq/dT)/U``. Each cell's content is constant, so its right-hand side is
smooth inside a cell and jumps at a face: each face the front reaches ends a step, located as the
Reynolds cavity's closing is (model/cavitation.py). It ends when the front reaches the axis; from
there the classic closed form is exact.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import entry, jit, leaf
from .cavitation import _root  # cavitation.cavity_fraction, compiled
from .dopri import (A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65,
                    B1, B3, B4, B5, B6, C2, C3, C4, C5, E1, E3, E4, E5, E6, E7,
                    after_acceptance, after_rejection, illinois, trial)

__all__ = ["REACHED", "CLOSED", "GROWS", "STOPPED", "outer_integral", "front_source", "force",
           "closes", "departure", "speed_at", "void_volume", "exact_for"]

# How a departure ended (``_integrate``)
REACHED, CLOSED, GROWS, STOPPED, TOO_MANY = 0, 1, 2, 3, -1
# on (U, T); q's error against RTOL times the cavity's extent at the start
RTOL, ATOL = 1e-10, 1e-14
_MAX_STEPS = 100_000
_EVENT_ITERATIONS = 100
# A face is reached once the front is this fraction of q's error scale (RTOL times the cavity's
# extent) past it: the front then moves on from the face, an error far below a step's
_FACE_TOLERANCE = 1e-3
_SERIES_FROM = 10.0  # sig above which I is summed as a series (the closed form cancels)
_FAR = 700.0  # in ln X, beyond any departure: U only falls, and the front must close first
# The front's last stretch to the axis: as q -> 0, I ~ ln(X/q)/X^3, so s0 ~ 1/ln(X/q) and the
# slope dq/d ln X has a derivative in q that grows as 1/(q ln^2): an explicit step shrinks with
# q, and q falls by a fixed factor a step. Below _CLOSED times the axis cell's face the rest of
# the refill takes ``d ln X ~ q ln(X/q)/(X |kappa|)``, ``kappa = (1 - Pi X^2/(3U))/2``, about
# 1e-12 of the axis cell in ln X: the cavity has closed.
_CLOSED = 1e-12
# A front that starts on the Reynolds cavity's edge starts this much outside it (relative): there
# ``s0 = q`` to the root's accuracy (1e-8, model/cavitation.py), and the front must refill, not grow
_STALL_MARGIN = 1e-7
# The front grows where s0 exceeds q by more than this (relative): a front that stalls on the
# Reynolds edge sits within rounding of it, and two runs of the same departure (a departure and
# its speed_at, stepping differently) must not tell growth from the stall by rounding
_GROWTH = 1e-9


@leaf
def outer_integral(x, q):
    """``I = Int_q^inf ds / (s (X + s)^3)`` (module docstring); for ``sig = q/X`` above
    ``_SERIES_FROM`` from the series ``X^-3 sum_{n>=3} (-1)^(n+1) (1/n - 1 + (n-1)/2) sig^-n``
    (the closed form's terms cancel to ``1/(3 sig^3)`` there)."""
    sig = q / x
    if sig <= _SERIES_FROM:
        return (math.log1p(1.0 / sig) - 1.0 / (1.0 + sig) - 0.5 / (1.0 + sig) ** 2) / x**3
    e = 1.0 / sig
    total, power = 0.0, e * e
    for n in range(3, 60):  # e <= 0.1: the terms fall about 10x each
        power *= e
        term = (-1) ** (n + 1) * power * (1.0 / n - 1.0 + 0.5 * (n - 1))
        total += term
        if abs(term) < 1e-18 * abs(total):
            break
    return total / x**3


@leaf
def front_source(x, u, q, pi):
    """``s0`` of the full film outside a cavity ``[0, q]`` (module docstring): the film's flux
    ``U (s - s0)`` vanishes at ``s0``; the front refills while ``s0 < q``."""
    return (3.0 * u / (x + q) ** 2 - pi) / (6.0 * u * outer_integral(x, q))


def force(x, u, q, pi):
    """The film force ``Int P ds / 3 = -U (X + 2q - s0)/(X + q)^2`` of rigid spheres at gaps
    ``x`` separating at ``u`` with the cavity ``[0, q]`` (equal-length 1-d arrays; module
    docstring); ``-U/X`` where ``q = 0``."""
    out = np.empty(len(x))
    _forces(np.asarray(x, dtype=float), np.asarray(u, dtype=float), np.asarray(q, dtype=float),
            float(pi), out)
    return out


@entry
@jit
def _forces(x, u, q, pi, out):
    """``force`` into ``out``, compiled."""
    for i in range(out.size):
        s0 = front_source(x[i], u[i], q[i], pi) if q[i] > 0.0 else 0.0
        out[i] = -u[i] * (x[i] + 2.0 * q[i] - s0) / (x[i] + q[i]) ** 2


@leaf
def _slope(lnx, u, q, stokes, pi, theta, x_rel):
    """``dU, dT, dq`` over ``d ln X`` (module docstring), the front in a cell of fraction
    ``theta`` at the release (gap ``x_rel``)."""
    x = math.exp(lnx)
    h = x + q
    s0 = front_source(x, u, q, pi)
    return (-x * (x + 2.0 * q - s0) / (stokes * h * h), x / u,
            x * (s0 - q) / (h - theta * (x_rel + q)))


@leaf
def _step(lnx, u, t, q, h, k1, stokes, pi, theta, x_rel):
    """One Dormand-Prince step of ``h`` from ``(ln X, U, T, q)`` whose slopes are ``k1`` (a
    3-tuple): the fifth-order state, its error estimate and the slopes there."""
    k1u, k1t, k1q = k1
    k2u, k2t, k2q = _slope(lnx + C2 * h, u + h * A21 * k1u, q + h * A21 * k1q, stokes, pi,
                           theta, x_rel)
    k3u, k3t, k3q = _slope(lnx + C3 * h, u + h * (A31 * k1u + A32 * k2u),
                           q + h * (A31 * k1q + A32 * k2q), stokes, pi, theta, x_rel)
    k4u, k4t, k4q = _slope(lnx + C4 * h, u + h * (A41 * k1u + A42 * k2u + A43 * k3u),
                           q + h * (A41 * k1q + A42 * k2q + A43 * k3q), stokes, pi, theta, x_rel)
    k5u, k5t, k5q = _slope(lnx + C5 * h,
                           u + h * (A51 * k1u + A52 * k2u + A53 * k3u + A54 * k4u),
                           q + h * (A51 * k1q + A52 * k2q + A53 * k3q + A54 * k4q),
                           stokes, pi, theta, x_rel)
    k6u, k6t, k6q = _slope(lnx + h,
                           u + h * (A61 * k1u + A62 * k2u + A63 * k3u + A64 * k4u + A65 * k5u),
                           q + h * (A61 * k1q + A62 * k2q + A63 * k3q + A64 * k4q + A65 * k5q),
                           stokes, pi, theta, x_rel)
    u_new = u + h * (B1 * k1u + B3 * k3u + B4 * k4u + B5 * k5u + B6 * k6u)
    t_new = t + h * (B1 * k1t + B3 * k3t + B4 * k4t + B5 * k5t + B6 * k6t)
    q_new = q + h * (B1 * k1q + B3 * k3q + B4 * k4q + B5 * k5q + B6 * k6q)
    k7 = _slope(lnx + h, u_new, q_new, stokes, pi, theta, x_rel)
    err_u = h * (E1 * k1u + E3 * k3u + E4 * k4u + E5 * k5u + E6 * k6u + E7 * k7[0])
    err_t = h * (E1 * k1t + E3 * k3t + E4 * k4t + E5 * k5t + E6 * k6t + E7 * k7[1])
    err_q = h * (E1 * k1q + E3 * k3q + E4 * k4q + E5 * k5q + E6 * k6q + E7 * k7[2])
    return u_new, t_new, q_new, err_u, err_t, err_q, k7


@leaf
def _step_to_face(lnx, u, t, q, h, q_hi, u_hi, t_hi, face, k1, stokes, pi, theta, x_rel,
                  q_tol):
    """The step ``s`` in ``(0, h]`` from ``(ln X, U, T, q)`` whose end puts the front on
    ``face`` (``q`` above it at the start, not above at the step ``h``'s end ``q_hi``), by the
    Illinois variant of the false position on ``s`` (each value a step of ``s`` itself, as
    model/cavitation.py locates the Reynolds cavity's closing), until the front is within
    ``q_tol`` of the face or to the rounding of ``ln X``; returns ``s`` and ``U, T`` there."""
    lo, hi, side = 0.0, h, 0
    f_lo, f_hi = face - q, face - q_hi  # the event function, at or past the face where >= 0
    for _ in range(_EVENT_ITERATIONS):
        if hi - lo <= 4e-16 * max(1.0, abs(lnx)) or f_hi <= q_tol:
            break
        s = trial(lo, hi, f_lo, f_hi)
        u_s, t_s, q_s, _, _, _, _ = _step(lnx, u, t, q, s, k1, stokes, pi, theta, x_rel)
        lo, hi, f_lo, f_hi, side = illinois(lo, hi, f_lo, f_hi, side, s, face - q_s)
        if side == 1:
            u_hi, t_hi = u_s, t_s
    return hi, u_hi, t_hi


@entry
@jit
def _integrate(ln_from, ln_to, u, t, x_rel, stokes, pi, faces, thetas, samples, path):
    """The departure from ``(ln X, U, T) = (ln_from, u, t)``, the front on the outer face of the
    cavity's last cell (``faces[k]`` the outer face of cell ``k``, ``thetas[k]`` its fraction at
    the release, gap ``x_rel``), towards ``ln_to``; steps end on each of ``samples`` (ascending)
    and ``path[:, k]`` takes ``U, T, q`` there. Returns ``(code, ln X, U, T, q, samples
    passed)``: ``REACHED`` ``ln_to``, ``CLOSED`` (the front at the axis), ``GROWS`` (``s0 > q``
    at an accepted state), ``STOPPED`` (``U`` reached 0 with the cavity open) or ``TOO_MANY``
    steps."""
    cell = faces.size - 1
    q = faces[cell]
    face = faces[cell - 1] if cell > 0 else 0.0
    q_scale = q
    lnx, k = ln_from, 0
    k1 = _slope(lnx, u, q, stokes, pi, thetas[cell], x_rel)
    h = min(1e-3, ln_to - ln_from)
    for _ in range(_MAX_STEPS):
        if lnx >= ln_to:
            return REACHED, lnx, u, t, q, k
        x = math.exp(lnx)
        if front_source(x, u, q, pi) > q * (1.0 + _GROWTH):
            return GROWS, lnx, u, t, q, k
        end = samples[k] if k < samples.size else ln_to
        if end <= lnx:  # a sample at the start, or repeated
            path[0, k], path[1, k], path[2, k] = u, t, q
            k += 1
            continue
        landing = h >= end - lnx
        step = end - lnx if landing else h
        if not landing and lnx + step == lnx:  # U at the rounding of its scale, or q in the
            return (CLOSED if cell == 0 else STOPPED), lnx, u, t, q, k  # axis cell's last stretch
        theta = thetas[cell]
        u_new, t_new, q_new, err_u, err_t, err_q, k7 = _step(lnx, u, t, q, step, k1, stokes, pi,
                                                             theta, x_rel)
        scale_u = ATOL + RTOL * max(abs(u), abs(u_new))
        scale_t = ATOL + RTOL * max(abs(t), abs(t_new), abs(t_new - t))
        scale_q = ATOL + RTOL * q_scale
        error = math.sqrt(((err_u / scale_u) ** 2 + (err_t / scale_t) ** 2
                           + (err_q / scale_q) ** 2) / 3.0)
        if not error <= 1.0 or not u_new > 0.0:  # NaN too (a trial stage past U = 0)
            if not u_new > 0.0 and error <= 1.0:
                return STOPPED, lnx, u, t, q, k
            h = after_rejection(step, error)
            continue
        if cell == 0 and q_new <= _CLOSED * faces[0]:
            return CLOSED, lnx + step, u_new, t_new, 0.0, k
        if q_new <= face:  # the front reaches the cell's inner face within the step
            s, u, t = _step_to_face(lnx, u, t, q, step, q_new, u_new, t_new, face, k1, stokes,
                                    pi, theta, x_rel, _FACE_TOLERANCE * RTOL * q_scale)
            lnx, q = lnx + s, face
            if cell == 0:
                return CLOSED, lnx, u, t, 0.0, k
            cell -= 1
            face = faces[cell - 1] if cell > 0 else 0.0
            k1 = _slope(lnx, u, q, stokes, pi, thetas[cell], x_rel)
            h = step  # the controller's step, which the next cell's error test then judges
            continue
        lnx = end if landing else lnx + step
        u, t, q, k1 = u_new, t_new, q_new, k7
        if landing and k < samples.size:
            path[0, k], path[1, k], path[2, k] = u, t, q
            k += 1
        grown = after_acceptance(step, error)
        h = max(h, grown) if landing else grown
    return TOO_MANY, lnx, u, t, q, k


def _cavity(s_face, theta, x_rel, u, pi):
    """``_cavity_cells`` of a release state from Python: None without a cavity."""
    faces, thetas = _cavity_cells(np.ascontiguousarray(s_face, dtype=float),
                                  np.ascontiguousarray(theta, dtype=float), float(x_rel),
                                  float(u), float(pi))
    return (faces, thetas) if faces.size else None


@entry
@jit
def _cavity_cells(s_face, theta, x_rel, u, pi):
    """The faces and fractions of the cells ``[0, q]`` from a release state's fractions ``theta``
    per cell (``< 1`` in a cavity; gap ``x_rel``, speed ``u``, floor ``-pi``): every cell inside
    the outermost cavitated one (module docstring); empty without a cavity.

    The outermost cell holds the front. Where it is fuller than the one inside it, the front has
    passed part of it: that part is full, the rest holds the inner cell's fraction, and the front
    lies where that holds the cell's liquid (``_front_in_cell``); but not inside the Reynolds
    cavity of the state (model/cavitation.py), where the film would open it again: there the
    front starts on that cavity's edge, with the cell's liquid inside it. Without this, the front
    started at the cell's outer face, a cell beyond where its void begins (the cavity up to 13 %
    wider at the release than the coupled phase's, at St 10, eps 1e-4, Pi 1e-6)."""
    last = -1
    for i in range(theta.size):
        if theta[i] < 1.0:
            last = i
    faces, thetas = np.empty(last + 1), np.empty(last + 1)
    for i in range(last + 1):
        faces[i], thetas[i] = s_face[i], min(theta[i], 1.0)
    if last > 0 and thetas[last] > thetas[last - 1]:
        inner, outer = faces[last - 1], faces[last]
        front = _front_in_cell(inner, outer, thetas[last - 1], thetas[last], x_rel)
        stall = _root(pi * x_rel * x_rel / (6.0 * u), 0.0) * x_rel * (1.0 + _STALL_MARGIN)
        front = min(outer, max(front, stall))
        # the cell's liquid inside [inner, front]: all of it less the full part beyond the front
        liquid = thetas[last] * _rigid_gap_integral(inner, outer, x_rel) \
            - _rigid_gap_integral(front, outer, x_rel)
        faces[last] = front
        thetas[last] = liquid / _rigid_gap_integral(inner, front, x_rel)
    return faces, thetas


@leaf
def _rigid_gap_integral(a, b, x_rel):
    """``Int_a^b (x_rel + s) ds``: a full rigid film's liquid over ``[a, b]``."""
    return x_rel * (b - a) + 0.5 * (b * b - a * a)


@leaf
def _front_in_cell(a, b, theta_in, theta_cell, x_rel):
    """The front ``q0`` in the cell ``[a, b]`` of fraction ``theta_cell`` whose part ``[q0, b]``
    is full and ``[a, q0]`` holds ``theta_in``: the same liquid, ``Int_a^q0 (x_rel + s) ds =
    (1 - theta_cell)/(1 - theta_in) Int_a^b (x_rel + s) ds``."""
    target = (1.0 - theta_cell) / (1.0 - theta_in) * _rigid_gap_integral(a, b, x_rel)
    # x_rel (q0 - a) + (q0^2 - a^2)/2 = target: q0 = -x_rel + sqrt((x_rel + a)^2 + 2 target)
    return min(b, math.sqrt((x_rel + a) ** 2 + 2.0 * target) - x_rel)


@jit
def closes(x, u, t, stokes, pi, s_face, theta):
    """Whether the refill departure from the release state ``(x, u > 0, t)`` with the cells'
    fractions ``theta`` (outer faces ``s_face``) ends with the cavity refilled (``CLOSED``), as
    ``departure``'s first pass decides it; True without a cavity. The time loop asks it where a
    JFO film's coupled phase would end (integration/stepper.py, events.RELAXED_APART): where it
    would not, the phase runs on until the film is full again, instead of being solved again."""
    faces, thetas = _cavity_cells(s_face, theta, x, u, pi)
    if faces.size == 0:
        return True
    ln0 = math.log(x)
    code = _integrate(ln0, ln0 + _FAR, u, t, x, stokes, pi, faces, thetas, np.empty(0),
                      np.empty((3, 0)))[0]
    return code == CLOSED


def departure(x_from, u_from, t_from, stokes, pi, s_face, theta, samples=40):
    """The refill departure from the release state ``(x_from, u_from > 0, t_from)`` whose cells
    (outer faces ``s_face``) hold the liquid fractions ``theta`` (module docstring).

    Returns ``(code, x, u, t, path)``: ``code`` ``CLOSED`` with the state where the cavity has
    refilled (the classic closed form holds from there) and ``path`` (4, samples), ``X, U, T, q``
    along the way; or ``GROWS`` / ``STOPPED`` (where the departure does not apply) or
    ``TOO_MANY`` (its steps ran out), ``path`` None: the caller runs the coupled phase on instead
    (pieces.RUN_ON). ``CLOSED`` at once, with a path of one sample, where no cell is cavitated."""
    if samples < 2:
        raise ValueError(f"the departure's path takes at least 2 samples (got {samples})")
    cavity = _cavity(s_face, theta, x_from, u_from, pi)
    if cavity is None:
        return CLOSED, x_from, u_from, t_from, np.array([[x_from], [u_from], [t_from], [0.0]])
    faces, thetas = cavity
    ln0 = math.log(x_from)
    code, ln_c, u_c, t_c, _, _ = _integrate(ln0, ln0 + _FAR, float(u_from), float(t_from),
                                            float(x_from), float(stokes), float(pi), faces,
                                            thetas, np.empty(0), np.empty((3, 0)))
    if code == REACHED:  # not met: U only falls, the front closes long before
        code = TOO_MANY
    if code != CLOSED:
        return code, math.exp(ln_c), u_c, t_c, None
    grid = np.linspace(ln0, ln_c, samples)
    path = np.empty((4, samples))
    path[0] = np.exp(grid)
    path[1:, 0] = u_from, t_from, faces[-1]
    path[1:, -1] = u_c, t_c, 0.0
    inner = path[1:, 1:-1]
    _, ln_end, _, _, _, passed = _integrate(ln0, ln_c, float(u_from), float(t_from),
                                            float(x_from), float(stokes), float(pi), faces,
                                            thetas, grid[1:-1].copy(), inner)
    # samples the second pass did not reach lie within rounding of the closing (its own
    # closing a hair before the first's): the closing state
    if passed < samples - 2 and not abs(ln_end - ln_c) <= 1e-8 * max(1.0, abs(ln_c)):
        return TOO_MANY, math.exp(ln_c), u_c, t_c, None  # the passes disagree: not seen
    inner[0, passed:], inner[1, passed:], inner[2, passed:] = u_c, t_c, 0.0
    path[1:, 1:-1] = inner
    return CLOSED, math.exp(ln_c), u_c, t_c, path


def speed_at(x_from, u_from, stokes, pi, s_face, theta, x_target):
    """The separation speed of the refill departure from ``(x_from, u_from > 0)`` when it passes
    ``x_target >= x_from`` (0 if it comes to rest before): the ODE while the cavity is open, the
    classic ``U = U_c - ln(x/X_c)/St`` after it has refilled; None where the departure does not
    apply (``GROWS``, ``STOPPED``) or its steps ran out."""
    if x_target <= x_from:
        return u_from
    cavity = _cavity(s_face, theta, x_from, u_from, pi)
    if cavity is not None:
        code, ln_end, u_end, _, _, _ = _integrate(
            math.log(x_from), math.log(x_target), float(u_from), 0.0, float(x_from),
            float(stokes), float(pi), cavity[0], cavity[1], np.empty(0), np.empty((3, 0)))
        if code == REACHED:  # still open at x_target
            return u_end
        if code != CLOSED:
            return None
        x_from, u_from = math.exp(ln_end), u_end
    return max(0.0, u_from - math.log(x_target / x_from) / stokes)


def void_volume(x, q, x_rel, u_rel, pi, s_face, theta):
    """The void of the cavity ``[0, q]`` at gap ``x`` (arrays ``x``, ``q``) of the departure from
    ``(x_rel, u_rel)``, ``Int (H - c) ds`` over it, the film's ``sum area (1 - theta) H``
    (model/film.py, ``jfo_void``)."""
    cavity = _cavity(s_face, theta, x_rel, u_rel, pi)
    if cavity is None:
        return np.zeros(np.shape(x))
    faces, thetas = cavity
    inner = np.concatenate(([0.0], faces[:-1]))
    x, q = np.asarray(x, dtype=float)[..., None], np.asarray(q, dtype=float)[..., None]
    top = np.clip(q, inner, faces)  # each cell's part inside the front
    # Int (X + s - theta (x_rel + s)) ds over [inner, top]
    return np.sum((x - thetas * x_rel) * (top - inner)
                  + 0.5 * (1.0 - thetas) * (top**2 - inner**2), axis=-1)


def exact_for(physics) -> bool:
    """Whether ``departure`` is the exact rigid departure of ``physics`` (a ``solver.Physics``):
    a JFO cavity with a floor ``0 < Pi < inf`` in a liquid of constant density (its cells hold
    ``theta H``; a compressible liquid's content is ``rho theta H``, and its coupled phase runs
    on until the film is full again)."""
    return (physics.cavitation == "jfo" and 0.0 < physics.Pi < math.inf
            and physics.density_law == "constant")
