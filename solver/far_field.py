"""The far-field restitution ``e_far``: the near-field collision seen from a reference distance.

docs/model.md, "Outer flow: the far-field restitution". The near field (``solver.collide``) starts
at ``x0`` with speed ``v0`` and ends, on the way out, with the departure speed ``e0 v0`` at ``x0``
(``e0`` = ``e_wet`` seen at ``x0``). Outside ``x0`` the spheres move rigidly (no deformation there,
the film's premise) through the exact quasi-steady Stokes resistance ``R(x)`` of
``model/outer_flow.py`` (not only the film's ``a/x``), with the added mass ``m C(x) phi`` of the
potential flow where the fluid has a density (``phi = density_ratio``). With
``M(x) = m (1 + phi C(x))`` the energy equation ``d/dt (M v^2 / 2) = -6 pi mu a R v^2`` makes
``sqrt(M/m) v`` linear in the resistance integral

    J(x0, x) = Int_x0^x R(y) (1 + phi C(y))^(-1/2) dy / a,

so that with ``s = sqrt(1 + phi C)``:

    approach:   s(x) V(x) = s(x0) + J / St,        departure:  s(x) U(x) = s(x0) e0 - J / St,

and the restitution read at ``x_ref`` is ``e_far = max(0, s0 e0 - J/St) / (s0 + J/St)``
(``J = J(x0, x_ref)``; ``s(x_ref)`` cancels). With ``R = a/x`` and no added mass this is exactly
``e_wet`` at ``x_ref`` (rigid.restitution). Everything here is a reading of the near-field result:
the near-field solve does not change, so these are arguments, not ``Physics`` groups.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np

from .model import outer_flow

__all__ = ["OuterFlow", "DEFAULT", "resistance_integral", "handover_defect", "far_restitution"]

X0_OVER_A = 0.01  # the scene layer's default near-field start (docs/scenes.md)
X_REF_OVER_A = 0.1  # where e_far reads the speeds by default (docs/model.md says why)
START_OVER_A = 1.0  # where the outer approach starts by default
MAX_OVER_A = 100.0  # the series converges anywhere; beyond 100 a the wall term is below 1 %

_GAUSS = np.polynomial.legendre.leggauss(16)  # per panel of width <= 1/2 in ln(x/a)
PANEL = 0.5  # 16 nodes per half unit of ln x: converged to 1e-12 (tests/test_far_field.py)


def _weight(geometry, gap, density_ratio):
    """``(1 + phi C(x))^(-1/2)``: the added mass' factor on the resistance integral."""
    if density_ratio == 0.0:
        return 1.0
    return 1.0 / math.sqrt(1.0 + density_ratio * outer_flow.added_mass(geometry, gap))


@functools.lru_cache(maxsize=256)
def resistance_integral(geometry: str, gap_from: float, gap_to: float,
                        density_ratio: float = 0.0, log_part: bool = True,
                        panel: float = PANEL) -> float:
    """``J = Int R(y) (1 + phi C(y))^(-1/2) dy / a`` from ``gap_from`` to ``gap_to`` (``x/a``),
    by Gauss-Legendre in ``u = ln(y/a)``, where ``y R = 1 + y (R - a/y)`` is smooth; the
    ``a/y`` part is exact (``ln(gap_to/gap_from)``) when there is no added mass. ``log_part``
    false: the integral of ``R - a/y`` alone (what the film leaves out)."""
    if not (0.0 < gap_from <= gap_to):
        raise ValueError(f"resistance_integral: need 0 < gap_from <= gap_to, got {gap_from!r}, "
                         f"{gap_to!r}")
    u0, u1 = math.log(gap_from), math.log(gap_to)
    if u1 == u0:
        return 0.0
    panels = max(1, math.ceil((u1 - u0) / panel))
    edges = np.linspace(u0, u1, panels + 1)
    nodes, weights = _GAUSS
    total = 0.0
    for lo, hi in zip(edges[:-1], edges[1:]):
        half = 0.5 * (hi - lo)
        for t, w in zip(nodes, weights):
            gap = math.exp(lo + half * (t + 1.0))
            extra = gap * outer_flow.outer(geometry, gap)
            if density_ratio == 0.0:
                value = extra
            else:
                value = ((1.0 if log_part else 0.0) + extra) * _weight(geometry, gap, density_ratio)
            total += w * half * value
    if density_ratio == 0.0 and log_part:
        total += u1 - u0
    return total


def handover_defect(geometry: str, x0_over_a: float) -> float:
    """``Int_0^x0 (R - a/y) dy / a``: the part of the exact resistance the film (``a/x``) leaves
    out inside ``x0``, an upper bound of what each pass through the near field misses (the pass
    ends at the closest approach ``h_m > 0``). Near contact ``R - a/y ~ c ln(a/y) + k``, so the
    piece below ``1e-6 a`` is added in closed form, ``y (c (ln(a/y) + 1) + k)``."""
    c = outer_flow.WALL_LOG if geometry == "wall" else outer_flow.EQUAL_LOG
    tiny = 1e-6
    k = (outer_flow.wall_outer_regular(tiny) if geometry == "wall"
         else outer_flow.equal_spheres_outer_regular(tiny))
    below = tiny * (c * (math.log(1.0 / tiny) + 1.0) + k)
    return below + resistance_integral(geometry, tiny, x0_over_a, 0.0, False)


def far_restitution(e0: float, stokes: float, integral: float, s0: float = 1.0) -> float:
    """``max(0, s0 e0 - J/St) / (s0 + J/St)``: the departure over the approach speed at the
    point the resistance integral ``J`` (from ``x0``) reaches, ``s0 = sqrt(M(x0)/m)``."""
    j = integral / stokes
    return max(0.0, s0 * e0 - j) / (s0 + j)


@dataclass(frozen=True)
class OuterFlow:
    """Where and how the near-field result is read from far away (docs/model.md, "Outer flow:
    the far-field restitution"). Lengths over the reduced radius ``a``.

    geometry
        ``"wall"`` (a sphere and a plane wall) or ``"spheres"`` (two equal spheres).
    x0_over_a
        The near-field start ``x0/a`` (the collision's ``x0``), in (0, 1].
    x_ref_over_a
        Where ``e_far`` reads the approach and departure speeds, in ``[x0_over_a,
        start_over_a]``.
    start_over_a
        Where the outer approach starts (``v_outer_start`` is the speed there), in
        ``(x0_over_a, 100]``.
    density_ratio
        ``phi``: the fluid mass the particle displaces over its mass, ``rho_f / rho_p`` (two
        spheres: ``rho_f V_sphere / (2 m)``, ``m`` the reduced mass), in [0, 1e6]; 0: no added
        mass (a dimensionless run has no densities).
    """

    geometry: str = "wall"
    x0_over_a: float = X0_OVER_A
    x_ref_over_a: float = X_REF_OVER_A
    start_over_a: float = START_OVER_A
    density_ratio: float = 0.0

    def __post_init__(self):
        if self.geometry not in outer_flow.GEOMETRIES:
            raise ValueError(f"outer geometry = {self.geometry!r}: must be one of "
                             f"{', '.join(outer_flow.GEOMETRIES)}")
        for name in ("x0_over_a", "x_ref_over_a", "start_over_a", "density_ratio"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value):
                raise ValueError(f"{name} = {value!r}: must be a finite number")
            object.__setattr__(self, name, float(value))
        if not 0.0 < self.x0_over_a <= 1.0:
            raise ValueError(f"x0_over_a = {self.x0_over_a:g}: the near-field start must be in "
                             "(0, 1] (x0/a)")
        if not self.x0_over_a < self.start_over_a <= MAX_OVER_A:
            raise ValueError(f"outer_start_over_a = {self.start_over_a:g}: the outer start must "
                             f"lie beyond the near-field start, in ({self.x0_over_a:g}, "
                             f"{MAX_OVER_A:g}] (x0/a = {self.x0_over_a:g})")
        if not self.x0_over_a <= self.x_ref_over_a <= self.start_over_a:
            raise ValueError(f"x_ref_over_a = {self.x_ref_over_a:g}: the reference distance must "
                             f"be in [{self.x0_over_a:g}, {self.start_over_a:g}] (between x0/a and "
                             "the outer start)")
        if not 0.0 <= self.density_ratio <= 1e6:
            raise ValueError(f"density_ratio = {self.density_ratio:g}: must be in [0, 1e6] "
                             "(rho_f / rho_p)")

    def as_dict(self) -> dict:
        return asdict(self)

    def mass_factor(self, gap: float) -> float:
        """``s = sqrt(M/m) = sqrt(1 + phi C(x))`` at gap ``x = gap * a``."""
        return 1.0 / _weight(self.geometry, gap, self.density_ratio)

    def integral(self, gap_to: float) -> float:
        """``J(x0, x)`` of the module docstring, ``x = gap_to * a``."""
        return resistance_integral(self.geometry, self.x0_over_a, float(gap_to),
                                   self.density_ratio)

    def restitution(self, e0: float, stokes: float) -> float:
        """``e_far`` from ``e0``, the departure speed at ``x0`` over ``v0`` (``e_wet`` seen at
        ``x0``), and ``St`` (at ``x0``): 0 when the spheres stop before they are back at
        ``x_ref``; NaN when ``e0`` is (a failed scene)."""
        if not math.isfinite(e0):
            return math.nan
        return far_restitution(e0, stokes, self.integral(self.x_ref_over_a),
                               self.mass_factor(self.x0_over_a))

    def approach_speed(self, stokes: float) -> float:
        """The approach speed at the outer start over ``v0``: what arrives at ``x0`` with
        ``v0``, ``(s0 + J(x0, start)/St) / s(start)``."""
        s0 = self.mass_factor(self.x0_over_a)
        return (s0 + self.integral(self.start_over_a) / stokes) / self.mass_factor(self.start_over_a)


DEFAULT = OuterFlow()
