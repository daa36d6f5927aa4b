"""The coupled time loop, entirely compiled (``nogil``): variable-step BDF2 on
Reynolds + elasticity + particle motion, Newton-coupled, with error-controlled steps.

Dimensionless, scale ``x1`` (docs/model.md, "Scales"); ``T`` is time in units of ``x1 / v0``. The
model's terms come from model/film.py; this module knows nothing of the physics beyond them.

- Step: ``y_{n+1} - a1 y_n - a2 y_{n-1} = b dt f(y_{n+1})`` (variable-step BDF2; the first step is
  implicit Euler), solved for ``(P, X, V)`` by a chord-Newton iteration whose LU is reused while
  ``b dt`` stays within 30 % of the factorised value; a stalled iteration first refreshes the
  Jacobian, then halves the step.
- Error: the local error is estimated from the distance to the quadratic predictor,
  ``dt / (t_{n+1} - t_{n-2}) |y_{n+1} - y_pred|``, measured on the gap (relative, floor
  ``GAP_FLOOR``), the pressure (floor ``PRESSURE_FLOOR`` of its maximum: a purely relative test
  collapses the step when the pressure passes through zero), ``X`` and ``V``; steps grow at most
  2x (BDF2 zero-stability needs < 2.41x) and are kept when the proposed growth is under 1.2x, so
  the LU can be reused.
- Cavitation (a pressure floor, model/film.py): the set of cavitated cells is decided from the
  film rows at each Newton iterate; a change refreshes the Jacobian, and a step converges only
  with a settled set. No BDF restart at a change: the error test rejects and shrinks the step
  across the switching kink, which keeps the integration second order (a restart to first order
  at every change made the whole integration first order in an independent implementation).
- End: a terminal event passed in by the caller (events.py), evaluated after each accepted step;
  for the classic model the release of model/rigid.py, from where the motion is rigid and exact.
"""

import numpy as np

from .._jit import jit
from ..model.film import (cavity_edge, cell_content, compression_work, constrain, jacobian,
                          residual, energy_rates, face_fluxes, film_force, gap, jfo_void,
                          update_cavity, update_cavity_jfo, void_work)
from ..model.liquid import isoviscous, kirchhoff_difference
from ..physics import CAVITATION, PI, ST
from ..observables import SERIES, SERIES_INDEX, STATUS_CODES
from .events import reached
from .linalg import lu_factor, lu_solve, matvec

# status codes of the loop (solver/observables.py: STATUS)
RUNNING = 0
OK = STATUS_CODES["ok"]
MAX_STEPS = STATUS_CODES["max_steps"]
STEP_UNDERFLOW = STATUS_CODES["step_underflow"]
NONFINITE = STATUS_CODES["nonfinite"]

GAP_FLOOR = 1e-2  # x1 units: below this the gap error counts as absolute
PRESSURE_FLOOR = 0.05  # fraction of max|P| below which the pressure error counts as absolute
NEWTON_KAPPA = 0.05  # Newton stops when its predicted remaining error is this fraction of tol
MAX_NEWTON = 7
MAX_SET_CHANGES = 4  # changes of the cavitated cells within one step attempt before it halves
SAFETY = 0.9

# columns of the series array (solver/observables.py: SERIES)
N_SERIES = len(SERIES)
_T, _X, _V, _F = SERIES_INDEX["T"], SERIES_INDEX["X"], SERIES_INDEX["V"], SERIES_INDEX["F"]
_W0, _H_MIN, _R_H_MIN = SERIES_INDEX["W0"], SERIES_INDEX["H_min"], SERIES_INDEX["R_H_min"]
_E_K, _E_S, _DISS = SERIES_INDEX["E_k"], SERIES_INDEX["E_s"], SERIES_INDEX["dissipated"]
_H0, _W_ABSMAX = SERIES_INDEX["H0"], SERIES_INDEX["W_absmax"]
_P_MAX, _P_MIN = SERIES_INDEX["P_max"], SERIES_INDEX["P_min"]
_R_CAV, _V_VOID = SERIES_INDEX["cavity_radius"], SERIES_INDEX["void_volume"]
_W_VOID, _E_C = SERIES_INDEX["void_work"], SERIES_INDEX["E_c"]


@jit
def _grow(a, rows):
    out = np.empty((rows, a.shape[1]))
    out[: a.shape[0]] = a
    return out


@jit
def _norm(dp, dx, dv, dh, p, x, v, h, rtol, p_abs):
    """Max-norm of a change, each component relative to ``rtol`` times its own scale; pressures
    below ``PRESSURE_FLOOR`` of the largest one (plus ``p_abs``) count as absolute."""
    pmax = 0.0
    for i in range(p.size):
        pmax = max(pmax, abs(p[i]))
    p_floor = PRESSURE_FLOOR * pmax + p_abs
    e = abs(dx) / (1.0 + abs(x))
    e = max(e, abs(dv) / (0.1 + abs(v)))
    for i in range(h.size):
        e = max(e, abs(dh[i]) / (abs(h[i]) + GAP_FLOOR))
        e = max(e, abs(dp[i]) / (abs(p[i]) + p_floor))
    return e / rtol


@jit
def _factorise(s, s_face, area, weight, influence, phys, bh, y, theta, h, active, active_lu, jac,
               dres_dh, piv, counters):
    """A fresh Jacobian at the iterate ``y`` (fluid fractions ``theta``, gap ``h``) with the
    cavitated cells ``active``, LU-factorised in place; counted. False if the matrix is
    singular."""
    n = s.size
    jacobian(s, s_face, area, weight, influence, phys, bh, y[:n], theta, h, active, jac, dres_dh)
    active_lu[:] = active
    counters[4] += 1
    counters[3] += 1
    return lu_factor(jac, piv)


@jit
def integrate(s, s_face, area, weight, influence, phys, x_init, v_init, p_init, t_init,
              dissipated_init, rtol, dt_init, dt_min, max_steps, stop_kind, stop_params,
              save_profiles):
    """Integrate from ``(T, X, V, P) = (t_init, x_init, v_init, p_init)`` until the terminal event
    ``stop_kind`` with ``stop_params`` (events.py) or a failure. ``phys`` is
    ``Physics.as_array()``.

    Returns
    -------
    status : int
        ``OK``, ``MAX_STEPS``, ``STEP_UNDERFLOW`` or ``NONFINITE``.
    counters : (5,) int64
        accepted steps, rejected steps, Newton iterations, LU factorisations, Jacobians.
    series : (rows, N_SERIES) float
        One row per accepted step (the first is the initial state); columns ``SERIES``.
    pressure, deformation : (rows, N) float
        Profiles at each row when ``save_profiles``, else (0, N).
    fluid_fraction : (rows, N-1) float
        The cells' fluid fraction ``theta`` at each row (1 in full cells and for every film but
        JFO) when ``save_profiles``, else (0, N-1).
    """
    n = s.size
    m = n + 2
    # current and past solutions y = (P, X, V), and gaps
    y0 = np.empty(m)
    y0[:n] = p_init
    y0[n] = x_init
    y0[n + 1] = v_init
    y1 = y0.copy()  # history slots: never read uninitialised (0 * NaN garbage is NaN)
    y2 = y0.copy()
    w = np.empty(n)
    h = np.empty(n)
    gap(s, influence, x_init, p_init, w, h)
    h0 = h.copy()
    h1 = h.copy()
    t0 = t_init
    t1 = t_init
    t2 = t_init
    n_hist = 1

    y = np.empty(m)
    y_pred = np.empty(m)
    res = np.empty(m)
    q = np.empty(n - 1)
    h_hist = np.empty(n)
    dh = np.empty(n)
    kdp = np.empty(n)
    kq = np.empty(n)  # Kirchhoff pressures of a pressure-dependent liquid (error control)
    piezo = not isoviscous(phys)
    jac = np.empty((m, m))
    dres_dh = np.empty((n, 3))
    piv = np.empty(m, dtype=np.int32)
    lu_valid = False
    bh_lu = 1.0
    floor = phys[CAVITATION] != 0.0  # a cavitation model is on
    # Absolute part of the pressure error scale. With a floor the film carries almost no
    # pressure once it has cavitated (|P| ~ Pi over the whole rebound), and a scale relative to
    # the instantaneous pressure made the steps collapse to 1e-9 where the last full cells at the
    # axis drained: pressures far below the collision's peak move neither the gap nor the force
    # (both in the norm on their own), so they count as absolute below PRESSURE_FLOOR of the
    # largest pressure seen so far, from the film's first cavity on. The classic film (and a
    # film that never cavitates) keeps its instantaneous scale.
    p_abs = 1e-12
    p_seen = 0.0
    active = np.zeros(n - 1, dtype=np.bool_)  # cavitated cells of the current iterate
    active_lu = np.zeros(n - 1, dtype=np.bool_)  # ... of the factorised Jacobian
    active0 = np.zeros(n - 1, dtype=np.bool_)  # ... of the last accepted state
    h_onset = np.zeros(n - 1)  # gap where each cell cavitated (void volume)
    # JFO (mass-conserving): the liquid fraction of each cell (1 where full, and always 1 for the
    # classic and Reynolds films, whose content theta H is then H bit for bit); the slot of a
    # cavitated cell in y holds P = -Pi, its unknown is theta
    jfo = phys[CAVITATION] == 2.0
    theta = np.ones(n - 1)  # of the current iterate
    theta0 = np.ones(n - 1)  # ... of the last two accepted states
    theta1 = np.ones(n - 1)
    dtheta = np.zeros(n - 1)
    worked = 0.0  # void work so far

    rows = 256
    series = np.empty((rows, N_SERIES))
    n_prof = rows if save_profiles else 0
    p_hist = np.empty((n_prof, n))
    w_hist = np.empty((n_prof, n))
    theta_hist = np.empty((n_prof, n - 1))
    counters = np.zeros(5, dtype=np.int64)

    # initial row
    face_fluxes(s, s_face, y0[:n], h, phys, q)
    strain, diss_rate = energy_rates(s, s_face, weight, phys, x_init, y0[:n], w, h, q)
    q_prev = q.copy()
    dissipated = dissipated_init
    n_rows = 0

    dt = dt_init
    status = RUNNING
    err = 0.0
    while True:
        # ---- record the accepted state (also the initial one) -------------------------------
        if n_rows == rows:
            rows *= 2
            series = _grow(series, rows)
            if save_profiles:
                p_hist = _grow(p_hist, rows)
                w_hist = _grow(w_hist, rows)
                theta_hist = _grow(theta_hist, rows)
        x = y0[n]
        v = y0[n + 1]
        imin = 0
        wmax = 0.0
        pmax = y0[0]
        pmin = y0[0]
        for i in range(n):
            if h[i] < h[imin]:
                imin = i
            wmax = max(wmax, abs(w[i]))
            pmax = max(pmax, y0[i])
            pmin = min(pmin, y0[i])
        row = series[n_rows]
        row[_T] = t0
        row[_X] = x
        row[_V] = v
        row[_F] = film_force(weight, y0[:n])
        row[_W0] = w[0]
        row[_H_MIN] = h[imin]
        row[_R_H_MIN] = np.sqrt(2.0 * s[imin])
        row[_E_K] = v * v
        row[_E_S] = strain
        row[_DISS] = dissipated
        row[_H0] = h[0]
        row[_W_ABSMAX] = wmax
        row[_P_MAX] = pmax
        row[_P_MIN] = pmin
        r_cav = cavity_edge(s, y0[:n], active0, phys)
        v_void = 0.0
        if jfo:
            v_void = jfo_void(area, theta0, h, active0)
        else:
            for i in range(n - 1):
                if active0[i]:
                    v_void += area[i] * (h[i] - h_onset[i])
        row[_R_CAV] = r_cav
        row[_V_VOID] = v_void
        row[_W_VOID] = worked
        row[_E_C] = compression_work(area, y0[:n], h, theta0, phys)
        if save_profiles:
            p_hist[n_rows] = y0[:n]
            w_hist[n_rows] = w
            theta_hist[n_rows] = theta0
        n_rows += 1

        if floor:
            p_seen = max(p_seen, pmax, -pmin)
            if r_cav > 0.0:
                p_abs = max(p_abs, PRESSURE_FLOOR * p_seen)
        if status != RUNNING:
            break
        r_event = r_cav
        if jfo:  # a cavity of axis cells alone can have a zero edge radius: still a cavity
            for i in range(n - 1):
                if active0[i]:
                    r_event = max(r_event, 1e-300)
        if reached(stop_kind, stop_params, counters[0], x, v, wmax, r_event):
            status = OK
            break

        # ---- attempt steps until one is accepted ---------------------------------------------
        accepted = False
        while not accepted:
            if counters[0] >= max_steps:
                status = MAX_STEPS
                break
            if dt < dt_min:
                status = STEP_UNDERFLOW
                break
            t_new = t0 + dt
            if n_hist == 1:
                a1 = 1.0
                a2 = 0.0
                b = 1.0
            else:
                om = dt / (t0 - t1)
                a1 = (1.0 + om) ** 2 / (1.0 + 2.0 * om)
                a2 = -(om**2) / (1.0 + 2.0 * om)
                b = (1.0 + om) / (1.0 + 2.0 * om)
            bh = b * dt
            for i in range(n - 1):  # the cells' content (H itself unless JFO)
                h_hist[i] = a1 * cell_content(theta0[i], h0[i], y0[i], phys)[0] \
                    + a2 * cell_content(theta1[i], h1[i], y1[i], phys)[0]
            h_hist[n - 1] = a1 * h0[n - 1] + a2 * h1[n - 1]
            x_hist = a1 * y0[n] + a2 * y1[n]
            v_hist = a1 * y0[n + 1] + a2 * y1[n + 1]
            # predictor: polynomial through the available history
            if n_hist >= 3:
                l0 = (t_new - t1) * (t_new - t2) / ((t0 - t1) * (t0 - t2))
                l1 = (t_new - t0) * (t_new - t2) / ((t1 - t0) * (t1 - t2))
                l2 = (t_new - t0) * (t_new - t1) / ((t2 - t0) * (t2 - t1))
                for k in range(m):
                    y_pred[k] = l0 * y0[k] + l1 * y1[k] + l2 * y2[k]
                err_fac = dt / (t_new - t2)
            elif n_hist == 2:
                l0 = (t_new - t1) / (t0 - t1)
                for k in range(m):
                    y_pred[k] = l0 * y0[k] + (1.0 - l0) * y1[k]
                err_fac = dt / (t_new - t1)
            else:
                y_pred[:] = y0
                err_fac = 0.0
            y[:] = y_pred
            if jfo:  # each attempt starts from the accepted cavity, its cells at the floor
                for i in range(n - 1):
                    active[i] = active0[i]
                    theta[i] = theta0[i]
                    if active[i]:
                        y[i] = -phys[PI]

            fresh = False
            if (not lu_valid) or abs(bh / bh_lu - 1.0) > 0.3:
                gap(s, influence, y[n], y[:n], w, h)
                lu_valid = _factorise(s, s_face, area, weight, influence, phys, bh, y, theta, h,
                                      active, active_lu, jac, dres_dh, piv, counters)
                bh_lu = bh
                fresh = True
                if not lu_valid:
                    status = NONFINITE
                    break

            # Newton: the gap update of an iterate is the next iterate's gap minus this one's,
            # so each iteration costs one K-product (in gap) and one LU solve. With a floor, the
            # cavitated cells are decided at the predictor and held while Newton converges; a
            # converged iterate whose cells would change (a full cell below the floor, a
            # cavitated one drawing liquid in) goes on with the new set and a fresh Jacobian.
            converged = False
            pending = False  # converged, if the cavity of the iterate is settled
            norm_prev = 0.0
            first = True
            set_changes = 0
            gap(s, influence, y[n], y[:n], w, h)
            it = 0
            while it < MAX_NEWTON or (pending and it == MAX_NEWTON):
                it += 1
                bad = False
                for i in range(n):
                    if not (h[i] > 0.0) or not np.isfinite(h[i]):
                        bad = True
                if bad:
                    break
                residual(s, s_face, area, weight, phys, bh, h_hist, x_hist, v_hist, y[n],
                         y[n + 1], y[:n], theta, h, q, res)
                if floor:
                    if it == 1 or pending:
                        if jfo:
                            # the switched slots moved P to the floor: the rows follow
                            if update_cavity_jfo(y[:n], theta, phys, active):
                                gap(s, influence, y[n], y[:n], w, h)
                                residual(s, s_face, area, weight, phys, bh, h_hist, x_hist,
                                         v_hist, y[n], y[n + 1], y[:n], theta, h, q, res)
                        else:
                            update_cavity(y[:n], res, phys, active)
                    same = True
                    for i in range(n - 1):
                        if active[i] != active_lu[i]:
                            same = False
                    if pending and same:
                        converged = True
                        break
                    pending = False
                    if not same:
                        set_changes += 1
                        if set_changes > MAX_SET_CHANGES:
                            break
                        lu_valid = _factorise(s, s_face, area, weight, influence, phys, bh, y,
                                              theta, h, active, active_lu, jac, dres_dh, piv,
                                              counters)
                        bh_lu = bh
                        fresh = True
                        first = True
                        it = 1
                        if not lu_valid:
                            break
                    if not jfo:
                        constrain(y[:n], res, active, phys)
                for k in range(m):
                    res[k] = -res[k]
                lu_solve(jac, piv, res)
                if jfo:  # a cavitated cell's slot updates theta (kept >= 0: a dry cell)
                    for i in range(n - 1):
                        dtheta[i] = 0.0
                        if active[i]:
                            dtheta[i] = res[i]
                            theta[i] = max(theta[i] + res[i], 0.0)
                            res[i] = 0.0
                for k in range(m):
                    y[k] += res[k]
                counters[2] += 1
                for i in range(n):
                    dh[i] = h[i]
                gap(s, influence, y[n], y[:n], w, h)
                for i in range(n):
                    dh[i] = h[i] - dh[i]
                norm = _norm(res[:n], res[n], res[n + 1], dh, y[:n], y[n], y[n + 1], h, rtol, p_abs)
                if jfo:  # the fractions' updates, absolute
                    for i in range(n - 1):
                        norm = max(norm, abs(dtheta[i]) / rtol)
                if not np.isfinite(norm):
                    break
                done = False
                if first:
                    done = norm < 1e-3 * NEWTON_KAPPA
                    first = False
                else:
                    rate = norm / norm_prev
                    if rate >= 1.0:
                        break
                    done = rate / (1.0 - rate) * norm < NEWTON_KAPPA
                if done:
                    if not floor:
                        converged = True
                        break
                    pending = True
                norm_prev = norm
            if floor and not lu_valid:
                status = NONFINITE
                break
            if not converged:
                if fresh:
                    dt *= 0.5
                    counters[1] += 1
                lu_valid = False
                continue

            positive = True
            for i in range(n):
                if not (h[i] > 0.0):
                    positive = False
            if not positive:
                dt *= 0.5
                counters[1] += 1
                continue
            # local error estimate
            if err_fac > 0.0:
                for k in range(m):
                    res[k] = err_fac * (y[k] - y_pred[k])
                matvec(influence, res[:n], kdp)
                for i in range(n):
                    dh[i] = res[n] + kdp[i]
                open_cavity = r_cav > 0.0
                refilled = False
                if jfo:
                    for i in range(n - 1):
                        refilled = refilled or (active0[i] and not active[i])
                for i in range(n - 1):
                    open_cavity = open_cavity or active[i]
                if floor and (open_cavity or refilled):
                    # while a cavity is open the pressure is not smooth in time wherever its edge
                    # crosses a node (the cells there and their neighbours), and a cavity that
                    # closes in this step makes it jump; the gap, X and V errors control the step
                    # (measured: every rejection came from these kinks; counting the jump of the
                    # last cell of an axis cavity as an error underflowed the step)
                    for i in range(n):
                        res[i] = 0.0
                if refilled:
                    # JFO: where a cavity closes the pressure jumps (the void's closing rate is
                    # finite up to the instant it vanishes), and the gap with it through W = K P:
                    # no step size makes the extrapolation of the gap across it accurate. X and V
                    # stay continuous; they control this step, and the history restarts after it
                    for i in range(n):
                        dh[i] = 0.0
                if piezo and not (floor and (open_cavity or refilled)):
                    # a pressure-dependent liquid: the pressure error in the variable the film
                    # sees, the Kirchhoff pressure Int rho/mu dP, smooth where a glassy lens
                    # makes P itself spike (that spike moves the gap, X and V only through W
                    # and the force, both in the norm on their own)
                    for i in range(n):
                        res[i] = err_fac * kirchhoff_difference(y_pred[i], y[i], phys)[0]
                        kq[i] = kirchhoff_difference(0.0, y[i], phys)[0]
                    err = _norm(res[:n], res[n], res[n + 1], dh, kq, y[n], y[n + 1], h, 1.0,
                                p_abs) / rtol
                else:
                    err = _norm(res[:n], res[n], res[n + 1], dh, y[:n], y[n], y[n + 1], h, 1.0,
                                p_abs) / rtol
            else:
                err = 0.0
            if not np.isfinite(err):
                status = NONFINITE
                break
            if err > 1.0:
                dt *= max(0.2, SAFETY * err ** (-1.0 / 3.0))
                counters[1] += 1
                continue
            accepted = True

        if not accepted:
            # record the last accepted state with the failure status, then stop; w and h hold
            # the rejected trial, so recompute them
            gap(s, influence, y0[n], y0[:n], w, h)
            continue

        # ---- shift history -------------------------------------------------------------------
        y2[:] = y1
        y1[:] = y0
        y0[:] = y
        h1[:] = h0
        h0[:] = h
        t2 = t1
        t1 = t0
        t0 = t0 + dt
        n_hist = min(n_hist + 1, 3)
        counters[0] += 1

        face_fluxes(s, s_face, y0[:n], h, phys, q)
        strain_new, diss_new = energy_rates(s, s_face, weight, phys, y0[n], y0[:n], w, h, q)
        dissipated += 0.5 * (diss_rate + diss_new) * dt
        if floor:
            if jfo:  # Pi dV_void exactly (film.jfo_void)
                worked += 2.0 * phys[PI] * (jfo_void(area, theta, h0, active)
                                            - jfo_void(area, theta0, h1, active0)) \
                    / (3.0 * phys[ST])
            else:
                worked += void_work(area, h0, h1, q, q_prev, dt, active, phys)
            theta1[:] = theta0
            theta0[:] = theta
            for i in range(n - 1):
                if active[i] and not active0[i]:
                    h_onset[i] = h1[i]
            active0[:] = active
            q_prev[:] = q
        strain = strain_new
        diss_rate = diss_new

        if err > 0.0:
            factor = min(2.0, max(0.2, SAFETY * err ** (-1.0 / 3.0)))
        else:
            factor = 2.0
        if 1.0 <= factor < 1.2:
            factor = 1.0
        dt *= factor

    kept = min(n_rows, p_hist.shape[0])
    return status, counters, series[:n_rows], p_hist[:kept], w_hist[:kept], theta_hist[:kept]
