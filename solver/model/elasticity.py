"""Elastic deformation of two half-spaces under an axisymmetric film pressure.

Dimensionless (scale ``x1``, docs/model.md, "Scales" and "Elasticity"): lengths along the axis by ``x1``, radii by
``sqrt(a x1)``, pressure by ``mu a v0 / x1**2``. The total surface deflection is then

    W(R) = Int_0^inf P(rho) phi(R, rho) d rho,
    phi(R, rho) = rho / (rho + R) * K(4 R rho / (R + rho)**2),

with ``K(m)`` the complete elliptic integral of the first kind (parameter ``m``).

Discretisation: the pressure is piecewise linear between the nodes of the radial grid (second
order on any smooth grid, stretched or not), and the deflection of a uniformly loaded disk of
radius ``C`` is known in closed form (Timoshenko & Goodier; Johnson, *Contact Mechanics*,
sec. 3.4), in these units

    D(R, C) = C E(R^2/C^2)                                   R <= C
    D(R, C) = R [E(C^2/R^2) - (1 - C^2/R^2) K(C^2/R^2)]       R >  C

so a uniformly loaded annulus ``[c0, c1]`` contributes ``D(R, c1) - D(R, c0)``: the logarithmic
singularity of ``phi`` at ``rho = R`` is integrated exactly, with no quadrature near it. Each
interval between nodes is split into ``SUB_ANNULI`` annuli carrying the mean of the linear
pressure on them (error ``O((h/SUB_ANNULI)^2)``, below the interpolation error ``O(h^2)``). ``K``
close to ``m = 1`` is evaluated in the complementary form ``ellipkm1(1 - m)`` so no digits are lost
(solver/special.py: the arithmetic-geometric mean).

The pressure beyond the last node ``R_L`` is the far-field tail ``P_L (R_L / rho)**4`` (rigid far
field ``P ~ 12 V / R**4``); its deflection decays only like ``1/R`` and is part of the matrix.
"""

from __future__ import annotations

import numpy as np
from .. import special

__all__ = ["kernel", "disk_deflection", "influence_matrix", "force_weights", "SUB_ANNULI",
           "TAIL_RATIO", "TAIL_CELLS"]

# Geometric sub-annuli carrying the far-field tail: ratio 1.08 over 150 cells reaches
# 1.08**150 ~ 1e5 R_L; beyond that phi = pi/2 to O((R/rho)^2) and the rest is summed in closed form.
SUB_ANNULI = 8
TAIL_RATIO = 1.08
TAIL_CELLS = 150


def kernel(r, y):
    """Kernel ``phi(r, y) = y/(y+r) K(4ry/(r+y)^2)`` of the deflection integral (vectorised).

    ``K`` is taken as ``ellipkm1((r-y)^2/(r+y)^2)``, accurate up to the log singularity at ``y = r``.
    """
    r = np.asarray(r, dtype=float)
    y = np.asarray(y, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        m1 = ((r - y) / (r + y)) ** 2
        return y / (y + r) * special.ellipkm1(m1)


def disk_deflection(r, c):
    """Deflection ``D(R, C)`` at radius ``r`` under unit pressure on the disk ``[0, c]``.

    Equal to ``Int_0^c phi(r, y) dy`` (see the module docstring); ``D(r, 0) = 0``.
    """
    r, c = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(c, dtype=float))
    out = np.zeros(r.shape)
    inside = (r <= c) & (c > 0)
    outside = r > c
    ci, ri = c[inside], r[inside]
    out[inside] = ci * special.ellipke((ri / ci) ** 2)[1]
    ro, co = r[outside], c[outside]
    m1 = (ro - co) * (ro + co) / ro**2  # 1 - m without cancellation
    k, e = special.ellipke((co / ro) ** 2, m1)
    out[outside] = ro * (e - m1 * k)
    return out


def _shape(r, width):
    """Far-field pressure shape ``(width + r^2/2)^-2`` (the rigid film's ``3V/H^2``)."""
    return (width + 0.5 * r * r) ** -2


def influence_matrix(nodes, width=None):
    """Deflection at the nodes per unit nodal pressure, ``W = K @ P``.

    Parameters
    ----------
    nodes : (N,) array
        Radii of the pressure nodes, ``nodes[0] = 0``, increasing.
    width : float, optional
        The pressure between nodes ``j`` and ``j+1`` is interpolated as
        ``[P_j hat_j + P_{j+1} hat_{j+1}] g(R) / g(R_j)`` per basis function, with
        ``g = (width + R^2/2)^-2``: exact for the rigid far field ``3V/H^2`` and still second
        order where the grid is fine, so coarse outer cells cost no accuracy. ``None``: plain
        linear interpolation. Beyond the last node ``R_L`` the pressure is ``P_L (R_L/R)^4``.

    Returns
    -------
    K : (N, N) array
    """
    nodes = np.asarray(nodes, dtype=float)
    n = nodes.size
    r_last = nodes[-1]
    # sub-annuli of every interval, each carrying the basis functions' values at its midpoint
    t_edges = np.linspace(0.0, 1.0, SUB_ANNULI + 1)
    t_mid = 0.5 * (t_edges[1:] + t_edges[:-1])
    left = nodes[:-1, None]
    width_ = np.diff(nodes)[:, None]
    edges = left + width_ * t_edges[None, :]  # (N-1, M+1)
    r_mid = left + width_ * t_mid[None, :]  # (N-1, M)
    falling = np.broadcast_to(1.0 - t_mid, r_mid.shape).copy()
    rising = np.broadcast_to(t_mid, r_mid.shape).copy()
    if width is not None:
        g = _shape(r_mid, width)
        falling *= g / _shape(nodes[:-1, None], width)
        rising *= g / _shape(nodes[1:, None], width)
    disk = disk_deflection(nodes[:, None, None], edges[None, :, :])  # (N, N-1, M+1)
    ring = np.diff(disk, axis=2)  # (N, N-1, M): deflection of each uniformly loaded sub-annulus
    K = np.zeros((n, n))
    K[:, :-1] += np.einsum("ijm,jm->ij", ring, falling)
    K[:, 1:] += np.einsum("ijm,jm->ij", ring, rising)

    # Far-field tail on geometric sub-annuli with the exact mean of (R_L/rho)^4 on each.
    t_edges = r_last * TAIL_RATIO ** np.arange(TAIL_CELLS + 1)
    mean_shape = r_last**4 * (t_edges[:-1] ** -3 - t_edges[1:] ** -3) / (3.0 * np.diff(t_edges))
    t_disk = disk_deflection(nodes[:, None], t_edges[None, :])
    tail = np.diff(t_disk, axis=1) @ mean_shape
    # Beyond the last sub-annulus phi = pi/2 (R << rho): Int (R_L/rho)^4 drho = R_L^4 / (3 rho^3).
    tail += 0.5 * np.pi * r_last**4 / (3.0 * t_edges[-1] ** 3)
    K[:, n - 1] += tail
    return K


def force_weights(nodes, width=None):
    """Weights ``w_j`` with ``Int_0^inf P R dR = sum_j w_j P_j`` for the pressure of
    ``influence_matrix`` (same ``width``; tail ``(R_L/R)^4`` beyond the last node: ``R_L^2/2``)."""
    nodes = np.asarray(nodes, dtype=float)
    a, b = nodes[:-1, None], nodes[1:, None]
    x, wq = np.polynomial.legendre.leggauss(10)  # exact for the linear case, 1e-10 otherwise
    t = 0.5 * (x + 1.0)[None, :]
    r = a + (b - a) * t
    falling = 1.0 - t
    rising = t
    if width is not None:
        g = _shape(r, width)
        falling = falling * g / _shape(a, width)
        rising = rising * g / _shape(b, width)
    jac = 0.5 * (b - a) * wq[None, :] * r
    w = np.zeros(nodes.size)
    w[:-1] += np.sum(jac * falling, axis=1)
    w[1:] += np.sum(jac * rising, axis=1)
    w[-1] += 0.5 * nodes[-1] ** 2
    return w
