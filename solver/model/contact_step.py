"""The asperity contact's part of the film's contract (model/step.py): what a rough film asks of
the time loop beyond the classic film (docs/model.md, "Surface roughness", "Losses in the
solids"; the law and its gap in model/contact.py).

Each hook reads the physics array and leaves the classic film's answer for smooth surfaces, so
model/step.py calls it unconditionally. A rough film's slot holds the total load ``T = P +
p_a(H)`` its surfaces carry (a JFO cavity's cell, held at the floor, excepted: model/
cavity_step.py); its state is the ``Contact`` record of model/state.py: the contact and film
pressures of the last gap computed, the unloading's set state, the film pressure's history.
"""

import numpy as np

from .._jit import copy_into, filled, hook, jit
from ..observables import SERIES_INDEX
from ..physics import E_DRY, PI, ST
from .cavity_step import held_cells
from .contact import (FREE, asperity_work, contact_derivatives, contact_gap, contact_slopes,
                      contact_state)
from .film import film_force, gap, strain_energy
from .kind import CONTACT_CODE, asks_contact
from .state import Coupling

# a rough film's Newton measures the change of its film pressure against its own size or this
# fraction of the asperities' pressure, whichever is larger (film_change)
CONTACT_SHARE = 0.01

_E_A, _LOST, _F_A = SERIES_INDEX["E_a"], SERIES_INDEX["solid_loss"], SERIES_INDEX["F_contact"]
_V, _X, _E_S = SERIES_INDEX["V"], SERIES_INDEX["X"], SERIES_INDEX["E_s"]


@hook
def on(phys):
    """Whether the surfaces are rough (asperity contact, model/contact.py): the slots hold loads.
    False in a copy of the loop without the contact's code (model/kind.py)."""
    if CONTACT_CODE:
        return asks_contact(phys)
    return False


@jit
def _held(film, phys):
    """The nodes held at the floor now (cavity_step.held_cells), into the contact's work array
    (a rough film asks at every Newton iteration: no allocation there)."""
    held = film.contact.held
    held_cells(film.cavity, phys, held)
    return held


@hook
def surface_gap(grid, phys, y, film, w, h):
    """The deflection ``W`` and gap ``H`` of the iterate ``y`` into ``w``, ``h``: ``W = K y``
    for a smooth film (film.gap); a rough film's with the contact pressure and film pressure
    they imply (contact.contact_gap, whose cells held at the floor are a JFO cavity's, solved
    from the gap ``h`` holds; a contact solve that fails leaves ``h`` NaN, which the loop treats
    as a failed iterate)."""
    n = grid.s.size
    if not on(phys):
        gap(grid.s, grid.influence, y[n], y[:n], w, h)
        return
    if not contact_gap(grid, y[n], y, film.contact, _held(film, phys), phys, w, h):
        h[:] = np.nan


@hook
def film_pressure(y, film, phys):
    """The film pressure of the state whose gap ``surface_gap`` computed last: the slots
    themselves for a smooth film (no copy), ``y - p_a`` where rough surfaces touch."""
    n = y.size - 2
    if not on(phys):
        return y[:n]
    return film.contact.p_film


@jit
def hold_switched(y, film, phys):
    """A JFO slot that switched to the floor (model/cavity_step.decide) holds the load at the
    floor, ``-Pi + p_a``, on rough surfaces (their gap is evaluated again next)."""
    if not on(phys):
        return
    cavity, pa = film.cavity, film.contact.pa
    active, was = cavity.active, cavity.active_was
    for i in range(active.size):
        if active[i] != was[i]:
            y[i] = -phys[PI] + pa[i]


@hook
def relaxing_deflection(w, w_absmax, film, phys):
    """The largest ``|W|`` the terminal events wait to relax (``w_absmax``, ``max |W|``): a rough
    film's permanent set (model/contact.py) never relaxes, so ``max |W - (1 - c) K T_set|``."""
    if not on(phys) or film.contact.load_scale[0] == 1.0:
        return w_absmax
    w_set = film.contact.w_set
    out = 0.0
    for i in range(w.size):
        out = max(out, abs(w[i] - w_set[i]))
    return out


@hook
def total_force(weight, y, film, phys):
    """``Int (P + p_a) R dR``, the force on the spheres (film.film_force), with the film and
    contact pressures of the last ``surface_gap``."""
    n = weight.size
    if not on(phys):
        return film_force(weight, y[:n])
    return film_force(weight, film.contact.p_film) + film_force(weight, film.contact.pa)


@hook
def strain(grid, phys, p, w, film, smooth_strain):
    """The strain energy of a rough film: of the total load ``P + p_a`` on the elastic part of
    ``W`` (less the permanent set); ``smooth_strain`` (film.energy_rates') for a smooth one."""
    if not on(phys):
        return smooth_strain
    n = grid.s.size
    pa, w_set = film.contact.pa, film.contact.w_set
    return strain_energy(grid.weight, grid.s[n - 1], p + pa, w - w_set, phys)


@hook
def motion(weight, phys, bh, film, res):
    """The contact load's part of the motion row of ``film.residual``: ``bh F_a / (3 St)``, with
    the contact pressure of the last ``surface_gap`` (nothing for a smooth film)."""
    if on(phys):
        res[weight.size + 1] += bh * film_force(weight, film.contact.pa) / (3.0 * phys[ST])


@jit
def coupling(grid, phys, film):
    """How the gap and the force follow the slots (state.Coupling, for film.jacobian): ``K``,
    ones, ``weight`` and 0 for a smooth film. A rough film's film pressure follows the gap where
    its slot is the load (contact.contact_slopes); its gap follows the slots through ``c K``
    while the solids unload, and a touching JFO cavity's gap and the force through its contact
    (contact.contact_derivatives)."""
    n = grid.s.size
    if not on(phys):
        return Coupling(grid.influence, filled(n, 1.0), grid.weight, 0.0, np.empty(0))
    c, slope = film.contact.load_scale[0], film.contact.slope
    held = _held(film, phys)
    dp_dh = np.empty(n)
    m = contact_slopes(slope, held, dp_dh)
    if m == 0 and c == 1.0:
        return Coupling(grid.influence, filled(n, 1.0), grid.weight, 0.0, dp_dh)
    k_eff = np.empty((n, n))
    dh_dx = np.empty(n)
    force_dp = np.empty(n)
    force_dx = contact_derivatives(grid.influence, grid.weight, slope, c, held, m, k_eff,
                                   dh_dx, force_dp)
    return Coupling(k_eff, dh_dx, force_dp, force_dx, dp_dh)


@hook
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
    if not on(phys):
        return dy, y[:n]
    held = _held(film, phys)
    contact = film.contact
    p, pa = contact.p_film, contact.pa
    scale, slope = contact.p_scale, contact.slope
    for i in range(n):
        dp[i] = dy[i]
        if not held[i]:
            dp[i] -= slope[i] * dh[i]
        scale[i] = abs(p[i]) + CONTACT_SHARE * pa[i]
    return dp, scale


@hook
def record(row, grid, h, film, phys):
    """The contact's columns of the series row (contact force, asperity energy, the energy lost
    in the solids; 0 for smooth surfaces), and what it tells the end of the coupled phase
    (contact.contact_state: ``FREE``, ``HOLD`` while near contact, ``REST`` at rest on its
    asperities)."""
    contact = film.contact
    row[_F_A] = 0.0
    row[_E_A] = 0.0
    row[_LOST] = contact.solid_lost[0]
    if not on(phys):
        return FREE
    row[_F_A] = film_force(grid.weight, contact.pa)
    row[_E_A] = asperity_work(grid.weight, h, contact.load_scale[0], contact.h_set, phys)
    return contact_state(h, row[_X], row[_V], row[_E_S] + row[_E_A], phys)


@hook
def accept(grid, y0, w, h0, film, phys):
    """A rough film's state after an accepted step (``y0`` its solution, ``w`` and ``h0`` its
    deflection and gap): the onset of the solids' unloading (``unload``)."""
    if on(phys):
        unload(grid, y0, w, h0, film.contact, phys)


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
