"""A replica of LIGGGHTS' ``gran model hooke ... viscous on`` normal contact law, and its calibration.

The law (LIGGGHTS-PUBLIC ``src/normal_model_hooke.h``, read for this replica, not copied): a linear
spring ``kn`` and a dashpot ``gamman = sqrt(4 meff kn / (1 + (pi / L)^2))`` with
``L = ln(MaximumRestitution) + CriticalStokes / St`` and ``St = meff vn / (6 pi mu reff^2)``
computed at every step from the instantaneous normal velocity ``vn`` (``vn < 0`` while the spheres
approach, so ``L = ln e_max - C/|St|`` on the way in and ``ln e_max + C/|St|`` on the way out).
``CriticalStokes`` is therefore the constant ``C`` of ``e = e_max exp(-C/St)``, not a threshold.

With the damping fixed (``L`` constant) the collision is a linear spring-dashpot whose restitution
is ``exp(-zeta pi / sqrt(1 - zeta^2)) = exp(L)`` in closed form (``zeta = gamman / (2 sqrt(meff
kn)) = 1 / sqrt(1 + (pi/L)^2)``, contact ending when the overlap returns to 0): the law gives its
target exactly. With ``vn`` changing through the contact it does not, so the values we export are
calibrated against this replica until its realised e(St) matches ours.

Dimensionless form (time ``sqrt(meff/kn)``, velocity the impact speed ``v_in``, overlap
``v_in sqrt(meff/kn)``; ``u = -vn / v_in``, ``St_in`` the impact Stokes number):

    y' = u,    u' = -y - 2 zeta(L) u,    L = ln e_max - C / (St_in u),    y(0) = 0, u(0) = 1,

until ``y`` returns to 0; ``e = -u`` there. ``kn`` drops out: the realised e depends on
``(St_in, e_max, C)`` only.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate, optimize

__all__ = ["replica_restitution", "closed_form_restitution", "calibrate", "snippet"]


def _zeta(log_e):
    if not math.isfinite(log_e):
        return 1.0  # vn = 0: L -> +-inf, critical damping
    return 1.0 / math.sqrt(1.0 + (math.pi / log_e) ** 2)


def closed_form_restitution(log_e: float) -> float:
    """Restitution of the linear spring-dashpot with fixed ``L = log_e < 0``:
    ``exp(-zeta pi / sqrt(1 - zeta^2))`` (which is ``exp(L)``)."""
    z = _zeta(log_e)
    return math.exp(-z * math.pi / math.sqrt(1.0 - z * z))


def replica_restitution(st_in, e_max, st_crit, *, fixed_stokes=None, limit_force=False,
                        rtol=1e-10) -> float:
    """Realised restitution of one head-on collision under LIGGGHTS' hooke ``viscous`` law.

    ``fixed_stokes``: compute the damping once from this Stokes number instead of the
    instantaneous one (the closed-form case). ``limit_force``: LIGGGHTS' ``limitForce on`` (the
    normal force is never attractive)."""
    log_max = math.log(e_max)

    def log_e(u):
        if fixed_stokes is not None:
            return log_max - st_crit / fixed_stokes
        if u == 0.0:
            return -math.inf
        return log_max - st_crit / (st_in * u)

    def rhs(t, s):
        y, u = s
        force = y + 2.0 * _zeta(log_e(u)) * u  # repulsive contact force, units kn v_in sqrt(m/kn)
        if limit_force and force < 0.0:
            force = 0.0
        return [u, -force]

    def out(t, s):
        return s[0]
    out.terminal, out.direction = True, -1.0
    sol = integrate.solve_ivp(rhs, (0.0, 100.0), [0.0, 1.0], events=out, rtol=rtol,
                              atol=rtol * 1e-2, method="DOP853", first_step=1e-6)
    if not sol.t_events[0].size:
        return 0.0  # never separates within 100 contact times: stuck (overdamped, limitForce)
    return float(max(0.0, -sol.y_events[0][0][1]))


def calibrate(st, e_target, e_max0=None, c0=None):
    """``(MaximumRestitution, CriticalStokes)`` whose replica reproduces ``e_target`` at ``st``
    (LIGGGHTS' convention = ours, impact speeds), by least squares over the rebounding rows.
    Returns ``(e_max, C, max_abs_error, realised)``."""
    st, e_target = np.asarray(st, float), np.asarray(e_target, float)
    keep = e_target > 0.0
    st, e_target = st[keep], e_target[keep]
    e_max0 = float(np.max(e_target)) if e_max0 is None else e_max0
    c0 = float(np.median(st * -np.log(np.clip(e_target / e_max0, 1e-6, 1.0)))) if c0 is None else c0

    def resid(p):
        return np.array([replica_restitution(s, p[0], p[1], rtol=1e-8) for s in st]) - e_target

    res = optimize.least_squares(resid, x0=[min(e_max0, 1.0), max(c0, 1e-3)],
                                 bounds=([1e-6, 0.0], [1.0, np.inf]), xtol=1e-10, ftol=1e-10)
    realised = resid(res.x) + e_target
    return float(res.x[0]), float(res.x[1]), float(np.max(np.abs(realised - e_target))), realised


def snippet(types: list[str], e_max, c, mu, youngs, poisson, v_char) -> str:
    """LIGGGHTS input lines for ``len(types)`` atom types: ``e_max``, ``c``, ``mu`` are
    ``(n, n)`` matrices (per type pair), ``youngs``, ``poisson`` per type."""
    n = len(types)

    def matrix(m):
        return " ".join(f"{m[i][j]:.6g}" for i in range(n) for j in range(n))

    lines = [
        "# wet restitution from ehd-collision (pipeline/dem): LIGGGHTS hooke model, viscous on.",
        "# CriticalStokes is the C of e = MaximumRestitution exp(-C/St), St = meff vn/(6 pi mu reff^2)",
        "# with the instantaneous normal velocity; the values are calibrated so that this law",
        "# realises the model's e(St) at impact (see the JSON for the calibration error).",
        "# atom types: " + ", ".join(f"{i + 1} = {t}" for i, t in enumerate(types)),
        "pair_style gran model hooke tangential history viscous on",
        "pair_coeff * *",
        "fix m1 all property/global youngsModulus peratomtype "
        + " ".join(f"{y:.6g}" for y in youngs),
        "fix m2 all property/global poissonsRatio peratomtype "
        + " ".join(f"{p:.6g}" for p in poisson),
        f"fix m3 all property/global characteristicVelocity scalar {v_char:.6g}",
        f"fix m4 all property/global FluidViscosity peratomtypepair {n} {matrix(mu)}",
        f"fix m5 all property/global CriticalStokes peratomtypepair {n} {matrix(c)}",
        f"fix m6 all property/global MaximumRestitution peratomtypepair {n} {matrix(e_max)}",
        "# also required by tangential history: coefficientFriction peratomtypepair (not set here)",
        "# walls: the same model and keywords in fix wall/gran (... model hooke tangential history"
        " viscous on ...)",
    ]
    return "\n".join(lines) + "\n"
