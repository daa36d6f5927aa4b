"""What the time loop asks of the film model: the contract between integration/stepper.py and the
physics.

The loop (integration/stepper.py) solves ``y = (y_0..y_{N-1}, X, V)`` by BDF2 and chord Newton and
knows no physics. The slot ``y_i`` of each node holds the load its surfaces carry, the film
pressure ``P_i`` of a smooth film, or its total load ``T_i = P_i + p_a(H_i)`` where rough surfaces
touch (model/contact.py); a JFO cavity's slot its liquid fraction. Everything a piece of physics
needs the loop to do goes through the functions here, which read the physics array ``phys``
(solver/physics.py) and decide:

- ``new_film`` (model/state.py), ``begin``: the film's own state beyond ``y``, named records
  (``Film``: a ``Cavity`` and a ``Contact``), which the loop carries and hands back but never
  reads, and its history at the first state;
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
from .state import Coupling, new_film  # noqa: F401 (new_film: the contract's start)

# a rough film's Newton measures the change of its film pressure against its own size or this
# fraction of the asperities' pressure, whichever is larger (film_change)
CONTACT_SHARE = 0.01

_R_CAV, _V_VOID = SERIES_INDEX["cavity_radius"], SERIES_INDEX["void_volume"]
_W_VOID, _E_C = SERIES_INDEX["void_work"], SERIES_INDEX["E_c"]
_E_A, _LOST, _F_A = SERIES_INDEX["E_a"], SERIES_INDEX["solid_loss"], SERIES_INDEX["F_contact"]
_V = SERIES_INDEX["V"]


@jit
def has_active_set(phys):
    """Whether the film has a constraint decided cell by cell (a cavitation floor)."""
    return phys[CAVITATION] != NO_FLOOR


@jit
def rough(phys):
    """Whether the surfaces are rough (asperity contact, model/contact.py)."""
    return phys[ROUGHNESS] != 0.0


@jit
def surface_gap(grid, phys, y, film, w, h):
    """The deflection ``W`` and gap ``H`` of the iterate ``y`` into ``w``, ``h``: ``W = K y``
    (film.gap), and for a rough film the contact pressure and film pressure they imply
    (contact.contact_gap, whose cells held at the floor are a JFO cavity's, solved from the gap
    ``h`` holds; a contact solve that fails leaves ``h`` NaN, which the loop treats as a failed
    iterate)."""
    n = grid.s.size
    if not rough(phys):
        gap(grid.s, grid.influence, y[n], y[:n], w, h)
        return
    if not contact_gap(grid, y[n], y, film.contact, held_cells(film.cavity, phys, n), phys, w,
                       h):
        h[:] = np.nan


@jit
def held_cells(cavity, phys, n):
    """The nodes whose slot is not their load (a JFO cavity's cells, held at the floor)."""
    held = np.zeros(n, dtype=np.bool_)
    if phys[CAVITATION] == JFO:
        held[:n - 1] = cavity.active
    return held


@jit
def film_pressure(y, film, phys):
    """The film pressure of the state whose gap ``surface_gap`` computed last: the slots
    themselves for a smooth film (no copy), ``y - p_a`` where rough surfaces touch."""
    n = y.size - 2
    if not rough(phys):
        return y[:n]
    return film.contact.p_film


@jit
def begin(film, phys):
    """The film's history at the first state (whose gap ``surface_gap`` computed last): a rough
    film's film pressure of the accepted states (``content_history``)."""
    if rough(phys):
        contact = film.contact
        contact.p_acc0[:] = contact.p_film
        contact.p_acc1[:] = contact.p_film


@jit
def relaxing_deflection(w, w_absmax, film, phys):
    """The largest ``|W|`` the terminal events wait to relax (``w_absmax``, ``max |W|``): a rough
    film's permanent set (model/contact.py) never relaxes, so ``max |W - (1 - c) K T_set|``."""
    if not rough(phys) or film.contact.load_scale[0] == 1.0:
        return w_absmax
    w_set = film.contact.w_set
    out = 0.0
    for i in range(w.size):
        out = max(out, abs(w[i] - w_set[i]))
    return out


@jit
def total_force(weight, y, film, phys):
    """``Int (P + p_a) R dR``, the force on the spheres (film.film_force), with the film and
    contact pressures of the last ``surface_gap``."""
    n = weight.size
    if not rough(phys):
        return film_force(weight, y[:n])
    return film_force(weight, film.contact.p_film) + film_force(weight, film.contact.pa)


@jit
def energies(grid, phys, y, w, h, q, film):
    """Strain energy and dissipation rate of the state (film.energy_rates): for a rough film the
    strain energy of the total load ``P + p_a`` on the elastic part of ``W`` (less the permanent
    set)."""
    s = grid.s
    n = s.size
    p = film_pressure(y, film, phys)
    strain, diss = energy_rates(s, grid.s_face, grid.weight, phys, y[n], p, w, h, q)
    if rough(phys):
        pa, w_set = film.contact.pa, film.contact.w_set
        strain = strain_energy(grid.weight, s[n - 1], p + pa, w - w_set, phys)
    return strain, diss


@jit
def fluid_fraction(film):
    """The accepted state's liquid fraction per cell (the profile the loop saves)."""
    return film.cavity.theta0


@jit
def pressure_scale(film):
    """The absolute part of the pressure error scale (``state.new_film``)."""
    return film.cavity.p_abs[0]


@jit
def content_history(a1, a2, y0, y1, h0, h1, film, phys, out):
    """``a1 C(state 0) + a2 C(state 1)`` per cell (``C = rho_bar theta H``, ``film.cell_content``),
    and the same combination of the boundary node's gap, into ``out`` (a rough film's film
    pressure of the two states from its ``Contact``: its slots hold their loads)."""
    n = out.size
    theta0, theta1 = film.cavity.theta0, film.cavity.theta1
    if phys[DENSITY] == CONSTANT:  # C = theta H (rho = 1)
        for i in range(n - 1):
            out[i] = a1 * (theta0[i] * h0[i]) + a2 * (theta1[i] * h1[i])
    else:
        p0, p1 = y0, y1
        if rough(phys):
            p0, p1 = film.contact.p_acc0, film.contact.p_acc1
        for i in range(n - 1):
            out[i] = a1 * cell_content(theta0[i], h0[i], p0[i], phys)[0] \
                + a2 * cell_content(theta1[i], h1[i], p1[i], phys)[0]
    out[n - 1] = a1 * h0[n - 1] + a2 * h1[n - 1]


@jit
def start_attempt(y, film, phys):
    """A step attempt of a JFO film starts from the accepted cavity, its cells' slots at the
    floor; the Reynolds film keeps the iterate's set."""
    if phys[CAVITATION] != JFO:
        return
    cavity = film.cavity
    active, active0 = cavity.active, cavity.active0
    theta, theta0 = cavity.theta, cavity.theta0
    for i in range(active.size):
        active[i] = active0[i]
        theta[i] = theta0[i]
        if active[i]:
            y[i] = -phys[PI]


@jit
def contact_motion(weight, phys, bh, film, res):
    """The contact load's part of the motion row of ``film.residual``: ``bh F_a / (3 St)``, with
    the contact pressure of the last ``surface_gap`` (nothing for a smooth film)."""
    if rough(phys):
        res[weight.size + 1] += bh * film_force(weight, film.contact.pa) / (3.0 * phys[ST])


@jit
def step_residual(grid, phys, step, y, film, decide, q, w, h, res):
    """The scaled residual of the step ``step`` (state.Step) at the iterate ``y``
    (``film.residual``) into ``res``; where ``decide``, the active set is decided first from it
    (a JFO switch moves slots to the floor, so the gap ``w, h`` and the rows follow); the rows
    of a Reynolds cavity are replaced by their constraint. ``q`` receives the face fluxes.
    ``w``, ``h`` (and a rough film's contact and film pressures) must be ``surface_gap``'s of
    ``y``."""
    n = grid.s.size
    p = film_pressure(y, film, phys)
    theta, active = film.cavity.theta, film.cavity.active
    residual(grid, phys, step, y[n], y[n + 1], p, theta, h, q, res)
    contact_motion(grid.weight, phys, step.bh, film, res)
    if not has_active_set(phys):
        return
    jfo = phys[CAVITATION] == JFO
    if decide:
        if jfo:
            was = active.copy()
            if update_cavity_jfo(p, theta, phys, active):
                if rough(phys):  # a switched slot holds the load at the floor
                    pa = film.contact.pa
                    for i in range(n - 1):
                        if active[i] != was[i]:
                            y[i] = -phys[PI] + pa[i]
                surface_gap(grid, phys, y, film, w, h)
                p = film_pressure(y, film, phys)
                residual(grid, phys, step, y[n], y[n + 1], p, theta, h, q, res)
                contact_motion(grid.weight, phys, step.bh, film, res)
        else:
            update_cavity(p, res, phys, active)
    if not jfo:
        constrain(p, res, active, phys)


@jit
def settled(film):
    """Whether the iterate's active set is the one the factorised Jacobian was built with."""
    active, active_lu = film.cavity.active, film.cavity.active_lu
    for i in range(active.size):
        if active[i] != active_lu[i]:
            return False
    return True


@jit
def step_jacobian(grid, phys, bh, y, h, film, jac, dres_dh):
    """The Jacobian of ``step_residual`` at ``y`` into ``jac`` (``film.jacobian``), recording the
    active set it is built with. A rough film's film pressure follows the gap where its slot is
    the load (contact.contact_slopes); its gap follows the slots through ``c K`` while the solids
    unload, and a touching JFO cavity's gap and the force through its contact
    (contact.contact_derivatives)."""
    n = grid.s.size
    cavity = film.cavity
    if rough(phys):
        c, slope = film.contact.load_scale[0], film.contact.slope
        held = held_cells(cavity, phys, n)
        dp_dh = np.empty(n)
        m = contact_slopes(slope, held, dp_dh)
        p = film.contact.p_film
        if m == 0 and c == 1.0:
            link = Coupling(grid.influence, np.ones(n), grid.weight, 0.0, dp_dh)
        else:
            k_eff = np.empty((n, n))
            dh_dx = np.empty(n)
            force_dp = np.empty(n)
            force_dx = contact_derivatives(grid.influence, grid.weight, slope, c, held, m, k_eff,
                                           dh_dx, force_dp)
            link = Coupling(k_eff, dh_dx, force_dp, force_dx, dp_dh)
        jacobian(grid, phys, bh, p, cavity.theta, h, cavity.active, link, jac, dres_dh)
    else:
        link = Coupling(grid.influence, np.ones(n), grid.weight, 0.0, np.empty(0))
        jacobian(grid, phys, bh, y[:n], cavity.theta, h, cavity.active, link, jac, dres_dh)
    cavity.active_lu[:] = cavity.active


@jit
def mark_factorised(film):
    """The Jacobian just built (``step_jacobian``) is the one the loop factorises."""
    film.cavity.active_base[:] = film.cavity.active_lu


@jit
def changed_slots(film, slots):
    """The slots whose rows and columns differ between the factorised Jacobian and the one for
    the iterate's active set (a cell that cavitated or refilled since the factorisation), into
    ``slots`` as far as it reaches; returns their number."""
    k = 0
    active, base = film.cavity.active, film.cavity.active_base
    for i in range(active.size):
        if active[i] != base[i]:
            if k < slots.size:
                slots[k] = i
            k += 1
    return k


@jit
def split_update(res, film, phys):
    """Take the Newton update of the slots that hold another unknown out of ``res``: a JFO
    cavity's slot updates its liquid fraction theta (kept >= 0: a dry cell), not ``P``."""
    if phys[CAVITATION] != JFO:
        return
    cavity = film.cavity
    active, theta, dtheta = cavity.active, cavity.theta, cavity.dtheta
    for i in range(active.size):
        dtheta[i] = 0.0
        if active[i]:
            dtheta[i] = res[i]
            theta[i] = max(theta[i] + res[i], 0.0)
            res[i] = 0.0


@jit
def film_change(dy, dh, y, h, film, phys, dp):
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
    held = held_cells(film.cavity, phys, n)
    contact = film.contact
    p, pa = contact.p_film, contact.pa
    scale, slope = contact.p_scale, contact.slope
    for i in range(n):
        dp[i] = dy[i]
        if not held[i]:
            dp[i] -= slope[i] * dh[i]
        scale[i] = abs(p[i]) + CONTACT_SHARE * pa[i]
    return dp, scale


@jit
def update_norm(norm, film, phys, rtol):
    """The Newton norm with the fractions' updates (absolute) of ``split_update``."""
    if phys[CAVITATION] != JFO:
        return norm
    dtheta = film.cavity.dtheta
    for i in range(dtheta.size):
        norm = max(norm, abs(dtheta[i]) / rtol)
    return norm


@jit
def step_error(y, y_pred, err_fac, h, film, phys, perr, dh, scale):
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
        rough_in_time = _cavity_in_time(film.cavity, phys)
        if rough_in_time:
            for i in range(n):
                perr[i] = 0.0
        if _refilled(film.cavity, phys):
            for i in range(n):
                dh[i] = 0.0
    kirchhoff = not isoviscous(phys) and not rough_in_time and not rough(phys)
    if kirchhoff:
        for i in range(n):
            perr[i] = err_fac * kirchhoff_difference(y_pred[i], y[i], phys)[0]
            scale[i] = kirchhoff_difference(0.0, y[i], phys)[0]
    return kirchhoff


@jit
def _refilled(cavity, phys):
    """Whether a JFO cavity's cell refilled in this step (its pressure jumps: ``step_error``)."""
    refilled = False
    if phys[CAVITATION] == JFO:
        active, active0 = cavity.active, cavity.active0
        for i in range(active.size):
            refilled = refilled or (active0[i] and not active[i])
    return refilled


@jit
def _cavity_in_time(cavity, phys):
    """Whether the pressure is not smooth in time over this step (``step_error``): a cavity open
    at its start or end, or a JFO cell that refilled in it."""
    open_cavity = cavity.r_edge[0] > 0.0
    for i in range(cavity.active.size):
        open_cavity = open_cavity or cavity.active[i]
    return open_cavity or _refilled(cavity, phys)


@jit
def record(row, grid, p, h, pmax, pmin, film, phys, floor_fraction):
    """The model's columns of the series row of an accepted state (cavity radius and void volume,
    work against the floor, compression energy; contact force, asperity energy and the energy
    lost in the solids), every one on every row, and the error scale's update from the largest
    pressure seen (``floor_fraction`` of it, from the first cavity on). Returns the radius the
    terminal events see: the cavity's, tiny but positive for a JFO cavity of axis cells alone
    (whose edge radius is zero); ``events.HELD`` while a rough film holds its contact and
    ``events.ENDED`` when it rests on its asperities (contact.contact_state)."""
    cavity, contact = film.cavity, film.contact
    row[_E_C] = compression_work(grid.area, p, h, cavity.theta0, phys)
    row[_W_VOID] = cavity.worked[0]
    row[_F_A] = 0.0
    row[_E_A] = 0.0
    row[_LOST] = contact.solid_lost[0]
    # a rough film near contact holds the coupled phase as a cavity does, and ends it at rest
    state = FREE
    if rough(phys):
        row[_F_A] = film_force(grid.weight, contact.pa)
        row[_E_A] = asperity_work(grid.weight, h, contact.load_scale[0], contact.h_set, phys)
        state = contact_state(h, row[_V], phys)
    r_event = cavity_columns(row, grid, p, h, pmax, pmin, cavity, phys, floor_fraction)
    if state == REST:
        return ENDED
    if state == HOLD:
        return HELD
    return r_event


@jit
def cavity_columns(row, grid, p, h, pmax, pmin, cavity, phys, floor_fraction):
    """The cavity's columns of the series row (radius and void volume; 0 for a film without a
    floor) and the error scale's update (``record``); returns the radius the terminal events
    see."""
    if not has_active_set(phys):  # no cavity ever
        row[_R_CAV] = 0.0
        row[_V_VOID] = 0.0
        return 0.0
    area = grid.area
    active0, h_onset = cavity.active0, cavity.h_onset
    r_cav = cavity_edge(grid.s, p, active0, phys)
    jfo = phys[CAVITATION] == JFO
    v_void = 0.0
    if jfo:
        v_void = jfo_void(area, cavity.theta0, h, active0)
    else:
        for i in range(active0.size):
            if active0[i]:
                v_void += area[i] * (h[i] - h_onset[i])
    row[_R_CAV] = r_cav
    row[_V_VOID] = v_void
    cavity.r_edge[0] = r_cav
    cavity.p_seen[0] = max(cavity.p_seen[0], pmax, -pmin)
    if r_cav > 0.0:
        cavity.p_abs[0] = max(cavity.p_abs[0], floor_fraction * cavity.p_seen[0])
    r_event = r_cav
    if jfo:
        for i in range(active0.size):
            if active0[i]:
                r_event = max(r_event, 1e-300)
    return r_event


@jit
def accept(grid, y0, w, h0, h1, q, dt, film, phys):
    """The model's state after an accepted step (``y0`` its solution, ``w`` and ``h0`` its
    deflection and gap, ``h1`` the previous one's, ``q`` its face fluxes): the work against the
    floor (JFO: ``Pi dV_void`` exactly, film.jfo_void; Reynolds: film.void_work), the fractions'
    history, where new cavity cells opened, and the accepted cavity; for a rough film, the onset
    of the solids' unloading (``unload``) and the history of its film pressure."""
    if rough(phys):
        contact = film.contact
        unload(grid, y0, w, h0, contact, phys)
        contact.p_acc1[:] = contact.p_acc0
        contact.p_acc0[:] = contact.p_film
    if not has_active_set(phys):
        return
    cavity = film.cavity
    active, active0 = cavity.active, cavity.active0
    theta, theta0, theta1 = cavity.theta, cavity.theta0, cavity.theta1
    area = grid.area
    if phys[CAVITATION] == JFO:
        cavity.worked[0] += 2.0 * phys[PI] * (jfo_void(area, theta, h0, active)
                                              - jfo_void(area, theta0, h1, active0)) \
            / (3.0 * phys[ST])
    else:
        cavity.worked[0] += void_work(area, h0, h1, q, cavity.q_prev, dt, active, phys)
    theta1[:] = theta0
    theta0[:] = theta
    for i in range(active.size):
        if active[i] and not active0[i]:
            cavity.h_onset[i] = h1[i]
    active0[:] = active
    cavity.q_prev[:] = q


@jit
def unload(grid, y0, w, h, contact, phys):
    """The losses in the solids (model/contact.py): once the asperities have carried load on
    approach (``V > 0``), the first accepted state with ``V <= 0`` starts the unloading along
    ``c = e_dry^2`` through its load ``T_set = P + p_a``, with the permanent set ``(1 - c) W``,
    and the asperities' from its gap ``H_set``; the strain and asperity energy the solids will
    not return, ``(1 - c) (E_s + E_a)``, is lost then."""
    if phys[E_DRY] == 1.0 or contact.load_scale[0] != 1.0:
        return
    n = grid.s.size
    pa, p = contact.pa, contact.p_film
    touching = False
    for i in range(n):
        touching = touching or pa[i] > 0.0
    if touching and y0[n + 1] > 0.0:
        contact.touched[0] = 1.0
    if contact.touched[0] == 0.0 or y0[n + 1] > 0.0:
        return
    c = phys[E_DRY] * phys[E_DRY]
    t_set, w_set, h_set = contact.t_set, contact.w_set, contact.h_set
    for i in range(n):
        t_set[i] = p[i] + pa[i]
        w_set[i] = (1.0 - c) * w[i]
        h_set[i] = h[i]
    contact.solid_lost[0] += (1.0 - c) * (strain_energy(grid.weight, grid.s[n - 1], t_set, w, phys)
                                          + asperity_work(grid.weight, h, 1.0, h_set, phys))
    contact.load_scale[0] = c
