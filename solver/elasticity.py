"""Elastic deformation of two half-spaces under an axisymmetric film pressure.

Dimensionless (scale ``x1``, physics.md): lengths along the axis by ``x1``, radii by
``sqrt(a x1)``, pressure by ``mu a v0 / x1**2``. The total surface deflection is then

    W(R) = Int_0^inf P(rho) phi(R, rho) d rho,
    phi(R, rho) = rho / (rho + R) * K(4 R rho / (R + rho)**2),

with ``K(m)`` the complete elliptic integral of the first kind (parameter ``m``).

Discretisation: the pressure is taken constant on each cell (annulus) of the radial grid, and the
deflection of a uniformly loaded disk of radius ``C`` is known in closed form (Timoshenko &
Goodier; Johnson, *Contact Mechanics*, sec. 3.4), in these units

    D(R, C) = C E(R^2/C^2)                                   R <= C
    D(R, C) = R [E(C^2/R^2) - (1 - C^2/R^2) K(C^2/R^2)]       R >  C

so an annulus ``[c0, c1]`` contributes ``D(R, c1) - D(R, c0)``. The logarithmic singularity of
``phi`` at ``rho = R`` is thereby integrated exactly (no quadrature near it); ``K`` close to
``m = 1`` is evaluated in the complementary form ``ellipkm1(1 - m)`` so no digits are lost.

The pressure beyond the last node ``R_L`` is the far-field tail ``P_L (R_L / rho)**4`` (rigid far
field ``P ~ 12 V / R**4``); its deflection decays only like ``1/R`` and is part of the matrix.
"""

from __future__ import annotations

import numpy as np
from scipy import special

__all__ = ["kernel", "disk_deflection", "influence_matrix", "TAIL_RATIO", "TAIL_CELLS"]

# Geometric sub-annuli carrying the far-field tail: ratio 1.08 over 150 cells reaches
# 1.08**150 ~ 1e5 R_L; beyond that phi = pi/2 to O((R/rho)^2) and the rest is summed in closed form.
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
    out[inside] = ci * special.ellipe((ri / ci) ** 2)
    ro, co = r[outside], c[outside]
    m = (co / ro) ** 2
    m1 = (ro - co) * (ro + co) / ro**2  # 1 - m without cancellation
    out[outside] = ro * (special.ellipe(m) - m1 * special.ellipkm1(m1))
    return out


def influence_matrix(nodes, faces):
    """Deflection at the nodes per unit cell pressure, ``W = K @ P``.

    Parameters
    ----------
    nodes : (N,) array
        Radii of the pressure nodes, ``nodes[0] = 0``, increasing.
    faces : (N-1,) array
        Cell boundaries, ``nodes[i] < faces[i] < nodes[i+1]``. Cell ``i`` is
        ``[faces[i-1], faces[i]]`` (``faces[-1] := 0``); the last cell is ``[faces[-1], R_L]``
        followed by the tail ``P_L (R_L/rho)^4`` for ``rho > R_L``.

    Returns
    -------
    K : (N, N) array
    """
    nodes = np.asarray(nodes, dtype=float)
    faces = np.asarray(faces, dtype=float)
    n = nodes.size
    r_last = nodes[-1]
    edges = np.concatenate(([0.0], faces, [r_last]))
    disk = disk_deflection(nodes[:, None], edges[None, :])  # (N, N+1)
    K = np.diff(disk, axis=1)

    # Far-field tail on geometric sub-annuli with the exact mean of (R_L/rho)^4 on each.
    t_edges = r_last * TAIL_RATIO ** np.arange(TAIL_CELLS + 1)
    mean_shape = r_last**4 * (t_edges[:-1] ** -3 - t_edges[1:] ** -3) / (3.0 * np.diff(t_edges))
    t_disk = disk_deflection(nodes[:, None], t_edges[None, :])
    tail = np.diff(t_disk, axis=1) @ mean_shape
    # Beyond the last sub-annulus phi = pi/2 (R << rho): Int (R_L/rho)^4 drho = R_L^4 / (3 rho^3).
    tail += 0.5 * np.pi * r_last**4 / (3.0 * t_edges[-1] ** 3)
    K[:, n - 1] += tail
    return K
