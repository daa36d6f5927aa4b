"""The cavitation floor's part of the film's contract (model/step.py): what a film with the floor
``P >= -Pi`` (the Reynolds condition or the mass-conserving JFO cavity) asks of the time loop
beyond the classic film (docs/model.md, "Cavitation"; docs/solver.md, "Cavitation").

Each hook reads the physics array and does nothing for a film without a floor, so model/step.py
calls it unconditionally. The floor's state is the ``Cavity`` record of model/state.py: its
active set (the cavitated cells) of the iterate, of the Jacobian and of the accepted states, the
JFO liquid fractions, the void's history. A JFO cavity's slot holds its liquid fraction, not its
pressure (``split_update``); a Reynolds cavity's row is replaced by its constraint
(``constrain_rows``).
"""

from .._jit import copy_into, hook, jit, leaf
from ..observables import SERIES_INDEX
from ..physics import CAVITATION, PI, ST
from .film import (JFO, cavity_edge, constrain, jfo_void, update_cavity, update_cavity_jfo,
                   void_work)
from .kind import CAVITATION_CODE, asks_floor
from .refill import closes

_R_CAV, _V_VOID = SERIES_INDEX["cavity_radius"], SERIES_INDEX["void_volume"]


@hook
def on(phys):
    """Whether the film has a floor: a constraint decided cell by cell (an active set). False in
    a copy of the loop without the floor's code (model/kind.py), whose branches numba prunes."""
    if CAVITATION_CODE:
        return asks_floor(phys)
    return False


@hook
def held(phys):
    """Whether the floor holds cells' slots at the floor with another unknown (JFO)."""
    if CAVITATION_CODE:
        return phys[CAVITATION] == JFO
    return False


@jit
def held_cells(cavity, phys, out):
    """The nodes whose slot is not their load (a JFO cavity's cells, held at the floor), into the
    boolean ``out`` (N,)."""
    n = out.size
    out[:] = False
    if held(phys):
        copy_into(out[:n - 1], cavity.active)


@hook
def start_attempt(y, film, phys):
    """A step attempt of a JFO film starts from the accepted cavity, its cells' slots at the
    floor; the Reynolds film keeps the iterate's set."""
    if not held(phys):
        return
    cavity = film.cavity
    active, active0 = cavity.active, cavity.active0
    theta, theta0 = cavity.theta, cavity.theta0
    for i in range(active.size):
        active[i] = active0[i]
        theta[i] = theta0[i]
        if active[i]:
            y[i] = -phys[PI]


@hook
def decide(p, res, film, phys):
    """Decide the iterate's active set from its film pressure ``p`` and residual ``res``: a JFO
    cavity from ``p`` and the liquid fractions (``film.update_cavity_jfo``; the set before is kept
    in ``active_was``), a Reynolds cavity from ``p`` and ``res`` (``film.update_cavity``). Returns
    True when JFO slots switched, whose gap and rows must then be evaluated again. (A hook that
    hands the record's arrays to a ``leaf``: as a ``jit`` function reading the record it made 17
    of the 226 reference counts per Newton iteration of the loop with every piece;
    docs/solver.md, "Reference counting".)"""
    cavity = film.cavity
    return _decide(p, res, cavity.active, cavity.active_was, cavity.theta, phys)


@leaf
def _decide(p, res, active, active_was, theta, phys):
    """``decide`` on the cavity's arrays."""
    if held(phys):
        for i in range(active.size):
            active_was[i] = active[i]
        return update_cavity_jfo(p, theta, phys, active)
    update_cavity(p, res, phys, active)
    return False


@hook
def constrain_rows(p, res, film, phys):
    """Replace the rows of a Reynolds cavity's cells by their constraint (``film.constrain``);
    a JFO cavity's rows stay its conservation law."""
    if on(phys) and not held(phys):
        constrain(p, res, film.cavity.active, phys)


@hook
def split_update(res, film, phys):
    """Take the Newton update of the slots that hold another unknown out of ``res``: a JFO
    cavity's slot updates its liquid fraction theta (kept >= 0: a dry cell), not ``P``."""
    if not held(phys):
        return
    cavity = film.cavity
    active, theta, dtheta = cavity.active, cavity.theta, cavity.dtheta
    for i in range(active.size):
        dtheta[i] = 0.0
        if active[i]:
            dtheta[i] = res[i]
            theta[i] = max(theta[i] + res[i], 0.0)
            res[i] = 0.0


@hook
def update_norm(norm, film, phys, rtol):
    """The Newton norm with the fractions' updates (absolute) of ``split_update``."""
    if not held(phys):
        return norm
    dtheta = film.cavity.dtheta
    for i in range(dtheta.size):
        norm = max(norm, abs(dtheta[i]) / rtol)
    return norm


@hook
def error_in_time(film, phys, degree, perr, dh):
    """The floor's part of ``step.step_error``: while a cavity is open (or a JFO cell refilled in
    this step) the pressure is not smooth in time, and its errors leave the norm (``perr`` to 0);
    where a JFO cavity refilled, the gap's too (``dh`` to 0), and where a cell cavitated or
    refilled over the predictor's states (of polynomial ``degree``) and this one, the gap's of
    that cell and its neighbours (``_edge_gaps``). Returns whether the pressure is not smooth in
    time."""
    if not on(phys):
        return False
    n = perr.size
    cavity = film.cavity
    refilled = _refilled(cavity.active, cavity.active0, phys)
    # a cavity open at the step's start (the accepted state's radius) or end, or a refill in it
    not_smooth = cavity.r_edge[0] > 0.0 or _any(cavity.active) or refilled
    if not_smooth:
        for i in range(n):
            perr[i] = 0.0
    if refilled:
        for i in range(n):
            dh[i] = 0.0
    _edge_gaps(cavity, degree, dh)
    return not_smooth


@jit
def _edge_gaps(cavity, degree, dh):
    """``dh`` to 0 at each cell that cavitated or refilled in this step or within the predictor's
    states (fewer than ``degree`` accepted steps ago), and at its two neighbours. There the cell's
    pressure meets or leaves the floor with a jump in its slope, and the gap, its elastic
    deflection, follows with a jump in its own slope: no predictor extrapolates across it. With
    those gaps in the norm each cell the cavity's edge crossed cost about three rejected steps
    (JFO, St 10, eps 1e-4, Pi 1e-3, standard: 184 rejections in 558 steps; 120 in 487 without);
    the other cells' gaps, ``X`` and ``V`` control the step."""
    active, active0, since = cavity.active, cavity.active0, cavity.since_switch
    n = dh.size
    for i in range(active.size):
        if active[i] != active0[i] or since[i] < degree:
            for c in range(max(0, i - 1), min(n, i + 2)):
                dh[c] = 0.0


@hook
def passive_gaps(film, phys, dh):
    """``dh`` to 0 at each cell of this step's cavity where the floor is the Reynolds condition.
    For ``step.step_error``, which asks only where no asperity load reads the gap (a rough
    film's cavity cells keep theirs). A choice by measurement (docs/solver.md, Versions,
    1.18.4): the condition puts the floor in such a cell's row instead of its mass balance, and
    its gap error kinks in time wherever any cell meets or leaves the floor, through the elastic
    kernel (as the film cells' near the edge do, which stay). In the norm, those errors set the
    step: the largest gap error lay within 3 cells of the cavity's edge in most steps (St 10,
    eps 1e-4, Pi 1e-3, standard). Without them, 10-21 % fewer steps and 26-56 % fewer
    factorisations at the standard preset, every error against benchmarks/cavitation.md's
    references (as solver 1.18.3 computed them) within 1.12x of what it was. The gap is still
    read where the cell's residual decides whether it refills, in the flux at the cavity's edge
    and in the void's volume and work. Kept in the norm: a JFO cavity cell's gap (it holds
    liquid that is conserved; without those gaps too, JFO's ``e_wet`` at St 10, eps 1e-2, Pi
    1e-2 moved 1.2x further from the reference), and a rough film's (the gap sets the
    asperities' load: without them, a Reynolds film on rough surfaces at St 300, eps 1e-2, Pi
    1e-6 ended 1.5x (fast) and 2.2x (standard) further from its fine preset's ``e_wet``)."""
    if not on(phys) or held(phys):
        return
    active = film.cavity.active
    for i in range(min(active.size, dh.size)):
        if active[i]:
            dh[i] = 0.0


@hook
def opened(film):
    """Whether the accepted state has a cavity."""
    return _any(film.cavity.active0)


@leaf
def _any(cells):
    """Whether any of the boolean ``cells`` is True."""
    for i in range(cells.size):
        if cells[i]:
            return True
    return False


@hook
def departure_holds(grid, x, v, t, film, phys):
    """Whether the rigid departure of the accepted state ``(x, v, t)`` holds, where the coupled
    phase would end there: for a JFO cavity open while the spheres separate, its refill
    departure must refill it (model/refill.py, ``closes``); otherwise True."""
    if not held(phys) or v >= 0.0 or not _any(film.cavity.active0):
        return True
    return closes(x, -v, t, phys[ST], phys[PI], grid.s_face, film.cavity.theta0)


@leaf
def _refilled(active, active0, phys):
    """Whether a JFO cavity's cell refilled in this step (its pressure jumps: ``step_error``),
    from the cavity's sets of this step and of the accepted state."""
    refilled = False
    if held(phys):
        for i in range(active.size):
            refilled = refilled or (active0[i] and not active[i])
    return refilled


@hook
def record(row, grid, p, h, pmax, pmin, cavity, phys, floor_fraction):
    """The cavity's columns of the series row (radius and void volume; 0 for a film without a
    floor) and the error scale's update (``step.record``); returns the radius the terminal events
    see: the cavity's, tiny but positive for a JFO cavity of axis cells alone (whose edge radius
    is zero)."""
    if not on(phys):  # no cavity ever
        row[_R_CAV] = 0.0
        row[_V_VOID] = 0.0
        return 0.0
    area = grid.area
    active0, h_onset = cavity.active0, cavity.h_onset
    r_cav = cavity_edge(grid.s, p, active0, phys)
    jfo = held(phys)
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
    if jfo and _any(active0):
        r_event = max(r_event, 1e-300)
    return r_event


@hook
def accept(grid, h0, h1, q, dt, film, phys):
    """The floor's state after an accepted step (``h0`` its gap, ``h1`` the previous one's, ``q``
    its face fluxes): the work against the floor (JFO: ``Pi dV_void`` exactly, film.jfo_void;
    Reynolds: film.void_work), the accepted fractions, where new cavity cells opened, and the
    accepted cavity."""
    if not on(phys):
        return
    cavity = film.cavity
    active, active0 = cavity.active, cavity.active0
    theta, theta0 = cavity.theta, cavity.theta0
    area = grid.area
    if held(phys):
        cavity.worked[0] += 2.0 * phys[PI] * (jfo_void(area, theta, h0, active)
                                              - jfo_void(area, theta0, h1, active0)) \
            / (3.0 * phys[ST])
    else:
        cavity.worked[0] += void_work(area, h0, h1, q, cavity.q_prev, dt, active, phys)
    copy_into(theta0, theta)
    for i in range(active.size):
        if active[i] and not active0[i]:
            cavity.h_onset[i] = h1[i]
        cavity.since_switch[i] = 0 if active[i] != active0[i] else cavity.since_switch[i] + 1
    copy_into(active0, active)
    copy_into(cavity.q_prev, q)
