"""What the time loop asks of the film model: the contract between integration/stepper.py and the
physics.

The loop (integration/stepper.py) solves ``y = (y_0..y_{N-1}, X, V)`` by BDF2 and chord Newton and
knows no physics. The slot ``y_i`` of each node holds the load its surfaces carry, the film
pressure ``P_i`` of a smooth film, or its total load ``T_i = P_i + p_a(H_i)`` where rough surfaces
touch (model/contact.py); a JFO cavity's slot its liquid fraction. Everything a piece of physics
needs the loop to do goes through the functions here, which read the physics array ``phys``
(solver/physics.py) and decide:

- ``new_film`` (model/state.py): the film's own state beyond ``y``, named records (``Film``: a
  ``Cavity`` and a ``Contact``), which the loop carries and hands back but never reads;
- ``surface_gap``, ``film_pressure``, ``total_force``, ``energies``: the gap and deflection of
  a state, its film pressure (what the loop records and its fluxes carry), the force on the
  spheres, the strain energy and dissipation rate;
- ``accepted_content``: the cells' liquid content of an accepted state, which the loop keeps
  for its steps' history (the BDF combination is the loop's: the film knows no time scheme);
- ``has_active_set``: whether the film has a complementarity constraint decided cell by cell
  (an active set); then a Newton iterate converges only with a settled set, a change refreshes
  the factorisation (``settled``), and the set is decided at the iterates ``decide`` marks;
- ``smooth_in_time``, ``smooth_from_now``: whether the solution is smooth in time from the start,
  and from the newest accepted state on, so that an order above 2 pays;
- ``start_attempt``, ``step_residual``, ``step_jacobian``: a step attempt's start, its residual
  (with the active set decided and its rows replaced) and its Jacobian (recording the set it was
  built with); ``mark_factorised`` and ``changed_slots``: which slots a change of the set touches
  since the last factorisation (the loop updates the factorisation there instead of refactorising),
  and ``refresh_at_set_change``: where a matrix factorised before the attempt is not updated so;
- ``split_update``, ``update_norm``, ``film_change``: unknowns whose slot in ``y`` holds another
  variable (a JFO cavity's liquid fraction), their part of the Newton norm, and the film
  pressure's change that the norm measures where the slots hold loads;
- ``step_error``: in which variable each slot's local error is measured, and which errors
  leave the norm where the solution is not smooth in time (an active set's edge);
- ``pressure_scale``: the absolute part of the pressure error scale;
- ``record``, ``accept``: the model's columns of the series row, and its state after an accepted
  step (the work against a floor, the history of the fractions).

Each function here is the classic film's answer composed with each piece's part of it: the
cavitation floor's in model/cavity_step.py, the asperity contact's in model/contact_step.py,
each a hook that does nothing where its piece is off; the pressure-dependent liquid's in
model/film.py and model/liquid.py, read through ``phys``. The physics behind each part:
model/film.py (terms), model/contact.py and docs/model.md (Cavitation; Pressure-dependent
viscosity and density; Surface roughness).
"""

from .._jit import copy_into, hook, jit, leaf
from ..integration.events import ENDED, HELD
from ..observables import SERIES_INDEX
from . import cavity_step, contact_step
# the contract's answers that one piece alone changes are that piece's hooks themselves (a
# wrapper here would cost a call and a reference count on the loop's hottest path)
from .cavity_step import on as has_active_set  # a floor: an active set
from .cavity_step import departure_holds, split_update, start_attempt, update_norm  # noqa: F401
from .contact_step import (film_change, film_pressure, relaxing_deflection,  # noqa: F401
                           surface_gap, total_force)
from .contact import HOLD, REST
# face_fluxes: the film's face fluxes of a state, which the residual reads, and the loop records
# and the void's work reads too
from .film import cell_content, compression_work, energy_rates, face_fluxes, jacobian, residual
# the gap of the rigid start, before the film's own state exists (its slots are the rigid film's
# pressures whatever the pieces)
from .film import gap as start_gap  # noqa: F401
from .liquid import (constant_density, isoviscous, kink_departure, kirchhoff_between,
                     kirchhoff_pressure, mobility)
from .state import new_film  # noqa: F401 (new_film: the contract's start)

_W_VOID, _E_C = SERIES_INDEX["void_work"], SERIES_INDEX["E_c"]


@hook
def energies(grid, phys, y, w, h, q, film):
    """Strain energy and dissipation rate of the state (film.energy_rates; the strain energy of
    rough surfaces' total load: contact_step.strain)."""
    s = grid.s
    n = s.size
    p = film_pressure(y, film, phys)
    strain, diss = energy_rates(s, grid.s_face, grid.weight, phys, y[n], p, w, h, q)
    return contact_step.strain(grid, phys, p, w, film, strain), diss


@jit
def fluid_fraction(film):
    """The accepted state's liquid fraction per cell (the profile the loop saves)."""
    return film.cavity.theta0


@jit
def pressure_scale(film):
    """The absolute part of the pressure error scale (``state.new_film``)."""
    return film.cavity.p_abs[0]


@hook
def accepted_content(y, h, film, phys, out):
    """The liquid content of the accepted state ``y`` (gap ``h``) per cell, ``C = rho_bar theta
    H`` (``film.cell_content``, with the accepted fractions and film pressure), and the boundary
    node's gap, into ``out``: the loop keeps it for the history of its steps (state.Step)."""
    n = out.size
    theta0 = film.cavity.theta0
    if constant_density(phys):  # C = theta H (rho = 1)
        for i in range(n - 1):
            out[i] = theta0[i] * h[i]
    else:
        p = film_pressure(y, film, phys)
        for i in range(n - 1):
            out[i] = cell_content(theta0[i], h[i], p[i], phys)[0]
    out[n - 1] = h[n - 1]


@hook
def step_residual(grid, phys, step, y, film, decide, q, w, h, res):
    """The scaled residual of the step ``step`` (state.Step) at the iterate ``y``
    (``film.residual``) into ``res``; where ``decide``, the active set is decided first from it
    (cavity_step.decide: a JFO switch moves slots to the floor, so the gap ``w, h`` and the rows
    follow); the rows of a Reynolds cavity are replaced by their constraint. ``q`` receives the
    face fluxes (``film.face_fluxes``). ``w``, ``h`` (and a rough film's contact and film
    pressures) must be ``surface_gap``'s of ``y``."""
    n = grid.s.size
    p = film_pressure(y, film, phys)
    theta = film.cavity.theta
    face_fluxes(grid, p, h, phys, q)
    residual(grid, phys, step, y[n], y[n + 1], p, theta, h, q, res)
    contact_step.motion(grid.weight, phys, step.bh, film, res)
    if not has_active_set(phys):
        return
    if decide and cavity_step.decide(p, res, film, phys):
        contact_step.hold_switched(y, film, phys)
        surface_gap(grid, phys, y, film, w, h)
        p = film_pressure(y, film, phys)
        face_fluxes(grid, p, h, phys, q)
        residual(grid, phys, step, y[n], y[n + 1], p, theta, h, q, res)
        contact_step.motion(grid.weight, phys, step.bh, film, res)
    cavity_step.constrain_rows(p, res, film, phys)


@jit
def smooth_in_time(phys):
    """Whether the film's solution is smooth in time from the start, so that the loop may raise
    the BDF order above 2 (integration/stepper.py) until ``smooth_from_now`` says otherwise: not
    on rough surfaces (the asperities touch, and the solids switch to unloading, at an instant:
    at St 2.5, eps 1e-2, roughness 1, order 5 gave v_r 0.118 against the converged 0.090, BDF2
    0.091)."""
    return not contact_step.on(phys)


@hook
def smooth_from_now(film, phys):
    """Whether the solution stays smooth in time from the newest accepted state on: not once a
    cavity opened (its edge switches cell by cell, and where it refills only ``X`` and ``V``
    control the step: ``step_error``). A cavitating film takes the classic film's orders up to
    its first cavity, then BDF2 at ``rtol``. With the orders above 2 throughout (and the
    tolerance's factor: 0.71x the CPU time of 12 cavitating scenes) the observed order of
    ``ln x_e`` under refinement fell below 1.3 (tests/test_cavitation.py; JFO, St 30, eps 1e-4,
    Pi 1e-4: 1.07-1.29 in the variants tried) and the energy closure of a Barus film with a JFO
    floor at beta 25 rose above 5e-3 (6.4e-3, 6.8e-3; tests/test_piezoviscous_film.py)."""
    return not (has_active_set(phys) and cavity_step.opened(film))


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
    active set it is built with; how the gap and the force follow the slots from
    contact_step.coupling."""
    cav = film.cavity
    link = contact_step.coupling(grid, phys, film)
    jacobian(grid, phys, bh, film_pressure(y, film, phys), cav.theta, h, cav.active, link, jac,
             dres_dh)
    copy_into(cav.active_lu, cav.active)


@jit
def mark_factorised(film):
    """The Jacobian just built (``step_jacobian``) is the one the loop factorises."""
    copy_into(film.cavity.active_base, film.cavity.active_lu)


@hook
def refresh_at_set_change(phys):
    """Whether a change of the active set refactorises a Newton matrix factorised before this
    step attempt, where one factorised in it is updated in the slots that changed
    (``changed_slots``): a JFO film's. Where its cavity refills, such a stale matrix, updated,
    took the iteration from a rate of 0.03 to 0.3-0.6 after the change, and the attempt failed
    after 7 iterations and was tried again from a fresh matrix, on which each change converged
    in 2 (St 10, eps 1e-4, Pi 1e-3, standard: 41 such attempts, 376 of 2233 Newton iterations).
    Refactorised, that collision took 1674 iterations and 213 factorisations instead of 2233 and
    155, 0.88x the CPU time (St 30: 0.95x). A Reynolds film's took 1.02-1.03x the CPU time
    refactorised, and keeps the update."""
    return cavity_step.held(phys)


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


@hook
def step_error(y, y_pred, states, err_fac, rtol, h, film, phys, perr, dh, scale):
    """Adjust the local error estimate of a converged step. On entry ``perr`` holds the pressure
    part ``err_fac (y - y_pred)`` and ``dh`` the gap's; ``states`` are the accepted states the
    predictor ``y_pred`` went through (newest first); ``rtol`` the step's relative tolerance.

    - While a cavity is open the pressure is not smooth in time wherever its edge crosses a node
      (the cells there and their neighbours), and a cavity that closes in this step makes it
      jump: the gap, X and V errors control the step (measured: every rejection came from these
      kinks; counting the jump of the last cell of an axis cavity as an error underflowed the
      step). The gap is not smooth either at a cell the edge crossed within the predictor's
      states: its errors there, and at its neighbours, leave the norm too
      (cavity_step._edge_gaps).
    - Reynolds: a cavity cell's row is the floor, and its gap error kinks at every switch of any
      cell, through the elastic kernel: the gaps of this step's cavity leave the norm (errors
      measured within 1.12x of what they were: cavity_step.passive_gaps), unless an asperity
      load reads them (rough surfaces).
    - JFO: where a cavity closes the pressure jumps (the void's closing rate is finite up to the
      instant it vanishes), and the gap with it through ``W = K P``: no step size makes the
      extrapolation of the gap across it accurate. X and V stay continuous; they control this
      step (no history restart: docs/solver.md, "Cavitation"). (Both:
      cavity_step.error_in_time.)
    - A pressure-dependent liquid: the pressure error in the variable the film sees, the
      Kirchhoff pressure ``Int rho/mu dP``, smooth where a glassy lens makes ``P`` itself spike
      (that spike moves the gap, X and V only through W and the force, both in the norm on their
      own). Where a cell's pressure crossed a kink of the liquid's laws over the predictor's
      states and this one (``P = 0``, where the viscosity law starts; a table's points) that
      departs from a smooth law by more than ``rtol``, its pressure is not smooth in time, nor
      its neighbours', which its fluxes reach: their errors leave the norm, and the gap, X and V
      control the step there (``_kinks_in_time``).
    - A rough film: its slots hold the load, which the gap sees, and the error is measured
      there, for a pressure-dependent liquid too (the Kirchhoff pressure needs ``P``, which the
      extrapolated loads do not give without the gap's contact).

    Returns True when ``scale`` holds the Kirchhoff pressures, False when the errors are measured
    against the slots themselves (``scale`` untouched)."""
    loaded = contact_step.on(phys)  # the gap sets the asperities' load
    not_smooth = cavity_step.error_in_time(film, phys, states.shape[0] - 1, perr, dh)
    if not loaded:
        cavity_step.passive_gaps(film, phys, dh)
    if isoviscous(phys) or not_smooth or loaded:
        return False
    _kirchhoff_errors(y_pred, y, err_fac, phys, perr, scale)
    _kinks_in_time(states, y, rtol, phys, perr)
    return True


@leaf
def _kirchhoff_errors(y_pred, y, err_fac, phys, perr, scale):
    """``step_error``'s pressure errors ``perr`` and their scales ``scale`` in the Kirchhoff
    pressure, cell by cell (a ``leaf``: inlined into the loop, each cell's call counted
    references, 1055 per Newton iteration of a Barus film)."""
    at_zero = mobility(0.0, phys)
    for i in range(perr.size):
        at_y = mobility(y[i], phys)
        perr[i] = err_fac * kirchhoff_between(y_pred[i], mobility(y_pred[i], phys), y[i], at_y,
                                              phys, False)[0]
        scale[i] = kirchhoff_pressure(y[i], at_y, at_zero, phys)


# How many cells on either side of a cell that crossed a kink in time (``_kinks_in_time``) are
# not smooth in time either: the kink reaches them through the fluxes and the solids, fading
# with the distance, and the finer the grid and the tolerance, the more cells the error test
# sees it in. In the rebound of Barus films the failing cell moved inwards with the tension
# region's edge, beyond the one cell left out on either side (Barus beta 2, St 30, eps 1e-4,
# fine: 247 rejected steps with one cell, 166 with 2, 93 with 3, 70 with 4; the classic film
# 31), while X, V and the gap, which stay in the norm, moved the results by far less than the
# presets' errors (docs/solver.md, Versions, 1.17.0).
KINK_REACH = 3


@leaf
def _kinks_in_time(states, y, rtol, phys, perr):
    """``step_error``'s pressure errors ``perr`` to 0 at each cell whose pressure, over the
    ``states`` and ``y``, crossed a kink of the liquid's laws that departs from a smooth law by
    more than ``rtol`` over that range (``liquid.kink_departure``), and at the ``KINK_REACH``
    cells on either side. At a kink the viscosity's slope jumps, and with it the pressure's
    second derivative in time: no order's predictor extrapolates across it, and the step's
    error test failed there at every order (Barus beta 1, St 10, eps 1e-4, standard: 109
    rejected steps, against the classic film's 13, and 16 with these errors left out). A kink
    below ``rtol`` (beta 1e-9) cannot move the error test: the film keeps the classic film's
    step decisions."""
    n = perr.size
    for i in range(n):
        lo, hi = y[i], y[i]
        for j in range(states.shape[0]):
            lo = min(lo, states[j, i])
            hi = max(hi, states[j, i])
        if kink_departure(lo, hi, phys) > rtol:
            for c in range(max(0, i - KINK_REACH), min(n, i + KINK_REACH + 1)):
                perr[c] = 0.0


@hook
def record(row, grid, p, h, pmax, pmin, film, phys, floor_fraction):
    """The model's columns of the series row of an accepted state (compression energy, work
    against the floor; the contact's columns, contact_step.record; the cavity's,
    cavity_step.record), every one on every row, and the error scale's update from the largest
    pressure seen (``floor_fraction`` of it, from the first cavity on). Returns the radius the
    terminal events see (the cavity's); ``events.HELD`` while a rough film holds its contact and
    ``events.ENDED`` when it rests on its asperities (contact.contact_state)."""
    cav = film.cavity
    row[_E_C] = compression_work(grid.area, p, h, cav.theta0, phys)
    row[_W_VOID] = cav.worked[0]
    # a rough film near contact holds the coupled phase as a cavity does, and ends it at rest
    state = contact_step.record(row, grid, h, film, phys)
    r_event = cavity_step.record(row, grid, p, h, pmax, pmin, cav, phys, floor_fraction)
    if state == REST:
        return ENDED
    if state == HOLD:
        return HELD
    return r_event


@hook
def accept(grid, y0, w, h0, h1, q, dt, film, phys):
    """The model's state after an accepted step (``y0`` its solution, ``w`` and ``h0`` its
    deflection and gap, ``h1`` the previous one's, ``q`` its face fluxes): each piece's
    (contact_step.accept, cavity_step.accept)."""
    contact_step.accept(grid, y0, w, h0, film, phys)
    cavity_step.accept(grid, h0, h1, q, dt, film, phys)
