"""Radial grid for the film: refined at the axis, uniform across the contact, stretched outside.

Radii are dimensionless (``R = r / sqrt(a x1)``). The grid is built once per resolution in
*reference units* (inner region ``[0, 1]``) and stretched by a factor ``radius`` for a
scene, so the elastic matrix is built once per resolution and only rescaled:
``D(lam R, lam C) = lam D(R, C)`` gives ``K(lam) = lam K_ref``.

The finite volumes live in ``s = R^2 / 2`` (``R dR = ds``); faces sit at the midpoints in ``s``,
so cell ``i`` covers ``[s_face[i-1], s_face[i]]`` with area ``area[i]`` (``Int P R dR`` of a
constant cell pressure is ``P * area``, used for the cell balances). The last node is the outer boundary; its "cell" runs from
the last face to ``R_L`` and the pressure beyond decays like the rigid far field ``(R_L/R)^4``.
Force and deflection see the pressure interpolated between nodes on the shaped basis of
elasticity.py (``force_weight``, ``influence``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .._jit import entry, jit
from ..model.elasticity import force_weights, influence_matrix
from ..model.state import array_record
from .radii import reference_radii

__all__ = ["RadialGrid", "Nodes", "reference_grid", "scaled_grid", "SHAPE_WIDTH"]

# Pressure between nodes follows (SHAPE_WIDTH + R^2/2)^-2 (reference units, inner radius 1):
# the rigid far field of a film about as wide as the contact region (elasticity.influence_matrix).
SHAPE_WIDTH = 0.25


@dataclass(frozen=True)
class RadialGrid:
    """Nodes, faces and cell areas of a radial grid (dimensionless, see module docstring)."""

    radius: np.ndarray  # (N,) node radii R_i, radius[0] = 0
    s: np.ndarray  # (N,) s_i = R_i^2 / 2
    s_face: np.ndarray  # (N-1,) face positions in s (midpoints)
    area: np.ndarray  # (N,) finite-volume cell areas in s (the last one ends at R_L)
    force_weight: np.ndarray  # (N,) Int P R dR = force_weight @ P, far-field tail included
    influence: np.ndarray  # (N, N) deflection per unit nodal pressure, W = influence @ P

    def nodes(self) -> "Nodes":
        """The arrays the compiled film and time loop read, as one record."""
        return _as_nodes(self.s, self.s_face, self.area, self.force_weight, self.influence)


# A grid as the compiled code reads it (``RadialGrid`` less the radii, ``weight`` its
# ``force_weight``): ``s``, ``s_face``, ``area``, ``weight``, ``influence``; one reference however
# many arrays (model/state.py: array_record), passed to every Newton iteration's functions.
Nodes = array_record("Nodes", ("s", "s_face", "area", "weight", "influence"),
                       "A grid as the compiled film and time loop read it (integration/grid.py).",
                       __name__)


@entry
@jit
def _as_nodes(s, s_face, area, weight, influence):
    """``Nodes`` built by compiled code, which loads from numba's cache: the record's Python
    constructor compiles a constructor of its own in every process (about 0.2 s of every warm
    ``ehd run``, benchmarks/startup.md)."""
    return Nodes(s, s_face, area, weight, influence)


@lru_cache(maxsize=16)
def reference_grid(n_inner: int, axis_ratio: float, axis_extent: float, stretch: float,
                   outer_extent: float, max_rel: float) -> RadialGrid:
    """Grid with its inner region on ``[0, 1]`` (cached: the elastic matrix is the cost)."""
    radius = reference_radii(n_inner, axis_ratio, axis_extent, stretch, outer_extent, max_rel)
    s = 0.5 * radius**2
    s_face = 0.5 * (s[1:] + s[:-1])
    area = np.empty_like(s)
    area[0] = s_face[0]
    area[1:-1] = np.diff(s_face)
    # last cell [s_face[-1], s_L] plus the tail: Int_{R_L}^inf (R_L/R)^4 R dR = R_L^2 / 2
    area[-1] = s[-1] - s_face[-1]
    weight = force_weights(radius, SHAPE_WIDTH)
    K = influence_matrix(radius, SHAPE_WIDTH)
    for a in (radius, s, s_face, area, weight, K):
        a.setflags(write=False)
    return RadialGrid(radius, s, s_face, area, weight, K)


def scaled_grid(ref: RadialGrid, radius: float) -> RadialGrid:
    """The reference grid stretched so that its uniform region ends at ``radius``."""
    lam = float(radius)
    return RadialGrid(
        radius=ref.radius * lam,
        s=ref.s * lam**2,
        s_face=ref.s_face * lam**2,
        area=ref.area * lam**2,
        force_weight=ref.force_weight * lam**2,
        influence=ref.influence * lam,
    )
