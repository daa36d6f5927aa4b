"""The liquid's constitutive laws: viscosity and density against the film pressure.

Dimensionless (docs/model.md, "Pressure-dependent viscosity and density"): ``mu_bar = mu/mu0``
and ``rho_bar = rho/rho0`` as functions of the gauge pressure ``P`` in ``p* = mu0 a v0 / x1^2``,
read from the physics array (solver/physics.py: ``BETA``, ``VISCOSITY``...):

- viscosity: constant; Barus ``ln mu_bar = beta P``; Roelands
  ``ln mu_bar = (beta P_R / Z) ((1 + P/P_R)^Z - 1)`` (slope ``beta`` at ``P = 0``); a measured
  table, ``ln mu_bar`` linear in ``P`` between its points (``TABLE``: their number ``K``, the
  pressures, the logs), beyond the last with its slope;
- density: constant; Dowson-Higginson ``rho_bar = 1 + c1 P / (1 + c2 P)``.

The viscosity law applies to compression only: where ``P <= 0`` the liquid keeps its ambient
viscosity (a real liquid cavitates long before the Barus formula's thinning in tension matters;
``viscosity_in_tension = "law"`` reads the viscosity law at ``P < 0`` too, for comparison). The
density's compressibility ``c1`` fades in tension over ``TENSION_WIDTH``, so it expands by at most
``c1 TENSION_WIDTH`` (docs/model.md says why neither "compression only" nor the law itself).

What the film needs from them (model/film.py):

- ``kirchhoff_difference``: ``Int rho_bar/mu_bar dP`` between two nodes, the pressure difference
  that drives the face flux (the generalised Kirchhoff transform). ``g = ln mu_bar - ln rho_bar``
  is taken linear in ``P`` between the nodes, so the integral is an exponential fit: exact for
  Barus with constant density (``g = beta P``), second order otherwise; evaluated relative to
  the node with the smaller ``g``, without the cancellation that ruins the reduced pressure
  ``(1 - exp(-beta P))/beta`` as an unknown once ``beta P ~ 30``. ``kirchhoff_between`` takes
  each node's ``mobility`` (``exp(-g)``), so a loop over the faces takes one exponential per
  node; ``kirchhoff_pressure`` is its value from 0 (the step's error scale, and the rigid film's
  inverse below);
- ``density``, for the cells' liquid content ``rho_bar theta H``;
- ``volume_difference`` (``Int dP / rho_bar``) and ``compression_energy``: the energy terms;
- ``pressure_of_kirchhoff``, its inverse: the pressure of a rigid film at constant density,
  whose Kirchhoff pressure is the classic film's (the coupled phase's start).
"""

import math

import numpy as np

from .._jit import entry, hook, jit, leaf
from ..physics import (BETA, DENSITY, DENSITY_LAWS, DH_C1, DH_C2, ROELANDS_PR, ROELANDS_Z, TABLE,
                       TENSION, TENSION_CHOICES, VISCOSITY, VISCOSITY_LAWS)
from .kind import LIQUID_CODE, asks_liquid_law

# codes in the physics array (solver/physics.py: a choice's code is its place in codes(name));
# CONSTANT is the code of the constant viscosity and of the constant density alike
CONSTANT, BARUS, ROELANDS, TABULATED = (float(VISCOSITY_LAWS.index(law))
                                        for law in ("constant", "barus", "roelands", "table"))
assert DENSITY_LAWS.index("constant") == CONSTANT
LAW_IN_TENSION = float(TENSION_CHOICES.index("law"))
# Roelands read in tension ("law") is undefined at P <= -P_R; it is held at this fraction of it
ROELANDS_TENSION_LIMIT = 0.99
# Tension over which a compressible liquid's compressibility fades (in p*; ~5 MPa at
# p* = 5e8 Pa, the order of liquids' tensile strength, beyond which they cavitate). Compression
# only with a jump of the compressibility at P = 0 made a draining compressed cell's pressure
# jump where it crossed 0 (its storage vanished): the step underflowed (docs/model.md)
TENSION_WIDTH = 0.01
# A viscosity law read in tension (viscosity_in_tension = "law") thins the liquid by exp(beta P):
# beyond exp(300) (1e130) its mobility is held there, or a Newton iterate at P = -16, beta = 45
# overflowed to inf (found by a random scan). No pressure a collision reaches is near it for the
# laws read in compression, where the mobility only falls.
THINNING_LIMIT = 300.0


@hook
def isoviscous(phys):
    """True when neither viscosity nor density depends on pressure (the classic film); always in
    a copy of the loop without the liquid's laws (model/kind.py), whose branches numba prunes."""
    if LIQUID_CODE and asks_liquid_law(phys):
        return False
    return True


@hook
def constant_density(phys):
    """True when the density does not depend on pressure."""
    if LIQUID_CODE and phys[DENSITY] != CONSTANT:
        return False
    return True


@leaf
def log_viscosity(p, phys):
    """``ln mu_bar`` at the pressure ``p`` and its derivative in ``p``."""
    law = phys[VISCOSITY]
    if law == CONSTANT:
        return 0.0, 0.0
    if p <= 0.0 and phys[TENSION] != LAW_IN_TENSION:
        return 0.0, 0.0
    if law == TABULATED:
        return _tabulated(p, phys)
    beta = phys[BETA]
    if law == BARUS:
        return beta * p, beta
    z = phys[ROELANDS_Z]
    p_r = phys[ROELANDS_PR]
    base = 1.0 + max(p, -ROELANDS_TENSION_LIMIT * p_r) / p_r
    slope = beta * base ** (z - 1.0) if p > -ROELANDS_TENSION_LIMIT * p_r else 0.0
    return beta * p_r / z * (base**z - 1.0), slope


@leaf
def _tabulated(p, phys):
    """``ln mu_bar`` of the table and its slope: linear between the points, extended beyond the
    ends with the end segments' slopes (in tension too when the law is read there)."""
    k = int(phys[TABLE])
    j = 0
    while j < k - 2 and p > phys[TABLE + 2 + j]:
        j += 1
    p0 = phys[TABLE + 1 + j]
    slope = (phys[TABLE + 1 + k + j + 1] - phys[TABLE + 1 + k + j]) / (phys[TABLE + 2 + j] - p0)
    return phys[TABLE + 1 + k + j] + slope * (p - p0), slope


@leaf
def _next_kink(x, b, phys):
    """The first pressure above ``x`` and below ``b`` where ``ln(mu/rho)`` has a kink: 0 (the
    viscosity law applies to compression only, and the density changes its law there) and a
    table's points; ``b`` when there is none."""
    nxt = b
    if x < 0.0 < nxt:
        nxt = 0.0
    if phys[VISCOSITY] == TABULATED:
        k = int(phys[TABLE])
        for j in range(1, k):
            pj = phys[TABLE + 1 + j]
            if x < pj < nxt:
                nxt = pj
    return nxt


@leaf
def kink_departure(p_lo, p_hi, phys):
    """How far the kinks of the laws strictly between ``p_lo`` and ``p_hi`` (``_next_kink``;
    ``p_lo <= p_hi``) take ``ln(mu/rho)`` from a smooth curve over that range: the largest jump of
    its slope at one of them times ``p_hi - p_lo`` (0 where there is none). Barus at ``P = 0``
    with the ambient viscosity in tension: ``beta (p_hi - p_lo)``. The slopes are read a
    ``1e-9`` of the range to either side (each law is smooth there, and linear for Barus and a
    table)."""
    width = 1e-9 * (p_hi - p_lo)
    largest = 0.0
    x = _next_kink(p_lo, p_hi, phys)
    while x < p_hi:
        jump = abs(_mobility_log(x + width, phys)[1] - _mobility_log(x - width, phys)[1])
        largest = max(largest, jump)
        x = _next_kink(x, p_hi, phys)
    return largest * (p_hi - p_lo)


@leaf
def density(p, phys):
    """``rho_bar`` at the pressure ``p`` and its derivative in ``p``: Dowson-Higginson in
    compression; in tension its compressibility ``c1`` at 0 fades over ``TENSION_WIDTH``,
    ``1 + c1 w (exp(P/w) - 1)``, so the density and its slope are continuous at 0 and the liquid
    expands by at most ``c1 w``."""
    if constant_density(phys):
        return 1.0, 0.0
    c1 = phys[DH_C1]
    if p <= 0.0:
        e = math.exp(p / TENSION_WIDTH)
        return 1.0 + c1 * TENSION_WIDTH * (e - 1.0), c1 * e
    c2 = phys[DH_C2]
    den = 1.0 + c2 * p
    return 1.0 + c1 * p / den, c1 / (den * den)


@leaf
def _mobility_log(p, phys):
    """``g = ln mu_bar - ln rho_bar`` (``rho_bar/mu_bar = exp(-g)``) and ``dg/dp``; held at
    ``-THINNING_LIMIT`` below it (only a viscosity law read in tension gets there)."""
    g, dg = log_viscosity(p, phys)
    if not constant_density(phys):
        rho, drho = density(p, phys)
        g -= math.log(rho)
        dg -= drho / rho
    if g < -THINNING_LIMIT:
        return -THINNING_LIMIT, 0.0
    return g, dg


@leaf
def mobility(p, phys):
    """``(g, dg/dp, exp(-g))`` at the pressure ``p``, ``g = ln mu_bar - ln rho_bar``
    (``_mobility_log``): a node's part of the faces' Kirchhoff differences, which the loops over
    the faces (model/film.py) compute once per node rather than once per face and end."""
    if isoviscous(phys):
        return 0.0, 0.0, 1.0
    g, dg = _mobility_log(p, phys)
    return g, dg, math.exp(-g)


# Below this spread of ``g`` across an interval, ``_fitted`` takes its series (the next terms,
# d^6/5040 and d^6/5760, are 2e-16 of 1 here); above it the ratio of the ends' mobilities, whose
# rounding (a few ulps) is a relative error of 1e-16/d in ``phi``: 2e-14 at most.
_SERIES_SPREAD = 1e-2


@leaf
def _fitted(a, b, at_a, at_b, slopes):
    """``Int_a^b exp(-g) dP`` with ``g`` linear between ``a`` and ``b`` (on one side of 0), and its
    derivatives in ``a`` and ``b`` where ``slopes`` (0 otherwise: a residual needs the value
    alone), from ``mobility`` at each end (``at_a``, ``at_b``).

    ``Int = (b - a) exp(-m) phi(d)``, ``m`` the smaller of ``g(a), g(b)``, ``d = |g(b) - g(a)|``,
    ``phi(d) = (1 - e^-d)/d``; with ``psi(d) = (1 - e^-d (1 + d))/d^2`` the derivative of the
    mean ``exp(-m) phi`` is ``-exp(-m) psi`` in the larger ``g`` and ``-exp(-m)(phi - psi)`` in
    the smaller. ``e^-d`` is the ends' mobilities' ratio: no exponential is taken here."""
    ga, dga, ea = at_a
    gb, dgb, eb = at_b
    if ga <= gb:
        d, scale, far = gb - ga, ea, eb
    else:
        d, scale, far = ga - gb, eb, ea
    psi = 0.0
    if d < _SERIES_SPREAD:
        phi = 1.0 - d * (1.0 / 2.0 - d * (1.0 / 6.0 - d * (1.0 / 24.0 - d * (1.0 / 120.0
                                                                          - d / 720.0))))
        if slopes:
            psi = 0.5 - d * (1.0 / 3.0 - d * (1.0 / 8.0 - d * (1.0 / 30.0 - d * (1.0 / 144.0
                                                                              - d / 840.0))))
    elif scale > 0.0:
        e_d = far / scale  # exp(-d); 0 where the far end's mobility underflowed
        phi = (1.0 - e_d) / d
        if slopes:
            psi = (1.0 - e_d * (1.0 + d)) / (d * d)
    else:  # both ends glassy beyond exp(-745): the interval passes nothing
        phi = 0.0
    mean = scale * phi
    if not slopes:
        return (b - a) * mean, 0.0, 0.0
    d_hi = -scale * psi  # d mean / d g of the node with the larger g
    d_lo = -scale * (phi - psi)
    if ga <= gb:
        dmean_da, dmean_db = d_lo, d_hi
    else:
        dmean_da, dmean_db = d_hi, d_lo
    span = b - a
    return span * mean, -mean + span * dmean_da * dga, mean + span * dmean_db * dgb


@leaf
def kirchhoff_difference(p_lo, p_hi, phys):
    """``Int_{p_lo}^{p_hi} rho_bar / mu_bar dP``, the pressure difference that drives the flux
    between two nodes, and its derivatives in ``p_lo`` and ``p_hi``: ``p_hi - p_lo`` exactly for
    the classic film (``kirchhoff_between`` with each node's ``mobility``)."""
    return kirchhoff_between(p_lo, mobility(p_lo, phys), p_hi, mobility(p_hi, phys), phys, True)


@leaf
def kirchhoff_between(p_lo, at_lo, p_hi, at_hi, phys, slopes):
    """``kirchhoff_difference`` from the nodes' ``mobility`` (``at_lo``, ``at_hi``), which a loop
    over the faces computes once per node; its derivatives only where ``slopes`` (0 otherwise:
    the residual and the error norm need the value alone, the Jacobian all three). The interval
    is split where the laws have a kink (``_next_kink``: 0, the table's points), so each piece is
    an exponential fit of a smooth ``ln(mu/rho)``, exact where it is linear (Barus, a table)."""
    if isoviscous(phys):
        return p_hi - p_lo, -1.0, 1.0
    if p_lo <= p_hi:
        a, at_a, b, at_b = p_lo, at_lo, p_hi, at_hi
    else:
        a, at_a, b, at_b = p_hi, at_hi, p_lo, at_lo
    total, d_a, d_b = 0.0, 0.0, 0.0
    start, at_start = a, at_a
    while True:
        end = _next_kink(start, b, phys)
        at_end = at_b if end >= b else mobility(end, phys)
        value, da, db = _fitted(start, end, at_start, at_end, slopes)
        if start == a:
            d_a = da
        total += value
        if end >= b:
            d_b = db
            break
        start, at_start = end, at_end
    if p_lo <= p_hi:
        return total, d_a, d_b
    return -total, -d_b, -d_a


@leaf
def kirchhoff_pressure(p, at_p, at_zero, phys):
    """The Kirchhoff pressure ``Int_0^p rho_bar/mu_bar dP`` (``kirchhoff_between``'s value) from
    the mobilities at ``p`` and at 0 (``at_p``, ``at_zero``), which a caller that needs it at
    many pressures takes once: the rigid film's inverse (``pressure_of_kirchhoff``) and the
    step's error scale (model/step.py)."""
    return kirchhoff_between(0.0, at_zero, p, at_p, phys, False)[0]


@leaf
def _specific_volume_integral(p, phys):
    """``Int_0^p dP / rho_bar``: ``p`` where the density is constant; for Dowson-Higginson
    (``rho_bar = (1 + b p)/(1 + c2 p)``, ``b = c1 + c2``) ``(c2/b) p + (c1/b^2) ln(1 + b p)``;
    in tension (``rho_bar = A + a exp(p/w)``, ``a = c1 w``, ``A = 1 - a``)
    ``(p - w ln rho_bar)/A``."""
    if constant_density(phys):
        return p
    c1 = phys[DH_C1]
    if p <= 0.0:
        rho = density(p, phys)[0]
        return (p - TENSION_WIDTH * math.log(rho)) / (1.0 - c1 * TENSION_WIDTH)
    b = c1 + phys[DH_C2]
    return phys[DH_C2] / b * p + c1 / (b * b) * math.log1p(b * p)


@leaf
def volume_difference(p_lo, p_hi, phys):
    """``Int_{p_lo}^{p_hi} dP / rho_bar``: the work per unit *volume* of liquid that crosses a
    face, which makes the face's dissipation from its mass flux (``p_hi - p_lo`` at constant
    density)."""
    if constant_density(phys):
        return p_hi - p_lo
    return _specific_volume_integral(p_hi, phys) - _specific_volume_integral(p_lo, phys)


@leaf
def compression_energy(p, phys):
    """Energy stored per unit mass of liquid (in ``p*/rho0``) compressed to ``p``:
    ``e = Int_0^p P rho_bar' / rho_bar^2 dP = Int_0^p dP/rho_bar - p/rho_bar`` (by parts;
    docs/model.md, "Energy"), 0 at constant density; for Dowson-Higginson
    ``(c1/b^2) (ln(1 + b p) - b p / (1 + b p))``, ``b = c1 + c2``; positive in tension too."""
    if constant_density(phys):
        return 0.0
    if p <= 0.0:
        return _specific_volume_integral(p, phys) - p / density(p, phys)[0]
    c1 = phys[DH_C1]
    b = c1 + phys[DH_C2]
    y = b * p
    return c1 / (b * b) * (math.log1p(y) - y / (1.0 + y))


# halvings of a bracket [lo, hi] in pressure before it is a few ulps wide (pressure_of_kirchhoff)
_BISECTIONS = 200
# doublings of a bracket's end before the law is taken not to reach the Kirchhoff pressure
_DOUBLINGS = 64


@entry
@jit
def pressure_of_kirchhoff(k, phys, out):
    """The pressure at each node whose Kirchhoff pressure ``Int_0^P rho_bar/mu_bar dP`` is ``k``,
    into ``out``: with constant density the rigid film's Reynolds equation in the Kirchhoff
    pressure is the classic one, so the rigid film of a pressure-dependent liquid has the
    pressure whose Kirchhoff pressure is the classic ``3 V/(X + s)^2`` (the Barus closed form,
    model/piezoviscous.py: ``rigid_pressure``, for any law). By bisection on ``[0, hi]``, ``hi``
    doubled from ``k`` (the Kirchhoff pressure rises with ``P``, from 0 at 0). False when some
    ``k`` is negative (a film in tension: not an approach's) or lies beyond what the law reaches
    (a Kirchhoff pressure with a ceiling, ``1/beta`` for Barus: a glass gap)."""
    at_zero = mobility(0.0, phys)
    for i in range(k.size):
        target = k[i]
        if target < 0.0:
            return False
        lo, hi = 0.0, target
        for _ in range(_DOUBLINGS):
            if kirchhoff_pressure(hi, mobility(hi, phys), at_zero, phys) >= target:
                break
            lo, hi = hi, 2.0 * hi + 1.0
        else:
            return False
        for _ in range(_BISECTIONS):
            mid = 0.5 * (lo + hi)
            if not lo < mid < hi:
                break
            if kirchhoff_pressure(mid, mobility(mid, phys), at_zero, phys) < target:
                lo = mid
            else:
                hi = mid
        out[i] = 0.5 * (lo + hi)
    return True


@entry
@leaf
def viscosity_ratio(p, phys):
    """``mu/mu0`` at the pressure ``p`` (inf beyond the double range)."""
    g = log_viscosity(p, phys)[0]
    return math.exp(g) if g < 709.0 else np.inf
