"""The film model: each physical term written once, as a small compiled function with its partial
derivatives, and the implicit step's residual, Jacobian and energy terms assembled from them.

Dimensionless, scale ``x1`` (docs/model.md, "Scales"). In ``s = R^2/2`` the Reynolds equation is a
1-D conservation law (docs/model.md, "Film equation")

    dH/dT = dq/ds,   q = (1/6) s H^3 dP/ds,   H = X + s + W,   W = K P,

integrated over finite volumes (integration/grid.py). The terms, one function each:

- ``flux_law`` (the formula) and ``face_flux`` (its drive): the flux between nodes ``i`` and
  ``i+1``,
  ``q_f = (P_{i+1} - P_i) s_f H_i^2 H_{i+1}^2 / (3 (s_{i+1} - s_i) (H_i + H_{i+1}))``, which
  holds ``s`` at its face value and integrates ``1/H^3`` across the face with ``H`` linear in ``s``:
  exact for the rigid pressure ``3V/H^2`` on any grid, so the stretched far field costs no accuracy;
- ``far_field_row``: the outer boundary node keeps ``P H^2`` equal to its neighbour's (rigid far
  field ``P = 3V/H^2``); the pressure beyond it is the tail ``P_L (R_L/R)^4``;
- ``cavitated`` and ``cell_constraint``: the pressure floor ``P >= -Pi`` of the Reynolds
  (Swift-Stieber) cavitation condition, a complementarity problem decided cell by cell (none in
  the classic film; docs/model.md, "Cavitation");
- ``deflection`` and ``gap``: the surface load that deflects the solids, ``W = K P``;
- ``film_force``: the load that moves them, ``Int P R dR = weight @ P``;
- ``face_dissipation``, ``far_field_dissipation``, ``strain_energy``, ``void_work``: the energy
  terms (docs/model.md, "Energy").

The unknowns of a step are ``y = (P_0..P_{N-1}, X, V)``; rows are scaled to gap units (``bh/area``
for the cells, ``bh`` for the motion), ``bh`` the implicit BDF coefficient times the step. The
physics array ``phys`` (solver/physics.py, ``Physics.as_array``) carries the dimensionless groups.
"""

import numpy as np

from .._jit import hook, jit, leaf
from ..integration.linalg import matvec
from ..physics import CAVITATION, CAVITATION_MODELS, PI, ST
from .liquid import (compression_energy, constant_density, density, isoviscous,
                     kirchhoff_between, mobility, volume_difference)
from .slip import flux_factor, slips

# the cavitation models' codes in the physics array (solver/physics.py: codes("cavitation"))
NO_FLOOR, REYNOLDS, JFO = (float(CAVITATION_MODELS.index(m)) for m in ("off", "reynolds", "jfo"))


# ---- the terms ------------------------------------------------------------------------------------
@jit
def flux_law(s_lo, s_hi, s_f, h_lo, h_hi, dp):
    """The flux through the face at ``s_f`` between nodes ``lo`` and ``hi`` driven by the
    pressure difference ``dp``, ``q_f = dp s_f H_lo^2 H_hi^2 / (3 (s_hi - s_lo) (H_lo + H_hi))``,
    its conductance ``dq/d(dp)`` and its partial derivatives in the gaps: the one place the
    formula is written (``face_flux``, ``face_fluxes`` and ``jacobian`` call it).

    Returns
    -------
    q, dq_ddp, dq_dh_lo, dq_dh_hi : float
    """
    ds3 = 3.0 * (s_hi - s_lo)
    sum_h = h_lo + h_hi
    q = s_f * h_lo * h_lo * h_hi * h_hi / (ds3 * sum_h) * dp
    k = s_f / ds3
    c = k * h_lo * h_lo * h_hi * h_hi / sum_h  # the conductance dq/d(dp)
    dq_dh_lo = dp * k * h_hi * h_hi * h_lo * (h_lo + 2.0 * h_hi) / (sum_h * sum_h)
    dq_dh_hi = dp * k * h_lo * h_lo * h_hi * (h_hi + 2.0 * h_lo) / (sum_h * sum_h)
    return q, c, dq_dh_lo, dq_dh_hi


@leaf
def face_flux(s_lo, s_hi, s_f, p_lo, p_hi, h_lo, h_hi, phys):
    """Flux ``q_f`` through the face at ``s_f`` between nodes ``lo`` and ``hi`` (``flux_law``),
    and its partial derivatives. The pressure difference that drives it is ``Int rho_bar/mu_bar
    dP`` (model/liquid.py: ``kirchhoff_difference``), ``P_hi - P_lo`` for the classic film: with
    it the film is isoviscous in the Kirchhoff variable, and the face stays exact for the rigid
    Barus film as it is for the classic one. Slip at the surfaces multiplies the flux by
    model/slip.py's ``flux_factor``.

    Returns
    -------
    q, dq_dp_lo, dq_dp_hi, dq_dh_lo, dq_dh_hi : float
    """
    return face_flux_between(s_lo, s_hi, s_f, p_lo, p_hi, mobility(p_lo, phys),
                             mobility(p_hi, phys), h_lo, h_hi, phys, True)


@leaf
def face_flux_between(s_lo, s_hi, s_f, p_lo, p_hi, at_lo, at_hi, h_lo, h_hi, phys, slopes):
    """``face_flux`` from the nodes' ``mobility`` (model/liquid.py; ``at_lo``, ``at_hi``), which
    the loops over the faces compute once per node; the pressure partials 0 unless ``slopes``
    (``liquid.kirchhoff_between``: a residual needs the flux alone)."""
    dp, ddp_lo, ddp_hi = kirchhoff_between(p_lo, at_lo, p_hi, at_hi, phys, slopes)
    q, c, dq_dh_lo, dq_dh_hi = flux_law(s_lo, s_hi, s_f, h_lo, h_hi, dp)
    g, dg_dh_lo, dg_dh_hi = flux_factor(h_lo, h_hi, phys)  # slip at the surfaces (model/slip.py)
    return (q * g, c * g * ddp_lo, c * g * ddp_hi, dq_dh_lo * g + q * dg_dh_lo,
            dq_dh_hi * g + q * dg_dh_hi)


@leaf
def face_dissipation(s_lo, s_hi, s_f, p_lo, p_hi, h_lo, h_hi, q, phys):
    """``Int J dP/ds ds`` over the face interval for the face's mass flux ``q`` (``J = q/rho_bar``
    the volume flux): with ``q ~ s`` and ``H`` linear in ``s`` as in ``flux_law`` it is
    ``q Int dP/rho_bar s_bar / s_f``, ``s_bar`` the mean of ``s`` under ``H^-3`` (exact for the
    rigid classic film; the plain ``q dP`` overestimates it on stretched cells). The viscosity
    does not enter: the volume flux is the same through the whole face interval; at constant
    density ``Int dP/rho_bar`` is ``P_hi - P_lo`` (model/liquid.py: ``volume_difference``)."""
    return dissipation_law(s_lo, s_hi, s_f, h_lo, h_hi, q, volume_difference(p_lo, p_hi, phys))


@leaf
def dissipation_law(s_lo, s_hi, s_f, h_lo, h_hi, q, dp):
    """``face_dissipation`` for the pressure work ``dp = Int dP/rho_bar`` per unit volume: ``q dp
    s_bar / s_f``, the one place the formula is written."""
    s_bar = s_lo + (s_hi - s_lo) * h_lo / (h_lo + h_hi)
    return q * dp * s_bar / s_f


@jit
def far_field_row(p_in, p_out, h_in, h_out):
    """Residual of the outer boundary node, ``P_L - P_{L-1} (H_{L-1}/H_L)^2`` (``P H^2`` constant,
    as in the rigid far field), and its partial derivatives.

    Returns
    -------
    r, dr_dp_in, dr_dp_out, dr_dh_in, dr_dh_out : float
    """
    ratio = h_in / h_out
    return (p_out - p_in * ratio * ratio, -ratio * ratio, 1.0,
            -2.0 * p_in * ratio / h_out, 2.0 * p_in * ratio * ratio / h_out)


@jit
def far_field_dissipation(x, s_last, p_last, h_last):
    """Dissipation beyond the grid end ``s_L``: the rigid film of velocity ``V = P_L H_L^2 / 3``;
    ``(2/(3 St))`` times this value is its part of ``D`` (docs/model.md, "Energy")."""
    v_far = p_last * h_last * h_last / 3.0
    xs = x + s_last
    return 6.0 * v_far * v_far * (1.0 / xs - x / (2.0 * xs * xs))


@leaf
def cavitated(p, r_film, was_cavitated, phys):
    """Whether a cell is in the cavity under the Reynolds (Swift-Stieber) condition, the
    complementarity ``P + Pi >= 0``, ``r >= 0``, ``(P + Pi) r = 0`` (``r`` the cell's film-equation
    residual: positive where the gap opens faster than the flux fills it). Decided as a
    primal-dual active set: a full cell cavitates when its pressure falls below the floor, a
    cavitated cell refills when its film equation would draw liquid in (``r < 0``); otherwise a
    cell keeps its state. The classic film never cavitates."""
    if phys[CAVITATION] == NO_FLOOR:
        return False
    if was_cavitated:
        return r_film >= 0.0
    return p + phys[PI] < 0.0


@leaf
def cell_constraint(p, phys):
    """The row that replaces the film equation of a cavitated cell, ``P + Pi = 0``, and its
    derivative in ``P``."""
    return p + phys[PI], 1.0


@leaf
def cell_content(theta, h, p, phys):
    """Liquid content of a cell per unit area, ``rho_bar theta H`` (``theta`` the fraction of the
    gap the liquid fills: 1 in a full cell, and in every cell of the classic and Reynolds films;
    ``rho_bar`` its density at the cell's pressure, model/liquid.py: 1 at constant density, where
    the content is exactly ``H``), and its partial derivatives in ``theta``, ``H`` and ``P``."""
    rho, drho = density(p, phys)
    return rho * theta * h, rho * h, rho * theta, drho * theta * h


@jit
def compression_work(area, p, h, theta, phys):
    """Energy stored in the compressed liquid, ``E_c = (2/(3 St)) Int rho_bar theta H e(P) ds``
    (``e`` per unit mass, model/liquid.py: ``compression_energy``), relative to the initial kinetic
    energy; 0 at constant density (docs/model.md, "Energy")."""
    if constant_density(phys):
        return 0.0
    total = 0.0
    for i in range(theta.size):  # the cells (the last node is the far-field boundary)
        total += area[i] * cell_content(theta[i], h[i], p[i], phys)[0] \
            * compression_energy(p[i], phys)
    return 2.0 * total / (3.0 * phys[ST])


@leaf
def jfo_cavitated(p, theta, was_cavitated, phys):
    """Whether a cell is in the cavity under the mass-conserving JFO / Elrod-Adams condition,
    ``(P + Pi)(1 - theta) = 0``, ``P >= -Pi``, ``theta <= 1``: a full cell cavitates when its
    pressure falls below the floor, a cavitated cell refills once its liquid fills the gap
    (``theta >= 1``); otherwise a cell keeps its state."""
    if was_cavitated:
        return theta < 1.0
    return p + phys[PI] < 0.0


@leaf
def cavity_edge(s, p, active, phys):
    """Radius of the outer edge of the cavity (0 without one). Outside a cavity edge ``s_c`` the
    film leaves the floor with zero slope, ``P + Pi ~ c (s - s_c)^2``, so ``sqrt(P + Pi)`` is
    linear in ``s``: extrapolated from the two full nodes past the outermost cavitated one, the
    edge is second-order accurate instead of a node position."""
    last = -1
    for i in range(active.size):
        if active[i]:
            last = i
    if last < 0:
        return 0.0
    s_c = s[last]
    if last + 2 < s.size:
        e1 = np.sqrt(max(p[last + 1] + phys[PI], 0.0))
        e2 = np.sqrt(max(p[last + 2] + phys[PI], 0.0))
        if e2 > e1:
            s_c = s[last + 1] - e1 * (s[last + 2] - s[last + 1]) / (e2 - e1)
            # the discrete edge may lie up to a cell either side of the outermost cavitated node
            s_c = min(max(s_c, s[last - 1] if last > 0 else 0.0), s[last + 1])
    return np.sqrt(2.0 * s_c)


@leaf
def void_work(area, h_new, h_old, q_new, q_old, dt, active, phys):
    """Work done against the floor over a step, ``(2/(3 St)) Pi dV_void`` (relative to the initial
    kinetic energy; docs/model.md, "Energy"): the energy that goes into creating the void. The
    void a cavitated cell gains is its opening ``area dH`` less the liquid its faces bring in,
    ``dt dq`` (trapezoidal in time; ``q`` the face fluxes at the two states): zero inside a
    cavity, where the pressure is flat, but not at its edge cells, which the film feeds."""
    total = 0.0
    for i in range(active.size):
        if active[i]:
            inflow_new = q_new[i] - (q_new[i - 1] if i > 0 else 0.0)
            inflow_old = q_old[i] - (q_old[i - 1] if i > 0 else 0.0)
            total += area[i] * (h_new[i] - h_old[i]) - 0.5 * dt * (inflow_new + inflow_old)
    return 2.0 * phys[PI] * total / (3.0 * phys[ST])


@leaf
def jfo_void(area, theta, h, active):
    """Void volume of a JFO film, ``sum_cav area (1 - theta) H``: the gap its cavitated cells'
    liquid does not fill. The film's discrete mass balance is exact, so the work against the floor
    over a step is ``(2/(3 St)) Pi`` times its change (``void_work`` counts the same with the
    fluxes integrated by the trapezoidal rule, which the BDF2 mass balance does not match: its
    closure was 5-11x worse, measured at rtol 1e-4 to 1e-6)."""
    total = 0.0
    for i in range(active.size):
        if active[i]:
            total += area[i] * (1.0 - theta[i]) * h[i]
    return total


@jit
def deflection(influence, p, w_out):
    """Surface deflection ``W = K P`` of both solids under the film pressure."""
    matvec(influence, p, w_out)


@jit
def gap(s, influence, x, p, w_out, h_out):
    """``W = K P`` and ``H = X + s + W`` into ``w_out``, ``h_out``."""
    deflection(influence, p, w_out)
    for i in range(s.size):
        h_out[i] = x + s[i] + w_out[i]


@jit
def film_force(weight, p):
    """``Int P R dR = weight @ P`` (pressure on the shaped basis of elasticity.py, tail included);
    its derivative in ``P`` is ``weight``. The force on the spheres in units of
    ``6 pi mu a^2 v0 / x1`` is a third of it, so ``dV/dT = -film_force / (3 St)``."""
    force = 0.0
    for i in range(p.size):
        force += weight[i] * p[i]
    return force


@jit
def strain_energy(weight, s_last, p, w, phys):
    """Strain energy ``E_s = (1/(3 St)) Int P W R dR`` relative to the initial kinetic energy,
    with the far-field tail (``W ~ W_L R_L / R``)."""
    n = p.size
    strain = 0.0
    for i in range(n):
        strain += weight[i] * p[i] * w[i]
    # weight[-1] counted the tail as P_L W_L R_L^2/2; the 1/R decay of W gives R_L^2/3 instead
    strain -= p[n - 1] * w[n - 1] * (2.0 * s_last) / 6.0
    return strain / (3.0 * phys[ST])


# ---- assembled from the terms ---------------------------------------------------------------------
@hook
def plain_flux(phys):
    """The face flux is ``flux_law`` with the drive ``P_hi - P_lo``: an isoviscous liquid that
    does not slip, decided once per call by the loops over the faces."""
    if isoviscous(phys) and not slips(phys):
        return True
    return False


@hook
def face_fluxes(grid, p, h, phys, q_out):
    """Face fluxes ``q_f`` of every face of the grid ``grid`` (integration/grid.py: ``Nodes``)
    into ``q_out`` (N-1 entries). The liquid's law is decided once, outside the loop: for an
    isoviscous liquid the drive is ``P_hi - P_lo`` (``kirchhoff_difference``'s value there) and
    the loop, ``flux_law`` inlined, is one the compiler vectorises (the liquid's law called per
    face made the classic residual slower, measured in docs/solver.md: 19 us against 0.6 us);
    slip (model/slip.py) and the pressure-dependent liquids take ``general_fluxes``. Inlined
    into its callers (``hook``), so the choice costs them no reference counts."""
    s, s_face = grid.s, grid.s_face
    if plain_flux(phys):
        for f in range(s.size - 1):
            q_out[f] = flux_law(s[f], s[f + 1], s_face[f], h[f], h[f + 1], p[f + 1] - p[f])[0]
    else:
        general_fluxes(s, s_face, p, h, phys, q_out)


@leaf
def general_fluxes(s, s_face, p, h, phys, q_out):
    """``face_fluxes`` for any liquid law and slip (nodes ``s``, faces ``s_face``): at every face
    ``face_flux_between``'s flux without its partials, the same to the bit (the Kirchhoff
    difference's value alone, the flux law, the slip factor: a call less per face), each node's
    ``mobility`` taken once and passed on to the next face. A ``leaf``, so it takes the grid's
    arrays rather than its record."""
    at_hi = mobility(p[0], phys)
    for f in range(s.size - 1):
        at_lo, at_hi = at_hi, mobility(p[f + 1], phys)
        dp = kirchhoff_between(p[f], at_lo, p[f + 1], at_hi, phys, False)[0]
        q_out[f] = flux_law(s[f], s[f + 1], s_face[f], h[f], h[f + 1], dp)[0] \
            * flux_factor(h[f], h[f + 1], phys)[0]


@jit
def residual(grid, phys, step, x, v, p, theta, h, q, res):
    """Scaled residual of one implicit step with the film equation in every cell: the cell's
    liquid content ``cell_content(theta_i, H_i)`` against its history, ``theta H - C_hist =
    bh dq/ds`` (``C_hist`` the BDF combination of the content at the accepted states; full cells
    have ``theta = 1``, and ``1 * H = H`` bit for bit), the far-field boundary row,
    ``X - X_hist = -bh V`` and ``V - V_hist = -bh F/(3 St)``. ``q`` holds the face fluxes of
    ``p``, ``h`` (``face_fluxes``, which the caller calls first: this function then calls none
    that is not inlined, and numba counts no reference in it; docs/solver.md, "Reference
    counting"). ``constrain`` then replaces the rows of Reynolds-cavitated cells; the JFO film
    keeps these rows in its cavitated cells, where the unknown is ``theta``. ``grid`` is the scene's
    (integration/grid.py: ``Nodes``), ``step`` the attempt's ``bh`` and history (model/state.py:
    ``Step``)."""
    s, area = grid.s, grid.area
    bh, c_hist = step.bh, step.c_hist
    n = s.size
    # one loop, the density's law chosen inside it: the compiler still makes two loops of it and
    # vectorises the first, and numba's reference counts, which a loop in each branch of an if
    # kept, are all removed (docs/solver.md, "Reference counting"); numba prunes the choice from
    # a copy of the loop without the liquid's laws (model/kind.py)
    constant = constant_density(phys)  # the content is theta H (cell_content with rho = 1)
    for i in range(n - 1):
        dq = q[i] - (q[i - 1] if i > 0 else 0.0)
        content = theta[i] * h[i] if constant else cell_content(theta[i], h[i], p[i], phys)[0]
        res[i] = content - c_hist[i] - bh / area[i] * dq
    res[n - 1] = far_field_row(p[n - 2], p[n - 1], h[n - 2], h[n - 1])[0]
    res[n] = x - step.x_hist + bh * v
    res[n + 1] = v - step.v_hist + bh * film_force(grid.weight, p) / (3.0 * phys[ST])


@leaf
def update_cavity(p, res, phys, active):
    """Update from the film rows ``res`` (before ``constrain``) which cells are cavitated, in
    ``active``; returns whether that changed."""
    changed = False
    for i in range(active.size):
        a = cavitated(p[i], res[i], active[i], phys)
        if a != active[i]:
            active[i] = a
            changed = True
    return changed


@leaf
def update_cavity_jfo(p, theta, phys, active):
    """The JFO active set (``jfo_cavitated``) from the iterate's pressures and fractions, with
    the slot switch: a cell that cavitates starts at ``theta = 1`` with ``P = -Pi`` fixed; a cell
    that refills is full (``theta = 1``) and its slot is ``P`` again, starting at ``-Pi``. Returns
    whether the set changed."""
    changed = False
    for i in range(active.size):
        a = jfo_cavitated(p[i], theta[i], active[i], phys)
        if a != active[i]:
            active[i] = a
            changed = True
            theta[i] = 1.0
            p[i] = -phys[PI]
    return changed


@leaf
def constrain(p, res, active, phys):
    """Replace the film rows of the cavitated cells by their constraint rows."""
    for i in range(active.size):
        if active[i]:
            res[i] = cell_constraint(p[i], phys)[0]


@jit
def jacobian(grid, phys, bh, p, theta, h, active, link, jac, dres_dh):
    """Jacobian of ``residual`` with respect to the slots ``(y, X, V)`` into ``jac`` (N+2, N+2),
    from the terms' partial derivatives.

    The cell rows depend on the gap at three nodes, and the gap on every slot through ``K``:
    ``J = (dres/dH) K + dres/dP``, with ``dres_i/dH_i`` the content's ``theta_i``. ``link``
    (model/state.py: ``Coupling``) holds ``dH/dy`` (``K``, or a rough film's, model/contact.py),
    ``dH/dX`` (ones without contact), the force's derivatives (``weight`` and 0 without
    contact), and ``dP/dH`` (empty: ``y = P``) of a film whose pressure is not its slot (a rough
    film's slot holds the total load, ``P = y - p_a(H)``: ``J = (dres/dH + dres/dP dP/dH) dH/dy
    + dres/dP``). Cavitated cells
    (``active``, N-1 entries): under the Reynolds condition their rows are their constraint's;
    under JFO their rows stay the content rows and their slot is ``theta_i`` (``P_i = -Pi``
    fixed), so the slot's column is ``d row_i / d theta_i = H_i e_i``. ``dres_dh`` (N, 3) is work
    space (columns i-1, i, i+1)."""
    s, s_face, area, force_dp = grid.s, grid.s_face, grid.area, link.force_dp
    n = s.size
    jac[:, :] = 0.0
    dres_dh[:, :] = 0.0
    classic_flux = plain_flux(phys)  # pruned, with face_flux, from a copy without its pieces
    at_hi = mobility(p[0], phys)  # each node's, once (model/liquid.py)
    for f in range(n - 1):
        if classic_flux:  # face_flux with the isoviscous drive P_hi - P_lo, decided once
            _, c, dq_dhi, dq_dhj = flux_law(s[f], s[f + 1], s_face[f], h[f], h[f + 1],
                                            p[f + 1] - p[f])
            dq_dpi = -c
            dq_dpj = c
        else:
            at_lo, at_hi = at_hi, mobility(p[f + 1], phys)
            _, dq_dpi, dq_dpj, dq_dhi, dq_dhj = face_flux_between(
                s[f], s[f + 1], s_face[f], p[f], p[f + 1], at_lo, at_hi, h[f], h[f + 1], phys,
                True)
        # row f: -bh/area_f * (+q_f);  row f+1 (if a cell row): -bh/area_{f+1} * (-q_f)
        g = bh / area[f]
        jac[f, f] -= g * dq_dpi
        jac[f, f + 1] -= g * dq_dpj
        dres_dh[f, 1] -= g * dq_dhi
        dres_dh[f, 2] -= g * dq_dhj
        if f + 1 < n - 1:
            g = bh / area[f + 1]
            jac[f + 1, f] += g * dq_dpi
            jac[f + 1, f + 1] += g * dq_dpj
            dres_dh[f + 1, 0] += g * dq_dhi
            dres_dh[f + 1, 1] += g * dq_dhj
    if constant_density(phys):  # cell_content's partials with rho = 1
        for i in range(n - 1):
            dres_dh[i, 1] += theta[i]
    else:
        for i in range(n - 1):
            _, _, dc_dh, dc_dp = cell_content(theta[i], h[i], p[i], phys)
            dres_dh[i, 1] += dc_dh
            jac[i, i] += dc_dp
    _, dr_dpi, dr_dpo, dr_dhi, dr_dho = far_field_row(p[n - 2], p[n - 1], h[n - 2], h[n - 1])
    jac[n - 1, n - 1] += dr_dpo
    jac[n - 1, n - 2] += dr_dpi
    dres_dh[n - 1, 0] = dr_dhi
    dres_dh[n - 1, 1] = dr_dho
    jfo = phys[CAVITATION] == JFO
    if not jfo:
        for i in range(n - 1):  # an active constraint replaces the whole row
            if active[i]:
                jac[i, :] = 0.0
                dres_dh[i, :] = 0.0
                jac[i, i] = cell_constraint(p[i], phys)[1]
    _through_gap(link, jac, dres_dh)
    jac[n, n] = 1.0
    jac[n, n + 1] = bh
    for j in range(n):
        jac[n + 1, j] = bh * force_dp[j] / (3.0 * phys[ST])
    jac[n + 1, n] = bh * link.force_dx / (3.0 * phys[ST])
    jac[n + 1, n + 1] = 1.0
    if jfo:  # a cavitated cell's slot is theta (P = -Pi fixed): its column is d row_i/d theta_i
        for i in range(n - 1):
            if active[i]:
                jac[:, i] = 0.0
                jac[i, i] = cell_content(theta[i], h[i], p[i], phys)[1]


@jit
def _through_gap(link, jac, dres_dh):
    """The gap's part of the film rows' Jacobian (``jacobian``): the chain rule through ``H = X +
    s + K P`` (``link.dh_dy``, ``link.dh_dx``), from the rows' gap partials ``dres_dh`` (N, 3),
    to which the pressure partials add first where ``P`` follows the gap (``link.dp_dh``)."""
    n = dres_dh.shape[0]
    influence, dh_dx, dp_dh = link.dh_dy, link.dh_dx, link.dp_dh
    if dp_dh.size:  # P = y - p_a(H): the pressure partials reach the gap too
        for i in range(n):
            for k in range(max(i - 1, 0), min(i + 2, n)):
                dres_dh[i, k - i + 1] += jac[i, k] * dp_dh[k]
    for i in range(n):
        lo = i - 1 if i > 0 else 0
        hi_ = i + 1 if i < n - 1 else n - 1
        dx = 0.0
        for k in range(lo, hi_ + 1):
            d = dres_dh[i, k - i + 1]
            if d != 0.0:
                dx += d * dh_dx[k]
                for j in range(n):
                    jac[i, j] += d * influence[k, j]
        jac[i, n] = dx


@jit
def energy_rates(s, s_face, weight, phys, x, p, w, h, q):
    """Strain energy ``E_s`` and dissipation rate ``D = (2/(3St)) Int q dP/ds ds`` (both relative to
    the initial kinetic energy; equal to ``(1/(18 St)) Int H^3 (dP/dR)^2 R dR``, docs/model.md,
    "Energy"), far field included. ``q`` must hold the face fluxes of ``p, h``."""
    n = s.size
    strain = strain_energy(weight, s[n - 1], p, w, phys)
    diss = 0.0
    if constant_density(phys):  # the volume difference is P_hi - P_lo: decided once
        for f in range(n - 1):
            diss += dissipation_law(s[f], s[f + 1], s_face[f], h[f], h[f + 1], q[f],
                                    p[f + 1] - p[f])
    else:
        for f in range(n - 1):
            diss += face_dissipation(s[f], s[f + 1], s_face[f], p[f], p[f + 1], h[f], h[f + 1],
                                     q[f], phys)
    diss += far_field_dissipation(x, s[n - 1], p[n - 1], h[n - 1])
    return strain, 2.0 * diss / (3.0 * phys[ST])
