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
``(St_in, e_max, C)`` only. Integrated by classic RK4 at a fixed step of 1/200 of the time unit
(about 630 steps per contact; compiled, 0.1 ms a collision), the crossing of ``y = 0`` located
on the step's cubic Hermite interpolant: 1e-11 from an adaptive DOP853 at rtol 1e-10 over
St 7-300 and e 0.001-0.94 (measured when it replaced that integrator, which made a 448-scene
export take minutes).

LIGGGHTS itself integrates with a fixed time step ``dt``; its spring is
``kn = 16/15 sqrt(reff) Yeff (15 meff vchar^2 / (16 sqrt(reff) Yeff))^(1/5)`` (the same header),
so its contact lasts about ``tc = pi sqrt(meff/kn)`` (the undamped half period; damping only
lengthens it). ``contact_time`` computes it; the snippets state ``dt <= tc / STEPS_PER_CONTACT``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from solver._jit import entry, jit

__all__ = ["replica_restitution", "replica_many", "closed_form_restitution", "calibrate",
           "calibrate_minimax",
           "snippet", "wall_snippet", "contact_time", "effective_modulus", "hooke_stiffness",
           "STEPS_PER_CONTACT", "TIME_STEP_ERROR", "MIN_CHARACTERISTIC_VELOCITY"]

# LIGGGHTS refuses characteristicVelocity < 1e-2 in SI units (src/global_properties.cpp); the
# value only sets the spring kn (the contact time), never the restitution, so a slower scene
# gets 1e-2 and a stiffer, shorter contact.
MIN_CHARACTERISTIC_VELOCITY = 1e-2
# Time steps per contact time the snippets ask for. Measured with LIGGGHTS 3.8.0 (the head-on
# runs of tests/test_dem_programs.py at St 6-1000, eps 1e-4 and 1e-6, both geometries), the
# largest |LIGGGHTS - replica| in e: 0.001 at tc/640, 0.004 at tc/200, 0.007 at tc/100, 0.012 at
# tc/50, 0.048 at tc/20. 200 keeps it (TIME_STEP_ERROR) an order below the calibration's error.
STEPS_PER_CONTACT = 200
TIME_STEP_ERROR = 0.004
# The replica's fixed RK4 step (time unit sqrt(meff/kn)) and horizon (a collision that has not
# separated after 100 time units, ~30 contact times, is taken as stuck).
_STEP = 5e-3
_T_MAX = 100.0
# (rebound speed / impact speed)^2 below which a collision counts as stuck: e < 1e-4, two orders
# below any error the export states (the creeping end of a near-critically damped contact took
# most of the time)
_NEGLIGIBLE = 1e-8


def _zeta(log_e):
    if not math.isfinite(log_e):
        return 1.0  # vn = 0: L -> +-inf, critical damping
    return 1.0 / math.sqrt(1.0 + (math.pi / log_e) ** 2)


def closed_form_restitution(log_e: float) -> float:
    """Restitution of the linear spring-dashpot with fixed ``L = log_e < 0``:
    ``exp(-zeta pi / sqrt(1 - zeta^2))`` (which is ``exp(L)``)."""
    z = _zeta(log_e)
    return math.exp(-z * math.pi / math.sqrt(1.0 - z * z))


@jit
def _force(y, u, log_max, st_crit, st_in, fixed, limit):
    """Repulsive contact force (units kn v_in sqrt(meff/kn)) of the hooke viscous law."""
    if fixed > 0.0:
        log_e = log_max - st_crit / fixed
    elif u == 0.0:
        log_e = -math.inf
    else:
        log_e = log_max - st_crit / (st_in * u)
    if math.isinf(log_e):
        zeta = 1.0
    else:
        r = math.pi / log_e
        zeta = 1.0 / math.sqrt(1.0 + r * r)
    f = y + 2.0 * zeta * u
    if limit and f < 0.0:
        f = 0.0
    return f


@jit
def _hermite(s, a, da, b, db, h):
    s2 = s * s
    s3 = s2 * s
    return ((2.0 * s3 - 3.0 * s2 + 1.0) * a + (s3 - 2.0 * s2 + s) * h * da
            + (3.0 * s2 - 2.0 * s3) * b + (s3 - s2) * h * db)


@entry
@jit
def _replica(st_in, log_max, st_crit, fixed, limit, h, t_max):
    y, u = 0.0, 1.0
    fy = -_force(y, u, log_max, st_crit, st_in, fixed, limit)
    for i in range(int(t_max / h)):
        k1u = fy
        y2, u2 = y + 0.5 * h * u, u + 0.5 * h * k1u
        k2u = -_force(y2, u2, log_max, st_crit, st_in, fixed, limit)
        y3, u3 = y + 0.5 * h * u2, u + 0.5 * h * k2u
        k3u = -_force(y3, u3, log_max, st_crit, st_in, fixed, limit)
        y4, u4 = y + h * u3, u + h * k3u
        k4u = -_force(y4, u4, log_max, st_crit, st_in, fixed, limit)
        yn = y + h / 6.0 * (u + 2.0 * u2 + 2.0 * u3 + u4)
        un = u + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u)
        fn = -_force(yn, un, log_max, st_crit, st_in, fixed, limit)
        if i > 0 and yn <= 0.0 < y:
            lo, hi = 0.0, 1.0  # the crossing on the step's cubic Hermite of y, by bisection
            for _ in range(60):
                s = 0.5 * (lo + hi)
                if _hermite(s, y, u, yn, un, h) > 0.0:
                    lo = s
                else:
                    hi = s
            return max(0.0, -_hermite(0.5 * (lo + hi), u, k1u, un, fn, h))
        if not limit and yn * yn + un * un < _NEGLIGIBLE:
            # spring plus kinetic energy only falls (the dashpot dissipates): the speed at
            # separation is below sqrt(y^2 + u^2) < 1e-4, a stuck collision for every purpose
            return 0.0
        y, u, fy = yn, un, fn
    return 0.0  # never separates within t_max: stuck (overdamped, limitForce)


@entry
@jit
def _replica_many(st_in, e_max, st_crit, limit, h, t_max):
    out = np.empty(st_in.size)
    log_max = math.log(e_max)
    for k in range(st_in.size):
        out[k] = _replica(st_in[k], log_max, st_crit, 0.0, limit, h, t_max)
    return out


def replica_restitution(st_in, e_max, st_crit, *, fixed_stokes=None, limit_force=False) -> float:
    """Realised restitution of one head-on collision under LIGGGHTS' hooke ``viscous`` law.

    ``fixed_stokes``: compute the damping once from this Stokes number instead of the
    instantaneous one (the closed-form case). ``limit_force``: LIGGGHTS' ``limitForce on`` (the
    normal force is never attractive)."""
    return float(_replica(float(st_in), math.log(e_max), float(st_crit),
                          0.0 if fixed_stokes is None else float(fixed_stokes),
                          bool(limit_force), _STEP, _T_MAX))


def replica_many(st_in, e_max, st_crit, *, limit_force=False) -> np.ndarray:
    """``replica_restitution`` at every impact Stokes number of ``st_in``."""
    return _replica_many(np.ascontiguousarray(st_in, dtype=float), float(e_max), float(st_crit),
                         bool(limit_force), _STEP, _T_MAX)


def calibrate(st, e_target, e_max0=None, c0=None, weights=None, e_cap=1.0):
    """``(MaximumRestitution, CriticalStokes)`` whose replica reproduces ``e_target`` at ``st``
    (LIGGGHTS' convention = ours, impact speeds), by least squares over the rebounding rows
    (``weights`` per row: where the user's collisions are), ``MaximumRestitution <= e_cap``
    (the pair's e_dry: the law's e tends to it at high St, and no real collision gives back
    more than dry solids). Returns
    ``(e_max, C, max_abs_error, realised)`` over the rebounding rows."""
    st, e_target = np.asarray(st, float), np.asarray(e_target, float)
    keep = e_target > 0.0
    st, e_target = st[keep], e_target[keep]
    w = np.ones_like(st) if weights is None else np.sqrt(np.asarray(weights, float)[keep])
    e_max0 = float(np.max(e_target)) if e_max0 is None else e_max0
    c0 = float(np.median(st * -np.log(np.clip(e_target / e_max0, 1e-6, 1.0)))) if c0 is None else c0

    def resid(p):
        return (replica_many(st, p[0], p[1]) - e_target) * w

    # CriticalStokes > 0 is required by LIGGGHTS (src/global_properties.cpp)
    res = optimize.least_squares(resid, x0=[min(e_max0, e_cap * (1.0 - 1e-9)), max(c0, 1e-3)],
                                 bounds=([1e-6, 1e-9], [e_cap, np.inf]), xtol=1e-10, ftol=1e-10)
    realised = replica_many(st, res.x[0], res.x[1])
    return float(res.x[0]), float(res.x[1]), float(np.max(np.abs(realised - e_target))), realised


def calibrate_minimax(st, e_target, e_max0, c0, max_evaluations=120, e_cap=1.0):
    """``(MaximumRestitution, CriticalStokes, max_abs_error)`` minimising the largest error over
    every row, sticking ones included (started from the least-squares values ``e_max0, c0``),
    ``MaximumRestitution <= e_cap`` (``calibrate``).
    The replica's e grows with St, so of the sticking rows only the one of largest St can hold
    the largest error: the others are not integrated."""
    st, e_target = np.asarray(st, float), np.asarray(e_target, float)
    up = e_target > 0.0
    use = up.copy()
    stuck = np.flatnonzero(~up)
    if stuck.size:
        use[stuck[np.argmax(st[stuck])]] = True
    st_u, e_u = st[use], e_target[use]

    def worst(p):
        if not (0.0 < p[0] <= e_cap and p[1] > 0.0):
            return np.inf
        return float(np.max(np.abs(replica_many(st_u, p[0], p[1]) - e_u)))

    r = optimize.minimize(worst, [e_max0, c0], method="Nelder-Mead",
                          options={"xatol": 1e-4, "fatol": 1e-5, "maxfev": max_evaluations,
                                   "initial_simplex": [[e_max0, c0],
                                                       # down where up would leave e_cap
                                                       [e_max0 * (1.02 if e_max0 * 1.02 <= e_cap
                                                                  else 0.98), c0],
                                                       [e_max0, c0 * 1.1]]})
    return float(r.x[0]), float(r.x[1]), float(r.fun)


def effective_modulus(youngs1, poisson1, youngs2, poisson2) -> float:
    """LIGGGHTS' ``Yeff = 1 / ((1 - nu1^2)/Y1 + (1 - nu2^2)/Y2)``."""
    return 1.0 / ((1.0 - poisson1**2) / youngs1 + (1.0 - poisson2**2) / youngs2)


def hooke_stiffness(meff, reff, yeff, v_char) -> float:
    """The hooke model's spring ``kn`` [N/m] (src/normal_model_hooke.h)."""
    s = math.sqrt(reff)
    return 16.0 / 15.0 * s * yeff * (15.0 * meff * v_char**2 / (16.0 * s * yeff)) ** 0.2


def contact_time(meff, reff, yeff, v_char) -> float:
    """``pi sqrt(meff / kn)``: the undamped contact time of the hooke spring [s]."""
    return math.pi * math.sqrt(meff / hooke_stiffness(meff, reff, yeff, v_char))


def snippet(lig: dict, *, types: list[str], values: dict, placeholders: bool,
            header: tuple = ()) -> str:
    """LIGGGHTS input lines for ``len(types)`` atom types, to paste after ``create_box`` and
    before the atoms: the pair style and every property the hooke ``viscous`` model reads.
    ``values``: ``youngs`` and ``poisson`` per type, ``viscosity``, ``v_char``; with
    ``placeholders`` also ``density`` and ``radius`` (example values marked REPLACE) from which
    the input computes the time step itself; else ``dt_max`` [s] (the scene's number).
    ``header``: comment lines (without ``#``) after the title: the e realised, its physics."""
    n = len(types)
    v = values
    rep = "  # REPLACE: " if placeholders else "  # the scene's "

    def matrix(x):
        return " ".join([f"{x:.6g}"] * (n * n))

    def per_type(name):
        if placeholders:
            return " ".join(f"${{ehd_{name}}}" for _ in range(n))
        return " ".join(f"{x:.6g}" for x in v[name])

    v_char = max(v["v_char"], MIN_CHARACTERISTIC_VELOCITY)
    lines = [
        "# ==== ehd-collision wet restitution for LIGGGHTS 3.8: gran model hooke, viscous on ====",
        *(f"# {line}" for line in header),
        "# Paste after create_box (" + f"{n} atom type{'s' if n > 1 else ''}: "
        + ", ".join(f"{i + 1} = {t}" for i, t in enumerate(types)) + ") and before the atoms.",
        "# CriticalStokes is the C of e = MaximumRestitution exp(-C/St), St = meff vn/(6 pi mu reff^2)",
        "# with LIGGGHTS' instantaneous vn; the two values are calibrated so that the law realises the",
        f"# model's e(St) at impact: largest error {lig['realised_max_error']:.3f} in e over every row "
        "(restitution.json: liggghts.realised_error_by_St), at dt <= ehd_dt_max.",
    ]
    if placeholders:
        lines += [
            f"variable ehd_viscosity equal {v['viscosity']:.6g}{rep}fluid viscosity [Pa s] (enters St)",
            f"variable ehd_youngs equal {v['youngs'][0]:.6g}{rep}Young's modulus [Pa] (kn: contact time only)",
            f"variable ehd_poisson equal {v['poisson'][0]:.6g}{rep}Poisson's ratio",
            f"variable ehd_vchar equal {v_char:.6g}{rep}typical impact speed [m/s], >= 0.01 (kn only)",
            f"variable ehd_density equal {v['density']:.6g}{rep}particle density [kg/m^3] (time step only)",
            f"variable ehd_radius equal {v['radius']:.6g}{rep}particle radius [m] (time step only)",
        ]
    lines += [
        "variable ehd_friction equal 0.5  # REPLACE: your friction coefficient (no effect head-on)",
        "# WARNING: keep limitForce off (LIGGGHTS' default; its docs recommend 'limitForce on'):",
        "# with it the force is never attractive, the dashpot cannot hold the spheres together and",
        "# collisions the model says stick rebound (e 0.24 measured in LIGGGHTS 3.8.0).",
        "hard_particles yes",
        "pair_style gran model hooke tangential history viscous on",
        "pair_coeff * *",
        f"fix ehd_m1 all property/global youngsModulus peratomtype {per_type('youngs')}",
        f"fix ehd_m2 all property/global poissonsRatio peratomtype {per_type('poisson')}",
        "fix ehd_m3 all property/global characteristicVelocity scalar "
        + ("${ehd_vchar}" if placeholders else f"{v_char:.6g}")
        + ("" if placeholders or v["v_char"] >= MIN_CHARACTERISTIC_VELOCITY else
           f"  # v0 {v['v_char']:.3g} m/s raised to LIGGGHTS' minimum (kn only)"),
        "fix ehd_m4 all property/global FluidViscosity peratomtypepair "
        + f"{n} " + (" ".join(["${ehd_viscosity}"] * (n * n)) if placeholders else matrix(v["viscosity"])),
        f"fix ehd_m5 all property/global CriticalStokes peratomtypepair {n} {matrix(lig['CriticalStokes'])}",
        f"fix ehd_m6 all property/global MaximumRestitution peratomtypepair {n} "
        f"{matrix(lig['MaximumRestitution'])}",
        f"fix ehd_m7 all property/global coefficientFriction peratomtypepair {n} "
        + " ".join(["${ehd_friction}"] * (n * n)),
        f"# time step: at most 1/{STEPS_PER_CONTACT} of the contact time tc = pi sqrt(meff/kn),",
        "# kn = 16/15 sqrt(reff) Yeff (15 meff vchar^2/(16 sqrt(reff) Yeff))^(1/5) (LIGGGHTS' hooke)",
    ]
    if placeholders:
        lines += [
            "# two equal spheres (meff = m/2, reff = r/2; a sphere on a wall has a longer contact)",
            "variable ehd_meff equal 2.0/3.0*PI*v_ehd_density*v_ehd_radius^3",
            "variable ehd_reff equal 0.5*v_ehd_radius",
            "variable ehd_yeff equal v_ehd_youngs/(2.0*(1.0-v_ehd_poisson^2))",
            "variable ehd_kn equal 16.0/15.0*sqrt(v_ehd_reff)*v_ehd_yeff*"
            "(15.0*v_ehd_meff*v_ehd_vchar^2/(16.0*sqrt(v_ehd_reff)*v_ehd_yeff))^0.2",
            f"variable ehd_dt_max equal PI*sqrt(v_ehd_meff/v_ehd_kn)/{STEPS_PER_CONTACT}"
            f"  # {_example_dt(v):.3g} s with the values above; use timestep ${{ehd_dt_max}} or smaller",
        ]
    else:
        lines.append(f"variable ehd_dt_max equal {v['dt_max']:.6g}  # [s], tc = "
                     f"{v['dt_max'] * STEPS_PER_CONTACT:.4g} s; use timestep ${{ehd_dt_max}} or smaller")
    return "\n".join(lines) + "\n"


def _example_dt(v) -> float:
    """``ehd_dt_max`` of a store snippet's example values (two equal spheres)."""
    m = 4.0 / 3.0 * math.pi * v["radius"] ** 3 * v["density"]
    yeff = effective_modulus(v["youngs"][0], v["poisson"][0], v["youngs"][0], v["poisson"][0])
    tc = contact_time(0.5 * m, 0.5 * v["radius"], yeff,
                      max(v["v_char"], MIN_CHARACTERISTIC_VELOCITY))
    return tc / STEPS_PER_CONTACT


def wall_snippet(wall_type: int, *, placeholders: bool, header: tuple = ()) -> str:
    """The wall line (paste after the snippet): the same model and keywords in fix wall/gran;
    the model keywords (``viscous on``) after the wall's own arguments, as LIGGGHTS requires.
    ``header``: as ``snippet``'s."""
    return "\n".join([
        "# ==== ehd-collision: walls (paste after the particle block) ====",
        *(f"# {line}" for line in header),
        "# the wall's material is atom type %d; the same law (meff, reff = the sphere's)" % wall_type,
        "variable ehd_wall_z equal 0.0  # REPLACE: the wall's position (or use your mesh walls with "
        "the same 'model hooke tangential history' and 'viscous on' after 'meshes ...')",
        f"fix ehd_wall all wall/gran model hooke tangential history primitive type {wall_type} "
        "zplane ${ehd_wall_z} viscous on",
    ]) + "\n"
