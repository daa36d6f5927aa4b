"""Asperity contact: the surface load that depends on the gap, and the losses where the solids
touch (docs/model.md, "Surface roughness", "Losses in the solids").

Dimensionless, scale ``x1``. Each surface carries asperities; where the local mean gap ``H``
falls below the combined rms roughness ``sigma`` (``phys[ROUGHNESS]``) they touch and carry the
contact pressure

    p_a(H) = k (sigma - H)^(3/2) sigma / H,      0 < H < sigma   (0 for H >= sigma),

``k`` the asperity stiffness (``phys[ASPERITY_K]``). Near first touch it is the Greenwood &
Williamson (1966) law of Hertzian asperities of one summit height, ``k (sigma - H)^(3/2)``; the
factor ``sigma / H`` closes the asperity layer where the mean planes would meet (the flattened
asperities fill the valleys), so the gap stays positive under any load. ``k -> inf`` is the
hard cut-off: contact at ``H = sigma``. The film flows through the mean gap ``H`` (flow factors
of the rough gap are 1 to within a few percent for ``H > 3 sigma``, Patir & Cheng 1978, and the
load is carried by the asperities below it).

The contact pressure deflects both solids through the same kernel as the film pressure: with
``T = P + p_a(H)`` the total surface load,

    H = X + s + K L,    L = c T + (1 - c) T_set,

``c = 1`` while the solids load. The losses in the solids (``e_dry``, ``phys[E_DRY]``): once the
spheres have touched on approach, from the instant they stop (``V <= 0``) the solids unload
along a stiffer line, ``c = e_dry^2``, through the load ``T_set`` of that instant (a permanent set
``(1 - c) K T_set``: the Walton & Braun (1986) hysteresis, written for the whole surface). The
elastic energy the solids then return is ``c`` times what they stored, so a dry impact restitutes
exactly ``e_dry`` of its speed; a collision that never touches is unchanged.

Given ``P`` and ``X`` the gap is implicit in the contact nodes ``C`` (``H < sigma``); it is solved
there by Newton (``contact_gap``), with ``(I - c K_CC D)`` its matrix, ``D = dp_a/dH <= 0``. The
derivatives of the gap and of the force on the spheres follow by the implicit function theorem
(``contact_derivatives``).
"""

import numpy as np

from .._jit import jit
from ..integration.linalg import lu_factor, lu_solve, matvec
from ..physics import ASPERITY_K, ROUGHNESS, ST

# the rigid film holds where every gap is at least this many roughnesses: the coupled phase
# starts before it on approach (rigid.contact_onset_separation) and ends after it on departure
CONTACT_MARGIN = 2.0
# a film near contact whose spheres move slower than this (in v0) rests on its asperities
REST_SPEED = 1e-6
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
    d = sigma - h
    sd = np.sqrt(d)
    return k * d * sd * sigma / h, -k * sigma * (1.5 * sd / h + d * sd / (h * h))


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
    """Energy stored in the asperities per unit area, ``Int_H^sigma p_a dh``: with ``U^2 = sigma
    - H``, ``2 k sigma (sigma^1.5 atanh(U / sqrt(sigma)) - sigma U - U^3 / 3)``, its leading term
    ``(2/5) k (sigma - H)^(5/2)`` (a Hertzian asperity). Summed as a series where the closed form
    cancels (``U^2 < sigma / 4``)."""
    sigma = phys[ROUGHNESS]
    if h >= sigma:
        return 0.0
    if h <= 0.0:
        return np.inf
    k = phys[ASPERITY_K]
    u = np.sqrt(sigma - h)
    rs = np.sqrt(sigma)
    z = u / rs
    if z < 0.5:
        # sigma^1.5 (atanh z - z - z^3/3) = sigma^1.5 sum_{j>=2} z^(2j+1) / (2j+1)
        total = 0.0
        term = z ** 5
        j = 2
        while True:
            add = term / (2 * j + 1)
            total += add
            if add < 1e-17 * total:
                break
            term *= z * z
            j += 1
        bracket = sigma * rs * total
    else:
        bracket = sigma * rs * np.arctanh(z) - sigma * u - u ** 3 / 3.0
    return 2.0 * k * sigma * bracket


@jit
def contact_gap(s, influence, x, p, c, t_set, h_set, phys, pa, w, h):
    """The gap of a rough film: ``H = X + s + K (c (P + p_a(H)) + (1 - c) T_set)``, solved in
    the contact nodes by Newton from the gap ``h`` holds on entry (the previous iterate's; any
    value, it is clipped into ``(0, sigma]``). Writes ``p_a`` into ``pa``, ``W`` into ``w``,
    ``H`` into ``h``; returns False when the contact Newton did not converge."""
    n = s.size
    sigma = phys[ROUGHNESS]
    guess = h.copy()
    if c == 1.0:
        matvec(influence, p, w)
    else:
        matvec(influence, c * p + (1.0 - c) * t_set, w)
    m = 0
    for i in range(n):
        pa[i] = 0.0
        h[i] = x + s[i] + w[i]
        if h[i] < sigma:
            m += 1
    if m == 0:
        return True
    idx = np.empty(m, dtype=np.int64)
    k = 0
    for i in range(n):
        if h[i] < sigma:
            idx[k] = i
            k += 1
    kcc = np.empty((m, m))
    base = np.empty(m)
    hc = np.empty(m)
    for a in range(m):
        base[a] = h[idx[a]]
        for b in range(m):
            kcc[a, b] = c * influence[idx[a], idx[b]]
        g = guess[idx[a]]
        hc[a] = min(max(g, 0.5 * max(base[a], 0.0)), sigma) if np.isfinite(g) and g > 0.0 \
            else max(0.5 * base[a], 0.5 * sigma)
        if hc[a] <= 0.0:
            hc[a] = 0.5 * sigma
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
            if not np.all(np.isfinite(mat)) or not lu_factor(mat, piv):
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
        h[i] = x + s[i] + w[i]
    return converged


@jit
def contact_derivatives(influence, weight, h, c, h_set, phys, k_eff, dh_dx, force_dp):
    """Derivatives of the rough film's gap and of the force ``weight @ (P + p_a)`` in ``P`` and
    ``X`` at the gap ``h`` (``contact_gap``), by the implicit function theorem: with ``C`` the
    contact nodes, ``D = dp_a/dH`` there, ``M = I - c K_CC D``, ``Z = M^-1 c K_C:`` and ``z =
    M^-1 1_C``: ``dH/dP = c K + c K_:C D Z`` into ``k_eff``, ``dH/dX = 1 + c K_:C D z`` into
    ``dh_dx``, ``dF/dP = weight + (weight_C D) Z`` into ``force_dp``; returns ``dF/dX =
    (weight_C D) z``; NaN where the contact's matrix is singular or ``h`` is not finite (the
    loop then sees a singular Newton matrix)."""
    n = h.size
    slope = np.empty(n)
    m = 0
    for i in range(n):
        slope[i] = contact_pressure(h[i], h_set[i], c, phys)[1]
        if slope[i] != 0.0:
            m += 1
    for i in range(n):
        dh_dx[i] = 1.0
        force_dp[i] = weight[i]
        for j in range(n):
            k_eff[i, j] = c * influence[i, j]
    if m == 0:
        return 0.0
    idx = np.empty(m, dtype=np.int64)
    d = np.empty(m)
    k = 0
    for i in range(n):
        if slope[i] != 0.0:
            idx[k] = i
            d[k] = slope[i]
            k += 1
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
    z = np.full((m, n + 1), np.nan)  # Z, then z (NaN: a singular or non-finite contact)
    if np.all(np.isfinite(mat)) and lu_factor(mat, piv):
        col = np.empty(m)
        for j in range(n + 1):
            for a in range(m):
                col[a] = rhs[a, j]
            lu_solve(mat, piv, col)
            for a in range(m):
                z[a, j] = col[a]
    if not np.all(np.isfinite(z)):
        k_eff[:, :] = np.nan
        return np.nan
    kd = np.empty((n, m))
    for i in range(n):
        for a in range(m):
            kd[i, a] = c * influence[i, idx[a]] * d[a]
    corr = kd @ z
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
def contact_state(h, v, phys):
    """``HOLD`` while the rigid departure cannot start yet (some gap within ``CONTACT_MARGIN``
    roughnesses and the spheres moving), ``REST`` when they are near contact and at rest
    (``|V| < REST_SPEED``: they stick on their asperities, whatever their deformation, which a
    permanent set keeps), ``FREE`` otherwise."""
    near = False
    for i in range(h.size):
        near = near or h[i] < CONTACT_MARGIN * phys[ROUGHNESS]
    if not near:
        return FREE
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
