"""Compiled kernels of the coupled film problem: one implicit step's residual and Jacobian, and
the energy terms. Pure arrays in, arrays out.

Dimensionless, scale ``x1`` (physics.md). In ``s = R^2/2`` the Reynolds equation is a 1-D
conservation law,

    dH/dT = dq/ds,   q = (1/6) s H^3 dP/ds,   H = X + s + W,   W = K P,

integrated over finite volumes (grid.py). The face flux between nodes ``i`` and ``i+1`` is

    q_f = (P_{i+1} - P_i) s_f H_i^2 H_{i+1}^2 / (3 (s_{i+1} - s_i) (H_i + H_{i+1})),

which integrates ``1/(s H^3)`` across the face with ``H`` linear in ``s``: it is exact for the rigid
pressure ``3V/H^2`` on any grid, so the stretched far field costs no accuracy. The outer boundary
node keeps ``P H^2`` equal to its neighbour's (rigid far field, ``P = 3V/H^2``); the pressure
beyond it is the tail ``P_L (R_L/R)^4``, counted in force, deflection and energies.

Force ``Int P R dR = weight @ P`` (pressure linear between nodes, elasticity.py).
The unknowns of a step are ``y = (P_0..P_{N-1}, X, V)``; rows are scaled to gap units
(``bh/area`` for the cells, ``bh`` for the motion) where ``bh`` is the implicit BDF coefficient
times the step.
"""

from .._jit import jit
from ..integration.linalg import matvec


@jit
def gap(s, influence, x, p, w_out, h_out):
    """``W = K P`` and ``H = X + s + W`` into ``w_out``, ``h_out``."""
    matvec(influence, p, w_out)
    for i in range(s.size):
        h_out[i] = x + s[i] + w_out[i]


@jit
def face_fluxes(s, s_face, p, h, q_out):
    """Face fluxes ``q_f`` (module docstring); ``q_out`` has N-1 entries."""
    for f in range(s.size - 1):
        hi = h[f]
        hj = h[f + 1]
        c = s_face[f] * hi * hi * hj * hj / (3.0 * (s[f + 1] - s[f]) * (hi + hj))
        q_out[f] = c * (p[f + 1] - p[f])


@jit
def residual(s, s_face, area, weight, stokes, bh, h_hist, x_hist, v_hist, x, v, p, h, q, res):
    """Scaled residual of one implicit step: ``H - H_hist = bh dq/ds`` per cell, the far-field
    boundary row, ``X - X_hist = -bh V`` and ``V - V_hist = -bh F/(3 St)``."""
    n = s.size
    face_fluxes(s, s_face, p, h, q)
    for i in range(n - 1):
        dq = q[i] - (q[i - 1] if i > 0 else 0.0)
        res[i] = h[i] - h_hist[i] - bh / area[i] * dq
    ratio = h[n - 2] / h[n - 1]
    res[n - 1] = p[n - 1] - p[n - 2] * ratio * ratio
    force = 0.0
    for i in range(n):
        force += weight[i] * p[i]
    res[n] = x - x_hist + bh * v
    res[n + 1] = v - v_hist + bh * force / (3.0 * stokes)


@jit
def jacobian(s, s_face, area, weight, influence, stokes, bh, p, h, jac, dres_dh):
    """Exact Jacobian of ``residual`` with respect to ``(P, X, V)`` into ``jac`` (N+2, N+2).

    The cell rows depend on the gap at three nodes, and the gap on every pressure through ``K``:
    ``J = (dres/dH) K + dres/dP``. ``dres_dh`` (N, 3) is work space (columns i-1, i, i+1)."""
    n = s.size
    jac[:, :] = 0.0
    dres_dh[:, :] = 0.0
    # derivatives of q_f with respect to H_i, H_{i+1} and P_i, P_{i+1}
    for f in range(n - 1):
        hi = h[f]
        hj = h[f + 1]
        k = s_face[f] / (3.0 * (s[f + 1] - s[f]))
        sum_h = hi + hj
        c = k * hi * hi * hj * hj / sum_h
        dp = p[f + 1] - p[f]
        dq_dhi = dp * k * hj * hj * hi * (hi + 2.0 * hj) / (sum_h * sum_h)
        dq_dhj = dp * k * hi * hi * hj * (hj + 2.0 * hi) / (sum_h * sum_h)
        # row f: -bh/area_f * (+q_f);  row f+1 (if a cell row): -bh/area_{f+1} * (-q_f)
        g = bh / area[f]
        jac[f, f] += g * c
        jac[f, f + 1] -= g * c
        dres_dh[f, 1] -= g * dq_dhi
        dres_dh[f, 2] -= g * dq_dhj
        if f + 1 < n - 1:
            g = bh / area[f + 1]
            jac[f + 1, f] -= g * c
            jac[f + 1, f + 1] += g * c
            dres_dh[f + 1, 0] += g * dq_dhi
            dres_dh[f + 1, 1] += g * dq_dhj
    for i in range(n - 1):
        dres_dh[i, 1] += 1.0
    # boundary row: P_L - P_{L-1} (H_{L-1}/H_L)^2
    ratio = h[n - 2] / h[n - 1]
    jac[n - 1, n - 1] += 1.0
    jac[n - 1, n - 2] -= ratio * ratio
    dres_dh[n - 1, 0] = -2.0 * p[n - 2] * ratio / h[n - 1]
    dres_dh[n - 1, 1] = 2.0 * p[n - 2] * ratio * ratio / h[n - 1]
    # chain rule through H = X + s + K P
    for i in range(n):
        lo = i - 1 if i > 0 else 0
        hi_ = i + 1 if i < n - 1 else n - 1
        dx = 0.0
        for k in range(lo, hi_ + 1):
            d = dres_dh[i, k - i + 1]
            if d != 0.0:
                dx += d
                for j in range(n):
                    jac[i, j] += d * influence[k, j]
        jac[i, n] = dx
    jac[n, n] = 1.0
    jac[n, n + 1] = bh
    for j in range(n):
        jac[n + 1, j] = bh * weight[j] / (3.0 * stokes)
    jac[n + 1, n + 1] = 1.0


@jit
def energy_rates(s, s_face, weight, stokes, x, p, w, h, q):
    """Strain energy ``E_s = (1/(3St)) Int P W R dR`` and dissipation rate
    ``D = (2/(3St)) Int q dP/ds ds`` (both relative to the initial kinetic energy; equal to
    ``(1/(18 St)) Int H^3 (dP/dR)^2 R dR`` of physics.md), with the
    far-field tail: ``W ~ W_L R_L/R`` and, for ``D``, the rigid film of velocity ``P_L H_L^2/3``.
    ``q`` must hold the face fluxes of ``p, h``."""
    n = s.size
    strain = 0.0
    for i in range(n):
        strain += weight[i] * p[i] * w[i]
    s_last = s[n - 1]
    # weight[-1] counted the tail as P_L W_L R_L^2/2; the 1/R decay of W gives R_L^2/3 instead
    strain -= p[n - 1] * w[n - 1] * (2.0 * s_last) / 6.0
    # Int q dP/ds ds over a face interval, with q ~ s and H linear in s as in the face flux:
    # q_f dP s_bar / s_f, s_bar the mean of s under H^-3 (exact for the rigid film; the plain
    # q_f dP overestimates it on stretched cells)
    diss = 0.0
    for f in range(n - 1):
        s_bar = s[f] + (s[f + 1] - s[f]) * h[f] / (h[f] + h[f + 1])
        diss += q[f] * (p[f + 1] - p[f]) * s_bar / s_face[f]
    v_far = p[n - 1] * h[n - 1] * h[n - 1] / 3.0
    xs = x + s_last
    diss += 6.0 * v_far * v_far * (1.0 / xs - x / (2.0 * xs * xs))
    return strain / (3.0 * stokes), 2.0 * diss / (3.0 * stokes)
