"""Asperity contact: the surface load that depends on the gap, and the losses where the solids
touch (docs/model.md, "Surface roughness", "Losses in the solids").

Dimensionless, scale ``x1``. Each surface carries asperities; where the local mean gap ``H``
falls below the height of the tallest summits, the combined rms roughness ``sigma``
(``phys[ROUGHNESS]``), they touch and carry the contact pressure of Greenwood & Williamson (1966),
Hertzian summits whose heights ``z`` are spread over the band ``0 < z < sigma`` above the mean
plane with the parabolic density ``phi(z) = (6 / sigma^3) z (sigma - z)``:

    p_a(H) = k (sigma / H) Int_H^sigma (z - H)^(3/2) phi(z) dz
           = k (sigma / H) (2/105) w^(3/2) D^(7/2) (9 - 2 D),     D = (sigma - H) / w,  w = sigma/2,

for ``0 < H < sigma`` (0 for ``H >= sigma``), ``k`` the asperity stiffness (``phys[ASPERITY_K]``).
The density vanishes linearly at the tallest summit, so the law starts as ``(24/35) k (sigma -
H)^(7/2) / sigma^2``: three times continuously differentiable at first touch, which keeps the
solution smooth in time as the contact's edge sweeps over the nodes (a single summit height,
``k (sigma - H)^(3/2)``, has an infinite second derivative there, and every node it crossed cost
the time stepping several rejected steps). The factor ``sigma / H`` closes the asperity layer
where the mean planes would meet (the flattened summits fill the valleys), so the gap stays
positive under any load. ``k -> inf`` is the hard cut-off: contact at ``H = sigma`` (the
penetration falls like ``k^(-2/9)`` to ``k^(-2/7)``, tests/test_contact.py). The film flows
through the mean gap ``H`` (flow factors of the rough gap are 1 to within a few percent for
``H > 3 sigma``, Patir & Cheng 1978, and the load is carried by the asperities below it).

The contact pressure deflects both solids through the same kernel as the film pressure: with
``T = P + p_a(H)`` the total surface load,

    H = X + s + K L,    L = c T + (1 - c) T_set,

``c = 1`` while the solids load. The losses in the solids (``e_dry``, ``phys[E_DRY]``): once the
spheres have touched on approach, from the instant they stop (``V <= 0``) the solids unload
along a stiffer line, ``c = e_dry^2``, through the load ``T_set`` of that instant (a permanent set
``(1 - c) K T_set``: the Walton & Braun (1986) hysteresis, written for the whole surface). The
elastic energy the solids then return is ``c`` times what they stored, so a dry impact restitutes
exactly ``e_dry`` of its speed; a collision that never touches is unchanged.

The unknown of a cell whose film pressure is free is its total load ``T`` (``contact_gap``): the
gap is then explicit, ``P = T - p_a(H)``, and the Jacobian couples ``P`` to the gap through the
contact's slope (``contact_gap`` computes it with the gap; ``contact_slopes``), as cheap as the
smooth film's. Only a cell held at a floor (a JFO cavity) has ``P`` fixed and its load follows
its gap; where it touches, its gap is implicit and solved by Newton, with ``(I - c K_CC D)`` its
matrix, ``D = dp_a/dH <= 0``, and the derivatives follow by the implicit function theorem
(``contact_derivatives``).
"""

import numpy as np

from .._jit import filled, jit
from ..integration.linalg import lu_factor, lu_solve, matmul, matvec
from ..physics import ASPERITY_K, PI, ROUGHNESS, ST

# Int_0^D (D - t)^1.5 (3/4) t (2 - t) dt = (2/105) D^3.5 (9 - 2 D): the summits' parabolic
# height density in units of their spread w = sigma/2 (asperity_pressure)
SUMMITS = 2.0 / 105.0
# the rigid film holds where every gap is at least this many roughnesses: the coupled phase
# starts before it on approach (rigid.contact_onset_separation) and ends after it on departure
CONTACT_MARGIN = 2.0
# a film near contact whose spheres move slower than this (in v0) rests on its asperities
REST_SPEED = 1e-6
# ... and so does a film at rest whose mean planes overlap (X <= 0, a permanent set's dent) once
# the solids hold less energy than the spheres' at REST_SPEED: nothing is left to part them, and
# no rigid departure starts from X <= 0 (St 30, eps 1e-4, roughness 1, e_dry 0.5: the spheres
# at rest in their dent, V 5e-13, the strain energy 1e-26, gaps 2.5 roughnesses: the phase ran on
# until its steps underflowed, at every preset)
REST_ENERGY = REST_SPEED**2
MAX_ITERATIONS = 60
GAP_TOL = 1e-12  # Newton tolerance of the contact gap, of sigma: far below any step tolerance


@jit
def asperity_pressure(h, phys):
    """``p_a(H)`` and ``dp_a/dH`` (module docstring); ``inf`` for ``H <= 0``."""
    sigma = phys[ROUGHNESS]
    if h >= sigma:
        return 0.0, 0.0
    if h <= 0.0:
        return np.inf, -np.inf
    k = phys[ASPERITY_K]
    w = 0.5 * sigma
    d = (sigma - h) / w
    d25 = d * d * np.sqrt(d)
    scale = k * sigma * SUMMITS * w * np.sqrt(w)  # k sigma (2/105) w^1.5
    load = scale * d25 * d * (9.0 - 2.0 * d)  # sigma/H aside: k sigma Int (z - H)^1.5 phi dz
    slope = -scale / w * d25 * (31.5 - 9.0 * d)
    return load / h, (slope - load / h) / h


@jit
def contact_pressure(h, h_set, c, phys):
    """The asperities' pressure and its derivative in ``H`` while loading (``c = 1``:
    ``asperity_pressure``) and while unloading from the gap ``h_set`` of the onset: the loading
    law read at ``h_set + (H - h_set)/c``, so the asperities give back ``c`` times the work they
    took, as the bulk does (Walton & Braun 1986). A node whose asperities were not touching at
    the onset (``h_set >= sigma``) was never loaded: it keeps the loading law."""
    if c == 1.0 or h_set >= phys[ROUGHNESS]:
        return asperity_pressure(h, phys)
    p, d = asperity_pressure(h_set + (h - h_set) / c, phys)
    return p, d / c


@jit
def asperity_energy(h, phys):
    """Energy stored in the asperities per unit area, ``Int_H^sigma p_a dh``. With ``D = (sigma -
    H)/w`` and ``sigma / h = 2 / (2 - D)`` it is ``k sigma (2/105) w^1.5 ((4/9) D^4.5 + 5 J(D))``,
    ``J(D) = Int_0^D t^3.5 / (2 - t) dt``: the series ``sum_j D^(4.5+j) / ((4.5 + j) 2^(j+1))``
    for ``D <= 1``, else, with ``U^2 = D``, ``2 (8 sqrt(2) atanh(U / sqrt(2)) - 8 U - (4/3) U^3 -
    (2/5) U^5 - U^7 / 7)`` (which cancels for small ``D``). Near first touch ``(16/105) k (sigma -
    H)^4.5 / sigma^2``."""
    sigma = phys[ROUGHNESS]
    if h >= sigma:
        return 0.0
    if h <= 0.0:
        return np.inf
    w = 0.5 * sigma
    d = (sigma - h) / w
    if d <= 1.0:
        j_d = 0.0
        term = d ** 4.5 * 0.5  # D^(4.5+j) / 2^(j+1), j = 0
        j = 0
        while True:
            add = term / (4.5 + j)
            j_d += add
            if add < 1e-17 * j_d:
                break
            term *= 0.5 * d
            j += 1
    else:
        u = np.sqrt(d)
        u2 = d
        j_d = 2.0 * (8.0 * np.sqrt(2.0) * np.arctanh(u / np.sqrt(2.0))
                     - u * (8.0 + u2 * (4.0 / 3.0 + u2 * (0.4 + u2 / 7.0))))
    return phys[ASPERITY_K] * sigma * SUMMITS * w * np.sqrt(w) \
        * ((4.0 / 9.0) * d ** 4.5 + 5.0 * j_d)


@jit
def contact_gap(grid, x, y, contact, held, phys, w, h):
    """The gap and the film pressure of a rough film (docs/solver.md, "Surface roughness").

    The slot ``y_i`` of each node holds its total surface load ``T_i = P_i + p_a(H_i)``. Where
    the film pressure is free, the gap follows explicitly, ``H = X + s + K (c y + (1 - c)
    T_set)``, and the film pressure is ``P_i = y_i - p_a(H_i)``. A cell held at the floor
    (``held``: a JFO cavity, whose unknown is its liquid fraction) has ``P_i = -Pi``; where its
    asperities touch, its load ``-Pi + p_a(H_i)`` depends on the gap it makes, and those cells'
    gaps are solved together by Newton from the gap ``h`` holds on entry (the previous iterate's;
    any value, it is clipped into ``(0, sigma]``); their slots receive their loads. Reads the
    unloading's ``c``, ``T_set``, ``H_set`` from ``contact`` (model/state.py: ``Contact``) and
    writes ``p_a`` into its ``pa``, ``dp_a/dH`` into its ``slope`` (what the Jacobian and the
    Newton's norm read at this gap), ``P`` into its ``p_film``; ``W`` into ``w``, ``H`` into
    ``h``; returns False when that Newton did not converge."""
    s, influence = grid.s, grid.influence
    c, t_set, h_set = contact.load_scale[0], contact.t_set, contact.h_set
    pa, slope, p = contact.pa, contact.slope, contact.p_film
    n = s.size
    sigma = phys[ROUGHNESS]
    load = contact.load  # the elastic load of every node: the set's part too while unloading
    for i in range(n):
        own = -phys[PI] if held[i] else y[i]
        load[i] = own if c == 1.0 else c * own + (1.0 - c) * t_set[i]
    matvec(influence, load, w)
    idx = contact.touching  # the held cells that touch (their gap is implicit)
    m = 0
    for i in range(n):
        pa[i] = 0.0
        if held[i] and x + s[i] + w[i] < sigma:
            idx[m] = i
            m += 1
    converged = True
    if m > 0:
        converged = _implicit_gap(s, influence, x, c, h_set, phys, idx[:m], pa, w, h)
    for i in range(n):
        h[i] = x + s[i] + w[i]
        law, slope[i] = contact_pressure(h[i], h_set[i], c, phys)
        if held[i]:
            p[i] = -phys[PI]
            y[i] = p[i] + pa[i]
        else:
            pa[i] = law
            p[i] = y[i] - pa[i]
    return converged


@jit
def _implicit_gap(s, influence, x, c, h_set, phys, idx, pa, w, h):
    """``contact_gap``'s Newton for the gaps of the touching cells held at a floor (nodes
    ``idx``), ``H = base + c K_CC p_a(H)`` (``base``: ``X + s + w`` without their contact), from
    the gaps ``h`` holds; adds their contact pressure to ``w`` and writes it into ``pa``."""
    n = s.size
    m = idx.size
    sigma = phys[ROUGHNESS]
    kcc = np.empty((m, m))
    base = np.empty(m)
    hc = np.empty(m)
    for a in range(m):
        base[a] = x + s[idx[a]] + w[idx[a]]
        for b in range(m):
            kcc[a, b] = c * influence[idx[a], idx[b]]
        g = h[idx[a]]
        hc[a] = min(max(g, 0.5 * max(base[a], 0.0)), sigma) if np.isfinite(g) and g > 0.0 \
            else max(0.5 * base[a], 0.5 * sigma)
        # inside the law's open layer: above where it closes (0, or a loaded node's unloading
        # law's closing gap, contact_pressure), where a guess below gave p_a = inf
        closed = h_set[idx[a]] * (1.0 - c) if c != 1.0 and h_set[idx[a]] < sigma else 0.0
        if hc[a] <= closed:
            hc[a] = closed + 0.5 * (sigma - closed)
    pc = np.empty(m)
    dc = np.empty(m)
    mat = np.empty((m, m))
    rhs = np.empty(m)
    piv = np.empty(m, dtype=np.int32)
    converged = False
    fresh = True  # factorise the matrix at the next iteration (chord iterations in between)
    step_prev = np.inf
    for _ in range(MAX_ITERATIONS):
        for a in range(m):
            pc[a], dc[a] = contact_pressure(hc[a], h_set[idx[a]], c, phys)
        for a in range(m):
            r = hc[a] - base[a]
            for b in range(m):
                r -= kcc[a, b] * pc[b]
            rhs[a] = -r
        if fresh:
            for a in range(m):
                for b in range(m):
                    mat[a, b] = -kcc[a, b] * dc[b]
                mat[a, a] += 1.0
            if not _all_finite(mat) or not lu_factor(mat, piv):
                return False
        dh = lu_solve(mat, piv, rhs)
        step = 0.0
        for a in range(m):
            new = hc[a] + dh[a]
            # where the law closes (contact_pressure: a loaded node's unloading law earlier)
            floor = h_set[idx[a]] * (1.0 - c) if c != 1.0 and h_set[idx[a]] < sigma else 0.0
            if new <= floor:  # past the closed layer: approach it geometrically
                new = floor + 0.1 * (hc[a] - floor)
            step = max(step, abs(new - hc[a]))
            hc[a] = new
        if step <= GAP_TOL * sigma:
            converged = True
            break
        fresh = step > 0.25 * step_prev  # a chord step that does not contract 4x: refactorise
        step_prev = step
    for a in range(m):
        pa[idx[a]] = contact_pressure(hc[a], h_set[idx[a]], c, phys)[0]
    for i in range(n):
        for a in range(m):
            w[i] += c * influence[i, idx[a]] * pa[idx[a]]
    return converged


@jit
def _all_finite(matrix):
    """Whether every entry of ``matrix`` (2-D) is finite: ``np.all(np.isfinite(matrix))`` without
    the array of flags it allocates (and numba's compile of the ufunc and of ``np.all``)."""
    for i in range(matrix.shape[0]):
        for j in range(matrix.shape[1]):
            if not np.isfinite(matrix[i, j]):
                return False
    return True


@jit
def contact_slopes(slope, held, dp_dh):
    """``dP/dH`` of the film pressure of each cell whose slot holds its load (``contact_gap``:
    ``P = y - p_a(H)``, so ``-dp_a/dH``, from the ``slope`` it computed) into ``dp_dh``, 0 in the
    cells held at a floor; returns the number of those that touch (their load depends on the
    gap: ``contact_derivatives``)."""
    m = 0
    for i in range(slope.size):
        dp_dh[i] = 0.0
        if held[i]:
            if slope[i] != 0.0:
                m += 1
        else:
            dp_dh[i] = -slope[i]
    return m


@jit
def contact_derivatives(influence, weight, slope, c, held, m, k_eff, dh_dx, force_dp):
    """Derivatives of the rough film's gap and of the force on the spheres in the slots ``y``
    and ``X`` where ``m`` touching cells are held at a floor (``contact_slopes``), by the
    implicit function theorem: with ``C`` those cells, ``D = dp_a/dH`` there (``slope``,
    ``contact_gap``'s), ``M = I - c K_CC
    D``, ``Z = M^-1 c K_C:`` and ``z = M^-1 1_C``: ``dH/dy = c K + c K_:C D Z`` into ``k_eff``,
    ``dH/dX = 1 + c K_:C D z`` into ``dh_dx``, ``dF/dy = weight + (weight_C D) Z`` into
    ``force_dp``; returns ``dF/dX = (weight_C D) z``; NaN where the matrix is singular or the
    slopes are not finite (the loop then sees a singular Newton matrix)."""
    n = slope.size
    idx = np.empty(m, dtype=np.int64)
    d = np.empty(m)
    k = 0
    for i in range(n):
        dh_dx[i] = 1.0
        force_dp[i] = weight[i]
        for j in range(n):
            k_eff[i, j] = c * influence[i, j]
        if held[i] and slope[i] != 0.0:
            idx[k] = i
            d[k] = slope[i]
            k += 1
    if m == 0:  # no implicit gap: dH/dy = c K
        return 0.0
    mat = np.empty((m, m))
    rhs = np.empty((m, n + 1))
    for a in range(m):
        for b in range(m):
            mat[a, b] = -c * influence[idx[a], idx[b]] * d[b]
        mat[a, a] += 1.0
        for j in range(n):
            rhs[a, j] = c * influence[idx[a], j]
        rhs[a, n] = 1.0
    piv = np.empty(m, dtype=np.int32)
    z = filled((m, n + 1), np.nan)  # Z, then z (NaN: a singular or non-finite contact)
    if _all_finite(mat) and lu_factor(mat, piv):
        col = np.empty(m)
        for j in range(n + 1):
            for a in range(m):
                col[a] = rhs[a, j]
            lu_solve(mat, piv, col)
            for a in range(m):
                z[a, j] = col[a]
    if not _all_finite(z):
        k_eff[:, :] = np.nan
        return np.nan
    kd = np.empty((n, m))
    for i in range(n):
        for a in range(m):
            kd[i, a] = c * influence[i, idx[a]] * d[a]
    corr = np.empty((n, n + 1))
    matmul(kd, z, corr)
    force_dx = 0.0
    for a in range(m):
        wd = weight[idx[a]] * d[a]
        for j in range(n):
            force_dp[j] += wd * z[a, j]
        force_dx += wd * z[a, n]
    for i in range(n):
        dh_dx[i] += corr[i, n]
        for j in range(n):
            k_eff[i, j] += corr[i, j]
    return force_dx


# what a rough film near contact tells the end of the coupled phase (contact_state)
FREE, HOLD, REST = 0, 1, 2


@jit
def contact_state(h, x, v, stored, phys):
    """``HOLD`` while the rigid departure cannot start yet (some gap within ``CONTACT_MARGIN``
    roughnesses and the spheres moving), ``REST`` when they are near contact and at rest
    (``|V| < REST_SPEED``: they stick on their asperities, whatever their deformation, which a
    permanent set keeps), or at rest in a dent (``X <= 0``) with less than ``REST_ENERGY`` stored
    in the solids (``stored``), ``FREE`` otherwise."""
    near = False
    for i in range(h.size):
        near = near or h[i] < CONTACT_MARGIN * phys[ROUGHNESS]
    if not near:
        dented_at_rest = x <= 0.0 and abs(v) < REST_SPEED and stored < REST_ENERGY
        return REST if dented_at_rest else FREE
    return REST if abs(v) < REST_SPEED else HOLD


@jit
def asperity_work(weight, h, c, h_set, phys):
    """Energy stored in the asperities, ``(2/(3 St)) Int e_a ds`` on the force's basis (so that
    its change under a rigid displacement is the contact force's work), relative to the initial
    kinetic energy (docs/model.md, "Energy"); while unloading, the ``c e_a`` they will give back
    (``contact_pressure``)."""
    total = 0.0
    for i in range(h.size):
        loaded = c != 1.0 and h_set[i] < phys[ROUGHNESS]  # contact_pressure's two laws
        hh = h_set[i] + (h[i] - h_set[i]) / c if loaded else h[i]
        if hh < phys[ROUGHNESS]:
            total += weight[i] * (c if loaded else 1.0) * asperity_energy(hh, phys)
    return 2.0 * total / (3.0 * phys[ST])
