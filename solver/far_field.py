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
from .physics import is_real_number

__all__ = ["OuterFlow", "DEFAULT", "resistance_integral", "handover_defect", "far_restitution",
           "history_coefficient", "history_restitution", "outer_tables", "OuterTables"]

X0_OVER_A = 0.01  # the scene layer's default near-field start (docs/scenes.md)
X_REF_OVER_A = 0.1  # where e_far reads the speeds by default (docs/model.md says why)
START_OVER_A = 1.0  # where the outer approach starts by default
MAX_OVER_A = 100.0  # the series converges anywhere; beyond 100 a the wall term is below 1 %
# The outer series' cost grows as (x0/a)^-1/2 (e_far of St 30: 0.18 s at x0 = 1e-6 a, 2.1 s at
# 1e-8, 16 s at 1e-10, minutes at 1e-12, then an allocation beyond memory): the nearest start
# taken. A scene's eps check keeps its x0 far above it.
MIN_X0_OVER_A = 1e-8
# The "pair" geometry's radius ratio a2/a1 within [1/PAIR_RATIO_MAX, PAIR_RATIO_MAX]: its series
# cost 1.3 s at 100, 9 s at 1e3, 4 min at 1e4 and did not converge at 1e6; beyond 1e3 the larger
# sphere is a wall to the outer flow (e_far of St 30 from the wall's: 3.3e-4 at 100, 3.4e-5 at 1e3)
PAIR_RATIO_MAX = 1e3


def pair_within_reach(radius_ratio: float) -> bool:
    """Whether the "pair" geometry takes ``a2/a1`` (``PAIR_RATIO_MAX``; a ratio that rounding put
    a few ulps beyond, as ``1 mm / 1 um``, is taken)."""
    limit = PAIR_RATIO_MAX * (1.0 + 1e-12)
    return 1.0 / limit <= radius_ratio <= limit

_GAUSS = np.polynomial.legendre.leggauss(16)  # per panel of width <= 1/2 in ln(x/a)
PANEL = 0.5  # 16 nodes per half unit of ln x: converged to 1e-12 (tests/test_far_field.py)


def _weight(geometry, gap, density_ratio, ratios=outer_flow.UNIT_RATIOS):
    """``(1 + phi C(x))^(-1/2)``: the added mass' factor on the resistance integral."""
    if density_ratio == 0.0:
        return 1.0
    return 1.0 / math.sqrt(1.0 + density_ratio * outer_flow.added_mass(geometry, gap,
                                                                       ratios=ratios))


@functools.lru_cache(maxsize=256)
def resistance_integral(geometry: str, gap_from: float, gap_to: float,
                        density_ratio: float = 0.0, log_part: bool = True,
                        panel: float = PANEL, ratios=outer_flow.UNIT_RATIOS) -> float:
    """``J = Int R(y) (1 + phi C(y))^(-1/2) dy / a`` from ``gap_from`` to ``gap_to`` (``x/a``),
    by Gauss-Legendre in ``u = ln(y/a)``, where ``y R = 1 + y (R - a/y)`` is smooth; the
    ``a/y`` part is exact (``ln(gap_to/gap_from)``) when there is no added mass. ``log_part``
    false: the integral of ``R - a/y`` alone (what the film leaves out). ``ratios``: the radius
    and mass ratios of the "pair" geometry (``outer_flow.pair_resistance``)."""
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
            extra = gap * outer_flow.outer(geometry, gap, ratios=ratios)
            if density_ratio == 0.0:
                value = extra
            else:
                value = ((1.0 if log_part else 0.0) + extra) * _weight(geometry, gap, density_ratio,
                                                                       ratios)
            total += w * half * value
    if density_ratio == 0.0 and log_part:
        total += u1 - u0
    return total


def handover_defect(geometry: str, x0_over_a: float, ratios=outer_flow.UNIT_RATIOS) -> float:
    """``Int_0^x0 (R - a/y) dy / a``: the part of the exact resistance the film (``a/x``) leaves
    out inside ``x0``, an upper bound of what each pass through the near field misses (the pass
    ends at the closest approach ``h_m > 0``). Near contact ``R - a/y ~ c ln(a/y) + k``, so the
    piece below ``1e-6 a`` is added in closed form, ``y (c (ln(a/y) + 1) + k)``."""
    c = outer_flow.log_coefficient(geometry, ratios)
    tiny = 1e-6
    k = outer_flow.outer(geometry, tiny, ratios=ratios) - c * math.log(1.0 / tiny)
    below = tiny * (c * (math.log(1.0 / tiny) + 1.0) + k)
    return below + resistance_integral(geometry, tiny, x0_over_a, 0.0, False, ratios=ratios)


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
        ``"wall"`` (a sphere and a plane wall), ``"spheres"`` (two equal spheres) or ``"pair"``
        (two free spheres of any radii and masses, in their relative motion at zero momentum:
        ``outer_flow.pair_resistance``, ``pair_added_mass``).
    x0_over_a
        The near-field start ``x0/a`` (the collision's ``x0``), in ``[MIN_X0_OVER_A, 1]``.
    x_ref_over_a
        Where ``e_far`` reads the approach and departure speeds, in ``[x0_over_a,
        start_over_a]``.
    start_over_a
        Where the outer approach starts (``v_outer_start`` is the speed there), in
        ``(x0_over_a, 100]``.
    density_ratio
        ``phi``: the fluid mass the particle displaces over its mass, ``rho_f / rho_p`` (two
        spheres: ``rho_f V_sphere / (2 m)``, ``m`` the reduced mass; "pair": ``rho_f V1 / (2 m)``
        with sphere 1's volume, the smaller sphere's in a scene), in [0, 1e6]; 0: no added mass (a dimensionless run has no
        densities).
    radius_ratio, mass_ratio
        ``a2/a1`` and ``m2/m1`` of the "pair" geometry (finite, > 0; the radii within
        ``PAIR_RATIO_MAX`` of each other); 1 for the others, which do not read them.
    """

    geometry: str = "wall"
    x0_over_a: float = X0_OVER_A
    x_ref_over_a: float = X_REF_OVER_A
    start_over_a: float = START_OVER_A
    density_ratio: float = 0.0
    radius_ratio: float = 1.0
    mass_ratio: float = 1.0

    def __post_init__(self):
        if self.geometry not in outer_flow.GEOMETRIES:
            raise ValueError(f"outer geometry = {self.geometry!r}: must be one of "
                             f"{', '.join(outer_flow.GEOMETRIES)}")
        for name in ("x0_over_a", "x_ref_over_a", "start_over_a", "density_ratio",
                     "radius_ratio", "mass_ratio"):
            value = getattr(self, name)
            if not (is_real_number(value) and math.isfinite(value)):
                raise ValueError(f"{name} = {value!r}: must be a finite number")
            object.__setattr__(self, name, float(value))
        if not MIN_X0_OVER_A <= self.x0_over_a <= 1.0:
            raise ValueError(f"x0_over_a = {self.x0_over_a:g}: the near-field start must be in "
                             f"[{MIN_X0_OVER_A:g}, 1] (x0/a; nearer, the outer series takes "
                             "minutes to hours)")
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
        for name in ("radius_ratio", "mass_ratio"):
            value = getattr(self, name)
            if self.geometry == "pair" and not value > 0.0:
                raise ValueError(f"{name} = {value:g}: must be > 0 (a2/a1, m2/m1)")
            if self.geometry == "pair" and name == "radius_ratio" and not pair_within_reach(
                    value):
                raise ValueError(f"radius_ratio = {value:g}: the pair's radii may differ by at "
                                 f"most {PAIR_RATIO_MAX:g}x; beyond, the larger sphere is a wall "
                                 "to the outer flow: use geometry 'wall'")
            if self.geometry != "pair" and value != 1.0:
                raise ValueError(f"{name} = {value:g}: only the 'pair' outer geometry has one "
                                 "(the others are 1)")

    @property
    def ratios(self) -> tuple[float, float]:
        """``(a2/a1, m2/m1)``: the shape of the "pair" geometry (1, 1 for the others)."""
        return self.radius_ratio, self.mass_ratio

    def as_dict(self) -> dict:
        return asdict(self)

    def mass_factor(self, gap: float) -> float:
        """``s = sqrt(M/m) = sqrt(1 + phi C(x))`` at gap ``x = gap * a``."""
        return 1.0 / _weight(self.geometry, gap, self.density_ratio, self.ratios)

    def integral(self, gap_to: float) -> float:
        """``J(x0, x)`` of the module docstring, ``x = gap_to * a``."""
        return resistance_integral(self.geometry, self.x0_over_a, float(gap_to),
                                   self.density_ratio, ratios=self.ratios)

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
        # a float's division: inf, without numpy's overflow warning, where St is a denormal
        return ((s0 + float(self.integral(self.start_over_a)) / stokes)
                / self.mass_factor(self.start_over_a))

    def arrival_speed(self, stokes_start: float) -> float:
        """The speed at ``x0`` over the approach speed ``V`` at the outer start, the inverse of
        ``approach_speed``: ``(s(start) - J(x0, start)/St_V) / s0`` with ``St_V = m V / (6 pi mu
        a^2)``, the Stokes number of ``V``. At or below 0 the outer flow stops the spheres before
        they reach ``x0`` (they stick without a film collision)."""
        if not stokes_start > 0.0:
            raise ValueError(f"stokes_start = {stokes_start!r}: must be > 0")
        s_start = self.mass_factor(self.start_over_a)
        return (s_start - self.integral(self.start_over_a) / stokes_start) \
            / self.mass_factor(self.x0_over_a)

    def stopping_gap(self, stokes_start: float) -> float:
        """Where the spheres stop (``x/a``) when the approach speed at the outer start, of Stokes
        number ``stokes_start``, is too slow to reach ``x0`` (``arrival_speed <= 0``): the gap
        whose ``J(x, start)`` equals ``s(start) St_V``, by bisection in ``ln x`` to 1e-10."""
        if self.arrival_speed(stokes_start) > 0.0:
            raise ValueError("stopping_gap: the spheres reach x0 at this approach speed")
        whole = self.integral(self.start_over_a)
        budget = self.mass_factor(self.start_over_a) * stokes_start
        lo, hi = math.log(self.x0_over_a), math.log(self.start_over_a)
        while hi - lo > 1e-10:
            mid = 0.5 * (lo + hi)
            if whole - self.integral(math.exp(mid)) > budget:  # J(mid, start): still moving
                lo = mid
            else:
                hi = mid
        return math.exp(hi)


DEFAULT = OuterFlow()


# ---- the history force: a bound on what unsteady viscous diffusion adds (docs/model.md) ----------
HISTORY_FIRST_STEP = 1e-6  # a/v0: the first step after a kink of the velocity (graded from there)
HISTORY_GROWTH = 1.02  # each step at most this much longer than the last
HISTORY_MAX_STEP = 2e-3  # a/v0, and this many gaps' worth beyond a gap of a
GAP_STEP = 0.01  # a step moves the gap by at most this fraction of itself


def history_coefficient(stokes: float, density_ratio: float) -> float:
    """``B = (3 / sqrt(2 pi)) sqrt(phi / St)``: the Basset history force
    ``6 a_s^2 sqrt(pi rho mu) Int (du/dtau) / sqrt(t - tau) dtau`` of each sphere in units of
    ``m v0^2 / a`` with time in ``a / v0`` (a sphere and a wall, or two equal spheres with
    ``phi`` and ``St`` as ``OuterFlow`` and ``Physics`` define them)."""
    return 3.0 / math.sqrt(2.0 * math.pi) * math.sqrt(density_ratio / stokes)


class OuterTables:
    """``R(x)``, ``C(x)`` and ``C'(x)`` on a log grid of the gap (``x/a`` from 1e-3 to 100),
    interpolated in ``ln x`` (``x R``, ``C`` smooth there) by cubic Hermite polynomials with the
    nodes' slopes from ``np.gradient`` (400 points a decade: 1e-7 relative or better). Hermite
    rather than linear: its first derivative is continuous, so an adaptive integrator
    (solver/trajectory.py) is not held to one step per node by the kinks of a linear
    interpolant (38 steps instead of 426 from 100 a down to 0.01 a, measured)."""

    def __init__(self, geometry: str, ratios=outer_flow.UNIT_RATIOS):
        self.u = np.linspace(math.log(1e-3), math.log(MAX_OVER_A), 2001)
        gaps = np.exp(self.u)
        self.xr = np.array([g * outer_flow.resistance(geometry, g, ratios=ratios) for g in gaps])
        self.c = np.array([outer_flow.added_mass(geometry, g, ratios=ratios) for g in gaps])
        self.dc = np.gradient(self.c, self.u) / gaps
        # plain lists and the uniform step: one lookup is called thousands of times per outer
        # phase (np.interp on a scalar costs ~10x this)
        values = (self.xr, self.c, self.dc)
        slopes = [np.gradient(v, self.u) for v in values]
        self._rows = list(zip(*(v.tolist() for v in values), *(d.tolist() for d in slopes)))
        self._u0, self._du = float(self.u[0]), float(self.u[1] - self.u[0])

    def __call__(self, gap):
        """``(R, C, dC/d(x/a))`` at ``x/a = gap``, cubic Hermite in ``ln x`` between the nodes
        (the end nodes' values beyond the ends)."""
        w = (math.log(gap) - self._u0) / self._du
        k = min(max(int(math.floor(w)), 0), len(self._rows) - 2)
        s = min(max(w - k, 0.0), 1.0)
        p, q = self._rows[k], self._rows[k + 1]
        h00, h01 = (1.0 + 2.0 * s) * (1.0 - s) ** 2, s * s * (3.0 - 2.0 * s)
        h10, h11 = s * (1.0 - s) ** 2 * self._du, s * s * (s - 1.0) * self._du
        xr, c, dc = (h00 * p[i] + h10 * p[i + 3] + h01 * q[i] + h11 * q[i + 3] for i in range(3))
        return xr / gap, c, dc


@functools.lru_cache(maxsize=4)
def outer_tables(geometry: str, ratios=outer_flow.UNIT_RATIOS) -> OuterTables:
    """The ``OuterTables`` of ``geometry`` (cached: built once per process and shape)."""
    return OuterTables(geometry, ratios)


class _History:
    """The speed history the history integral reads: the times and each interval's slope
    ``dU/dtau`` of the piecewise-linear speeds, in arrays that grow by doubling. (Rebuilt from
    the lists at every step, as they were, they took 14 of the 22 s of the far starts of
    tests/test_far_field.py.)"""

    def __init__(self, times, speeds):
        self.n = len(times)
        self.t = np.empty(max(2 * self.n, 1024))
        self.slope = np.empty_like(self.t)
        self.t[:self.n] = times
        self.slope[:self.n - 1] = np.diff(speeds) / np.diff(times)
        self.u_last = speeds[-1]

    def append(self, t_new, u_new):
        if self.n == self.t.size:
            self.t = np.concatenate((self.t, np.empty_like(self.t)))
            self.slope = np.concatenate((self.slope, np.empty_like(self.slope)))
        n = self.n
        self.slope[n - 1] = (u_new - self.u_last) / (t_new - self.t[n - 1])
        self.t[n] = t_new
        self.n, self.u_last = n + 1, u_new

    def integral(self, t_new):
        """``Int_(t_0)^(t_new) (dU/dtau) / sqrt(t_new - tau) dtau`` (exact for the
        piecewise-linear speeds)."""
        if self.n < 2:
            return 0.0
        t = self.t[:self.n]
        return float(np.sum(self.slope[:self.n - 1] * 2.0
                            * (np.sqrt(t_new - t[:-1]) - np.sqrt(t_new - t[1:]))))


def _advance(times, speeds, gap, gap_stop, phi, stokes, b, tables, moving_out):
    """March the outer phase from the last of ``times``/``speeds`` (``speeds`` the gap's rate,
    ``dx/dt``) at ``gap`` until the gap passes ``gap_stop`` or the motion stops short of it:
    ``M dU/dT = -R U / St - (1/2) M' U^2 - B H``, ``M = 1 + phi C``, ``H`` the history integral,
    implicit in ``U`` (the last interval of ``H`` included) with ``R``, ``M`` at the step's start;
    steps graded from ``HISTORY_FIRST_STEP`` after the start. Returns the gaps reached."""
    gaps = [gap]
    history = _History(times, speeds)
    dt = HISTORY_FIRST_STEP
    while (gap < gap_stop if moving_out else gap > gap_stop):
        u_old = speeds[-1]
        if (u_old <= 0.0) if moving_out else (u_old >= 0.0):  # the motion stopped short of it
            break
        r, c, dc = tables(gap)
        mass = 1.0 + phi * c
        # H(t_new): the known intervals', and the last one's 2 (U_new - U_old) / sqrt(dt)
        earlier = history.integral(times[-1] + dt)
        coeff = mass / dt + r / stokes + 2.0 * b / math.sqrt(dt)
        rhs = mass * u_old / dt - 0.5 * phi * dc * u_old * u_old - b * earlier \
            + 2.0 * b * u_old / math.sqrt(dt)
        u_new = rhs / coeff
        gap = gap + 0.5 * dt * (u_old + u_new)
        times.append(times[-1] + dt)
        speeds.append(u_new)
        history.append(times[-1], u_new)
        gaps.append(gap)
        # steps graded from the start, and short against the time to cross the gap
        dt = min(dt * HISTORY_GROWTH, HISTORY_MAX_STEP * max(gap, 1.0),
                 GAP_STEP * gap / max(abs(u_new), 1e-3))
    return gaps


def near_field_history(result, x0_over_a):
    """The near field's speed history in the outer units: times ``t v0 / a`` from the arrival
    at ``x0`` (0) to the departure's return to ``x0``, and the gap's rate ``dx/dt`` over ``v0``
    (``-V``), from the result's series (``tau = v0 t / x0``; ``X`` over ``x1``); None when the
    spheres do not come back to ``x0``."""
    s = result.series
    x_start = result.physics.x_start
    tau, x, v = np.asarray(s["tau"]), np.asarray(s["X"]), np.asarray(s["V"])
    out = np.nonzero((v < 0.0) & (x >= x_start))[0]
    if out.size == 0:
        return None
    k = int(out[0])
    # the crossing of x0 on the way out, between rows k-1 and k
    w = (x_start - x[k - 1]) / (x[k] - x[k - 1])
    tau_end = tau[k - 1] + w * (tau[k] - tau[k - 1])
    v_end = v[k - 1] + w * (v[k] - v[k - 1])
    return np.append(tau[:k], tau_end) * x0_over_a, -np.append(v[:k], v_end)


def history_restitution(result, outer=None, coefficient=None):
    """``e_far`` with the Basset history force added to the outer phase (docs/model.md, "Outer
    flow: the history force"): the approach from the outer start, where the spheres moved
    steadily before (shot so that they arrive at ``x0`` with ``v0``), the near field's own speed
    history (``near_field_history``), and the departure until ``x_ref``, all with
    ``M dU/dT = -R U / St - (1/2) M' U^2 - B Int (dU/dtau) / sqrt(T - tau) dtau``
    (``history_coefficient``). The kernel is an isolated sphere's in unsteady Stokes flow, which
    over-estimates the history of a sphere near a wall (whose gap flow is quasi-steady) and at a
    finite Reynolds number (whose kernel decays faster): a bound on what the history force takes
    off, not a prediction. NaN for a failed result, 0 where the spheres stick or stop before
    ``x_ref``; ``e_far`` itself without a fluid density (no history force without it).
    ``coefficient`` replaces ``B`` (0: the same integration without the history force, which
    reproduces ``e_far``: tests/test_far_field.py)."""
    from scipy import optimize  # here: startup paths import this module, not scipy (0.3 s)

    outer = result.outer if outer is None else outer
    if not result.ok:
        return math.nan
    if outer.density_ratio == 0.0:
        return outer.restitution(result.e_x0, result.physics.St)
    if result.e_x0 <= 0.0:
        return 0.0
    stokes, phi = result.physics.St, outer.density_ratio
    b = history_coefficient(stokes, phi) if coefficient is None else coefficient
    tables = outer_tables(outer.geometry, outer.ratios)
    near = near_field_history(result, outer.x0_over_a)
    if near is None:
        return 0.0

    def approach(speed):
        times, speeds = [0.0], [-speed]
        gaps = _advance(times, speeds, outer.start_over_a, outer.x0_over_a, phi, stokes, b,
                        tables, moving_out=False)
        return times, speeds, gaps

    def arrival(speed):  # the speed at x0, interpolated in the gap, less v0 (-1: stopped short)
        _, speeds, gaps = approach(speed)
        if gaps[-1] > outer.x0_over_a:
            return -1.0
        return -np.interp(outer.x0_over_a, gaps[::-1], speeds[::-1]) - 1.0

    guess = outer.approach_speed(stokes)  # without the history force
    hi = guess
    while arrival(hi) < 0.0:
        hi *= 1.5
    lo = hi
    while arrival(lo) > 0.0:
        lo /= 1.5
    speed = optimize.brentq(arrival, lo, hi, xtol=1e-10 * guess, rtol=1e-10)
    times, speeds, gaps = approach(speed)
    v_in = -float(np.interp(outer.x_ref_over_a, gaps[::-1], speeds[::-1]))
    # the near field from the arrival at x0 (the approach's last step ends just past x0)
    t0 = times[-1]
    times += list(t0 + near[0][1:])
    speeds += list(near[1][1:])
    gaps_out = _advance(times, speeds, outer.x0_over_a, outer.x_ref_over_a, phi, stokes, b,
                        tables, moving_out=True)
    if gaps_out[-1] < outer.x_ref_over_a:
        return 0.0
    u_out = float(np.interp(outer.x_ref_over_a, gaps_out, speeds[-len(gaps_out):]))
    return max(u_out, 0.0) / v_in
