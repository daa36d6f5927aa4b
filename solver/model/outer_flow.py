"""The exact Stokes resistance of two rigid spheres (or a sphere and a wall) on their line of centres.

Pure numerics (numpy), no I/O; docs/model.md, "Outer flow: the exact Stokes resistance".
Units follow docs/model.md: ``a`` is the *reduced* radius ``a1 a2 / (a1 + a2)`` (wall: ``a = a1``),
``x`` the gap between the surfaces (surface to surface, or surface to wall), ``v`` the relative
approach velocity, and a resistance is ``R = F / (6 pi mu a v)``, so that the lubrication limit of
every case is ``R ~ a / x`` (the model's rigid force ``f = 6 pi mu a^2 v / x``). ``gap`` arguments
are ``x / a``.

In bispherical coordinates ``(xi, eta)`` with focal distance ``c`` the spheres are ``xi = alpha``
and ``xi = -beta`` (a plane wall: ``beta = 0``), and the stream function is
``psi = (cosh xi - cos eta)^(-3/2) sum_n U_n(xi) C_{n+1}^{-1/2}(cos eta)`` with
``U_n = a_n cosh((n-1/2) xi) + b_n sinh((n-1/2) xi) + c_n cosh((n+3/2) xi) + d_n sinh((n+3/2) xi)``
(Stimson & Jeffery 1926). No slip on a sphere moving with ``u`` along the axis fixes ``U_n`` and
``U_n'`` there (``k_n`` below: the expansion of ``(1 - mu^2)(cosh xi - mu)^(-1/2)``); four
conditions per ``n``, and the force on the sphere ``xi = alpha`` is
``F = 2 pi mu c u sum_n (a_n + b_n + c_n + d_n)`` for coefficients normalised by ``u c^2 / sqrt 2``,
i.e. ``F / (6 pi mu a1 u) = (sinh alpha / 3) sum_n (a_n + b_n + c_n + d_n)``.

- Sphere and wall (Brenner 1961): the closed-form sum, ``wall_resistance``.
- Two equal spheres approaching each other with equal and opposite velocities: the flow is odd
  in ``xi`` (``a_n = c_n = 0``), a 2x2 system per ``n`` solved in closed form,
  ``equal_spheres_resistance`` (the same problem as a sphere approaching a free surface, Brenner
  1961; Maude 1961).
- Two spheres of any sizes and velocities: the 4x4 system per ``n``, ``pair_forces``.
- Two free spheres of any sizes and masses in their relative motion (zero momentum of the pair):
  ``pair_resistance`` and ``pair_added_mass`` (docs/model.md, "Outer flow: two unequal spheres").

Convergence: every term behaves like ``n^2 exp(-(2n+1) alpha)`` at large ``n`` (the exponentials
of the solution decay as ``exp(-2 n alpha)`` away from the spheres), so past some ``n`` the ratio of
successive terms ``r_n = t_n / t_{n-1}`` is below 1 and non-increasing (``((n/(n-1))^2 e^(-2 alpha)``);
the tail after term ``N`` is then bounded by the geometric series ``t_N r_N / (1 - r_N)``. The sum
is extended (number of terms doubled) until that bound, checked on the last terms, is below
``tol`` absolute (default 1e-12: absolute rather than relative so that ``R - a/x`` keeps its
digits at small gaps, where ``R ~ a/x`` is large). Near contact ``alpha ~ sqrt(2 x / a)`` and the
number of terms grows like ``30 / alpha`` (16000 at ``x = 1e-6 a``; vectorised, milliseconds).

The small-gap cancellations (``sinh(m alpha) - m sinh alpha`` is ``O(alpha^3)``) are evaluated by
their series, and every exponential is scaled by ``exp(-(2n+1) alpha)``, so the closed forms keep
their relative precision from ``x = 1e-8 a`` to ``x = 1e8 a``. ``pair_forces`` solves the linear
system directly and loses ``~ log10(1 / alpha^2)`` digits at small gaps (use it for
``x > 1e-4 a`` where 1e-9 matters).

Joining the lubrication region: ``wall_outer`` and ``equal_spheres_outer`` give ``R - a/x``, the
part of the exact resistance the film's ``a/x`` leaves out. It is finite for every ``x > 0`` but
grows like ``c1 ln(a/x)`` as ``x -> 0`` (Cox & Brenner 1967: ``c1 = 1/5`` for the wall, ``9/20`` for
equal spheres in these units; Jeffrey & Onishi 1984); ``*_outer_regular`` subtracts that
logarithm too and tends to a constant (wall: 0.971, Cox & Brenner 1967).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "WALL_LOG", "EQUAL_LOG", "wall_resistance", "equal_spheres_resistance", "pair_forces",
    "wall_outer", "equal_spheres_outer", "wall_outer_regular", "equal_spheres_outer_regular",
    "alpha_wall", "alpha_equal", "GEOMETRIES", "resistance", "outer",
    "wall_added_mass", "equal_spheres_added_mass", "added_mass", "ZETA3",
    "pair_log", "pair_velocities", "pair_resistance", "pair_added_mass", "log_coefficient",
]

# coefficient of ln(a/x) in R (units of the module docstring): Cox & Brenner (1967) for the wall;
# for two spheres Jeffrey & Onishi (1984) g2 = l(1 + 7 l + l^2) / (5 (1 + l)^3), ratio l = 1: 9/40
# for X11 - X12 with their single-sphere scales, i.e. 9/20 in R (a = reduced radius, v relative).
WALL_LOG = 0.2
EQUAL_LOG = 0.45

TOL = 1e-12
_N_MAX = 1 << 22


def _check_gap(gap: float) -> float:
    gap = float(gap)
    if not (math.isfinite(gap) and gap > 0.0):
        raise ValueError(f"gap must be a finite number > 0 (x / a), got {gap!r}")
    return gap


def alpha_wall(gap: float) -> float:
    """``alpha`` of a sphere at gap ``x = gap * a`` from a wall: ``cosh alpha = 1 + x/a``
    (``h = a cosh alpha`` the centre's distance to the wall), without cancellation."""
    gap = _check_gap(gap)
    return math.asinh(math.sqrt(gap * (2.0 + gap)))


def alpha_equal(gap: float) -> float:
    """``alpha`` of each of two equal spheres (radius ``2a``, ``a`` the reduced radius) at gap
    ``x = gap * a``: ``cosh alpha = d / (4 a) = 1 + gap/4`` (``d`` the centre distance)."""
    gap = _check_gap(gap)
    g = 0.25 * gap
    return math.asinh(math.sqrt(g * (2.0 + g)))


# The powers 2k+1 (k = 1..24) of _sinh_excess's series and their factorials:
# (y t)^(2k) / (2k+1)! < 1e-17 relative by k = 10 when y t < 1
_ODD = 2.0 * np.arange(1, 25) + 1.0
_ODD_FACTORIAL = np.array([float(math.factorial(int(k))) for k in _ODD])


def _sinh_excess(y: np.ndarray, t: float) -> np.ndarray:
    """``exp(-y t) (sinh(y t) - y sinh t)`` for ``y >= 1``, ``t > 0``, accurate where it is
    ``O(t^3)`` (series ``sum_k (y^(2k+1) - y) t^(2k+1) / (2k+1)!`` for ``y t < 1``)."""
    yt = y * t
    out = np.empty_like(yt)
    small = yt < 1.0
    if small.any():
        ys = y[small][:, None]
        acc = ((ys**_ODD - ys) * (t**_ODD / _ODD_FACTORIAL)).sum(axis=1)
        out[small] = np.exp(-yt[small]) * acc
    big = ~small
    if big.any():
        yb = yt[big]
        out[big] = 0.5 * (1.0 - np.exp(-2.0 * yb)) - y[big] * math.sinh(t) * np.exp(-yb)
    return out


def _tail_bound(t: np.ndarray) -> float:
    """Bound on the sum of the terms after the last of ``t`` (inf if the terms do not yet decay
    geometrically with non-increasing ratio over the last 8)."""
    last = np.abs(t[-8:])
    if last[-1] == 0.0:
        return 0.0 if np.all(last[:-1] >= last[1:]) else math.inf
    if np.any(last[:-1] == 0.0):
        return math.inf
    ratios = last[1:] / last[:-1]
    r = ratios[-1]
    # non-increasing up to round-off in the ratio itself
    if r < 1.0 and np.all(np.diff(ratios) <= 1e-9 * ratios[1:]):
        return float(last[-1] * r / (1.0 - r))
    return math.inf


def _sum_series(terms, n_guess: int, tol: float):
    """Sum ``terms(n)`` (n = 1, 2, ...; one row or several) until the geometric tail bound of
    every row is below ``tol``, doubling the number of terms."""
    n_terms = max(16, int(n_guess))
    while True:
        n = np.arange(1, n_terms + 1, dtype=float)
        t = np.atleast_2d(terms(n))
        if not np.all(np.isfinite(t)):
            raise FloatingPointError("outer-flow series produced a non-finite term")
        if all(_tail_bound(row) < tol for row in t):
            totals = np.sum(t, axis=-1)
            return float(totals[0]) if totals.size == 1 else tuple(float(v) for v in totals)
        if n_terms >= _N_MAX:
            raise FloatingPointError(f"outer-flow series not converged with {n_terms} terms")
        n_terms *= 2


def _n_guess(alpha: float, tol: float) -> int:
    # terms ~ n^2 exp(-2 n alpha) / alpha: enough for exp(-2 N alpha) ~ tol alpha^3
    return int(math.ceil((math.log(1.0 / tol) + 3.0 * math.log(1.0 + 1.0 / alpha)) / (2.0 * alpha))) + 8


def wall_resistance(gap: float, tol: float = TOL) -> float:
    """``lambda = F / (6 pi mu a v)`` of a sphere (radius ``a``) moving at ``v`` normal to a plane
    wall at gap ``x = gap * a`` (surface to wall; centre distance ``h = a + x = a cosh alpha``).

    Brenner (1961), eq. (2.19):
    ``lambda = (4/3) sinh alpha sum_{n>=1} n(n+1) / ((2n-1)(2n+3)) [ (2 sinh((2n+1) alpha)
    + (2n+1) sinh(2 alpha)) / (4 sinh^2((n+1/2) alpha) - (2n+1)^2 sinh^2 alpha) - 1 ]``,
    evaluated as ``E [2(1-E) + m sinh 2a + m^2 sinh^2 a] / (4 s_-(n) s_+(n))`` with
    ``m = 2n+1``, ``E = exp(-m alpha)`` and ``s_(+-) = exp(-m a/2)(sinh(m a/2) +- (m/2) sinh a)``.
    """
    alpha = alpha_wall(gap)
    sh, sh2 = math.sinh(alpha), math.sinh(2.0 * alpha)

    def terms(n):
        m = 2.0 * n + 1.0
        y = 0.5 * m
        e = np.exp(-m * alpha)
        minus = _sinh_excess(y, alpha)
        plus = 0.5 * (1.0 - np.exp(-2.0 * y * alpha)) + y * sh * np.exp(-y * alpha)
        num = e * (2.0 * (-np.expm1(-m * alpha)) + m * sh2 + m * m * sh * sh)
        return n * (n + 1.0) / ((2.0 * n - 1.0) * (2.0 * n + 3.0)) * num / (4.0 * minus * plus)

    return 4.0 / 3.0 * sh * _sum_series(terms, _n_guess(alpha, tol), tol)


def _k(n, alpha):
    """Expansion coefficient of ``(1 - mu^2)(cosh xi - mu)^(-1/2)`` at ``xi = alpha > 0`` in
    ``C_{n+1}^{-1/2}(mu)``, divided by ``sqrt 2``, and its ``xi``-derivative (Stimson & Jeffery)."""
    ep, eq = np.exp(-(n - 0.5) * alpha), np.exp(-(n + 1.5) * alpha)
    nn = n * (n + 1.0)
    return nn * (ep / (2.0 * n - 1.0) - eq / (2.0 * n + 3.0)), 0.5 * nn * (eq - ep)


def equal_spheres_resistance(gap: float, tol: float = TOL) -> float:
    """``F / (6 pi mu a v)`` on each of two equal spheres (radius ``2a``: ``a`` is the reduced
    radius) approaching each other, each at ``v/2`` (``v`` the relative velocity), at gap
    ``x = gap * a``. Equals ``F / (6 pi mu a_s u)`` with ``a_s = 2a`` the sphere's radius and
    ``u = v/2`` its own speed (the single-sphere convention): the two factors of 2 cancel.

    The flow is odd in ``xi``: ``U_n = b_n sinh(p xi) + d_n sinh(q xi)``, ``p = n - 1/2``,
    ``q = n + 3/2``, with ``U_n(alpha) = k_n``, ``U_n'(alpha) = k_n'``, so
    ``b_n + d_n = [k_n (q cosh q a - p cosh p a) + k_n' (sinh p a - sinh q a)] / Delta_n``,
    ``Delta_n = sinh((2n+1) a) - (2n+1) sinh a cosh a`` (the denominator of Brenner's 1961
    free-surface series), and ``R = (sinh alpha / 3) sum_n (b_n + d_n)``.
    """
    alpha = alpha_equal(gap)
    sh = math.sinh(alpha)
    cm1 = 2.0 * math.sinh(0.5 * alpha) ** 2  # cosh alpha - 1

    def terms(n):
        p, q, m = n - 0.5, n + 1.5, 2.0 * n + 1.0
        k, kp = _k(n, alpha)
        # numerator and Delta both times 2 exp(-m alpha), Delta written as
        # (sinh(m a) - m sinh a) - m sinh a (cosh a - 1) to keep its O(alpha^3) digits
        delta = 2.0 * _sinh_excess(m, alpha) - m * sh * cm1 * 2.0 * np.exp(-m * alpha)
        # 2 e^{-m a} cosh(s a) = e^{(s-m) a} + e^{-(s+m) a}, likewise sinh
        cq = np.exp((q - m) * alpha) + np.exp(-(q + m) * alpha)
        cp = np.exp((p - m) * alpha) + np.exp(-(p + m) * alpha)
        sp = np.exp((p - m) * alpha) - np.exp(-(p + m) * alpha)
        sq = np.exp((q - m) * alpha) - np.exp(-(q + m) * alpha)
        return (k * (q * cq - p * cp) + kp * (sp - sq)) / delta

    return sh / 3.0 * _sum_series(terms, _n_guess(alpha, tol), tol)


def pair_forces(gap: float, radius_ratio: float, u1: float, u2: float,
                tol: float = TOL) -> tuple[float, float]:
    """Forces on two spheres (radii ``a1``, ``a2 = radius_ratio * a1``) moving along their line of
    centres with velocities ``u1``, ``u2`` (positive: from sphere 1 towards sphere 2), at gap
    ``x = gap * a``, ``a = a1 a2 / (a1 + a2)`` the reduced radius.

    Returns ``(F1 / (6 pi mu a1), F2 / (6 pi mu a2))`` (velocity units, positive along the same
    direction): an isolated sphere gives ``-u``. The 4x4 system per ``n`` is solved in the basis
    ``exp(+-s (xi - alpha))``, ``exp(+-s (xi + beta))`` (``s = p, q``), whose matrix entries are at
    most 1. Small-gap precision: see the module docstring.
    """
    gap = _check_gap(gap)
    ratio = float(radius_ratio)
    if not (math.isfinite(ratio) and ratio > 0.0):
        raise ValueError(f"radius_ratio must be a finite number > 0, got {radius_ratio!r}")
    a1, a2 = 1.0, ratio
    x = gap * a1 * a2 / (a1 + a2)
    d = a1 + a2 + x
    # cosh alpha - 1 = x (x + 2 a2) / (2 d a1), cosh beta - 1 = x (x + 2 a1) / (2 d a2)
    ca, cb = x * (x + 2.0 * a2) / (2.0 * d * a1), x * (x + 2.0 * a1) / (2.0 * d * a2)
    alpha, beta = math.asinh(math.sqrt(ca * (2.0 + ca))), math.asinh(math.sqrt(cb * (2.0 + cb)))
    # sphere 1 at xi = alpha (z > 0); "towards sphere 2" is -z
    w1, w2 = -float(u1), -float(u2)

    def solve(n):
        p, q = n - 0.5, n + 1.5
        ep, eq = np.exp(-p * (alpha + beta)), np.exp(-q * (alpha + beta))
        ka, kpa = _k(n, alpha)
        kb, kpb = _k(n, beta)
        one = np.ones_like(n)
        mat = np.stack([
            np.stack([one, ep, one, eq], -1),
            np.stack([p, -p * ep, q, -q * eq], -1),
            np.stack([ep, one, eq, one], -1),
            np.stack([p * ep, -p, q * eq, -q], -1)], -2)
        rhs = np.stack([w1 * ka, w1 * kpa, w2 * kb, -w2 * kpb], -1)
        A, B, C, D = np.linalg.solve(mat, rhs[..., None])[..., 0].T
        # a+b+c+d on xi = alpha and a-b+c-d on xi = -beta
        return (2.0 * (A * np.exp(-p * alpha) + C * np.exp(-q * alpha)),
                2.0 * (B * np.exp(-p * beta) + D * np.exp(-q * beta)))

    s1, s2 = _sum_series(lambda n: np.stack(solve(n)), _n_guess(max(alpha, beta), tol), tol)
    # with w = -u the coefficients give F / (6 pi mu a_i) along the direction "towards the other
    # sphere" of each: sphere 1 gets -u1 lambda, sphere 2 the mirror image (checked in the tests
    # against the isolated-sphere drag, the first reflection and the wall limit)
    return math.sinh(alpha) / 3.0 * s1, math.sinh(beta) / 3.0 * s2


def wall_outer(gap: float, tol: float = TOL) -> float:
    """``lambda - a/x`` for the sphere and wall: what the exact resistance adds to the film's
    ``a/x``. Finite for ``x > 0``; ``~ (1/5) ln(a/x) + 0.971`` as ``x -> 0``, ``-> 1 - a/x`` far
    away. The rigid approach's force is ``6 pi mu a v (a/x + wall_outer(x/a))``."""
    return wall_resistance(gap, tol) - 1.0 / _check_gap(gap)


def wall_outer_regular(gap: float, tol: float = TOL) -> float:
    """``lambda - a/x - (1/5) ln(a/x)``: bounded, tends to Cox & Brenner's 0.971 as ``x -> 0``."""
    return wall_outer(gap, tol) - WALL_LOG * math.log(1.0 / gap)


def equal_spheres_outer(gap: float, tol: float = TOL) -> float:
    """``R - a/x`` for two equal spheres (``a`` the reduced radius, ``R`` of
    ``equal_spheres_resistance``); ``~ (9/20) ln(a/x) + const`` as ``x -> 0``."""
    return equal_spheres_resistance(gap, tol) - 1.0 / _check_gap(gap)


def equal_spheres_outer_regular(gap: float, tol: float = TOL) -> float:
    """``R - a/x - (9/20) ln(a/x)`` for two equal spheres: bounded as ``x -> 0``."""
    return equal_spheres_outer(gap, tol) - EQUAL_LOG * math.log(1.0 / gap)


# ---- the outer phase: resistance by geometry, and the added mass of potential flow ----------------

GEOMETRIES = ("wall", "spheres", "pair")  # a sphere and a plane wall; two equal spheres;
# two spheres of any radii and masses ("pair": needs ``ratios``, the radius and mass ratios)
UNIT_RATIOS = (1.0, 1.0)

ZETA3 = 1.2020569031595942  # Riemann zeta(3): the contact value of the image series below


def _check_geometry(geometry: str) -> str:
    if geometry not in GEOMETRIES:
        raise ValueError(f"geometry must be one of {', '.join(GEOMETRIES)}, got {geometry!r}")
    return geometry


def resistance(geometry: str, gap: float, tol: float = TOL, ratios=UNIT_RATIOS) -> float:
    """``R = F / (6 pi mu a v)`` of ``geometry`` ("wall": ``wall_resistance``; "spheres": two
    equal spheres, ``equal_spheres_resistance``; "pair": ``pair_resistance`` with
    ``ratios = (a2/a1, m2/m1)``) at gap ``x = gap * a``."""
    if _check_geometry(geometry) == "wall":
        return wall_resistance(gap, tol)
    if geometry == "pair":
        return pair_resistance(gap, *ratios, tol=tol)
    return equal_spheres_resistance(gap, tol)


def outer(geometry: str, gap: float, tol: float = TOL, ratios=UNIT_RATIOS) -> float:
    """``R - a/x`` of ``geometry``: what the exact resistance adds to the film's ``a/x``."""
    return resistance(geometry, gap, tol, ratios) - 1.0 / _check_gap(gap)


def log_coefficient(geometry: str, ratios=UNIT_RATIOS) -> float:
    """The coefficient of ``ln(a/x)`` in ``R`` near contact (``WALL_LOG``, ``EQUAL_LOG``,
    ``pair_log``)."""
    if _check_geometry(geometry) == "wall":
        return WALL_LOG
    return pair_log(ratios[0]) if geometry == "pair" else EQUAL_LOG


def wall_added_mass(gap: float, tol: float = TOL) -> float:
    """Added-mass coefficient ``C = m_a / (rho_f V)`` of a sphere (radius ``a``, volume ``V``)
    moving normal to a plane wall at gap ``x = gap * a``, in potential flow:

        C = 1/2 + (3/2) sum_(n>=2) (sinh alpha / sinh(n alpha))^3,    cosh alpha = 1 + x/a.

    The wall is the mirror plane of the sphere and its image approaching each other; an axial
    dipole outside a sphere at distance ``f`` from its centre has the image dipole ``(a/f)^3``
    times as strong at the inverse point (the sphere theorem; Milne-Thomson, *Theoretical
    Hydrodynamics*, ch. 16), and the chain of images has strengths ``(sinh alpha/sinh n alpha)^3``
    (Hicks 1880; Lamb 1932, art. 98); the kinetic energy of the fluid gives ``C`` (docs/model.md,
    "Outer flow: the far-field restitution"). Far away ``C = 1/2 + (3/16)(a/h)^3 + ...``
    (``h = a + x``); at contact ``1/2 + (3/2)(zeta(3) - 1) = 0.80309``: finite.

    Terms ``t_n`` fall with ratio below ``exp(-3 alpha)``, so the tail after ``N`` is below
    ``t_N exp(-3 alpha) / (1 - exp(-3 alpha))``; terms are added until that is below ``tol``.
    """
    alpha = alpha_wall(gap)
    q = math.exp(-3.0 * alpha)
    n_terms = 64
    while True:
        n = np.arange(2, n_terms + 2, dtype=float)
        # sinh a / sinh(n a) = exp(-(n-1) a) (1 - exp(-2a)) / (1 - exp(-2 n a)), no overflow
        ratio = np.exp(-(n - 1.0) * alpha) * (-math.expm1(-2.0 * alpha)) / (-np.expm1(-2.0 * n * alpha))
        t = ratio ** 3
        if t[-1] * q / (1.0 - q) < tol:
            return 0.5 + 1.5 * float(np.sum(t[::-1]))
        if n_terms >= _N_MAX:
            raise FloatingPointError(f"added-mass series not converged with {n_terms} terms")
        n_terms *= 2


def equal_spheres_added_mass(gap: float, tol: float = TOL) -> float:
    """``C`` of each of two equal spheres (radius ``2a``, ``a`` the reduced radius) approaching
    each other at gap ``x = gap * a``: the midplane is a plane of symmetry, so each sphere sees
    the wall at gap ``x/2``, i.e. ``wall_added_mass(gap / 4)`` in units of its own radius."""
    return wall_added_mass(_check_gap(gap) / 4.0, tol)


def added_mass(geometry: str, gap: float, tol: float = TOL, ratios=UNIT_RATIOS) -> float:
    """``C`` of ``geometry`` at gap ``x = gap * a`` (``wall_added_mass``,
    ``equal_spheres_added_mass`` or ``pair_added_mass`` with ``ratios = (a2/a1, m2/m1)``)."""
    if _check_geometry(geometry) == "wall":
        return wall_added_mass(gap, tol)
    if geometry == "pair":
        return pair_added_mass(gap, *ratios, tol=tol)
    return equal_spheres_added_mass(gap, tol)


# ---- two free spheres of any radii and masses: their relative motion --------------------------

def _check_ratios(radius_ratio: float, mass_ratio: float) -> tuple[float, float]:
    out = []
    for name, value in (("radius_ratio", radius_ratio), ("mass_ratio", mass_ratio)):
        value = float(value)
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        out.append(value)
    return out[0], out[1]


def pair_log(radius_ratio: float) -> float:
    """Coefficient of ``ln(a/x)`` in ``pair_resistance`` near contact: Jeffrey & Onishi's (1984)
    ``g2 = l (1 + 7 l + l^2) / (5 (1 + l)^3)`` (``l = a2/a1``, in ``F / (6 pi mu a1 u)``) in
    units of the reduced radius, ``(1 + 7 l + l^2) / (5 (1 + l)^2)``: 9/20 at ``l = 1``, 1/5 as
    ``l -> inf`` (the wall). The film's forces on the two spheres are equal and opposite to this
    order, so it does not depend on the masses."""
    lam, _ = _check_ratios(radius_ratio, 1.0)
    return (1.0 + 7.0 * lam + lam * lam) / (5.0 * (1.0 + lam) ** 2)


def pair_velocities(mass_ratio: float) -> tuple[float, float]:
    """``(u1, u2)`` of two free spheres approaching each other at unit relative speed with zero
    momentum (``m1 u1 + m2 u2 = 0``): ``u1 = m/m1``, ``u2 = -m/m2``, ``m`` the reduced mass."""
    _, mu = _check_ratios(1.0, mass_ratio)
    return mu / (1.0 + mu), -1.0 / (1.0 + mu)


def pair_resistance(gap: float, radius_ratio: float, mass_ratio: float,
                    tol: float = TOL) -> float:
    """``R = Q / (6 pi mu a v)`` of two free spheres (radii ``a1``, ``a2 = radius_ratio a1``,
    masses ``m2 = mass_ratio m1``) approaching each other at relative speed ``v`` with zero
    momentum (``pair_velocities``), ``Q = m (F1/m1 - F2/m2)`` the generalised force of the
    relative coordinate (``m dv/dt = -Q``; ``Q v`` is the power the fluid takes, ``-(F1 u1 + F2
    u2)``), at gap ``x = gap * a``. From ``pair_forces`` (its precision). Equal spheres and
    masses: ``equal_spheres_resistance``; ``a2, m2 -> inf``: ``wall_resistance``."""
    lam, mu = _check_ratios(radius_ratio, mass_ratio)
    u1, u2 = pair_velocities(mu)
    f1, f2 = pair_forces(gap, lam, u1, u2, tol)
    a = lam / (1.0 + lam)  # a1 = 1
    # F_i / m_i over (6 pi mu a v / m): a_i f_i m / m_i, with m/m1 = u1, m/m2 = -u2
    return -(f1 * u1 + lam * f2 * u2) / a


def pair_added_mass(gap: float, radius_ratio: float, mass_ratio: float,
                    tol: float = TOL) -> float:
    """Added-mass coefficient ``C`` of two free spheres in the relative motion of
    ``pair_velocities`` at unit relative speed, at gap ``x = gap * a``: the fluid's kinetic energy
    is ``(1/2) m phi C v^2`` with ``phi = rho_f V1 / (2 m)`` (the scene's ``density_ratio`` of
    two spheres), i.e. ``C = 4 T / (rho_f V1 v^2)``; two equal spheres and masses:
    ``equal_spheres_added_mass``; a wall (``a2, m2 -> inf``): ``2 wall_added_mass``.

    Potential flow: each sphere's own dipole ``-u_i a_i^3 / 2`` and the chain of its images in the
    other sphere and back (an axial dipole ``q`` at distance ``f`` from the centre of a sphere of
    radius ``b`` has the image ``-q (b/f)^3`` at the inverse point ``b^2/f``, Hicks 1880; Lamb
    1932, art. 98). On sphere ``i`` (``n`` its outward normal) ``Int phi n_z dS =
    V_i (3 E_i / 2 - u_i / 2)``, ``E_i`` the axial gradient at its centre of the dipoles inside
    the other sphere, so ``T = (rho/2) sum_i V_i u_i (u_i / 2 - 3 E_i / 2)``. The images' terms
    fall geometrically; they are added until the geometric tail bound is below ``tol``."""
    lam, mu = _check_ratios(radius_ratio, mass_ratio)
    gap = _check_gap(gap)
    radius = (1.0, lam)
    centre = (0.0, 1.0 + lam + gap * lam / (1.0 + lam))
    velocity = pair_velocities(mu)
    volume = (1.0, lam ** 3)
    grad = [0.0, 0.0]  # E_1, E_2
    for home in (0, 1):
        q, z = -0.5 * velocity[home] * radius[home] ** 3, centre[home]
        other = 1 - home
        grad[other] += -2.0 * q / abs(centre[other] - z) ** 3
        # what each term adds to T is V_other |term|; it falls by the same ratio each round trip
        # (an image in the other sphere and its image back), so the tail is bounded from those
        weights = [math.inf, math.inf]
        for _ in range(_N_MAX):
            home, other = other, home  # the image lies in the other sphere
            f = abs(z - centre[home])
            q = -q * (radius[home] / f) ** 3
            z = centre[home] + math.copysign(radius[home] ** 2 / f, z - centre[home])
            term = -2.0 * q / abs(centre[other] - z) ** 3
            grad[other] += term
            weight = volume[other] * abs(term)
            ratio = weight / weights[other]  # 0 on the first term of each sphere: not yet known
            weights[other] = weight
            if 0.0 < ratio < 1.0 and max(weights) * ratio / (1.0 - ratio) < tol:
                break
        else:
            raise FloatingPointError("pair added-mass image chain not converged")
    return 2.0 * sum(v * u * (0.5 * u - 1.5 * e) for v, u, e in zip(volume, velocity, grad))
