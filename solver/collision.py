"""One collision ("scene"): analytic rigid approach, coupled EHD phase, analytic rigid departure.

Scales (physics.md): lengths along the axis by ``x1 = (4 theta mu a^1.5 v0)^0.4``, radii by
``sqrt(a x1)``, time by ``x1/v0`` (``T``; ``tau = v0 t / x0 = T eps^0.4``), pressure by
``mu a v0 / x1^2``, velocity by ``v0``, energies by the initial kinetic energy ``m v0^2 / 2``.
Forces are reported in units of ``6 pi mu a^2 v0 / x1`` (the rigid film force at gap ``x1`` and
speed ``v0``), so ``F = (1/3) Int P R dR`` and ``dV/dT = -F / St``.

Only the physics a scene needs is switched on: the rigid solution is exact until ``W(0)/X``
reaches ``switch`` (a scene that never gets there is answered analytically, ``model = "rigid"``),
and again once the deformation has relaxed below ``release`` on the way out, which gives the
equilibrium separation in closed form.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field

import numpy as np

from .integration import stepper
from .model import rigid
from .integration.grid import reference_grid, scaled_grid
from .settings import Numerics, resolve, validate_scene

__all__ = ["collide", "Collision", "SOLVER_VERSION", "STATUS", "hertz_overlap", "JSON_KEYS"]

# Bump with any change that can alter numbers: stamped into every result and store.
SOLVER_VERSION = "1.2.0"

STATUS = {
    stepper.OK: ("ok", ""),
    stepper.MAX_STEPS: ("max_steps", "step budget (max_steps) exhausted before the deformation relaxed"),
    stepper.STEP_UNDERFLOW: ("step_underflow", "time step fell below its minimum (nonlinear solve or error control failed)"),
    stepper.NONFINITE: ("nonfinite", "non-finite values or a singular Newton matrix in the coupled solve"),
}
# Not a numerical failure: the model's premise fails. The coupled phase starts from the rigid
# pressure's deformation, whose strain energy is 3.08 eps/St of the kinetic energy when the
# hand-over is at the start; beyond START_STRAIN_LIMIT the start x0 is not deformation-free
# (eps is not small for this St) and the answer depends on that assumption (e.g. v_r > 1 at
# St = 0.05, eps = 0.1). The observables are still reported, with this status.
START_DEFORMED = ("start_deformed", "eps is not small for this St: the assumed starting "
                  "deformation already stores {ratio:.3g} of the kinetic energy (limit {limit:g})")
START_STRAIN_LIMIT = 0.1

DIMPLE_DEPTH = 1e-3  # x1 units: a central gap this much above the minimum counts as a dimple

JSON_KEYS = (
    "St", "eps", "accuracy", "model", "status", "message", "v_r", "h_m_x1", "h_m_x0",
    "h_m_approach_x1", "h_m_approach_x0", "x_e_x1", "x_e_x0", "ln_x_e_x1", "ln_x_e_x0",
    "tau_max_deformation", "tau_v_zero", "tau_max_rebound", "tau_peak_force", "peak_force",
    "w0_max_x1", "x_min_x1", "dimple", "dimple_depth_x1", "tau_dimple", "escaped",
    "energy_error", "start_strain_energy", "steps", "rejected_steps", "newton_iterations", "lu_factorizations",
    "wall_s", "solver_version",
)


def hertz_overlap(stokes):
    """Dry Hertz maximum overlap over ``x1``: ``(90 pi^2 St / 64)^(2/5)`` (physics.md)."""
    return (90.0 * math.pi**2 * stokes / 64.0) ** 0.4


@dataclass
class Collision:
    """Result of one collision. Failures are data: ``status != "ok"`` with a ``message`` and NaN
    observables (never a guess). Lengths in ``x1`` (suffix ``_x1``) or ``x0`` (``_x0``), times as
    ``tau = v0 t / x0``, force in ``6 pi mu a^2 v0 / x1``, energies relative to the initial
    kinetic energy."""

    St: float
    eps: float
    accuracy: str
    numerics: Numerics
    model: str  # "rigid" (no coupled solve needed), "ehd", or "master" (solver.master fast path)
    status: str  # "ok" or a failure code (STATUS)
    message: str
    v_r: float = 0.0  # max rebound speed / v0
    h_m_x1: float = math.nan  # closest approach of the deformed surfaces, whole collision
    h_m_approach_x1: float = math.nan  # closest approach until v first reaches 0
    ln_x_e_x1: float = math.nan  # log of the equilibrium separation (finite even when x_e overflows)
    tau_max_deformation: float = math.nan  # time of the largest W(0)
    tau_v_zero: float = math.nan  # first time v = 0 (inf: the spheres never stop in finite time)
    tau_max_rebound: float = math.nan  # time of the largest rebound speed (nan: no rebound)
    tau_peak_force: float = math.nan
    peak_force: float = math.nan
    w0_max_x1: float = math.nan  # largest central deformation W(0)
    x_min_x1: float = math.nan  # smallest X (negative: undeformed surfaces overlap)
    dimple: bool | None = False  # None when the scene failed
    dimple_depth_x1: float = 0.0  # largest H(0) - min_R H
    tau_dimple: float = math.nan  # first time the dimple is deeper than DIMPLE_DEPTH
    energy_error: float = math.nan  # max |E_k + E_s + dissipated - const| in the coupled phase
    start_strain_energy: float = 0.0  # E_s / E_k where the coupled phase starts
    steps: int = 0
    rejected_steps: int = 0
    newton_iterations: int = 0
    lu_factorizations: int = 0
    wall_s: float = 0.0
    tau_handover: float = math.nan  # rigid -> coupled
    tau_release: float = math.nan  # coupled -> rigid
    series: dict = field(default_factory=dict, repr=False)  # time series (see time_series)
    radius: np.ndarray | None = field(default=None, repr=False)  # (N,) grid radii R
    profile_tau: np.ndarray | None = field(default=None, repr=False)  # (rows,)
    pressure: np.ndarray | None = field(default=None, repr=False)  # (rows, N) P
    deformation: np.ndarray | None = field(default=None, repr=False)  # (rows, N) W
    profile_x: np.ndarray | None = field(default=None, repr=False)  # (rows,) X at profile times

    # ---- derived quantities ---------------------------------------------------------------
    @property
    def x0_over_x1(self) -> float:
        return self.eps ** -0.4

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def h_m_x0(self) -> float:
        return self.h_m_x1 / self.x0_over_x1

    @property
    def h_m_approach_x0(self) -> float:
        return self.h_m_approach_x1 / self.x0_over_x1

    @property
    def ln_x_e_x0(self) -> float:
        return self.ln_x_e_x1 - math.log(self.x0_over_x1)

    @property
    def x_e_x1(self) -> float:
        return _exp(self.ln_x_e_x1)

    @property
    def x_e_x0(self) -> float:
        return _exp(self.ln_x_e_x0)

    @property
    def escaped(self) -> bool | None:
        """The rebound carries the spheres back beyond x0: the model's verdict "no sticking"
        (None when the scene failed and x_e is unknown)."""
        ln_x_e = self.ln_x_e_x0
        return bool(ln_x_e > 0.0) if math.isfinite(ln_x_e) else None

    @property
    def gap(self) -> np.ndarray | None:
        """Film thickness ``H = X + R^2/2 + W`` at the profile times, (rows, N)."""
        if self.deformation is None:
            return None
        return self.profile_x[:, None] + 0.5 * self.radius[None, :] ** 2 + self.deformation

    def to_dict(self) -> dict:
        """The scalar results (JSON_KEYS), non-finite numbers as None."""
        out = {}
        for key in JSON_KEYS:
            value = self.accuracy if key == "accuracy" else getattr(self, key, None)
            if key == "solver_version":
                value = SOLVER_VERSION
            if isinstance(value, (bool, np.bool_)):
                value = bool(value)
            elif isinstance(value, (int, np.integer)):
                value = int(value)
            elif isinstance(value, (float, np.floating)):
                value = float(value) if math.isfinite(value) else None
            out[key] = value
        return out

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    def to_xarray(self):
        """Self-describing Dataset: scalars as attrs, time series along ``tau``, profiles
        along ``(profile_tau, R)``."""
        import xarray as xr

        attrs = {k: (int(v) if isinstance(v, bool) else v) for k, v in self.to_dict().items()
                 if v is not None}
        attrs.update({f"numerics_{k}": (int(v) if isinstance(v, bool) else v)
                      for k, v in self.numerics.as_dict().items()})
        attrs["scaling"] = (
            "lengths along the axis / x1 (x1 = (4 theta mu a^1.5 v0)^0.4), radius / sqrt(a x1), "
            "tau = v0 t / x0, pressure / (mu a v0 / x1^2), velocity / v0, force / "
            "(6 pi mu a^2 v0 / x1), energies / (m v0^2 / 2)")
        ds = xr.Dataset(attrs=attrs)
        tau = self.series["tau"]
        ds = ds.assign_coords(tau=("tau", tau, {"long_name": "time v0 t / x0"}))
        meta = {
            "T": ("time v0 t / x1", "x1/v0"), "X": ("separation of undeformed surfaces", "x1"),
            "V": ("approach velocity", "v0"), "F": ("film force", "6 pi mu a^2 v0 / x1"),
            "W0": ("central deformation W(0)", "x1"), "H_min": ("minimum gap", "x1"),
            "R_H_min": ("radius of the minimum gap", "sqrt(a x1)"),
            "E_k": ("kinetic energy", "m v0^2/2"), "E_s": ("strain energy", "m v0^2/2"),
            "dissipated": ("viscous dissipation so far", "m v0^2/2"),
            "phase": ("0 rigid approach, 1 coupled, 2 rigid departure", "1"),
        }
        for name, (long_name, units) in meta.items():
            ds[name] = ("tau", self.series[name], {"long_name": long_name, "units": units})
        if self.pressure is not None and self.pressure.size:
            ds = ds.assign_coords(
                R=("R", self.radius, {"long_name": "radius", "units": "sqrt(a x1)"}),
                profile_tau=("profile_tau", self.profile_tau, {"long_name": "time v0 t / x0"}))
            ds["P"] = (("profile_tau", "R"), self.pressure,
                       {"long_name": "film pressure", "units": "mu a v0 / x1^2"})
            ds["W"] = (("profile_tau", "R"), self.deformation,
                       {"long_name": "total surface deformation", "units": "x1"})
            ds["H"] = (("profile_tau", "R"), self.gap, {"long_name": "film thickness", "units": "x1"})
        return ds


def _exp(v):
    if not math.isfinite(v):
        return v
    return math.exp(v) if v < 709.0 else math.inf


def _parabolic_peak(t, f, i):
    """Vertex of the parabola through samples i-1, i, i+1 (the discrete extremum ``i``)."""
    if i <= 0 or i >= len(f) - 1:
        return t[i], f[i]
    t0, t1, t2 = t[i - 1], t[i], t[i + 1]
    f0, f1, f2 = f[i - 1], f[i], f[i + 1]
    d1 = (f1 - f0) / (t1 - t0)
    d2 = (f2 - f1) / (t2 - t1)
    curv = (d2 - d1) / (t2 - t0)  # half the second derivative
    if curv == 0.0:
        return t1, f1
    tv = 0.5 * (t0 + t1) - d1 / (2.0 * curv)
    if not (t0 <= tv <= t2):
        return t1, f1
    fv = f1 + d1 * (tv - t1) + curv * (tv - t0) * (tv - t1)
    return tv, fv


FAR_FIELD_REACH = 8.0  # the grid reaches this many film widths sqrt(2 X) beyond the axis


def scene_grid(stokes, x_switch, numerics: Numerics):
    """The radial grid of a scene.

    The inner region covers the Hertz contact radius ``sqrt(delta_H)`` (at least 2, the film's
    width at small St). The grid must also reach well beyond the widest film the coupled phase
    sees, ``sqrt(2 X)`` at the hand-over and at the release (where ``W(0)/X = release`` on the
    rigid path with ``V <= 1``); its extent doubles until it does (a few outer cells each time).
    """
    inner = numerics.inner_factor * max(math.sqrt(hertz_overlap(stokes)), 2.0)
    x_release = (rigid.HANDOVER_COEFF / numerics.release) ** 0.4
    reach = FAR_FIELD_REACH * math.sqrt(2.0 * max(x_switch, x_release)) / inner
    extent = numerics.outer_extent
    while extent < reach:
        extent *= 2.0
    ref = reference_grid(numerics.n_inner, numerics.axis_ratio, numerics.axis_extent,
                         numerics.stretch, extent, numerics.max_rel)
    return scaled_grid(ref, inner)


def collide(St, eps, *, accuracy: str = "standard", **overrides) -> Collision:
    """Solve one head-on collision of two elastic spheres through a viscous film.

    Parameters
    ----------
    St : float
        Stokes number ``m v0 / (6 pi mu a^2)``, in (0, 1e4].
    eps : float
        Elasticity parameter ``4 theta mu v0 a^1.5 / x0^2.5``, in (0, 0.1].
    accuracy : {"fast", "standard", "fine"}
        Preset of numerical settings (settings.PRESETS).
    **overrides
        Any field of ``settings.Numerics`` (e.g. ``switch=0.005``, ``n_inner=64``).

    Returns
    -------
    Collision
        ``status == "ok"`` or a failure code with ``message``; see the class docstring.
    """
    stokes, eps = validate_scene(St, eps)
    numerics = resolve(accuracy, **overrides)
    wall = time.perf_counter()
    x_start = eps ** -0.4
    tau_per_t = eps ** 0.4  # tau = T * x1/x0
    x_switch = rigid.handover_separation(x_start, stokes, numerics.switch)
    if x_switch is None:
        result = _rigid_only(stokes, eps, accuracy, numerics, x_start, tau_per_t)
    else:
        result = _coupled(stokes, eps, accuracy, numerics, x_start, x_switch, tau_per_t)
    result.wall_s = time.perf_counter() - wall
    return result


def _rigid_path(x_from, v_from, t_from, stokes, x):
    v = rigid.velocity(x, x_from, v_from, stokes)
    t = t_from + rigid.elapsed_time(x, x_from, v_from, stokes)
    return t, v


def _series_block(t, x, v, tau_per_t, phase, dissipated, h_min=None, w0=None, force=None,
                  strain=None, r_h_min=None):
    n = len(t)
    zeros = np.zeros(n)
    return {
        "T": t, "tau": t * tau_per_t, "X": x, "V": v,
        "F": force if force is not None else v / x,
        "W0": w0 if w0 is not None else 3.0 * v * x**-1.5 * rigid.I0,
        "H_min": h_min if h_min is not None else x,
        "R_H_min": r_h_min if r_h_min is not None else zeros,
        "E_k": v * v, "E_s": strain if strain is not None else zeros,
        "dissipated": dissipated, "phase": np.full(n, phase, dtype=np.int8),
    }


def _concat(blocks):
    return {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]}


def _rigid_only(stokes, eps, accuracy, numerics, x_start, tau_per_t):
    """The scene never deforms enough to need the coupled solution: everything is analytic."""
    ln_x_stop = rigid.rest_separation(x_start, 1.0, stokes)
    u = np.linspace(0.0, 0.999 * stokes, 200) if stokes < 30 else np.linspace(0.0, 30.0, 200)
    x = x_start * np.exp(-u)
    t, v = _rigid_path(x_start, 1.0, 0.0, stokes, x)
    series = _series_block(t, x, v, tau_per_t, 0, 1.0 - v * v)

    peaks = _rigid_peaks(x_start, stokes, 0.0, tau_per_t)
    return Collision(
        St=stokes, eps=eps, accuracy=accuracy, numerics=numerics, model="rigid", status="ok",
        message="deformation stays below the hand-over threshold: rigid solution (exact)",
        v_r=0.0, h_m_x1=math.exp(ln_x_stop), h_m_approach_x1=math.exp(ln_x_stop),
        ln_x_e_x1=ln_x_stop, tau_v_zero=math.inf, tau_max_rebound=math.nan,
        x_min_x1=math.exp(ln_x_stop), energy_error=0.0, series=series, **peaks)


def include_rigid_peaks(result, x_start, x_switch):
    """Peaks are the larger of the coupled phase's (already in ``result``) and those of the
    analytic rigid approach before the hand-over at ``x_switch``."""
    head = _rigid_peaks(x_start, result.St, x_switch, result.eps**0.4)
    if head["peak_force"] > result.peak_force:
        result.peak_force, result.tau_peak_force = head["peak_force"], head["tau_peak_force"]
    if head["w0_max_x1"] > result.w0_max_x1:
        result.w0_max_x1 = head["w0_max_x1"]
        result.tau_max_deformation = head["tau_max_deformation"]


def _rigid_peaks(x_start, stokes, x_end, tau_per_t):
    """Largest force and central deformation on the rigid path from ``x_start`` down to
    ``x_end``: the force 3V/X (1/3 of it in our unit) peaks where V = 1/St, W(0) = 3 I0 V X^-1.5
    where V = 2/(3 St); clipped to the path (at the start when St < 1, resp. 2/3)."""

    def peak_at(u_peak):
        u_end = math.log(x_start / x_end) if x_end > 0 else math.inf
        x = x_start * math.exp(-min(max(u_peak, 0.0), u_end))
        v = float(rigid.velocity(x, x_start, 1.0, stokes))
        return x, v, float(rigid.elapsed_time(x, x_start, 1.0, stokes)) * tau_per_t

    x_f, v_f, tau_f = peak_at(stokes - 1.0)
    x_w, v_w, tau_w = peak_at(stokes - 2.0 / 3.0)
    return {"peak_force": v_f / x_f, "tau_peak_force": tau_f,
            "w0_max_x1": 3.0 * v_w * x_w**-1.5 * rigid.I0, "tau_max_deformation": tau_w}


def _coupled(stokes, eps, accuracy, numerics, x_start, x_switch, tau_per_t):
    v_switch = float(rigid.velocity(x_switch, x_start, 1.0, stokes))
    t_switch = float(rigid.elapsed_time(x_switch, x_start, 1.0, stokes))

    grid = scene_grid(stokes, x_switch, numerics)
    p_init = 3.0 * v_switch / (x_switch + grid.s) ** 2  # rigid pressure; K p = asymptotic W
    time_scale = x_switch / max(v_switch, 1e-3)
    code, counters, rows, p_hist, w_hist = stepper.integrate(
        grid.s, grid.s_face, grid.area, grid.force_weight, grid.influence, stokes, x_switch, v_switch, p_init,
        t_switch, 1.0 - v_switch**2, numerics.rtol, 1e-3 * time_scale, 1e-12 * time_scale,
        numerics.max_steps, numerics.release, numerics.save_profiles)
    name, message = STATUS[code]
    cols = {c: rows[:, k] for k, c in enumerate(stepper.SERIES)}
    cols["F"] = cols["F"] / 3.0  # force unit 6 pi mu a^2 v0 / x1
    t_c, x_c, v_c = cols["T"], cols["X"], cols["V"]

    # rigid approach (analytic) up to the hand-over
    blocks = []
    if x_switch < x_start:
        x_head = x_start * np.exp(-np.linspace(0.0, math.log(x_start / x_switch), 60))[:-1]
        t_head, v_head = _rigid_path(x_start, 1.0, 0.0, stokes, x_head)
        blocks.append(_series_block(t_head, x_head, v_head, tau_per_t, 0, 1.0 - v_head**2))
    blocks.append(_series_block(
        t_c, x_c, v_c, tau_per_t, 1, cols["dissipated"], h_min=cols["H_min"], w0=cols["W0"],
        force=cols["F"], strain=cols["E_s"], r_h_min=cols["R_H_min"]))

    result = Collision(
        St=stokes, eps=eps, accuracy=accuracy, numerics=numerics, model="ehd", status=name,
        message=message, steps=int(counters[0]), rejected_steps=int(counters[1]),
        newton_iterations=int(counters[2]), lu_factorizations=int(counters[3]),
        tau_handover=t_switch * tau_per_t, radius=grid.radius)
    if numerics.save_profiles:
        result.profile_tau = t_c * tau_per_t
        result.pressure = p_hist
        result.deformation = w_hist
        result.profile_x = x_c
    if name != "ok":
        result.v_r = result.dimple_depth_x1 = math.nan
        result.dimple = None
        result.series = _concat(blocks)
        result.message = (f"{message} (St={stokes:g}, eps={eps:g}, after {counters[0]} steps at "
                          f"tau={t_c[-1] * tau_per_t:.4g})")
        return result

    # rigid departure (analytic) from the release state
    t_rel, x_rel, v_rel = t_c[-1], x_c[-1], v_c[-1]
    ln_x_e = rigid.rest_separation(x_rel, v_rel, stokes)
    u_end = max(-30.0, min(30.0, -0.99 * stokes * v_rel))
    if u_end != 0.0:
        x_tail = x_rel * np.exp(np.linspace(0.0, u_end, 41)[1:])
        t_tail, v_tail = _rigid_path(x_rel, v_rel, t_rel, stokes, x_tail)
        diss_tail = cols["dissipated"][-1] + (v_rel**2 - v_tail**2)
        blocks.append(_series_block(t_tail, x_tail, v_tail, tau_per_t, 2, diss_tail))
    result.series = _concat(blocks)
    result.tau_release = t_rel * tau_per_t
    result.ln_x_e_x1 = ln_x_e

    # ---- observables from the coupled phase (the rigid parts are monotone) ------------------
    tau = t_c * tau_per_t
    result.v_r = 0.0
    if np.any(v_c < 0.0):
        i = int(np.argmin(v_c))
        t_pk, v_pk = _parabolic_peak(tau, v_c, i)
        result.v_r = float(-v_pk)
        result.tau_max_rebound = float(t_pk)
    h_min = cols["H_min"]
    i = int(np.argmin(h_min))
    result.h_m_x1 = float(_parabolic_peak(tau, h_min, i)[1])
    below = np.nonzero(v_c <= 0.0)[0]
    if below.size:
        # approach phase ends at the interpolated v = 0 between rows j-1 and j
        j = int(below[0])
        frac = v_c[j - 1] / (v_c[j - 1] - v_c[j])
        result.tau_v_zero = float(tau[j - 1] + (tau[j] - tau[j - 1]) * frac)
        h_at_stop = h_min[j - 1] + (h_min[j] - h_min[j - 1]) * frac
        ia = int(np.argmin(h_min[:j]))
        h_app = _parabolic_peak(tau[:j], h_min[:j], ia)[1] if ia < j - 1 else h_min[j - 1]
        result.h_m_approach_x1 = float(min(h_app, h_at_stop))
    else:
        result.tau_v_zero = math.inf  # rigid creep to rest: v reaches 0 only as t -> inf
        ia = int(np.argmin(h_min))
        result.h_m_approach_x1 = float(_parabolic_peak(tau, h_min, ia)[1])
    if v_rel > 0.0:  # still approaching when released: rigid creep down to x_e
        result.h_m_x1 = min(result.h_m_x1, math.exp(ln_x_e))
        if below.size == 0:
            result.h_m_approach_x1 = min(result.h_m_approach_x1, math.exp(ln_x_e))
    i = int(np.argmax(cols["F"]))
    result.tau_peak_force, result.peak_force = map(float, _parabolic_peak(tau, cols["F"], i))
    i = int(np.argmax(cols["W0"]))
    result.tau_max_deformation, result.w0_max_x1 = map(float, _parabolic_peak(tau, cols["W0"], i))
    include_rigid_peaks(result, x_start, x_switch)
    i = int(np.argmin(x_c))
    result.x_min_x1 = float(_parabolic_peak(tau, x_c, i)[1])
    depth = cols["H0"] - h_min
    result.dimple_depth_x1 = float(depth.max())
    deep = np.nonzero(depth > DIMPLE_DEPTH)[0]
    result.dimple = bool(deep.size > 0)
    if deep.size:
        result.tau_dimple = float(tau[deep[0]])
    total = cols["E_k"] + cols["E_s"] + cols["dissipated"]
    result.energy_error = float(np.max(np.abs(total - total[0])))
    result.start_strain_energy = float(cols["E_s"][0] / cols["E_k"][0])
    if result.start_strain_energy > START_STRAIN_LIMIT:
        result.status = START_DEFORMED[0]
        result.message = START_DEFORMED[1].format(ratio=result.start_strain_energy,
                                                  limit=START_STRAIN_LIMIT)
    return result
