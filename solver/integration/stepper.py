"""The coupled time loop, entirely compiled (``nogil``): variable-step BDF on the film model's
equations and the particle motion, Newton-coupled, with error-controlled steps; of order 2 (the
presets), or up to ``Control.max_order`` (at most ``MAX_ORDER``), the order chosen step by step.

Dimensionless, scale ``x1`` (docs/model.md, "Scales"); ``T`` is time in units of ``x1 / v0``. The
unknowns are ``y = (P_0..P_{N-1}, X, V)``. Everything that depends on the physics comes through
the film model's contract (model/step.py): its residual and Jacobian, its own state, whether it
has an active set, in which variable its errors are measured, its columns of the series. This
module names no piece of physics.

The loop in parts, each a function of its own (in the spirit of SciPy's BDF, ``_step_impl``):

- ``_coefficients``: those of ``y_{n+1} - a1 y_n - ... - ak y_{n+1-k} = b dt f(y_{n+1})``
  (variable-step BDF of order ``k``, the variable-step BDF2 in closed form, ``_bdf2``; the first
  step is implicit Euler);
- ``_predict``: the polynomial through the history at the new time, and the error factor;
- ``_next_step``: the next step's size (bound after changes of an active set:
  ``_set_change_factor``) and, above order 2, its order (``_next_order``);
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

Counters: ``STEPS``, ``REJECTED``, ``NEWTON``, ``LU``, ``JACOBIANS``, ``LOWRANK`` and
``HIGHER_ORDER`` (accepted steps above order 2) index the counter array the loop returns
(``COUNTERS`` names them in that order).
"""

from typing import NamedTuple

import numpy as np

from .._jit import copy_into, entry, filled, hook, jit, leaf
from ..model import step as model
from ..model.kind import LOG_CODE, holds_asked
from ..model.state import Step, array_record
from ..observables import SERIES, SERIES_INDEX, STATUS_CODES
from .dense import combine, dissipated_in_step, extremum_in_step, lagrange_basis, stop_in_step
from .events import RELAXED_APART, RELAXED_FULL, reached
from .linalg import MAX_SLOTS, lowrank_prepare, lowrank_solve, lu_factor, lu_solve, matvec

# status codes of the loop (solver/observables.py: STATUS)
RUNNING = 0
OK = STATUS_CODES["ok"]
MAX_STEPS = STATUS_CODES["max_steps"]
STEP_UNDERFLOW = STATUS_CODES["step_underflow"]
NONFINITE = STATUS_CODES["nonfinite"]

# the counters, in the order of the array integrate returns
COUNTERS = ("steps", "rejected_steps", "newton_iterations", "lu_factorizations", "jacobians",
            "lowrank_updates", "higher_order_steps")
STEPS, REJECTED, NEWTON, LU, JACOBIANS, LOWRANK, HIGHER_ORDER = range(len(COUNTERS))

# outcomes of _newton
CONVERGED, DIVERGED, SINGULAR = 0, 1, 2

GAP_SCALE = 1e-2  # x1 units: below this the gap error counts as absolute
PRESSURE_SCALE = 0.05  # fraction of max|P| below which the pressure error counts as absolute
X_FLOOR, V_FLOOR = 1.0, 0.1  # below these |X| and |V| their errors count as absolute
NEWTON_KAPPA = 0.05  # Newton stops when its predicted remaining error is this fraction of tol
MAX_NEWTON = 7
# Above order 2, a step whose Newton took this many iterations on a matrix factorised at an
# earlier step has the next attempt factorise afresh: its steps are 3-5x longer than BDF2's, so
# a reused matrix is further from the solution (4.5 iterations a step against BDF2's 2.7).
# Measured on the classic film (alternated, 5 rounds): 0.93x the CPU time at the standard preset
# (18 scenes, scene medians 0.86-1.02; 30 % fewer iterations for 8 % more factorisations), 0.95x
# at the fine one (5 scenes, 0.92-1.03). At orders 1-2 the loop keeps the matrix while b dt
# stays within 30 % (BDF2's results unchanged).
SLOW_NEWTON = 4
MAX_ORDER = 5  # the highest BDF order the loop takes (Control.max_order chooses up to it)
SLOTS = MAX_ORDER + 1  # accepted states held at most: the order-5 predictor's points
# The largest growth of the step per accepted step, by order: variable-step BDF2 stays
# zero-stable below 1 + sqrt(2); the higher orders are zero-stable on grids whose steps change
# smoothly (ratios 1 + O(1/N): BIT Numer. Math. 58 (2018), doi:10.1007/s10543-018-0716-y), so
# their growth is held smaller (heuristic bounds, not proven ones)
GROWTH = (2.0, 2.0, 2.0, 1.5, 1.5, 1.5)
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
_ORDER, _H_MIN_STEP = SERIES_INDEX["order"], SERIES_INDEX["H_min_step"]
_P_MAX_STEP, _H0_AT_P_MAX_STEP = SERIES_INDEX["P_max_step"], SERIES_INDEX["H0_at_P_max_step"]
_H_MIN_AT_V0, _P_MAX_AT_V0 = SERIES_INDEX["H_min_at_v0"], SERIES_INDEX["P_max_at_v0"]
_H0_AT_V0, _T_AT_V0 = SERIES_INDEX["H0_at_v0"], SERIES_INDEX["T_at_v0"]

# The attempt log (``integrate``'s ``log_rows`` > 0): one row per step attempt, these columns.
# ``outcome``: ATTEMPT_OUTCOMES' codes; ``error``: the local error in units of the tolerance
# (NaN where none was computed); ``largest``: LARGEST_TERMS' code of the error's largest term and
# ``cell`` its node (NaN for X and V). Diagnostics only: nothing the loop decides reads them.
LOG_COLUMNS = ("t", "dt", "order", "outcome", "newton", "fresh", "set_changes", "error",
               "largest", "cell")
N_LOG = len(LOG_COLUMNS)
ATTEMPT_OUTCOMES = ("accepted", "rejected_error", "diverged_fresh", "diverged_older",
                    "gap_not_positive")
# (floats, as the log holds them: int constants are literal types to numba, and each would
# compile ``_log_attempt`` once more)
ACCEPTED, REJECTED_ERROR, DIVERGED_FRESH, DIVERGED_OLDER, GAP_NOT_POSITIVE = (
    float(code) for code in range(len(ATTEMPT_OUTCOMES)))
LARGEST_TERMS = ("pressure", "gap", "X", "V")


# ---- the records: what the caller hands in, and what the loop allocates once -------------------
# (History, Work and Factorisation, passed to the loop's functions, are StructRefs: one
# reference however many arrays, state.array_record)
class Start(NamedTuple):
    """The state the coupled phase starts from (time, separation, speed, pressure profile) and
    the energy dissipated before it."""

    t: float
    x: float
    v: float
    p: np.ndarray
    dissipated: float


class Control(NamedTuple):
    """The step control: relative tolerance, first and smallest step, most accepted steps, the
    highest BDF order (1 to ``MAX_ORDER``; 2: BDF2), and the factor on the tolerance where the
    order may rise above 2 (``_film_control``)."""

    rtol: float
    dt_init: float
    dt_min: float
    max_steps: int
    max_order: int
    high_order_rtol_factor: float


@jit
def _refuse_absent_pieces(phys):
    """Raises where the physics asks for a piece whose code this copy of the loop lacks
    (model/kind.py: its hooks would answer as though the piece were off); ``loop_for``
    (integration/kinds.py) never hands it one."""
    if not holds_asked(phys):
        raise ValueError("integrate: this copy of the loop lacks the code of a piece the physics "
                         "asks for (integration/kinds.py: loop_for chooses the copy)")


@jit
def _film_control(control, phys):
    """The control the film's integration takes: where the order may rise above 2 (``max_order >
    2`` and a film smooth in time, model/step.py: ``smooth_in_time``) its tolerance is ``rtol``
    times ``high_order_rtol_factor`` (solver/settings.py: the presets' factors keep every error
    of benchmarks/accuracy.md at or below BDF2's at ``rtol``), and the factor stays in the
    control (``_control_from_now`` divides by it); a film that is not smooth in time gets BDF2
    at ``rtol`` (``max_order`` 2: the loop asks the control alone which orders it may take)."""
    if control.max_order <= 2:
        return control
    if model.smooth_in_time(phys):
        return Control(control.rtol * control.high_order_rtol_factor, control.dt_init,
                       control.dt_min, control.max_steps, control.max_order,
                       control.high_order_rtol_factor)
    return Control(control.rtol, control.dt_init, control.dt_min, control.max_steps, 2, 1.0)


# The accepted states the BDF step and its predictor read, newest first (row 0), as many rows as
# the highest order's predictor reads (``_history``: 3 for BDF2, ``max_order + 1`` above):
# solutions ``y`` (rows, m), gaps ``h`` and the cells' content ``c`` (rows, N) (model/step.py:
# ``accepted_content``), their times ``t`` and the dissipation rates ``r`` (rows,) and how many
# are held, ``n`` (1,), at most rows; ``order`` (2,): the order the next step takes (as far as
# the history reaches) and the steps accepted since it was chosen. A record, not a NamedTuple:
# a NamedTuple's arrays were a reference count each at each call of a function that takes it
# (docs/solver.md, "Reference counting").
History = array_record("History", ("y", "h", "c", "t", "r", "n", "order"),
                       "The accepted states the step reads (integration/stepper.py).", __name__)


# The iterate and the loop's work arrays, allocated once per coupled phase (m = N + 2 unknowns):
# ``y``, ``y_pred``, ``res`` (m,): the iterate, the predictor, the residual (then the Newton
# update, then the local error); ``w``, ``h`` (N,): the iterate's deflection and gap; ``q``
# (N-1,): its face fluxes; ``c_hist`` (N,): the content's history (state.Step); ``dh``, ``kdp``,
# ``scale`` (N,): the gap's change, the film pressure's change (a rough film's) or K times an
# error, the pressure's error scale (model/step.py: step_error); ``dres_dh`` (N, 3): the
# Jacobian's gap partials (film.jacobian); ``a`` (SLOTS,): the step's BDF coefficients
# (``_coefficients``); ``basis`` (4, SLOTS): the Lagrange basis of the newest states, its values
# and slopes at a point, its slopes at the step's start and end (``extremum_in_step``, which
# keeps a cell's Newton coefficients in the slopes' row, ``dissipated_in_step``); ``counters``:
# ``COUNTERS``; ``log`` (rows, N_LOG): the attempt log (0 rows: none kept), ``log_n`` (1,): its
# rows written, ``own_scale`` (1,): 1 where the last local error measured the pressures against
# ``scale``, 0 against the slots, -1 where it measured nothing (the first step; ``_local_error``).
Work = array_record("Work", ("y", "y_pred", "res", "w", "h", "q", "c_hist", "dh", "kdp",
                               "scale", "dres_dh", "a", "basis", "counters", "log", "log_n",
                               "own_scale"),
                      "The time loop's work arrays (integration/stepper.py).", __name__)

# The Newton matrix: ``jac`` (factorised in place) and its pivots ``piv``, ``base`` its copy
# before factorising, ``fresh`` a fresh Jacobian, ``u``, ``v``, ``z``, ``cap``, ``cpiv`` the
# low-rank update's arrays (linalg.lowrank_prepare), ``slots`` the updated slots and ``rank``
# their number (``rank[0]``, 0: the factorised matrix itself), ``work`` the solve's work space;
# ``valid`` (1,): whether it is usable, ``bh`` (1,): the ``bh`` it was factorised at.
Factorisation = array_record(
    "Factorisation", ("jac", "piv", "base", "fresh", "u", "v", "z", "cap", "cpiv", "slots",
                      "rank", "work", "valid", "bh"),
    "The Newton matrix and its LU state (integration/stepper.py).", __name__)


@jit
def _rows(rows, cols):
    """Rows of the series or the profiles, NaN until written: a column a row never wrote reads
    NaN, never uninitialised memory (it had stored a rough film's cavity radius as 6e-314 and
    619, different from run to run)."""
    return filled((rows, cols), np.nan)


@jit
def _grown(rows, series, p_hist, w_hist, theta_hist, save_profiles):
    """The series and the profiles (``integrate``) at twice ``rows`` rows (the profiles only
    where every row is kept): the new row count and the arrays."""
    rows *= 2
    if save_profiles:
        p_hist, w_hist, theta_hist = (_grow(p_hist, rows), _grow(w_hist, rows),
                                      _grow(theta_hist, rows))
    return rows, _grow(series, rows), p_hist, w_hist, theta_hist


@jit
def _grow(a, rows):
    out = _rows(rows, a.shape[1])
    copy_into(out[: a.shape[0]], a)
    return out


@jit
def _norm(dp, dx, dv, dh, p, x, v, h, rtol, p_abs):
    """Max-norm of a change, each component relative to ``rtol`` times its own scale; pressures
    below ``PRESSURE_SCALE`` of the largest one (plus ``p_abs``) count as absolute (the terms:
    ``_term``; which is largest: ``_largest_term``)."""
    p_small = _pressure_floor(p, p_abs)
    e = _term(dx, x, X_FLOOR)
    e = max(e, _term(dv, v, V_FLOOR))
    for i in range(h.size):
        e = max(e, _term(dh[i], h[i], GAP_SCALE))
        e = max(e, _term(dp[i], p[i], p_small))
    return e / rtol


@leaf
def _term(change, value, floor):
    """One term of ``_norm``: ``change`` relative to ``|value|``, absolute below ``floor``."""
    return abs(change) / (abs(value) + floor)


@leaf
def _pressure_floor(p, p_abs):
    """Where ``_norm`` measures the pressures' changes as absolute: ``PRESSURE_SCALE`` of the
    largest ``|p|``, plus ``p_abs``."""
    pmax = 0.0
    for i in range(p.size):
        pmax = max(pmax, abs(p[i]))
    return PRESSURE_SCALE * pmax + p_abs


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
def _coefficients(dt, t, k, a):
    """The BDF step of order ``k`` and size ``dt`` after the accepted times ``t`` (newest first):
    ``a[:k]`` and the returned ``b`` of ``y_new - sum_j a_j y_j = b dt f(y_new)``. Orders 1 and 2
    in the closed form of ``_bdf2``; higher orders from the Lagrange basis ``l_j`` through
    ``t_new`` and the ``k`` newest times: ``b dt = 1 / l_new'(t_new)``, ``a_j = -l_j'(t_new) /
    l_new'(t_new)``."""
    if k <= 2:
        a1, a2, b = _bdf2(dt, t[0], t[1], k)
        a[0] = a1
        a[1] = a2
        return b
    t_new = t[0] + dt
    d_new = 0.0  # l_new'(t_new)
    for j in range(k):
        d_new += 1.0 / (t_new - t[j])
    for j in range(k):
        num = 1.0
        den = t[j] - t_new
        for i in range(k):
            if i != j:
                num *= t_new - t[i]
                den *= t[j] - t[i]
        a[j] = -num / den / d_new
    return 1.0 / (d_new * dt)


@hook
def _history_term(a, k, u, out):
    """``sum_j a_j u_j`` over the ``max(k, 2)`` newest rows of ``u`` into ``out`` (a step's
    history of the cells' content, ``_coefficients``)."""
    for i in range(out.size):
        out[i] = a[0] * u[0, i] + a[1] * u[1, i]
        for j in range(2, k):
            out[i] += a[j] * u[j, i]


@jit
def _history_value(a, k, y, col):
    """``sum_j a_j y_j`` of the column ``col`` of ``y`` (``_history_term``; X and V)."""
    out = a[0] * y[0, col] + a[1] * y[1, col]
    for j in range(2, k):
        out += a[j] * y[j, col]
    return out


@jit
def _predict(dt, t, d, y, y_pred):
    """The polynomial of degree ``d`` through the ``d + 1`` newest states of ``y`` (times ``t``)
    at ``t[0] + dt`` into ``y_pred``; returns the error factor ``dt / (t_new - t_d)`` (0 for
    ``d = 0``: no history to compare with)."""
    m = y_pred.size
    t0 = t[0]
    t_new = t0 + dt
    if d == 0:
        copy_into(y_pred, y[0])
        return 0.0
    if d == 2:
        t1, t2 = t[1], t[2]
        l0 = (t_new - t1) * (t_new - t2) / ((t0 - t1) * (t0 - t2))
        l1 = (t_new - t0) * (t_new - t2) / ((t1 - t0) * (t1 - t2))
        l2 = (t_new - t0) * (t_new - t1) / ((t2 - t0) * (t2 - t1))
        for k in range(m):
            y_pred[k] = l0 * y[0, k] + l1 * y[1, k] + l2 * y[2, k]
        return dt / (t_new - t2)
    if d == 1:
        l0 = (t_new - t[1]) / (t0 - t[1])
        for k in range(m):
            y_pred[k] = l0 * y[0, k] + (1.0 - l0) * y[1, k]
        return dt / (t_new - t[1])
    for k in range(m):
        y_pred[k] = 0.0
    for j in range(d + 1):
        lj = 1.0
        for i in range(d + 1):
            if i != j:
                lj *= (t_new - t[i]) / (t[j] - t[i])
        for k in range(m):
            y_pred[k] += lj * y[j, k]
    return dt / (t_new - t[d])


@jit
def _factorisation(m):
    """The Newton matrix's work space (``Factorisation``), not yet factorised."""
    r = 2 * MAX_SLOTS
    return Factorisation(np.empty((m, m)), np.empty(m, dtype=np.int32), np.empty((m, m)),
                         np.empty((m, m)), np.empty((r, m)), np.empty((r, m)), np.empty((r, m)),
                         np.empty(r * r), np.empty(r, dtype=np.int32),
                         np.empty(MAX_SLOTS, dtype=np.int64), filled(1, 0), np.empty(r),
                         filled(1, False), filled(1, 1.0))


@jit
def _work(n, log_rows):
    """The loop's work arrays (``Work``) for ``n`` nodes, an attempt log of ``log_rows`` rows."""
    m = n + 2
    return Work(np.empty(m), np.empty(m), np.empty(m), np.empty(n), np.empty(n),
                np.empty(n - 1), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                np.empty((n, 3)), filled(SLOTS, 0.0), filled((4, SLOTS), 0.0),
                filled(len(COUNTERS), 0), filled((log_rows, N_LOG), np.nan), filled(1, 0),
                filled(1, 0.0))


@jit
def _log_attempt(work, film, t, dt, k, outcome, newton, fresh, set_changes, err):
    """One row of the attempt log (``LOG_COLUMNS``; with an error ``err``, its largest term from
    the terms ``_local_error`` left in ``work``); nothing once the log is full. Only in a copy of
    the loop compiled with the log (model/kind.py: ``LOG_CODE``)."""
    row = work.log_n[0]
    if row >= work.log.shape[0]:
        return
    log = work.log[row]
    log[0], log[1], log[2], log[3] = t, dt, k, outcome
    log[4], log[5], log[6], log[7] = newton, fresh, set_changes, err
    log[8], log[9] = np.nan, np.nan
    if not np.isnan(err) and work.own_scale[0] >= 0.0:
        y, n = work.y, work.h.size
        _largest_term(work.res[:n], work.res[n], work.res[n + 1], work.dh,
                      work.scale if work.own_scale[0] == 1.0 else y[:n], y[n], y[n + 1], work.h,
                      model.pressure_scale(film), log[8:])
    work.log_n[0] = row + 1


@jit
def _factorise(grid, phys, bh, y, h, film, fac, work):
    """A fresh Jacobian at the iterate ``y`` (gap ``h``), LU-factorised in place; counted.
    ``fac.valid[0]`` False if the matrix is singular."""
    model.step_jacobian(grid, phys, bh, y, h, film, fac.jac, work.dres_dh)
    model.mark_factorised(film)
    if model.has_active_set(phys):  # kept for low-rank updates at a change of the set
        copy_into(fac.base, fac.jac)
    fac.rank[0] = 0
    work.counters[JACOBIANS] += 1
    work.counters[LU] += 1
    fac.valid[0] = lu_factor(fac.jac, fac.piv)
    fac.bh[0] = bh


@jit
def _update_for_set(grid, phys, bh, y, h, film, fac, work, fresh):
    """After a change of the active set: the factorised matrix with the rows and columns of the
    slots that changed since it was factorised replaced by a fresh Jacobian's
    (linalg.lowrank_prepare), instead of a new factorisation; the other rows keep the factorised
    values (a chord iteration). False when more than ``MAX_SLOTS`` slots changed or the update is
    singular, or when the matrix was factorised before this attempt (not ``fresh``) of a film
    that refactorises it then (model/step.py: ``refresh_at_set_change``): then the caller
    factorises afresh."""
    if not fresh and model.refresh_at_set_change(phys):
        return False
    model.step_jacobian(grid, phys, bh, y, h, film, fac.fresh, work.dres_dh)
    work.counters[JACOBIANS] += 1
    k = model.changed_slots(film, fac.slots)
    if k > MAX_SLOTS:
        return False
    fac.rank[0] = 0
    if k > 0:
        if not lowrank_prepare(fac.jac, fac.piv, fac.base, fac.fresh, fac.slots, k, fac.u,
                               fac.v, fac.z, fac.cap, fac.cpiv):
            return False
        fac.rank[0] = k
    work.counters[LOWRANK] += 1
    return True


@jit
def _solve(fac, b):
    """Solve with the Newton matrix (the factorised one, or its low-rank update) in place. The
    factorised matrix alone, every solve of a film without an active set, is LAPACK's solve
    inlined here. The low-rank path is a function of its own: with ``lowrank_solve`` called in
    this one, the matrix and pivots that both branches read were reference-counted at every
    solve (its compiled code: 8 increments and 12 decrements, against 2 and 4)."""
    if fac.rank[0] == 0:
        lu_solve(fac.jac, fac.piv, b)
    else:
        _solve_updated(fac, b)


@jit
def _solve_updated(fac, b):
    """``_solve`` with the low-rank update of the factorised matrix (``fac.rank[0]`` > 0)."""
    lowrank_solve(fac.jac, fac.piv, fac.rank[0], fac.v, fac.z, fac.cap, fac.cpiv, b, fac.work)


@jit
def _positive(h):
    """Whether every gap is positive (not NaN)."""
    for i in range(h.size):
        if not (h[i] > 0.0):
            return False
    return True


@jit
def _admissible(h):
    """Whether every gap is positive and finite (a Newton iterate's)."""
    for i in range(h.size):
        if not (h[i] > 0.0) or not np.isfinite(h[i]):
            return False
    return True


@jit
def _newton(grid, phys, step, rtol, film, fac, work):
    """Solve the step ``step`` (state.Step) from the predictor in ``work.y`` by chord Newton
    (module docstring), reusing the LU while ``bh`` stays within 30 % of the ``bh`` it was
    factorised at. The gap update of an iterate is the next iterate's gap minus this one's, so
    each iteration costs one K-product (in gap) and one LU solve. With an active set, the set is
    decided at the first iterate and held while Newton converges; a converged iterate whose set
    would change goes on with the new set and the matrix updated in the slots that changed
    (``_update_for_set``; a fresh factorisation when too many did).

    Returns
    -------
    outcome, fresh, set_changes
        ``CONVERGED``, ``DIVERGED`` or ``SINGULAR``; whether the LU was factorised in this
        attempt (its state in ``fac``); how many times the iterate's set differed from the
        matrix's (at the first iterate, and at each converged one).
    """
    bh = step.bh
    y, w, h = work.y, work.w, work.h
    fresh = False
    if (not fac.valid[0]) or abs(bh / fac.bh[0] - 1.0) > 0.3:
        model.surface_gap(grid, phys, y, film, w, h)
        if not _positive(h):  # the predictor's gap is not admissible: a smaller step
            return DIVERGED, True, 0
        _factorise(grid, phys, bh, y, h, film, fac, work)
        fresh = True
        if not fac.valid[0]:
            return SINGULAR, fresh, 0
    active_set = model.has_active_set(phys)
    p_abs = model.pressure_scale(film)
    converged = False
    pending = False  # converged, if the active set of the iterate is settled
    norm_prev = 0.0
    first = True
    set_changes = 0
    model.surface_gap(grid, phys, y, film, w, h)
    it = 0
    while it < MAX_NEWTON or (pending and it == MAX_NEWTON):
        it += 1
        if not _admissible(h):
            break
        model.step_residual(grid, phys, step, y, film, it == 1 or pending, work.q, w, h,
                            work.res)
        if active_set:
            same = model.settled(film)
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
                if not _update_for_set(grid, phys, bh, y, h, film, fac, work, fresh):
                    _factorise(grid, phys, bh, y, h, film, fac, work)
                    fresh = True
                if not fac.valid[0]:
                    break
        norm = _newton_update(grid, phys, rtol, p_abs, film, fac, work)
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
    if active_set and not fac.valid[0]:
        return SINGULAR, fresh, set_changes
    return (CONVERGED if converged else DIVERGED), fresh, set_changes


@jit
def _newton_update(grid, phys, rtol, p_abs, film, fac, work):
    """One Newton update of the iterate from the residual in ``work.res`` (the gap follows):
    returns the update's norm (``_norm``, with the film model's measure of its pressures)."""
    y, w, h, res, dh = work.y, work.w, work.h, work.res, work.dh
    n = h.size
    m = n + 2
    for k in range(m):
        res[k] = -res[k]
    _solve(fac, res)
    model.split_update(res, film, phys)
    for k in range(m):
        y[k] += res[k]
    work.counters[NEWTON] += 1
    for i in range(n):
        dh[i] = h[i]
    model.surface_gap(grid, phys, y, film, w, h)
    for i in range(n):
        dh[i] = h[i] - dh[i]
    dp_film, p = model.film_change(res[:n], dh, y, h, film, phys, work.kdp)
    norm = _norm(dp_film, res[n], res[n + 1], dh, p, y[n], y[n + 1], h, rtol, p_abs)
    return model.update_norm(norm, film, phys, rtol)


@jit
def _local_error(grid, phys, err_fac, states, rtol, film, work):
    """The step's local error in units of the tolerance (``_norm`` of ``err_fac (y - y_pred)``,
    the pressures' part as the film model measures it: model/step.py, ``step_error``; ``states``
    the accepted states the predictor went through); 0 for the first step, which has no history
    to compare with. ``res``, ``kdp``, ``dh`` and ``scale`` of ``work`` are work space; they keep
    the error's terms, and ``work.own_scale`` whether ``scale`` holds the pressures' scale, for
    the attempt log (``_log_attempt``)."""
    if err_fac == 0.0:
        if LOG_CODE:
            work.own_scale[0] = -1.0  # no terms to report
        return 0.0
    y, y_pred, h, res, kdp, dh = work.y, work.y_pred, work.h, work.res, work.kdp, work.dh
    n = h.size
    m = n + 2
    for k in range(m):
        res[k] = err_fac * (y[k] - y_pred[k])
    matvec(grid.influence, res[:n], kdp)
    for i in range(n):
        dh[i] = res[n] + kdp[i]
    own_scale = model.step_error(y, y_pred, states, err_fac, rtol, h, film, phys, res[:n], dh,
                                 work.scale)
    if LOG_CODE:
        work.own_scale[0] = 1.0 if own_scale else 0.0
    p_scale = work.scale if own_scale else y[:n]
    return _norm(res[:n], res[n], res[n + 1], dh, p_scale, y[n], y[n + 1], h, 1.0,
                 model.pressure_scale(film)) / rtol


@jit
def _largest_term(dp, dx, dv, dh, p, x, v, h, p_abs, where):
    """Which term of ``_norm`` (the same arguments, ``rtol`` 1) is the largest: its code
    (``LARGEST_TERMS``) and node (NaN for ``X`` and ``V``) into ``where`` (2,)."""
    p_small = _pressure_floor(p, p_abs)
    best = _term(dx, x, X_FLOOR)
    where[0], where[1] = 2.0, np.nan
    e = _term(dv, v, V_FLOOR)
    if e > best:
        best, where[0] = e, 3.0
    for i in range(h.size):
        e = _term(dh[i], h[i], GAP_SCALE)
        if e > best:
            best, where[0], where[1] = e, 1.0, float(i)
        e = _term(dp[i], p[i], p_small)
        if e > best:
            best, where[0], where[1] = e, 0.0, float(i)


@jit
def _record(row, t, grid, phys, y, w, h, strain, dissipated, film):
    """The series row of the accepted state ``y`` at ``t`` (gap ``h``, deflection ``w``, strain
    energy ``strain``, energy dissipated so far ``dissipated``); returns the largest ``|W|`` that
    can still relax and the radius the terminal events see (model/step.py:
    ``relaxing_deflection``, ``record``)."""
    s = grid.s
    n = s.size
    x = y[n]
    v = y[n + 1]
    p = model.film_pressure(y, film, phys)
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
    row[_F] = model.total_force(grid.weight, y, film, phys)
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
    r_event = model.record(row, grid, p, h, pmax, pmin, film, phys, PRESSURE_SCALE)
    return model.relaxing_deflection(w, wmax, film, phys), r_event


@jit
def _record_step(row, hist, k, basis):
    """The series row's step columns: the order ``k`` of the step that ended at it (0: the first
    row); above order 2, the smallest gap and the largest film pressure over the cells and that
    step, and the central gap when the pressure peaks (``extremum_in_step``), and where the
    approach speed ``V`` falls through 0 inside the step, that time and the smallest gap, the
    largest pressure and the central gap there (``stop_in_step``; the time NaN where it does
    not). A film that rises above order 2 is smooth,
    so its pressures are the solution's own slots (model/step.py: ``smooth_in_time``). At orders
    0-2, the row's own ``H_min``, ``P_max`` and ``H0``."""
    row[_ORDER] = k
    h_min, p_max, h0_at_p_max = row[_H_MIN], row[_P_MAX], row[_H0]
    h_v0, p_v0, h0_v0, t_v0 = h_min, p_max, h0_at_p_max, np.nan
    if k > 2:
        cells = hist.h.shape[1]
        h_min = min(h_min, extremum_in_step(hist.t, hist.h, cells, k, 1.0, basis)[0])
        p_step, t_p = extremum_in_step(hist.t, hist.y, cells, k, -1.0, basis)
        if p_step > p_max:
            lagrange_basis(hist.t, k, t_p, basis[0], basis[1])
            p_max, h0_at_p_max = p_step, combine(basis[0], k, hist.h, 0)
        if hist.y[1, cells + 1] > 0.0 >= hist.y[0, cells + 1]:
            t_v0 = stop_in_step(hist.t, hist.y, cells + 1, k, basis)
            h_v0, p_v0 = np.inf, -np.inf
            for i in range(cells):
                h_v0 = min(h_v0, combine(basis[0], k, hist.h, i))
                p_v0 = max(p_v0, combine(basis[0], k, hist.y, i))
            h0_v0 = combine(basis[0], k, hist.h, 0)
    row[_H_MIN_STEP] = h_min
    row[_P_MAX_STEP] = p_max
    row[_H0_AT_P_MAX_STEP] = h0_at_p_max
    row[_H_MIN_AT_V0] = h_v0
    row[_P_MAX_AT_V0] = p_v0
    row[_H0_AT_V0] = h0_v0
    row[_T_AT_V0] = t_v0


@jit
def _step_factor(err, order):
    """The next step's size over this one's after an accepted step of error ``err`` at
    ``order`` (its error ``~ dt^(order+1)``; orders 1 and 2 as BDF2's), at most ``GROWTH``."""
    growth = GROWTH[order]
    factor = min(growth, max(0.2, SAFETY * err ** (-1.0 / (max(order, 2) + 1.0)))) \
        if err > 0.0 else growth
    if 1.0 <= factor < 1.2:
        factor = 1.0
    return factor


@jit
def _set_change_factor(set_changes):
    """The largest factor on the next step after an accepted step whose Newton iteration changed
    the active set ``set_changes`` times (``_newton``; none: no bound). The changes come where
    the cavity's edge crosses cells, which it does at a finite speed, so a step ``f`` times as
    long meets about ``f`` times as many; one that meets more than ``MAX_SET_CHANGES`` fails and
    is halved, after about 10 Newton iterations and a factorisation. The bound
    ``f <= MAX_SET_CHANGES / (c + 1)`` keeps the next step's expected changes, ``f c``, below
    the limit, and stops the growth from ``c = MAX_SET_CHANGES - 1``.

    Where a JFO cavity refills, the cells refill one per change, each found once Newton
    converged with the one before it (docs/solver.md, "Cavitation"). Without the bound each
    accepted step there grew 2x and the next attempt failed (JFO, St 10, eps 1e-4, Pi 1e-3,
    standard: 40 attempts failed so, with 396 of the 2286 Newton iterations and a factorisation
    each); with it 12 did (124 iterations), and the collision took 155 factorisations instead of
    176 and 0.90x the CPU time (solver 1.18.0)."""
    if set_changes == 0:
        return np.inf
    return MAX_SET_CHANGES / (set_changes + 1.0)


@jit
def _next_order(grid, phys, control, hist, dt, err, film, work):
    """After an accepted step (``work.y``) of order ``k = hist.order[0]`` with error ``err``:
    the local errors of orders ``k - 1`` and ``k + 1`` (``_local_error`` with their predictors;
    ``k + 1`` only where the history holds ``k + 2`` states and up to ``control.max_order``),
    and the order among the three whose error allows the largest step. Returns that order and
    its error."""
    k = hist.order[0]
    k_max = control.max_order
    best, best_err = k, err
    rate = err ** (-1.0 / (k + 1.0)) if err > 0.0 else np.inf
    for q in (k - 1, k + 1):
        if q < 1 or q > k_max or hist.n[0] < q + 1:
            continue
        fac = _predict(dt, hist.t, q, hist.y, work.y_pred)
        e = _local_error(grid, phys, fac, hist.y[: q + 1], control.rtol, film, work)
        r = e ** (-1.0 / (q + 1.0)) if e > 0.0 else np.inf
        if r > rate:
            best, best_err, rate = q, e, r
    return best, best_err


@jit
def _next_step(grid, phys, control, hist, dt, err, set_changes, film, work):
    """After an accepted step of error ``err`` whose Newton iteration met ``set_changes``
    changes of the active set: the next step's order into ``hist.order``, and its size over this
    one's (``_step_factor``, at most ``_set_change_factor``). Above order 2, once ``k + 1``
    steps were taken at the order ``k``, ``_next_order`` chooses it again, and the choice (the
    same order or another) holds for ``k + 1`` steps, as SciPy's BDF does: checking after every
    step cost about one Newton iteration a step (two predictors and two error norms, each with
    an N x N product): 0.77-0.79x the CPU time of a collision at order 5 with the same steps
    (standard preset, 4 scenes St 2.5-100, one run of each after the other, not alternated). A
    film whose solution is not smooth in time has ``max_order`` 2 (``_film_control``, and
    ``_control_from_now`` from where it stops being so)."""
    k = hist.order[0]
    if control.max_order > 2 and hist.order[1] >= k + 1:
        k, err = _next_order(grid, phys, control, hist, dt, err, film, work)
        hist.order[0] = k
        hist.order[1] = -1
    hist.order[1] += 1
    return min(_step_factor(err, k), _set_change_factor(set_changes))


@jit
def _attempt(grid, phys, control, hist, dt, film, fac, work):
    """Attempt steps from the newest accepted state at ``hist.t[0]`` until one is accepted (its
    solution in ``work.y``, gap ``work.h``) or the loop must stop: a diverged Newton halves the
    step once its Jacobian was fresh, a non-positive gap halves it, an error above the tolerance
    shrinks it. The order is ``hist.order[0]``, as far as the history reaches; a halved step
    above order 2 is tried again one order lower (not a step rejected for its error: lowering the
    order there too took 65-113 rejections per classic collision at order 5, against 13-20).

    Returns
    -------
    status, accepted, dt, err, set_changes
        ``RUNNING`` or the failure; whether a step was accepted, its size and error, and the
        changes of the active set its Newton iteration made (``_newton``)."""
    counters = work.counters
    y, t = hist.y, hist.t
    n_hist = hist.n[0]
    n = work.h.size
    a = work.a
    status = RUNNING
    err = 0.0
    set_changes = 0
    accepted = False
    while not accepted:
        if counters[STEPS] >= control.max_steps:
            status = MAX_STEPS
            break
        if not dt > control.dt_min:  # also where dt_min underflowed to 0 and the halved dt
            status = STEP_UNDERFLOW   # reached it (St 5e-324 looped for ever), or dt is NaN
            break
        k = min(hist.order[0], n_hist)
        b = _coefficients(dt, t, k, a)
        _history_term(a, k, hist.c, work.c_hist)
        x_hist = _history_value(a, k, y, n)
        v_hist = _history_value(a, k, y, n + 1)
        d = min(n_hist - 1, k)
        err_fac = _predict(dt, t, d, y, work.y_pred)
        copy_into(work.y, work.y_pred)
        model.start_attempt(work.y, film, phys)
        step = Step(b * dt, work.c_hist, x_hist, v_hist)
        newton_before = counters[NEWTON]
        outcome, fresh, set_changes = _newton(grid, phys, step, control.rtol, film, fac, work)
        newton = counters[NEWTON] - newton_before
        if k > 2 and not fresh and newton >= SLOW_NEWTON:
            fac.valid[0] = False  # a fresh Jacobian for the next attempt (docs at SLOW_NEWTON)
        if outcome == SINGULAR:
            status = NONFINITE
            break
        if outcome == DIVERGED:
            if LOG_CODE:
                _log_attempt(work, film, t[0], dt, k, DIVERGED_FRESH if fresh else DIVERGED_OLDER,
                             newton, fresh, set_changes, np.nan)
            if fresh:
                dt *= 0.5
                counters[REJECTED] += 1
                _lower_order(hist)
            fac.valid[0] = False
            continue
        if not _positive(work.h):
            if LOG_CODE:
                _log_attempt(work, film, t[0], dt, k, GAP_NOT_POSITIVE, newton, fresh,
                             set_changes, np.nan)
            dt *= 0.5
            counters[REJECTED] += 1
            _lower_order(hist)
            continue
        err = _local_error(grid, phys, err_fac, y[: d + 1], control.rtol, film, work)
        if not np.isfinite(err):
            status = NONFINITE
            break
        if LOG_CODE:
            _log_attempt(work, film, t[0], dt, k, REJECTED_ERROR if err > 1.0 else ACCEPTED,
                         newton, fresh, set_changes, err)
        if err > 1.0:
            dt *= max(0.2, SAFETY * err ** (-1.0 / (max(k, 2) + 1.0)))
            counters[REJECTED] += 1
            continue
        accepted = True
        if k > 2:
            counters[HIGHER_ORDER] += 1
    return status, accepted, dt, err, set_changes


@jit
def _control_from_now(control, hist, factor, film, phys):
    """After an accepted step: where a film smooth in time so far stops being so
    (model/step.py: ``smooth_from_now``), BDF2 at the tolerance asked for (``_film_control``'s
    ``rtol`` over its factor) from the next step on, which does not grow (its tolerance
    tightens by that factor). Returns the control and the next step's factor."""
    if control.max_order > 2 and not model.smooth_from_now(film, phys):
        hist.order[0] = min(hist.order[0], 2)
        return (Control(control.rtol / control.high_order_rtol_factor, control.dt_init,
                        control.dt_min, control.max_steps, min(control.max_order, 2), 1.0),
                min(factor, 1.0))
    return control, factor


@jit
def _lower_order(hist):
    """After a halved step above order 2 (Newton failed, or a gap went non-positive): the next
    attempt one order lower."""
    if hist.order[0] > 2:
        hist.order[0] -= 1
        hist.order[1] = 0


@jit
def _history(grid, start, max_order):
    """The history at the start, ``max(3, max_order + 1)`` states (the quadratic predictor of
    BDF2, the order-``max_order`` one above): every slot the initial state and its rigid gap
    (never read uninitialised: 0 * NaN garbage is NaN), the content written by ``integrate``
    once the film's state exists; the order 2, or ``max_order`` if lower."""
    s = grid.s
    n = s.size
    slots = max(3, max_order + 1)
    y = np.empty((slots, n + 2))
    copy_into(y[0, :n], start.p)
    y[0, n] = start.x
    y[0, n + 1] = start.v
    _fill(y, y[0])
    w = np.empty(n)
    h = np.empty((slots, n))
    model.start_gap(s, grid.influence, start.x, start.p, w, h[0])
    _fill(h, h[0])
    order = filled(2, 0)
    order[0] = min(max_order, 2)
    return History(y, h, filled((slots, n), np.nan), filled(slots, start.t),
                   filled(slots, np.nan), filled(1, 1), order)


@jit
def _fill(rows, row):
    """Every row of ``rows`` a copy of ``row`` (the history at the start)."""
    for j in range(rows.shape[0]):
        copy_into(rows[j], row)


@leaf
def _shift(y, h, c, t, r, n, dt, y_new, h_new):
    """The accepted step of size ``dt`` (``y_new``, ``h_new``) becomes the newest state of the
    history's arrays (``History``); each older one moves down a row (the content's newest row is
    written by ``_accept``, the dissipation rate's by ``integrate``). A ``leaf``: with the
    history's record it counted a reference for each row it copied, 26 per Newton iteration."""
    slots = t.size
    for j in range(slots - 1, 0, -1):
        copy_into(y[j], y[j - 1])
        copy_into(h[j], h[j - 1])
        copy_into(c[j], c[j - 1])
        t[j] = t[j - 1]
        r[j] = r[j - 1]
    copy_into(y[0], y_new)
    copy_into(h[0], h_new)
    t[0] = t[0] + dt
    n[0] = min(n[0] + 1, slots)


@jit
def _accept(grid, phys, hist, dt, film, work):
    """The accepted step of size ``dt`` becomes the newest state (``_shift``): its face fluxes
    into ``work.q``, the film's state after it (model/step.py: ``accept``) and its cells'
    content in the history."""
    _shift(hist.y, hist.h, hist.c, hist.t, hist.r, hist.n, dt, work.y, work.h)
    work.counters[STEPS] += 1
    y0, h0 = hist.y[0], hist.h[0]
    model.face_fluxes(grid, model.film_pressure(y0, film, phys), work.h, phys, work.q)
    model.accept(grid, y0, work.w, h0, hist.h[1], work.q, dt, film, phys)
    model.accepted_content(y0, h0, film, phys, hist.c[0])


@jit
def _series(rows, n, save_profiles):
    """The series and the profiles (``integrate``), NaN until written, ``rows`` rows each; the
    profiles one row (the newest state's) unless ``save_profiles``."""
    n_prof = rows if save_profiles else 1
    return _rows(rows, N_SERIES), _rows(n_prof, n), _rows(n_prof, n), _rows(n_prof, n - 1)


@jit
def _keep_profiles(row, p_hist, w_hist, theta_hist, y0, w, film, phys):
    """The accepted state's pressure, deflection and fluid fractions into ``row`` of the
    profiles (``integrate``: every row's, or the newest state's alone in row 0)."""
    copy_into(p_hist[row], model.film_pressure(y0, film, phys))
    copy_into(w_hist[row], w)
    copy_into(theta_hist[row], model.fluid_fraction(film))


@jit
def _initial_film(grid, phys, hist, work):
    """The film at the start, ``hist``'s newest state: its face fluxes (``work.q``), its state
    (model/step.py: ``new_film``), its gap with a contact load, if any (``work.w``, ``work.h``),
    and the gap, content and dissipation rate in every row of the history. Returns the film, its
    strain energy and its dissipation rate."""
    n = grid.s.size
    y0, w, h, q = hist.y[0], work.w, work.h, work.q
    copy_into(h, hist.h[0])
    model.face_fluxes(grid, y0[:n], h, phys, q)
    film = model.new_film(q)
    model.surface_gap(grid, phys, y0, film, w, h)
    _fill(hist.h, h)
    model.accepted_content(y0, h, film, phys, hist.c[0])
    _fill(hist.c, hist.c[0])
    strain, diss_rate = model.energies(grid, phys, y0, w, h, q, film)
    for j in range(hist.r.size):
        hist.r[j] = diss_rate
    return film, strain, diss_rate


@entry
@jit
def integrate(grid, phys, start, control, stop_kind, stop_params, save_profiles, log_rows):
    """Integrate on the grid ``grid`` (grid.py: ``Nodes``) from ``start`` (``Start``) with the
    step control ``control`` (``Control``) until the terminal event ``stop_kind`` with
    ``stop_params`` (events.py) or a failure. ``phys`` is ``Physics.as_array()``.

    Returns
    -------
    status : int
        ``OK``, ``MAX_STEPS``, ``STEP_UNDERFLOW`` or ``NONFINITE``.
    counters : (7,) int64
        ``COUNTERS`` (accepted and rejected steps, Newton iterations, factorisations...).
    series : (rows, N_SERIES) float
        One row per accepted step (the first is the initial state); columns ``SERIES``.
    pressure, deformation : (rows, N) float
        Profiles at each row when ``save_profiles``, else the last row's alone (1, N): the
        release state's, where a departure needs it (model/refill.py).
    fluid_fraction : (rows, N-1) float
        The cells' fluid fraction ``theta`` at each row (model/step.py: 1 in full cells) when
        ``save_profiles``, else the last row's alone (1, N-1).
    attempts : (attempts, N_LOG) float
        The attempt log: a row per step attempt (``LOG_COLUMNS``), the first ``log_rows``."""
    _refuse_absent_pieces(phys)
    n = grid.s.size
    control = _film_control(control, phys)
    hist = _history(grid, start, control.max_order)
    work = _work(n, log_rows)
    fac = _factorisation(n + 2)
    w, h, q = work.w, work.h, work.q
    y0 = hist.y[0]  # the newest accepted state: _shift writes each new one into this row
    rows = np.int64(256)  # (as the literal, _grown and _rows compiled twice)
    series, p_hist, w_hist, theta_hist = _series(rows, n, save_profiles)
    film, strain, diss_rate = _initial_film(grid, phys, hist, work)
    dissipated = start.dissipated
    n_rows = 0
    # the order of the step that ended at the newest state (0: none yet), an int64 from the start
    k_step = np.int64(0)  # (as the literal 0, a second compile: docs/solver.md, "Compiled code")
    dt = control.dt_init
    status = RUNNING
    while True:
        if n_rows == rows:  # ---- record the accepted state (also the initial one) ----------
            rows, series, p_hist, w_hist, theta_hist = _grown(rows, series, p_hist, w_hist,
                                                              theta_hist, save_profiles)
        wmax, r_event = _record(series[n_rows], hist.t[0], grid, phys, y0, w, h, strain,
                                dissipated, film)
        _record_step(series[n_rows], hist, k_step, work.basis)
        _keep_profiles(n_rows if save_profiles else np.int64(0), p_hist, w_hist, theta_hist, y0,
                       w, film, phys)
        n_rows += 1
        if status != RUNNING:
            break
        if reached(stop_kind, stop_params, work.counters[STEPS], y0[n], y0[n + 1], wmax,
                   r_event):
            if stop_kind != RELAXED_APART or model.departure_holds(grid, y0[n], y0[n + 1],
                                                                   hist.t[0], film, phys):
                status = OK
                break
            stop_kind = RELAXED_FULL  # its departure would not hold: on until the film is full
        # ---- attempt steps until one is accepted ---------------------------------------------
        status, accepted, dt, err, set_changes = _attempt(grid, phys, control, hist, dt, film,
                                                          fac, work)
        if not accepted:
            # record the last accepted state with the failure status, then stop; w and h (and
            # the active set) hold the rejected trial's, so restore the state's and recompute
            model.start_attempt(y0, film, phys)
            model.surface_gap(grid, phys, y0, film, w, h)
            continue
        k_step = min(hist.order[0], hist.n[0])
        factor = _next_step(grid, phys, control, hist, dt, err, set_changes, film, work)
        _accept(grid, phys, hist, dt, film, work)
        control, factor = _control_from_now(control, hist, factor, film, phys)
        strain_new, diss_new = model.energies(grid, phys, y0, w, h, q, film)
        hist.r[0] = diss_new
        dissipated += (dissipated_in_step(hist.t, hist.r, k_step, work.basis) if k_step > 2
                       else 0.5 * (diss_rate + diss_new) * dt)
        strain, diss_rate = strain_new, diss_new
        dt *= factor
    kept = min(n_rows, p_hist.shape[0])
    return (status, work.counters, series[:n_rows], p_hist[:kept], w_hist[:kept],
            theta_hist[:kept], work.log[:work.log_n[0]])
