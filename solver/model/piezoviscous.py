"""The rigid film with a pressure-dependent viscosity (Barus law): closed forms and the rigid
approach (docs/model.md, "Rigid piezoviscous film (Barus)"; Barnocky & Davis 1989).

Dimensionless, scale ``x1`` (docs/model.md, "Scales"). Rigid spheres (``W = 0``, ``H = X + s``,
``s = R^2/2``) approaching at ``V`` (``dH/dT = -V``; ``V < 0``: separating at ``U = -V``) through
a liquid of viscosity ``mu_bar = mu/mu0 = exp(beta P)``. The film equation

    dH/dT = (1/6) d/ds( s H^3 / mu_bar dP/ds ),     flux 0 at s = 0,  P -> 0 as s -> inf,

integrates once to ``(1/6) s H^3 exp(-beta P) dP/ds = -V s``. With the reduced pressure
``q = (1 - exp(-beta P))/beta`` (``dq/ds = exp(-beta P) dP/ds``, ``q -> 0`` with ``P``) this is the
isoviscous film in ``q``: ``dq/ds = -6V/H^3``, so

    q = 3V/(X + s)^2,        P = -(1/beta) ln(1 - beta q) = -(1/beta) ln(1 - z X^2/(X + s)^2),

``z = 3 beta V / X^2``. In approach the film exists only while ``beta q < 1`` everywhere, i.e.
``z < 1``, ``X > k = sqrt(3 beta V)`` (the "glass gap": at ``X = k`` the axis viscosity is
infinite). With ``y = X + s`` and ``Int ln(y -+ k) dy = (y -+ k) ln(y -+ k) - y``, the load is

    Int_0^inf P ds = (1/beta) [(X - k) ln(X - k) + (X + k) ln(X + k) - 2 X ln X]
                   = (3V/X) S(z),     S(z) = sum_{n>=1} z^(n-1) / (n (2n - 1))
                                            = (2 e artanh(e) + ln(1 - z)) / z,  e = sqrt(z),

``S(0) = 1`` (the classic ``3V/X``), ``S(1) = 2 ln 2`` (the load stays finite at ``X = k``:
``2 ln2 k/beta``; only the axis pressure diverges, logarithmically). Separating, with the law
read in tension (``viscosity_in_tension = "law"``) ``z < 0``, ``kap = sqrt(3 beta U)``,
``P = -(1/beta) ln(1 + kap^2/(X + s)^2)`` and

    Int_0^inf P ds = -(1/beta) [pi kap - X ln(1 + kap^2/X^2) - 2 kap arctan(X/kap)]
                   = (3V/X) S(z),   S(z) = (2 w arctan(w) - ln(1 + w^2)) / w^2,  w = sqrt(-z)

(the same power series); with the default ``"ambient"`` the separating film is in tension
everywhere, keeps ``mu0`` and is the classic ``-3U/X``.

The central deflection (docs/model.md, "Small deformation": ``phi(0, rho) = pi/2``) is
``W(0) = (pi/2) Int_0^inf P dR``; with ``R = sqrt(2) u`` and
``Int_0^inf ln((u^2 + a)/(u^2 + b)) du = pi (sqrt a - sqrt b)``,

    W(0) = (pi^2 / (sqrt(2) beta)) (2 sqrt(X) - sqrt(X - k) - sqrt(X + k))
         = 3 I0 V X^(-3/2) G(z),      G(z) = 8 / ((1 + a)(1 + b)(a + b)),  a, b = sqrt(1 -+ e),

``G(0) = 1`` (the classic ``3 I0 V X^-1.5``), finite at ``X = k``; in tension (law)
``G = 2 / (c^2 (1 + c))``, ``c = sqrt((1 + sqrt(1 - z))/2)``. All these forms are free of
cancellation as ``beta -> 0`` (``S`` by its series for small ``|z|``).

The rigid approach ``dX/dT = -V``, ``dV/dT = -(Int P ds)/(3 St)`` is, in ``u = ln(X_1/X)``, the
scalar ODE ``dV/du = -S(z)/St`` (the classic ``V = V1 - u/St`` at ``z = 0``), integrated by
``approach`` until the hand-over, the glass margin or rest.

Exact for the Barus law with constant density during the approach (``exact_for``): the film is in
compression there, where ``viscosity_in_tension`` and a cavitation floor never act.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from ..physics import TENSION_CHOICES
from .rigid import I0

__all__ = [
    "GLASS_LOG_VISCOSITY",
    "GLASS_MARGIN",
    "TENSION_CHOICES",
    "rigid_pressure",
    "rigid_force",
    "glass_gap",
    "axis_deflection",
    "load_factor",
    "deflection_factor",
    "RigidApproach",
    "approach",
    "exact_for",
]

# Where the rigid approach gives way to the coupled solver near the glass gap: the axis's
# ln(mu/mu0) = beta P(0) = -ln(1 - z) reaches 1, i.e. X = GLASS_MARGIN k. Why there: a gap change
# dX (a deformation W does that) changes the rigid axis pressure by d ln P(0)/d ln X =
# -2 (exp(p) - 1)/p, p = beta P(0), against -2 for the classic film, and without bound as X -> k.
# The hand-over criterion W(0)/X <= switch bounds the rigid pressure's error only through that
# factor; at p <= 1 it is at most e - 1 = 1.72 times the classic one (at p = 2, 3.2 times), so
# the rigid phase is as trustworthy as the classic rigid approach at the same switch, within a
# factor below 2. Beyond it the axis pressure is set by X - k, not X, and the coupled film takes
# over while the axis viscosity is still only e times mu0.
GLASS_LOG_VISCOSITY = 1.0
GLASS_MARGIN = 1.0 / math.sqrt(-math.expm1(-GLASS_LOG_VISCOSITY))  # X/k there: 1.2578

# Gauss-Legendre nodes per sample interval of the path's time quadrature (``approach``)
_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(24)
_SERIES_BELOW = 0.05  # |z| below which S(z) is summed as its series (the closed form is 0/0 at 0)
_SERIES_TERMS = 14  # 0.05^13 / (14 * 27) < 1e-19: the series' truncation is below round-off
_CLOSE_TO_GLASS = 0.5  # z above which S uses the (1 +- e) log1p(+-e) form (artanh diverges at 1)
_ROUND_OFF_Z = 4.0 * np.finfo(float).eps  # z within this above 1 is the glass gap itself


def _check_tension(in_tension):
    if in_tension not in TENSION_CHOICES:
        raise ValueError(f"in_tension must be one of {list(TENSION_CHOICES)}, got {in_tension!r}")


def _reduced_z(x, v, beta, in_tension):
    """``z = 3 beta V / X^2`` where the Barus law acts (0 where the film keeps ``mu0``: beta = 0,
    or separating with ``in_tension = "ambient"``); within round-off above 1 clipped to 1."""
    x, v = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(v, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = 3.0 * beta * v / (x * x)
    if in_tension == "ambient":
        z = np.where(v < 0.0, 0.0, z)
    z = np.where((z > 1.0) & (z <= 1.0 + _ROUND_OFF_Z), 1.0, z)
    return x, v, z


def load_factor(z):
    """``S(z)``: the rigid Barus load over the classic one, ``Int P ds = (3V/X) S(z)``.

    Parameters
    ----------
    z : array_like
        ``3 beta V / X^2`` (``< 0`` separating with the law read in tension).

    Returns
    -------
    ndarray
        ``S(z) = sum_{n>=1} z^(n-1)/(n (2n-1))``: 1 at ``z = 0``, ``2 ln 2`` at ``z = 1``, ``inf``
        beyond (no rigid film: ``X`` inside the glass gap); decreasing for ``z < 0``.
    """
    return _load_factor_array(z)


def _load_factor_scalar(z):
    """``load_factor`` of one float in ``math``: the one place its branches are written (the ODE's
    right-hand side calls it per step, where numpy's per-call overhead on scalars was most of the
    rigid approach's time)."""
    if math.isnan(z):
        return math.nan
    if abs(z) <= _SERIES_BELOW:
        total = 0.0
        for n in range(_SERIES_TERMS, 0, -1):  # Horner
            total = total * z + 1.0 / (n * (2.0 * n - 1.0))
        return total
    if z < -_SERIES_BELOW:
        w = math.sqrt(-z)
        return (2.0 * w * math.atan(w) - math.log1p(-z)) / (-z)
    if z <= _CLOSE_TO_GLASS:
        e = math.sqrt(z)
        return (2.0 * e * math.atanh(e) + math.log1p(-z)) / z
    if z <= 1.0:  # near the glass gap: artanh diverges, the (1 -+ e) log1p(+-e) form does not
        e = math.sqrt(z)
        tail = (1.0 - e) * math.log1p(-e) if e < 1.0 else 0.0
        return ((1.0 + e) * math.log1p(e) + tail) / z
    return math.inf


_load_factor_array = np.vectorize(_load_factor_scalar, otypes=[float])


def _load_log_slope(z):
    """``d ln S / d ln z = artanh(e)/(e S) - 1`` (``e = sqrt(z)``, ``0 < z < 1``; ``~ z/6``)."""
    if z <= 0.0:
        return 0.0
    e = math.sqrt(z)
    return math.atanh(e) / (e * _load_factor_scalar(z)) - 1.0


def deflection_factor(z):
    """``G(z)``: the central deflection of the rigid Barus pressure over the classic one,
    ``W(0) = 3 I0 V X^-1.5 G(z)``.

    Parameters
    ----------
    z : array_like
        ``3 beta V / X^2`` (``< 0`` separating with the law read in tension).

    Returns
    -------
    ndarray
        ``8 / ((1 + a)(1 + b)(a + b))``, ``a, b = sqrt(1 -+ sqrt(z))``, for ``0 <= z <= 1``
        (1 at 0, ``8/(sqrt 2 (1 + sqrt 2)) = 2.343`` at the glass gap); ``2/(c^2 (1 + c))``,
        ``c = sqrt((1 + sqrt(1 - z))/2)``, for ``z < 0``; ``inf`` for ``z > 1``.
    """
    z = np.asarray(z, dtype=float)
    out = np.full(z.shape, np.inf)
    pos = (z >= 0.0) & (z <= 1.0)
    e = np.sqrt(z[pos])
    a, b = np.sqrt(1.0 - e), np.sqrt(1.0 + e)
    out[pos] = 8.0 / ((1.0 + a) * (1.0 + b) * (a + b))
    neg = z < 0.0
    c = np.sqrt(0.5 * (1.0 + np.sqrt(1.0 - z[neg])))
    out[neg] = 2.0 / (c * c * (1.0 + c))
    out[np.isnan(z)] = np.nan
    return out


def _deflection_log_slope(z):
    """``d ln G / d ln z = (1 + a)(1 + b)/(4 a b) - 1`` (``0 <= z < 1``; ``~ 5 z/16``)."""
    if z <= 0.0:
        return 0.0
    e = math.sqrt(z)
    a, b = math.sqrt(1.0 - e), math.sqrt(1.0 + e)
    return (1.0 + a) * (1.0 + b) / (4.0 * a * b) - 1.0


def rigid_pressure(s, x, v, beta, in_tension="ambient"):
    """Film pressure of rigid spheres at gap ``x`` approaching at ``v`` (Barus viscosity).

    Parameters
    ----------
    s : array_like
        ``R^2/2`` (``>= 0``).
    x, v : array_like
        Gap of the undeformed surfaces (``> 0``) and approach velocity (``< 0``: separating).
    beta : float
        Piezoviscous number (``>= 0``; 0: the classic ``3V/(X + s)^2``).
    in_tension : {"ambient", "law"}
        Viscosity where ``P < 0`` (solver.Physics.viscosity_in_tension): ``mu0``, or the law.

    Returns
    -------
    ndarray
        ``P = -(1/beta) ln(1 - beta q)`` with ``q = 3V/(X + s)^2`` (module docstring); ``q`` where
        the viscosity is ``mu0``; ``inf`` where ``beta q >= 1`` (inside the glass gap).
    """
    _check_tension(in_tension)
    s, x, v = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (s, x, v)))
    h = x + s
    q = 3.0 * v / (h * h)
    y = beta * q
    if in_tension == "ambient":
        y = np.where(q < 0.0, 0.0, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(y == 0.0, 1.0, -np.log1p(-np.minimum(y, 1.0)) / y)  # -ln(1-y)/y, 1 at 0
    return np.where(y >= 1.0, np.inf, q * ratio)


def rigid_force(x, v, beta, in_tension="ambient"):
    """The load ``Int_0^inf P ds = Int_0^inf P R dR`` of the rigid Barus film.

    Three times the force ``F`` in the unit ``6 pi mu0 a^2 v0 / x1`` (docs/model.md, "Motion and
    force"): ``dV/dT = -rigid_force / (3 St)``.

    Parameters
    ----------
    x, v : array_like
        Gap (``> 0``) and approach velocity (``< 0``: separating).
    beta : float
        Piezoviscous number (``>= 0``).
    in_tension : {"ambient", "law"}
        Viscosity of a separating (tensile) film: ``mu0`` (the classic ``3V/X``) or the law.

    Returns
    -------
    ndarray or float
        ``(3V/X) S(3 beta V/X^2)`` (module docstring): ``3V/X`` at ``beta = 0``, ``2 ln2 k/beta``
        at the glass gap ``X = k`` (within round-off), ``inf`` inside it (``X < k``, and any
        ``X <= 0`` when approaching); NaN for ``X <= 0`` otherwise (no film).
    """
    _check_tension(in_tension)
    x, v, z = _reduced_z(x, v, beta, in_tension)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 3.0 * v / x * load_factor(np.where(x > 0.0, z, 0.0))
    out = np.where(x > 0.0, out, np.where(v > 0.0, np.inf, np.nan))
    out = np.where((x > 0.0) & (v == 0.0), 0.0, out)
    return out[()] if out.ndim == 0 else out


def glass_gap(v, beta):
    """The glass gap ``k = sqrt(3 beta V)``: the rigid Barus film approaching at ``v`` exists only
    for ``X > k`` (0 when not approaching: a film in tension has none)."""
    out = np.sqrt(3.0 * beta * np.maximum(np.asarray(v, dtype=float), 0.0))
    return out[()] if out.ndim == 0 else out


def axis_deflection(x, v, beta, in_tension="ambient"):
    """Central deflection ``W(0) = (pi/2) Int_0^inf P dR`` of the rigid Barus pressure.

    Parameters
    ----------
    x, v : array_like
        Gap (``> 0``) and approach velocity (``< 0``: separating).
    beta : float
        Piezoviscous number (``>= 0``).
    in_tension : {"ambient", "law"}
        Viscosity of a separating film (``rigid_pressure``).

    Returns
    -------
    ndarray or float
        ``3 I0 V X^-1.5 G(z)`` (module docstring; ``G = 1`` is rigid.py's classic estimate):
        finite at the glass gap (the axis pressure's singularity is logarithmic), ``inf`` inside
        it.
    """
    _check_tension(in_tension)
    x, v, z = _reduced_z(x, v, beta, in_tension)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 3.0 * I0 * v * x**-1.5 * deflection_factor(np.where(x > 0.0, z, 0.0))
    out = np.where(x > 0.0, out, np.where(v > 0.0, np.inf, np.nan))
    out = np.where((x > 0.0) & (v == 0.0), 0.0, out)
    return out[()] if out.ndim == 0 else out


def exact_for(physics) -> bool:
    """Whether ``approach`` is the exact rigid approach of ``physics`` (a ``solver.Physics``): a
    constant or Barus viscosity with constant density (the approach film is in compression, so
    ``viscosity_in_tension`` and a cavitation floor do not act)."""
    return physics.viscosity_law in ("constant", "barus") and physics.density_law == "constant"


@dataclass(frozen=True)
class RigidApproach:
    """The rigid Barus approach from one state to its end (``approach``).

    Attributes
    ----------
    t, x, v : ndarray
        Time, gap and approach velocity along the path (``samples`` points uniform in
        ``ln X``, the start and the end included; ``t = inf`` at a ``"rest"`` end).
    p_axis : ndarray
        Axis pressure ``P(s = 0) = -ln(1 - z)/beta`` (the largest of the film).
    force : ndarray
        Force ``F = rigid_force / 3`` in the unit ``6 pi mu0 a^2 v0 / x1`` (the series column
        ``F``; ``dV/dT = -F/St``).
    w0 : ndarray
        Central deflection of the rigid pressure, ``axis_deflection``.
    event : {"handover", "glass", "rest"}
        What ended the path: ``W(0)/X`` reached ``switch``; ``X`` reached ``glass_margin`` times
        the glass gap; the spheres stopped (``v_end = 0``, ``t_end = inf``, ``x_end`` the rest
        separation: the scene is rigid throughout).
    x_end, v_end, t_end : float
        The end state.
    peaks : dict
        The largest force, central deflection and axis pressure on the path, with their times
        (keys as rigid.approach_peaks: ``peak_force``, ``t_peak_force``, ``w0_max``,
        ``t_max_deformation``, ``p_max``, ``t_p_max``, and ``x_p_max`` the gap at ``p_max``).
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    p_axis: np.ndarray
    force: np.ndarray
    w0: np.ndarray
    event: str
    x_end: float
    v_end: float
    t_end: float
    peaks: dict = field(default_factory=dict)


def approach(x_from, v_from, t_from, stokes, beta, switch, glass_margin=GLASS_MARGIN,
             samples=60, x_stop=0.0):
    """Rigid approach through the Barus film from ``(X, V, T) = (x_from, v_from, t_from)``.

    ``dX/dT = -V``, ``dV/dT = -rigid_force/(3 St)``, integrated in ``u = ln(x_from/X)`` as
    ``dV/du = -S(z)/St`` (``z = 3 beta V/X^2``, ``load_factor``; a smooth scalar ODE, also
    through ``V = 0``) with DOP853 at ``rtol = 1e-12``; the time is the quadrature
    ``T = t_from + Int X/V du`` of its dense output. It ends at the first of

    - ``"handover"``: ``W(0)/X >= switch`` with the Barus ``W(0)`` (``axis_deflection``), the
      criterion of rigid.handover_separation;
    - ``"glass"``: ``X <= glass_margin k`` (``glass_gap``), i.e. ``beta P(0) >=
      -ln(1 - 1/glass_margin^2)``; the default ``GLASS_MARGIN`` ends at ``beta P(0) = 1``;
    - ``"rest"``: ``V = 0``, reached at a finite ``X`` after infinite time;
    - ``"contact"``: ``X = x_stop``, where rough surfaces are about to touch (the coupled phase
      must take over before them: rigid.contact_onset_separation; 0: none).

    Both of the first two are thresholds on functions that rise and then fall along the path; each
    function's maxima are located too (events on its derivative), so a crossing that starts and
    ends within one step is not missed. At ``beta = 0`` this is the classic rigid.velocity,
    rigid.elapsed_time and rigid.handover_separation.

    Parameters
    ----------
    x_from, v_from, t_from : float
        Start state; ``x_from > 0``, ``v_from > 0`` (approaching).
    stokes : float
        Stokes number ``St > 0``.
    beta : float
        Piezoviscous number ``>= 0``.
    switch : float
        Hand-over threshold on ``W(0)/X`` (``> 0``; ``inf``: never).
    glass_margin : float
        ``> 1``: how far outside the glass gap the path ends (module constant ``GLASS_MARGIN``).
    samples : int
        Number of points on the returned path (``>= 2``; one when it ends at its start).
    x_stop : float
        The path ends at ``X = x_stop`` at the latest (``"contact"``); 0: no such end.

    Returns
    -------
    RigidApproach
        The path, its end state and event, and its peaks.
    """
    _check_approach(x_from, v_from, stokes, beta, switch, glass_margin, samples)
    f = _path_functions(x_from, stokes, beta, switch, glass_margin)
    y0 = [float(v_from)]
    started = [name for name, (g, _) in f.thresholds.items() if g(0.0, y0) >= 0.0]
    u_stop = math.log(x_from / x_stop) if x_stop > 0.0 else math.inf
    if u_stop <= 0.0:
        started.append("contact")
    if started:
        return _single(x_from, v_from, t_from, beta, started[0])

    # S >= 1 while approaching: V reaches 0 by u = St v_from
    u_max = min(stokes * v_from * 1.01 + 1.0, u_stop)
    events = [f.handover, f.glass if beta > 0.0 else None, f.rest, f.d_handover, f.d_pressure,
              f.d_force, f.d_deflection]
    active = [ev for ev in events if ev is not None]
    from scipy.integrate import solve_ivp  # here: a run without this piece never imports it
    sol = solve_ivp(f.rhs, (0.0, u_max), y0, method="DOP853", rtol=1e-12, atol=1e-15,
                    dense_output=True, events=active, max_step=0.5 if beta > 0.0 else math.inf)
    reached_stop = sol.status == 0 and u_max == u_stop
    if sol.status != 1 and not reached_stop:
        raise RuntimeError(f"the rigid Barus approach did not reach an end: {sol.message}")
    t_events = dict(zip((ev.__name__ for ev in active), sol.t_events))
    u_end, event = _path_end(sol, t_events, f.thresholds, u_stop if reached_stop else None)
    v_end = 0.0 if event == "rest" else float(sol.sol(u_end)[0])
    u_s, x_s, v_s, t_s = _sampled_path(sol, x_from, v_from, t_from, u_end, v_end, event, samples)
    peaks = _path_peaks(sol, t_events, f, x_from, v_from, beta, u_end, v_end, u_s, t_s)
    return RigidApproach(
        t=t_s, x=x_s, v=v_s, p_axis=rigid_pressure(0.0, x_s, v_s, beta),
        force=rigid_force(x_s, v_s, beta) / 3.0, w0=axis_deflection(x_s, v_s, beta), event=event,
        x_end=float(x_s[-1]), v_end=float(v_end), t_end=float(t_s[-1]), peaks=peaks)


def _check_approach(x_from, v_from, stokes, beta, switch, glass_margin, samples):
    """``approach``'s arguments, each refused with what it must be."""
    if not (x_from > 0.0 and v_from > 0.0 and stokes > 0.0 and beta >= 0.0 and switch > 0.0):
        raise ValueError(f"approach needs x_from > 0, v_from > 0, St > 0, beta >= 0, switch > 0; "
                         f"got {x_from!r}, {v_from!r}, {stokes!r}, {beta!r}, {switch!r}")
    if not glass_margin > 1.0:
        raise ValueError(f"glass_margin = {glass_margin!r} must be > 1 (the rigid film ends at the "
                         "glass gap itself)")
    if samples < 2:
        raise ValueError(f"samples = {samples!r} must be at least 2")


def _path_functions(x_from, stokes, beta, switch, glass_margin):
    """The approach ODE in ``u = ln(x_from/X)`` (``approach``), its terminal thresholds and the
    derivatives of their logs along the path (solve_ivp events), as a namespace."""
    ln_x0 = math.log(x_from)
    ln_switch = math.log(switch)
    ln_3beta = math.log(3.0 * beta) if beta > 0.0 else -math.inf
    ln_z_glass = -2.0 * math.log(glass_margin)
    ln_coeff = math.log(3.0 * I0)

    def z_of(u, v):  # 3 beta V/X^2, signed: the law's continuation past V = 0 keeps rhs smooth
        if v == 0.0 or beta == 0.0:
            return 0.0
        return math.copysign(math.exp(min(ln_3beta + math.log(abs(v)) - 2.0 * ln_x0 + 2.0 * u,
                                          700.0)), v)

    # S(z) beyond the glass margin only feeds trial stages of the step that crosses it: continued
    # linearly from midway to the glass gap (smooth, finite; the path ends before it matters)
    z_cont = 0.5 * (1.0 + math.exp(ln_z_glass))
    s_cont = float(load_factor(z_cont))
    ds_cont = _load_log_slope(z_cont) * s_cont / z_cont

    def s_of(z):
        return s_cont + ds_cont * (z - z_cont) if z > z_cont else _load_factor_scalar(z)

    def rhs(u, y):
        return [-s_of(z_of(u, y[0])) / stokes]

    # ---- thresholds (>= 0: reached) and the derivatives of their logs along the path ------------
    def handover(u, y):
        v = y[0]
        if v <= 0.0:
            return -math.inf
        g = float(deflection_factor(min(z_of(u, v), 1.0)))
        return ln_coeff + math.log(v) - 2.5 * (ln_x0 - u) + math.log(g) - ln_switch

    def glass(u, y):
        v = y[0]
        return -math.inf if v <= 0.0 else ln_3beta + math.log(v) - 2.0 * (ln_x0 - u) - ln_z_glass

    def rest(u, y):
        return y[0]

    def rate(u, v):  # A = -d ln V/du = S/(St V), and z
        z = z_of(u, v)
        return s_of(z) / (stokes * v), min(z, 1.0)

    d_pressure, d_force, d_deflection, d_handover = _peak_events(rate)
    for ev, terminal, direction in ((handover, True, 1.0), (glass, True, 1.0), (rest, True, -1.0),
                                    (d_handover, False, -1.0), (d_pressure, False, -1.0),
                                    (d_force, False, -1.0), (d_deflection, False, -1.0)):
        ev.terminal, ev.direction = terminal, direction
    thresholds = {"handover": (handover, d_handover)}
    if beta > 0.0:
        thresholds["glass"] = (glass, d_pressure)
    return SimpleNamespace(rhs=rhs, handover=handover, glass=glass, rest=rest,
                           d_pressure=d_pressure, d_force=d_force, d_deflection=d_deflection,
                           d_handover=d_handover, thresholds=thresholds)


def _peak_events(rate):
    """The derivatives of the thresholds' logs along the path (``_path_functions``; ``rate(u,
    V)`` gives ``A = -d ln V/du`` and ``z``), whose zeros are the peaks. With A increasing along
    the path (it does while z < 1 - 1/e: d ln S/d ln z < 0.19 < 1), ln z rises while A < 2: z
    and the axis pressure peak at A = 2, the force at A = (1 + 2 sig)/(1 + sig) (classic: V =
    1/St), W(0) at A = (1.5 + 2 gam)/(1 + gam), W(0)/X at (2.5 + 2 gam)/(1 + gam) (classic: V =
    0.4/St); sig, gam the log-slopes of S and G."""

    def d_pressure(u, y):
        if y[0] <= 0.0:
            return -1.0
        a, _ = rate(u, y[0])
        return 2.0 - a

    def d_force(u, y):
        if y[0] <= 0.0:
            return -1.0
        a, z = rate(u, y[0])
        return 1.0 - a + _load_log_slope(z) * (2.0 - a)

    def d_deflection(u, y):
        if y[0] <= 0.0:
            return -1.0
        a, z = rate(u, y[0])
        return 1.5 - a + _deflection_log_slope(z) * (2.0 - a)

    def d_handover(u, y):
        if y[0] <= 0.0:
            return -1.0
        a, z = rate(u, y[0])
        return 2.5 - a + _deflection_log_slope(z) * (2.0 - a)

    return d_pressure, d_force, d_deflection, d_handover


def _path_end(sol, t_events, thresholds, u_stop=None):
    """``(u_end, event)``: the terminal event (or ``"contact"`` at ``u_stop`` where the
    integration stopped there), or an earlier crossing hidden inside one step (its function's
    maximum lies above the threshold)."""
    from scipy import optimize  # here: a run without this piece never imports it (0.2 s)

    def v_at(u):
        return float(sol.sol(u)[0])

    u_term = float(sol.t[-1])
    ends = [] if u_stop is None else [(float(u_stop), "contact")]
    for name in ("handover", "glass", "rest"):
        if name in t_events and t_events[name].size:
            ends.append((float(t_events[name][0]), name))
    for name, (f, d) in thresholds.items():
        for u_p in t_events[d.__name__]:
            if u_p <= u_term and f(u_p, [v_at(u_p)]) >= 0.0:
                lo = float(sol.t[max(np.searchsorted(sol.t, u_p, side="right") - 1, 0)])
                lo = min(lo, u_p)
                if f(lo, [v_at(lo)]) < 0.0:
                    u_c = optimize.brentq(lambda u, f=f: f(u, [v_at(u)]), lo, u_p, xtol=1e-15,
                                          rtol=4 * np.finfo(float).eps)
                    ends.append((u_c, name))
                break
    return min(ends)


def _elapsed(sol, x_from, u_a, u_b):
    """``Int X/V du`` over each interval ``[u_a[i], u_b[i]]``: Gauss-Legendre on the dense
    output, one vectorised call (``X/V`` is analytic inside each interval; its nearest
    singularity, ``V = 0`` at a rest, lies at least one sample interval beyond, where
    ``_GAUSS_POINTS`` nodes converge to round-off)."""
    u_a, u_b = np.atleast_1d(u_a), np.atleast_1d(u_b)
    half = 0.5 * (u_b - u_a)
    u = (u_a + u_b)[:, None] * 0.5 + half[:, None] * _GAUSS_NODES[None, :]
    v = sol.sol(u.ravel())[0].reshape(u.shape)
    return half * np.sum(_GAUSS_WEIGHTS * x_from * np.exp(-u) / v, axis=1)


def _sampled_path(sol, x_from, v_from, t_from, u_end, v_end, event, samples):
    """``samples`` points ``(u, X, V, T)`` from the start to the end (a rest is reached after
    infinite time)."""
    u_s = np.linspace(0.0, u_end, samples)
    v_s = sol.sol(u_s)[0]
    v_s[0], v_s[-1] = v_from, v_end
    finite = samples - 1 if event == "rest" else samples
    t_s = np.full(samples, math.inf)
    t_s[:finite] = t_from + np.concatenate([[0.0], np.cumsum(
        _elapsed(sol, x_from, u_s[:finite - 1], u_s[1:finite]))])
    x_s = x_from * np.exp(-u_s)
    x_s[-1] = x_from * math.exp(-u_end)
    return u_s, x_s, v_s, t_s


def _path_peaks(sol, t_events, f, x_from, v_from, beta, u_end, v_end, u_s, t_s):
    """The path's peaks of force, central deflection and axis pressure (with the gap there): at
    the ends or at an interior maximum (events on the log-derivatives)."""
    def time_at(u):
        i = int(np.searchsorted(u_s, u, side="right") - 1)
        return t_s[i] + float(_elapsed(sol, x_from, u_s[i], u)[0])  # t_s[i] finite: u < u_end

    peaks = {}
    for key, t_key, d, quantity in (
            ("peak_force", "t_peak_force", f.d_force,
             lambda x, v: rigid_force(x, v, beta) / 3.0),
            ("w0_max", "t_max_deformation", f.d_deflection,
             lambda x, v: axis_deflection(x, v, beta)),
            ("p_max", "t_p_max", f.d_pressure, lambda x, v: rigid_pressure(0.0, x, v, beta))):
        cands = [0.0, u_end] + [float(u) for u in t_events[d.__name__] if 0.0 < u < u_end]
        vals = [float(quantity(x_from * math.exp(-u), v_from if u == 0.0 else
                               (v_end if u == u_end else float(sol.sol(u)[0])))) for u in cands]
        best = int(np.argmax(vals))
        peaks[key] = vals[best]
        peaks[t_key] = float(time_at(cands[best]) if cands[best] < u_end else t_s[-1])
        if key == "p_max":  # the gap there (the rigid film's central gap)
            peaks["x_p_max"] = x_from * math.exp(-cands[best])
    return peaks


def _single(x, v, t, beta, event):
    """The path of an approach that ends where it starts."""
    arr = np.array
    force = float(rigid_force(x, v, beta)) / 3.0
    w0 = float(axis_deflection(x, v, beta))
    p0 = float(rigid_pressure(0.0, x, v, beta))
    return RigidApproach(
        t=arr([t], dtype=float), x=arr([x], dtype=float), v=arr([v], dtype=float),
        p_axis=arr([p0]), force=arr([force]), w0=arr([w0]), event=event, x_end=float(x),
        v_end=float(v), t_end=float(t),
        peaks={"peak_force": force, "t_peak_force": float(t), "w0_max": w0,
               "t_max_deformation": float(t), "p_max": p0, "t_p_max": float(t),
               "x_p_max": float(x)})
