"""The coupled time loop, entirely compiled (``nogil``): variable-step BDF2 on the film model's
equations and the particle motion, Newton-coupled, with error-controlled steps.

Dimensionless, scale ``x1`` (docs/model.md, "Scales"); ``T`` is time in units of ``x1 / v0``. The
unknowns are ``y = (P_0..P_{N-1}, X, V)``. Everything that depends on the physics comes through
the film model's contract (model/step.py): its residual and Jacobian, its own state, whether it
has an active set, in which variable its errors are measured, its columns of the series. This
module names no piece of physics.

The loop in parts, each a function of its own (in the spirit of SciPy's BDF, ``_step_impl``):

- ``_bdf2``: the coefficients of ``y_{n+1} - a1 y_n - a2 y_{n-1} = b dt f(y_{n+1})``
  (variable-step BDF2; the first step is implicit Euler);
- ``_predict``: the polynomial through the history at the new time, and the error factor;
- ``_newton``: a chord-Newton iteration whose LU is reused while ``b dt`` stays within 30 % of
  the factorised value; a stalled iteration first refreshes the Jacobian, then halves the step.
  With an active set, a converged iterate whose set would change goes on with the new set and
  the matrix updated where the set changed (a low-rank update of its factorisation, not a new
  one), and converges only with a settled set (no BDF restart at a change: the error
  test rejects and shrinks the step across the switching kink, which keeps the integration
  second order);
- ``_local_error``: the distance to the predictor, ``dt / (t_{n+1} - t_{n-2}) |y_{n+1} -
  y_pred|``, measured on the gap (relative above ``GAP_SCALE``), the pressure (absolute below
  ``PRESSURE_SCALE`` of its maximum: a purely relative test collapses the step when the pressure
  passes through zero), ``X`` and ``V``; steps grow at most 2x (BDF2 zero-stability needs
  < 2.41x) and are kept when the proposed growth is under 1.2x, so the LU can be reused;
- ``_record``: the series row of an accepted state;
- the end: a terminal event passed in by the caller (events.py), evaluated after each accepted
  step.

Counters: ``STEPS``, ``REJECTED``, ``NEWTON``, ``LU``, ``JACOBIANS`` index the counter array the
loop returns (``COUNTERS`` names them in that order).
"""

import numpy as np

from .._jit import jit
from ..model import step as model
from ..model.film import face_fluxes, gap
from ..observables import SERIES, SERIES_INDEX, STATUS_CODES
from .events import reached
from .linalg import MAX_SLOTS, lowrank_prepare, lowrank_solve, lu_factor, matvec

# status codes of the loop (solver/observables.py: STATUS)
RUNNING = 0
OK = STATUS_CODES["ok"]
MAX_STEPS = STATUS_CODES["max_steps"]
STEP_UNDERFLOW = STATUS_CODES["step_underflow"]
NONFINITE = STATUS_CODES["nonfinite"]

# the counters, in the order of the array integrate returns
COUNTERS = ("steps", "rejected_steps", "newton_iterations", "lu_factorizations", "jacobians",
            "lowrank_updates")
STEPS, REJECTED, NEWTON, LU, JACOBIANS, LOWRANK = range(len(COUNTERS))

# outcomes of _newton
CONVERGED, DIVERGED, SINGULAR = 0, 1, 2

GAP_SCALE = 1e-2  # x1 units: below this the gap error counts as absolute
PRESSURE_SCALE = 0.05  # fraction of max|P| below which the pressure error counts as absolute
NEWTON_KAPPA = 0.05  # Newton stops when its predicted remaining error is this fraction of tol
MAX_NEWTON = 7
MAX_SET_CHANGES = 4  # changes of the active set within one step attempt before it halves
SAFETY = 0.9

# columns of the series array (solver/observables.py: SERIES) that the loop writes itself; the
# film model writes its own (model/step.py: record)
N_SERIES = len(SERIES)
_T, _X, _V, _F = SERIES_INDEX["T"], SERIES_INDEX["X"], SERIES_INDEX["V"], SERIES_INDEX["F"]
_W0, _H_MIN, _R_H_MIN = SERIES_INDEX["W0"], SERIES_INDEX["H_min"], SERIES_INDEX["R_H_min"]
_E_K, _E_S, _DISS = SERIES_INDEX["E_k"], SERIES_INDEX["E_s"], SERIES_INDEX["dissipated"]
_H0, _W_ABSMAX = SERIES_INDEX["H0"], SERIES_INDEX["W_absmax"]
_P_MAX, _P_MIN = SERIES_INDEX["P_max"], SERIES_INDEX["P_min"]


@jit
def _rows(rows, cols):
    """Rows of the series or the profiles, NaN until written: a column a row never wrote reads
    NaN, never uninitialised memory (it had stored a rough film's cavity radius as 6e-314 and
    619, different from run to run)."""
    return np.full((rows, cols), np.nan)


@jit
def _grow(a, rows):
    out = _rows(rows, a.shape[1])
    out[: a.shape[0]] = a
    return out


@jit
def _norm(dp, dx, dv, dh, p, x, v, h, rtol, p_abs):
    """Max-norm of a change, each component relative to ``rtol`` times its own scale; pressures
    below ``PRESSURE_SCALE`` of the largest one (plus ``p_abs``) count as absolute."""
    pmax = 0.0
    for i in range(p.size):
        pmax = max(pmax, abs(p[i]))
    p_small = PRESSURE_SCALE * pmax + p_abs
    e = abs(dx) / (1.0 + abs(x))
    e = max(e, abs(dv) / (0.1 + abs(v)))
    for i in range(h.size):
        e = max(e, abs(dh[i]) / (abs(h[i]) + GAP_SCALE))
        e = max(e, abs(dp[i]) / (abs(p[i]) + p_small))
    return e / rtol


@jit
def _bdf2(dt, t0, t1, n_hist):
    """``(a1, a2, b)`` of the variable-step BDF2 step of size ``dt`` after ``t1, t0`` (implicit
    Euler while the history holds one state)."""
    if n_hist == 1:
        return 1.0, 0.0, 1.0
    om = dt / (t0 - t1)
    return ((1.0 + om) ** 2 / (1.0 + 2.0 * om), -(om**2) / (1.0 + 2.0 * om),
            (1.0 + om) / (1.0 + 2.0 * om))


@jit
def _predict(dt, t0, t1, t2, n_hist, y0, y1, y2, y_pred):
    """The polynomial through the available history at ``t0 + dt`` into ``y_pred``; returns the
    error factor ``dt / (t_new - t_oldest)`` (0 when there is no history to compare with)."""
    m = y0.size
    t_new = t0 + dt
    if n_hist >= 3:
        l0 = (t_new - t1) * (t_new - t2) / ((t0 - t1) * (t0 - t2))
        l1 = (t_new - t0) * (t_new - t2) / ((t1 - t0) * (t1 - t2))
        l2 = (t_new - t0) * (t_new - t1) / ((t2 - t0) * (t2 - t1))
        for k in range(m):
            y_pred[k] = l0 * y0[k] + l1 * y1[k] + l2 * y2[k]
        return dt / (t_new - t2)
    if n_hist == 2:
        l0 = (t_new - t1) / (t0 - t1)
        for k in range(m):
            y_pred[k] = l0 * y0[k] + (1.0 - l0) * y1[k]
        return dt / (t_new - t1)
    y_pred[:] = y0
    return 0.0


@jit
def _factorisation(m):
    """Work space of the Newton matrix: the matrix (factorised in place) and its pivots, its copy
    before factorising, a fresh Jacobian, the low-rank update's arrays (linalg.lowrank_prepare),
    the updated slots and their number (``rank[0]``, 0: the factorised matrix itself)."""
    r = 2 * MAX_SLOTS
    return (np.empty((m, m)), np.empty(m, dtype=np.int32), np.empty((m, m)), np.empty((m, m)),
            np.empty((r, m)), np.empty((r, m)), np.empty((r, m)), np.empty(r * r),
            np.empty(r, dtype=np.int32), np.empty(MAX_SLOTS, dtype=np.int64),
            np.zeros(1, dtype=np.int64), np.empty(r))


@jit
def _factorise(s, s_face, area, weight, influence, phys, bh, y, h, marks, cells, scalars, fac,
               dres_dh, counters):
    """A fresh Jacobian at the iterate ``y`` (gap ``h``), LU-factorised in place; counted. False
    if the matrix is singular."""
    jac, piv, base, rank = fac[0], fac[1], fac[2], fac[10]
    model.step_jacobian(s, s_face, area, weight, influence, phys, bh, y, h, marks, cells, scalars,
                        jac, dres_dh)
    model.mark_factorised(marks)
    if model.has_active_set(phys):  # kept for low-rank updates at a change of the set
        base[:, :] = jac
    rank[0] = 0
    counters[JACOBIANS] += 1
    counters[LU] += 1
    return lu_factor(jac, piv)


@jit
def _update_for_set(s, s_face, area, weight, influence, phys, bh, y, h, marks, cells, scalars,
                    fac, dres_dh, counters):
    """After a change of the active set: the factorised matrix with the rows and columns of the
    slots that changed since it was factorised replaced by a fresh Jacobian's
    (linalg.lowrank_prepare), instead of a new factorisation; the other rows keep the factorised
    values (a chord iteration). False when more than ``MAX_SLOTS`` slots changed or the update is
    singular: then the caller factorises afresh."""
    jac, piv, base, fresh, u, v, z, cap, cpiv, slots, rank = fac[:11]
    model.step_jacobian(s, s_face, area, weight, influence, phys, bh, y, h, marks, cells, scalars,
                        fresh, dres_dh)
    counters[JACOBIANS] += 1
    k = model.changed_slots(marks, slots)
    if k > MAX_SLOTS:
        return False
    rank[0] = 0
    if k > 0:
        if not lowrank_prepare(jac, piv, base, fresh, slots, k, u, v, z, cap, cpiv):
            return False
        rank[0] = k
    counters[LOWRANK] += 1
    return True


@jit
def _solve(fac, b):
    """Solve with the Newton matrix (the factorised one, or its low-rank update) in place."""
    lowrank_solve(fac[0], fac[1], fac[10][0], fac[5], fac[6], fac[7], fac[8], b, fac[11])


@jit
def _newton(s, s_face, area, weight, influence, phys, bh, c_hist, x_hist, v_hist, rtol, y,
            marks, cells, scalars, q, w, h, res, dh, dp, fac, dres_dh, lu_valid, bh_lu, counters):
    """Solve the step from the predictor in ``y`` by chord Newton (module docstring), reusing
    the LU while ``bh`` stays within 30 % of ``bh_lu``. The gap update of an iterate is the next
    iterate's gap minus this one's, so each iteration costs one K-product (in gap) and one LU
    solve. With an active set, the set is decided at the first iterate and held while Newton
    converges; a converged iterate whose set would change goes on with the new set and the
    matrix updated in the slots that changed (``_update_for_set``; a fresh factorisation when
    too many did).

    Returns
    -------
    outcome, lu_valid, bh_lu, fresh
        ``CONVERGED``, ``DIVERGED`` or ``SINGULAR``; whether the LU is still usable, the ``bh``
        it was factorised at, and whether it was factorised in this attempt.
    """
    n = s.size
    m = n + 2
    fresh = False
    if (not lu_valid) or abs(bh / bh_lu - 1.0) > 0.3:
        model.surface_gap(s, influence, phys, y, marks, scalars, w, h)
        for i in range(n):
            if not (h[i] > 0.0):  # the predictor's gap is not admissible: a smaller step
                return DIVERGED, lu_valid, bh_lu, True
        lu_valid = _factorise(s, s_face, area, weight, influence, phys, bh, y, h, marks, cells,
                              scalars, fac, dres_dh, counters)
        bh_lu = bh
        fresh = True
        if not lu_valid:
            return SINGULAR, lu_valid, bh_lu, fresh
    active_set = model.has_active_set(phys)
    p_abs = model.pressure_scale(scalars)
    converged = False
    pending = False  # converged, if the active set of the iterate is settled
    norm_prev = 0.0
    first = True
    set_changes = 0
    model.surface_gap(s, influence, phys, y, marks, scalars, w, h)
    it = 0
    while it < MAX_NEWTON or (pending and it == MAX_NEWTON):
        it += 1
        bad = False
        for i in range(n):
            if not (h[i] > 0.0) or not np.isfinite(h[i]):
                bad = True
        if bad:
            break
        model.step_residual(s, s_face, area, weight, influence, phys, bh, c_hist, x_hist,
                            v_hist, y, marks, cells, scalars, it == 1 or pending, q, w, h, res)
        if active_set:
            same = model.settled(marks)
            if pending and same:
                converged = True
                break
            pending = False
            if not same:
                set_changes += 1
                if set_changes > MAX_SET_CHANGES:
                    break
                first = True
                it = 1
                if not _update_for_set(s, s_face, area, weight, influence, phys, bh, y, h, marks,
                                       cells, scalars, fac, dres_dh, counters):
                    lu_valid = _factorise(s, s_face, area, weight, influence, phys, bh, y, h,
                                          marks, cells, scalars, fac, dres_dh, counters)
                    bh_lu = bh
                    fresh = True
                    if not lu_valid:
                        break
        for k in range(m):
            res[k] = -res[k]
        _solve(fac, res)
        model.split_update(res, marks, cells, phys)
        for k in range(m):
            y[k] += res[k]
        counters[NEWTON] += 1
        for i in range(n):
            dh[i] = h[i]
        model.surface_gap(s, influence, phys, y, marks, scalars, w, h)
        for i in range(n):
            dh[i] = h[i] - dh[i]
        dp_film, p = model.film_change(res[:n], dh, y, h, marks, scalars, phys, dp)
        norm = _norm(dp_film, res[n], res[n + 1], dh, p, y[n], y[n + 1], h, rtol, p_abs)
        norm = model.update_norm(norm, cells, phys, rtol)
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
            if not active_set:
                converged = True
                break
            pending = True
        norm_prev = norm
    if active_set and not lu_valid:
        return SINGULAR, lu_valid, bh_lu, fresh
    return (CONVERGED if converged else DIVERGED), lu_valid, bh_lu, fresh


@jit
def _local_error(influence, phys, y, y_pred, err_fac, h, marks, scalars, rtol, res, kdp, dh,
                 scale):
    """The step's local error in units of the tolerance (``_norm`` of ``err_fac (y - y_pred)``,
    the pressures' part as the film model measures it: model/step.py, ``step_error``); 0 for the
    first step, which has no history to compare with. ``res``, ``kdp``, ``dh`` and ``scale`` are
    work space."""
    if err_fac == 0.0:
        return 0.0
    n = h.size
    m = n + 2
    for k in range(m):
        res[k] = err_fac * (y[k] - y_pred[k])
    matvec(influence, res[:n], kdp)
    for i in range(n):
        dh[i] = res[n] + kdp[i]
    p_scale = scale if model.step_error(y, y_pred, err_fac, h, marks, scalars, phys, res[:n], dh,
                                        scale) else y[:n]
    return _norm(res[:n], res[n], res[n + 1], dh, p_scale, y[n], y[n + 1], h, 1.0,
                 model.pressure_scale(scalars)) / rtol


@jit
def _record(row, t, s, area, weight, y, w, h, strain, dissipated, marks, cells, scalars, phys):
    """The series row of the accepted state ``y`` at ``t`` (gap ``h``, deflection ``w``); returns
    the largest ``|W|`` that can still relax and the radius the terminal events see
    (model/step.py: ``relaxing_deflection``, ``record``)."""
    n = s.size
    x = y[n]
    v = y[n + 1]
    p = model.film_pressure(y, scalars, phys)
    imin = 0
    wmax = 0.0
    pmax = p[0]
    pmin = p[0]
    for i in range(n):
        if h[i] < h[imin]:
            imin = i
        wmax = max(wmax, abs(w[i]))
        pmax = max(pmax, p[i])
        pmin = min(pmin, p[i])
    row[_T] = t
    row[_X] = x
    row[_V] = v
    row[_F] = model.total_force(weight, y, scalars, phys)
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
    r_event = model.record(row, s, area, weight, p, h, pmax, pmin, marks, cells, scalars, phys,
                           PRESSURE_SCALE)
    return model.relaxing_deflection(w, wmax, scalars, phys), r_event


@jit
def _step_factor(err):
    """The next step's size over this one's after an accepted step of error ``err``."""
    factor = min(2.0, max(0.2, SAFETY * err ** (-1.0 / 3.0))) if err > 0.0 else 2.0
    if 1.0 <= factor < 1.2:
        factor = 1.0
    return factor


@jit
def _attempt(s, s_face, area, weight, influence, phys, rtol, dt, dt_min, max_steps, t0, t1, t2,
             n_hist, y0, y1, y2, h0, h1, y, y_pred, marks, cells, scalars, q, w, h, res, c_hist,
             dh, kdp, scale, fac, dres_dh, lu_valid, bh_lu, counters):
    """Attempt steps from the accepted state ``y0`` at ``t0`` until one is accepted (its solution
    in ``y``, gap ``h``) or the loop must stop: a diverged Newton halves the step once its
    Jacobian was fresh, a non-positive gap halves it, an error above the tolerance shrinks it.

    Returns
    -------
    status, accepted, dt, err, lu_valid, bh_lu
        ``RUNNING`` or the failure; whether a step was accepted, its size and error; the LU's
        state.
    """
    n = s.size
    status = RUNNING
    err = 0.0
    accepted = False
    while not accepted:
        if counters[STEPS] >= max_steps:
            status = MAX_STEPS
            break
        if dt < dt_min:
            status = STEP_UNDERFLOW
            break
        a1, a2, b = _bdf2(dt, t0, t1, n_hist)
        bh = b * dt
        model.content_history(a1, a2, y0, y1, h0, h1, cells, scalars, phys, c_hist)
        x_hist = a1 * y0[n] + a2 * y1[n]
        v_hist = a1 * y0[n + 1] + a2 * y1[n + 1]
        err_fac = _predict(dt, t0, t1, t2, n_hist, y0, y1, y2, y_pred)
        y[:] = y_pred
        model.start_attempt(y, marks, cells, phys)

        outcome, lu_valid, bh_lu, fresh = _newton(
            s, s_face, area, weight, influence, phys, bh, c_hist, x_hist, v_hist, rtol, y,
            marks, cells, scalars, q, w, h, res, dh, kdp, fac, dres_dh, lu_valid, bh_lu, counters)
        if outcome == SINGULAR:
            status = NONFINITE
            break
        if outcome == DIVERGED:
            if fresh:
                dt *= 0.5
                counters[REJECTED] += 1
            lu_valid = False
            continue

        positive = True
        for i in range(n):
            if not (h[i] > 0.0):
                positive = False
        if not positive:
            dt *= 0.5
            counters[REJECTED] += 1
            continue
        err = _local_error(influence, phys, y, y_pred, err_fac, h, marks, scalars, rtol, res,
                           kdp, dh, scale)
        if not np.isfinite(err):
            status = NONFINITE
            break
        if err > 1.0:
            dt *= max(0.2, SAFETY * err ** (-1.0 / 3.0))
            counters[REJECTED] += 1
            continue
        accepted = True
    return status, accepted, dt, err, lu_valid, bh_lu


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
        ``COUNTERS``: accepted steps, rejected steps, Newton iterations, LU factorisations,
        Jacobians.
    series : (rows, N_SERIES) float
        One row per accepted step (the first is the initial state); columns ``SERIES``.
    pressure, deformation : (rows, N) float
        Profiles at each row when ``save_profiles``, else (0, N).
    fluid_fraction : (rows, N-1) float
        The cells' fluid fraction ``theta`` at each row (model/step.py: 1 in full cells) when
        ``save_profiles``, else (0, N-1).
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
    c_hist = np.empty(n)
    dh = np.empty(n)
    kdp = np.empty(n)
    scale = np.empty(n)
    fac = _factorisation(m)
    dres_dh = np.empty((n, 3))
    lu_valid = False
    bh_lu = 1.0

    rows = 256
    series = _rows(rows, N_SERIES)
    n_prof = rows if save_profiles else 0
    p_hist = _rows(n_prof, n)
    w_hist = _rows(n_prof, n)
    theta_hist = _rows(n_prof, n - 1)
    counters = np.zeros(len(COUNTERS), dtype=np.int64)

    # initial row
    face_fluxes(s, s_face, y0[:n], h, phys, q)
    marks, cells, scalars = model.new_state(q)
    model.surface_gap(s, influence, phys, y0, marks, scalars, w, h)  # with a contact load, if any
    model.begin(scalars, phys)
    h0[:] = h
    h1[:] = h
    strain, diss_rate = model.energies(s, s_face, weight, phys, y0, w, h, q, scalars)
    dissipated = dissipated_init
    n_rows = 0

    dt = dt_init
    status = RUNNING
    while True:
        # ---- record the accepted state (also the initial one) -------------------------------
        if n_rows == rows:
            rows *= 2
            series = _grow(series, rows)
            if save_profiles:
                p_hist = _grow(p_hist, rows)
                w_hist = _grow(w_hist, rows)
                theta_hist = _grow(theta_hist, rows)
        wmax, r_event = _record(series[n_rows], t0, s, area, weight, y0, w, h, strain, dissipated,
                                marks, cells, scalars, phys)
        if save_profiles:
            p_hist[n_rows] = model.film_pressure(y0, scalars, phys)
            w_hist[n_rows] = w
            theta_hist[n_rows] = model.fluid_fraction(cells)
        n_rows += 1
        if status != RUNNING:
            break
        if reached(stop_kind, stop_params, counters[STEPS], y0[n], y0[n + 1], wmax, r_event):
            status = OK
            break

        # ---- attempt steps until one is accepted ---------------------------------------------
        status, accepted, dt, err, lu_valid, bh_lu = _attempt(
            s, s_face, area, weight, influence, phys, rtol, dt, dt_min, max_steps, t0, t1, t2,
            n_hist, y0, y1, y2, h0, h1, y, y_pred, marks, cells, scalars, q, w, h, res, c_hist,
            dh, kdp, scale, fac, dres_dh, lu_valid, bh_lu, counters)

        if not accepted:
            # record the last accepted state with the failure status, then stop; w and h (and
            # the active set) hold the rejected trial's, so restore the state's and recompute
            model.start_attempt(y0, marks, cells, phys)
            model.surface_gap(s, influence, phys, y0, marks, scalars, w, h)
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
        counters[STEPS] += 1

        face_fluxes(s, s_face, model.film_pressure(y0, scalars, phys), h, phys, q)
        model.accept(s, area, weight, y0, w, h0, h1, q, dt, marks, cells, scalars, phys)
        strain_new, diss_new = model.energies(s, s_face, weight, phys, y0, w, h, q, scalars)
        dissipated += 0.5 * (diss_rate + diss_new) * dt
        strain = strain_new
        diss_rate = diss_new
        dt *= _step_factor(err)

    kept = min(n_rows, p_hist.shape[0])
    return status, counters, series[:n_rows], p_hist[:kept], w_hist[:kept], theta_hist[:kept]
