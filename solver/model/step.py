"""What the time loop asks of the film model: the contract between integration/stepper.py and the
physics.

The loop (integration/stepper.py) solves ``y = (y_0..y_{N-1}, X, V)`` by BDF2 and chord Newton and
knows no physics. The slot ``y_i`` of each node holds the load its surfaces carry, the film
pressure ``P_i`` of a smooth film, or its total load ``T_i = P_i + p_a(H_i)`` where rough surfaces
touch (model/contact.py); a JFO cavity's slot its liquid fraction. Everything a piece of physics
needs the loop to do goes through the functions here, which read the physics array ``phys``
(solver/physics.py) and decide:

- ``new_state``, ``begin``: the film's own state beyond ``y`` (``marks``, ``cells``,
  ``scalars`` below), which the loop carries and hands back but never reads, and its history
  at the first state;
- ``surface_gap``, ``film_pressure``, ``total_force``, ``energies``: the gap and deflection of
  a state, its film pressure (what the loop records and its fluxes carry), the force on the
  spheres, the strain energy and dissipation rate;
- ``content_history``: the BDF combination of the cells' liquid content at the accepted states;
- ``has_active_set``: whether the film has a complementarity constraint decided cell by cell
  (an active set); then a Newton iterate converges only with a settled set, a change refreshes
  the factorisation (``settled``), and the set is decided at the iterates ``decide`` marks;
- ``start_attempt``, ``step_residual``, ``step_jacobian``: a step attempt's start, its residual
  (with the active set decided and its rows replaced) and its Jacobian (recording the set it was
  built with); ``mark_factorised`` and ``changed_slots``: which slots a change of the set touches
  since the last factorisation (the loop updates the factorisation there instead of refactorising);
- ``split_update``, ``update_norm``, ``film_change``: unknowns whose slot in ``y`` holds another
  variable (a JFO cavity's liquid fraction), their part of the Newton norm, and the film
  pressure's change that the norm measures where the slots hold loads;
- ``step_error``: in which variable each slot's local error is measured, and which errors
  leave the norm where the solution is not smooth in time (an active set's edge);
- ``pressure_scale``: the absolute part of the pressure error scale;
- ``record``, ``accept``: the model's columns of the series row, and its state after an accepted
  step (the work against a floor, the history of the fractions).

The physics behind each branch: model/film.py (terms), model/contact.py and docs/model.md
(Cavitation; Pressure-dependent viscosity and density; Surface roughness).
"""

import numpy as np

from .._jit import jit
from ..integration.events import ENDED, HELD
from ..observables import SERIES_INDEX
from ..physics import CAVITATION, DENSITY, E_DRY, PI, ROUGHNESS, ST
from .contact import (FREE, HOLD, REST, asperity_work, contact_derivatives, contact_gap,
                      contact_slopes, contact_state)
from .film import (JFO, NO_FLOOR, cavity_edge, cell_content, compression_work, constrain,
                   energy_rates, film_force, gap, jacobian, jfo_void, residual, strain_energy,
                   update_cavity, update_cavity_jfo, void_work)
from .liquid import CONSTANT, isoviscous, kirchhoff_difference

# rows of ``marks`` (bool, one entry per cell): the cavitated cells of the current iterate, of the
# Jacobian the loop solves with, of the last accepted state, and of the Jacobian it factorised
# (which low-rank updates correct to ACTIVE_LU)
ACTIVE, ACTIVE_LU, ACTIVE0, ACTIVE_BASE = 0, 1, 2, 3
# rows of ``cells`` (float, one entry per cell): the liquid fraction theta of the iterate and of
# the last two accepted states (1 in full cells, and in every cell but a JFO cavity's), the
# fraction's Newton update, the gap where each cell cavitated (the void volume), the face fluxes
# of the last accepted state
THETA, THETA0, THETA1, DTHETA, H_ONSET, Q_PREV = 0, 1, 2, 3, 4, 5
# entries of ``scalars``: the work against the floor so far, the absolute pressure error scale,
# the largest pressure seen, the accepted state's cavity radius; for a rough film the solids'
# unloading scale c (model/contact.py: 1 while they load, e_dry^2 once they unload), whether
# they touched on approach, the energy lost in the solids; then blocks of one entry per node:
# the contact pressure p_a and the film pressure P of the last gap computed, the load T_set,
# the permanent set (1 - c) K T_set and the gap H_set where the solids began to unload, the
# film pressure of the last two accepted states, the scale film_change measures it by, and
# the contact law's slope dp_a/dH at the last gap computed
WORKED, P_ABS, P_SEEN, R_EDGE, LOAD_SCALE, TOUCHED, SOLID_LOST = 0, 1, 2, 3, 4, 5, 6
NODE_BLOCKS = 7
PA, P_FILM, T_SET, W_SET, H_SET, P_ACC0, P_ACC1, P_SCALE, SLOPE = 0, 1, 2, 3, 4, 5, 6, 7, 8
N_BLOCKS = 9
# a rough film's Newton measures the change of its film pressure against its own size or this
# fraction of the asperities' pressure, whichever is larger (film_change)
CONTACT_SHARE = 0.01

_R_CAV, _V_VOID = SERIES_INDEX["cavity_radius"], SERIES_INDEX["void_volume"]
_W_VOID, _E_C = SERIES_INDEX["void_work"], SERIES_INDEX["E_c"]
_E_A, _LOST, _F_A = SERIES_INDEX["E_a"], SERIES_INDEX["solid_loss"], SERIES_INDEX["F_contact"]
_V = SERIES_INDEX["V"]


@jit
def new_state(q):
    """The film's state at the start (``q`` the face fluxes of the initial state): no cavity,
    full cells."""
    cells_n = q.size
    marks = np.zeros((4, cells_n), dtype=np.bool_)
    cells = np.zeros((6, cells_n))
    cells[THETA, :] = 1.0
    cells[THETA0, :] = 1.0
    cells[THETA1, :] = 1.0
    cells[Q_PREV, :] = q
    scalars = np.zeros(NODE_BLOCKS + N_BLOCKS * (cells_n + 1))
    scalars[LOAD_SCALE] = 1.0
    # Absolute part of the pressure error scale. With a floor the film carries almost no
    # pressure once it has cavitated (|P| ~ Pi over the whole rebound), and a scale relative to
    # the instantaneous pressure made the steps collapse to 1e-9 where the last full cells at the
    # axis drained: pressures far below the collision's peak move neither the gap nor the force
    # (both in the norm on their own), so they count as absolute below a fraction of the largest
    # pressure seen so far, from the film's first cavity on (``record``). The classic film (and
    # a film that never cavitates) keeps its instantaneous scale.
    scalars[P_ABS] = 1e-12
    return marks, cells, scalars


@jit
def has_active_set(phys):
    """Whether the film has a constraint decided cell by cell (a cavitation floor)."""
    return phys[CAVITATION] != NO_FLOOR


@jit
def rough(phys):
    """Whether the surfaces are rough (asperity contact, model/contact.py)."""
    return phys[ROUGHNESS] != 0.0


@jit
def node_block(scalars, k):
    """Block ``k`` (``PA``, ``T_SET``, ``W_SET``, ``H_SET``) of ``scalars``: one entry per
    node."""
    n = (scalars.size - NODE_BLOCKS) // N_BLOCKS
    return scalars[NODE_BLOCKS + k * n:NODE_BLOCKS + (k + 1) * n]


@jit
def surface_gap(s, influence, phys, y, marks, scalars, w, h):
    """The deflection ``W`` and gap ``H`` of the iterate ``y`` into ``w``, ``h``: ``W = K y``
    (film.gap), and for a rough film the contact pressure and film pressure they imply
    (contact.contact_gap, whose cells held at the floor are a JFO cavity's, solved from the gap
    ``h`` holds; a contact solve that fails leaves ``h`` NaN, which the loop treats as a failed
    iterate)."""
    n = s.size
    if not rough(phys):
        gap(s, influence, y[n], y[:n], w, h)
        return
    if not contact_gap(s, influence, y[n], y, scalars[LOAD_SCALE], node_block(scalars, T_SET),
                       node_block(scalars, H_SET), held_cells(marks, phys, n), phys,
                       node_block(scalars, PA), node_block(scalars, SLOPE),
                       node_block(scalars, P_FILM), w, h):
        h[:] = np.nan


@jit
def held_cells(marks, phys, n):
    """The nodes whose slot is not their load (a JFO cavity's cells, held at the floor)."""
    held = np.zeros(n, dtype=np.bool_)
    if phys[CAVITATION] == JFO:
        held[:n - 1] = marks[ACTIVE]
    return held


@jit
def film_pressure(y, scalars, phys):
    """The film pressure of the state whose gap ``surface_gap`` computed last: the slots
    themselves for a smooth film (no copy), ``y - p_a`` where rough surfaces touch."""
    n = y.size - 2
    if not rough(phys):
        return y[:n]
    return node_block(scalars, P_FILM)


@jit
def begin(scalars, phys):
    """The film's history at the first state (whose gap ``surface_gap`` computed last): a rough
    film's film pressure of the accepted states (``content_history``)."""
    if rough(phys):
        node_block(scalars, P_ACC0)[:] = node_block(scalars, P_FILM)
        node_block(scalars, P_ACC1)[:] = node_block(scalars, P_FILM)


@jit
def relaxing_deflection(w, w_absmax, scalars, phys):
    """The largest ``|W|`` the terminal events wait to relax (``w_absmax``, ``max |W|``): a rough
    film's permanent set (model/contact.py) never relaxes, so ``max |W - (1 - c) K T_set|``."""
    if not rough(phys) or scalars[LOAD_SCALE] == 1.0:
        return w_absmax
    w_set = node_block(scalars, W_SET)
    out = 0.0
    for i in range(w.size):
        out = max(out, abs(w[i] - w_set[i]))
    return out


@jit
def total_force(weight, y, scalars, phys):
    """``Int (P + p_a) R dR``, the force on the spheres (film.film_force), with the film and
    contact pressures of the last ``surface_gap``."""
    n = weight.size
    if not rough(phys):
        return film_force(weight, y[:n])
    return film_force(weight, node_block(scalars, P_FILM)) \
        + film_force(weight, node_block(scalars, PA))


@jit
def energies(s, s_face, weight, phys, y, w, h, q, scalars):
    """Strain energy and dissipation rate of the state (film.energy_rates): for a rough film the
    strain energy of the total load ``P + p_a`` on the elastic part of ``W`` (less the permanent
    set)."""
    n = s.size
    p = film_pressure(y, scalars, phys)
    strain, diss = energy_rates(s, s_face, weight, phys, y[n], p, w, h, q)
    if rough(phys):
        pa, w_set = node_block(scalars, PA), node_block(scalars, W_SET)
        strain = strain_energy(weight, s[n - 1], p + pa, w - w_set, phys)
    return strain, diss


@jit
def fluid_fraction(cells):
    """The accepted state's liquid fraction per cell (the profile the loop saves)."""
    return cells[THETA0]


@jit
def pressure_scale(scalars):
    """The absolute part of the pressure error scale (``new_state``)."""
    return scalars[P_ABS]


@jit
def content_history(a1, a2, y0, y1, h0, h1, cells, scalars, phys, out):
    """``a1 C(state 0) + a2 C(state 1)`` per cell (``C = rho_bar theta H``, ``film.cell_content``),
    and the same combination of the boundary node's gap, into ``out`` (``scalars``: a rough
    film's film pressure of the two states, whose slots hold their loads)."""
    n = out.size
    theta0, theta1 = cells[THETA0], cells[THETA1]
    if phys[DENSITY] == CONSTANT:  # C = theta H (rho = 1)
        for i in range(n - 1):
            out[i] = a1 * (theta0[i] * h0[i]) + a2 * (theta1[i] * h1[i])
    else:
        p0, p1 = y0, y1
        if rough(phys):
            p0, p1 = node_block(scalars, P_ACC0), node_block(scalars, P_ACC1)
        for i in range(n - 1):
            out[i] = a1 * cell_content(theta0[i], h0[i], p0[i], phys)[0] \
                + a2 * cell_content(theta1[i], h1[i], p1[i], phys)[0]
    out[n - 1] = a1 * h0[n - 1] + a2 * h1[n - 1]


@jit
def start_attempt(y, marks, cells, phys):
    """A step attempt of a JFO film starts from the accepted cavity, its cells' slots at the
    floor; the Reynolds film keeps the iterate's set."""
    if phys[CAVITATION] != JFO:
        return
    active, active0 = marks[ACTIVE], marks[ACTIVE0]
    theta, theta0 = cells[THETA], cells[THETA0]
    for i in range(active.size):
        active[i] = active0[i]
        theta[i] = theta0[i]
        if active[i]:
            y[i] = -phys[PI]


@jit
def contact_motion(weight, phys, bh, scalars, res):
    """The contact load's part of the motion row of ``film.residual``: ``bh F_a / (3 St)``, with
    the contact pressure of the last ``surface_gap`` (nothing for a smooth film)."""
    if rough(phys):
        res[weight.size + 1] += bh * film_force(weight, node_block(scalars, PA)) \
            / (3.0 * phys[ST])


@jit
def step_residual(s, s_face, area, weight, influence, phys, bh, c_hist, x_hist, v_hist, y,
                  marks, cells, scalars, decide, q, w, h, res):
    """The scaled residual of the step at the iterate ``y`` (``film.residual``) into ``res``;
    where ``decide``, the active set is decided first from it (a JFO switch moves slots to the
    floor, so the gap ``w, h`` and the rows follow); the rows of a Reynolds cavity are replaced by
    their constraint. ``q`` receives the face fluxes. ``w``, ``h`` (and a rough film's contact
    and film pressures) must be ``surface_gap``'s of ``y``."""
    n = s.size
    p = film_pressure(y, scalars, phys)
    theta, active = cells[THETA], marks[ACTIVE]
    residual(s, s_face, area, weight, phys, bh, c_hist, x_hist, v_hist, y[n], y[n + 1], p, theta,
             h, q, res)
    contact_motion(weight, phys, bh, scalars, res)
    if not has_active_set(phys):
        return
    jfo = phys[CAVITATION] == JFO
    if decide:
        if jfo:
            was = active.copy()
            if update_cavity_jfo(p, theta, phys, active):
                if rough(phys):  # a switched slot holds the load at the floor
                    pa = node_block(scalars, PA)
                    for i in range(n - 1):
                        if active[i] != was[i]:
                            y[i] = -phys[PI] + pa[i]
                surface_gap(s, influence, phys, y, marks, scalars, w, h)
                p = film_pressure(y, scalars, phys)
                residual(s, s_face, area, weight, phys, bh, c_hist, x_hist, v_hist, y[n],
                         y[n + 1], p, theta, h, q, res)
                contact_motion(weight, phys, bh, scalars, res)
        else:
            update_cavity(p, res, phys, active)
    if not jfo:
        constrain(p, res, active, phys)


@jit
def settled(marks):
    """Whether the iterate's active set is the one the factorised Jacobian was built with."""
    active, active_lu = marks[ACTIVE], marks[ACTIVE_LU]
    for i in range(active.size):
        if active[i] != active_lu[i]:
            return False
    return True


@jit
def step_jacobian(s, s_face, area, weight, influence, phys, bh, y, h, marks, cells, scalars, jac,
                  dres_dh):
    """The Jacobian of ``step_residual`` at ``y`` into ``jac`` (``film.jacobian``), recording the
    active set it is built with. A rough film's film pressure follows the gap where its slot is
    the load (contact.contact_slopes); its gap follows the slots through ``c K`` while the solids
    unload, and a touching JFO cavity's gap and the force through its contact
    (contact.contact_derivatives)."""
    n = s.size
    if rough(phys):
        c, slope = scalars[LOAD_SCALE], node_block(scalars, SLOPE)
        held = held_cells(marks, phys, n)
        dp_dh = np.empty(n)
        m = contact_slopes(slope, held, dp_dh)
        p = node_block(scalars, P_FILM)
        if m == 0 and c == 1.0:
            jacobian(s, s_face, area, weight, influence, phys, bh, p, cells[THETA], h,
                     marks[ACTIVE], jac, dres_dh, np.ones(n), weight, 0.0, dp_dh)
        else:
            k_eff = np.empty((n, n))
            dh_dx = np.empty(n)
            force_dp = np.empty(n)
            force_dx = contact_derivatives(influence, weight, slope, c, held, m, k_eff, dh_dx,
                                           force_dp)
            jacobian(s, s_face, area, weight, k_eff, phys, bh, p, cells[THETA], h,
                     marks[ACTIVE], jac, dres_dh, dh_dx, force_dp, force_dx, dp_dh)
    else:
        jacobian(s, s_face, area, weight, influence, phys, bh, y[:n], cells[THETA], h,
                 marks[ACTIVE], jac, dres_dh, np.ones(n), weight, 0.0, np.empty(0))
    marks[ACTIVE_LU, :] = marks[ACTIVE]


@jit
def mark_factorised(marks):
    """The Jacobian just built (``step_jacobian``) is the one the loop factorises."""
    marks[ACTIVE_BASE, :] = marks[ACTIVE_LU]


@jit
def changed_slots(marks, slots):
    """The slots whose rows and columns differ between the factorised Jacobian and the one for
    the iterate's active set (a cell that cavitated or refilled since the factorisation), into
    ``slots`` as far as it reaches; returns their number."""
    k = 0
    active, base = marks[ACTIVE], marks[ACTIVE_BASE]
    for i in range(active.size):
        if active[i] != base[i]:
            if k < slots.size:
                slots[k] = i
            k += 1
    return k


@jit
def split_update(res, marks, cells, phys):
    """Take the Newton update of the slots that hold another unknown out of ``res``: a JFO
    cavity's slot updates its liquid fraction theta (kept >= 0: a dry cell), not ``P``."""
    if phys[CAVITATION] != JFO:
        return
    active, theta, dtheta = marks[ACTIVE], cells[THETA], cells[DTHETA]
    for i in range(active.size):
        dtheta[i] = 0.0
        if active[i]:
            dtheta[i] = res[i]
            theta[i] = max(theta[i] + res[i], 0.0)
            res[i] = 0.0


@jit
def film_change(dy, dh, y, h, marks, scalars, phys, dp):
    """The change of the film pressure over a Newton update of the slots by ``dy`` that moved the
    gap by ``dh`` (to ``h``), and the scale it is measured against: the slots' own change and
    values for a smooth film (no copy). A rough film whose slots hold the load: ``dP = dy -
    p_a'(H) dH`` into ``dp``, against ``|P| + CONTACT_SHARE p_a`` (the load converges with the
    gap and the film pressure). Measured on the load alone, the film pressure inside a stiff
    contact, the small difference of two large loads, was left with the Newton's noise: its
    dissipation broke the energy closure (1.6e-2 at asperity stiffness 1e4, 9e-2 at 1e8, against
    7e-5 and 1.1e-3 so; tests/test_contact.py checks 1e4)."""
    n = h.size
    if not rough(phys):
        return dy, y[:n]
    held = held_cells(marks, phys, n)
    p, pa = node_block(scalars, P_FILM), node_block(scalars, PA)
    scale, slope = node_block(scalars, P_SCALE), node_block(scalars, SLOPE)
    for i in range(n):
        dp[i] = dy[i]
        if not held[i]:
            dp[i] -= slope[i] * dh[i]
        scale[i] = abs(p[i]) + CONTACT_SHARE * pa[i]
    return dp, scale


@jit
def update_norm(norm, cells, phys, rtol):
    """The Newton norm with the fractions' updates (absolute) of ``split_update``."""
    if phys[CAVITATION] != JFO:
        return norm
    dtheta = cells[DTHETA]
    for i in range(dtheta.size):
        norm = max(norm, abs(dtheta[i]) / rtol)
    return norm


@jit
def step_error(y, y_pred, err_fac, h, marks, scalars, phys, perr, dh, scale):
    """Adjust the local error estimate of a converged step. On entry ``perr`` holds the pressure
    part ``err_fac (y - y_pred)`` and ``dh`` the gap's.

    - While a cavity is open the pressure is not smooth in time wherever its edge crosses a node
      (the cells there and their neighbours), and a cavity that closes in this step makes it
      jump: the gap, X and V errors control the step (measured: every rejection came from these
      kinks; counting the jump of the last cell of an axis cavity as an error underflowed the
      step).
    - JFO: where a cavity closes the pressure jumps (the void's closing rate is finite up to the
      instant it vanishes), and the gap with it through ``W = K P``: no step size makes the
      extrapolation of the gap across it accurate. X and V stay continuous; they control this
      step, and the history restarts after it.
    - A pressure-dependent liquid: the pressure error in the variable the film sees, the
      Kirchhoff pressure ``Int rho/mu dP``, smooth where a glassy lens makes ``P`` itself spike
      (that spike moves the gap, X and V only through W and the force, both in the norm on their
      own).
    - A rough film: its slots hold the load, which the gap sees, and the error is measured
      there, for a pressure-dependent liquid too (the Kirchhoff pressure needs ``P``, which the
      extrapolated loads do not give without the gap's contact).

    Returns True when ``scale`` holds the Kirchhoff pressures, False when the errors are measured
    against the slots themselves (``scale`` untouched)."""
    n = perr.size
    rough_in_time = False
    if has_active_set(phys):
        active, active0 = marks[ACTIVE], marks[ACTIVE0]
        open_cavity = scalars[R_EDGE] > 0.0
        refilled = False
        if phys[CAVITATION] == JFO:
            for i in range(active.size):
                refilled = refilled or (active0[i] and not active[i])
        for i in range(active.size):
            open_cavity = open_cavity or active[i]
        rough_in_time = open_cavity or refilled
        if rough_in_time:
            for i in range(n):
                perr[i] = 0.0
        if refilled:
            for i in range(n):
                dh[i] = 0.0
    kirchhoff = not isoviscous(phys) and not rough_in_time and not rough(phys)
    if kirchhoff:
        for i in range(n):
            perr[i] = err_fac * kirchhoff_difference(y_pred[i], y[i], phys)[0]
            scale[i] = kirchhoff_difference(0.0, y[i], phys)[0]
    return kirchhoff


@jit
def record(row, s, area, weight, p, h, pmax, pmin, marks, cells, scalars, phys, floor_fraction):
    """The model's columns of the series row of an accepted state (cavity radius and void volume,
    work against the floor, compression energy; contact force, asperity energy and the energy
    lost in the solids), every one on every row, and the error scale's update from the largest
    pressure seen (``floor_fraction`` of it, from the first cavity on). Returns the radius the
    terminal events see: the cavity's, tiny but positive for a JFO cavity of axis cells alone
    (whose edge radius is zero); ``events.HELD`` while a rough film holds its contact and
    ``events.ENDED`` when it rests on its asperities (contact.contact_state)."""
    theta0 = cells[THETA0]
    row[_E_C] = compression_work(area, p, h, theta0, phys)
    row[_W_VOID] = scalars[WORKED]
    row[_F_A] = 0.0
    row[_E_A] = 0.0
    row[_LOST] = scalars[SOLID_LOST]
    # a rough film near contact holds the coupled phase as a cavity does, and ends it at rest
    state = FREE
    if rough(phys):
        row[_F_A] = film_force(weight, node_block(scalars, PA))
        row[_E_A] = asperity_work(weight, h, scalars[LOAD_SCALE], node_block(scalars, H_SET),
                                  phys)
        state = contact_state(h, row[_V], phys)
    r_event = cavity_columns(row, s, area, p, h, pmax, pmin, marks, cells, scalars, phys,
                             floor_fraction)
    if state == REST:
        return ENDED
    if state == HOLD:
        return HELD
    return r_event


@jit
def cavity_columns(row, s, area, p, h, pmax, pmin, marks, cells, scalars, phys, floor_fraction):
    """The cavity's columns of the series row (radius and void volume; 0 for a film without a
    floor) and the error scale's update (``record``); returns the radius the terminal events
    see."""
    if not has_active_set(phys):  # no cavity ever
        row[_R_CAV] = 0.0
        row[_V_VOID] = 0.0
        return 0.0
    active0, h_onset = marks[ACTIVE0], cells[H_ONSET]
    r_cav = cavity_edge(s, p, active0, phys)
    jfo = phys[CAVITATION] == JFO
    v_void = 0.0
    if jfo:
        v_void = jfo_void(area, cells[THETA0], h, active0)
    else:
        for i in range(active0.size):
            if active0[i]:
                v_void += area[i] * (h[i] - h_onset[i])
    row[_R_CAV] = r_cav
    row[_V_VOID] = v_void
    scalars[R_EDGE] = r_cav
    scalars[P_SEEN] = max(scalars[P_SEEN], pmax, -pmin)
    if r_cav > 0.0:
        scalars[P_ABS] = max(scalars[P_ABS], floor_fraction * scalars[P_SEEN])
    r_event = r_cav
    if jfo:
        for i in range(active0.size):
            if active0[i]:
                r_event = max(r_event, 1e-300)
    return r_event


@jit
def accept(s, area, weight, y0, w, h0, h1, q, dt, marks, cells, scalars, phys):
    """The model's state after an accepted step (``y0`` its solution, ``w`` and ``h0`` its
    deflection and gap, ``h1`` the previous one's, ``q`` its face fluxes): the work against the
    floor (JFO: ``Pi dV_void`` exactly, film.jfo_void; Reynolds: film.void_work), the fractions'
    history, where new cavity cells opened, and the accepted cavity; for a rough film, the onset
    of the solids' unloading (``unload``) and the history of its film pressure."""
    if rough(phys):
        unload(s, weight, y0, w, h0, scalars, phys)
        node_block(scalars, P_ACC1)[:] = node_block(scalars, P_ACC0)
        node_block(scalars, P_ACC0)[:] = node_block(scalars, P_FILM)
    if not has_active_set(phys):
        return
    active, active0 = marks[ACTIVE], marks[ACTIVE0]
    theta, theta0, theta1 = cells[THETA], cells[THETA0], cells[THETA1]
    h_onset, q_prev = cells[H_ONSET], cells[Q_PREV]
    if phys[CAVITATION] == JFO:
        scalars[WORKED] += 2.0 * phys[PI] * (jfo_void(area, theta, h0, active)
                                             - jfo_void(area, theta0, h1, active0)) \
            / (3.0 * phys[ST])
    else:
        scalars[WORKED] += void_work(area, h0, h1, q, q_prev, dt, active, phys)
    theta1[:] = theta0
    theta0[:] = theta
    for i in range(active.size):
        if active[i] and not active0[i]:
            h_onset[i] = h1[i]
    active0[:] = active
    q_prev[:] = q


@jit
def unload(s, weight, y0, w, h, scalars, phys):
    """The losses in the solids (model/contact.py): once the asperities have carried load on
    approach (``V > 0``), the first accepted state with ``V <= 0`` starts the unloading along
    ``c = e_dry^2`` through its load ``T_set = P + p_a``, with the permanent set ``(1 - c) W``,
    and the asperities' from its gap ``H_set``; the strain and asperity energy the solids will
    not return, ``(1 - c) (E_s + E_a)``, is lost then."""
    if phys[E_DRY] == 1.0 or scalars[LOAD_SCALE] != 1.0:
        return
    n = s.size
    pa, p = node_block(scalars, PA), node_block(scalars, P_FILM)
    contact = False
    for i in range(n):
        contact = contact or pa[i] > 0.0
    if contact and y0[n + 1] > 0.0:
        scalars[TOUCHED] = 1.0
    if scalars[TOUCHED] == 0.0 or y0[n + 1] > 0.0:
        return
    c = phys[E_DRY] * phys[E_DRY]
    t_set, w_set = node_block(scalars, T_SET), node_block(scalars, W_SET)
    h_set = node_block(scalars, H_SET)
    for i in range(n):
        t_set[i] = p[i] + pa[i]
        w_set[i] = (1.0 - c) * w[i]
        h_set[i] = h[i]
    scalars[SOLID_LOST] += (1.0 - c) * (strain_energy(weight, s[n - 1], t_set, w, phys)
                                        + asperity_work(weight, h, 1.0, h_set, phys))
    scalars[LOAD_SCALE] = c
