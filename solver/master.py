"""One-parameter fast path: a master curve in ``S = St * V_switch``.

Where the coupled phase takes over from the analytic rigid approach, ``W(0)/X`` equals the
hand-over threshold and the state is ``(X_s, V_s)`` with ``X_s = (c V_s / switch)^(2/5)``.
Measured in the local film scale ``x1' = x1 V_s^(2/5)`` (the ``x1`` of a collision at speed
``V_s v0``) with velocities in ``V_s v0``, that state is the same for every scene, and the rest
of the collision depends on ``S = St V_s`` alone (physics.md). So a table of coupled solutions
started exactly at the threshold, one per ``S``, answers every scene whose hand-over comes after
its start (``3 I0 eps < switch``), for the price of the analytic rigid phase:

    v_r = V_s v_r'(S),    h/x1 = lam h'(S),    ln(x_e/x1) = ln lam + ln(x_e'/x1')(S),
    F = (V_s / lam) F'(S),    T = T_s + (lam / V_s) T'(S),    lam = V_s^(2/5).

Scenes that hand over at their start (``eps`` large) or never (rigid) are solved directly. The
path is an option, never the default: ``benchmarks/accuracy.md`` gives its error against direct
solves.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from .model import rigid
from .collision import DIMPLE_DEPTH, Collision, collide, include_rigid_peaks
from .settings import resolve, validate_scene

__all__ = ["MasterCurve"]

# interpolated in log S; lengths as logs (they span decades), v_r linear
_LOG = ("h_m_x1", "h_m_approach_x1", "w0_max_x1", "peak_force")
_LIN = ("v_r", "ln_x_e_x1", "x_min_x1", "t_v_zero", "t_max_rebound", "t_max_deformation",
        "t_peak_force", "energy_error", "dimple_depth_x1")


@dataclass(frozen=True)
class MasterCurve:
    """Coupled solutions started exactly at the hand-over, tabulated in ``S = St V_s``."""

    accuracy: str
    overrides: tuple  # sorted (name, value) pairs of numerical overrides
    s: np.ndarray  # (K,) tabulated S
    table: dict  # name -> (K,) values (times T' in x1'/(V_s v0) from the hand-over)

    @classmethod
    def build(cls, accuracy="standard", s_min=0.4, s_max=1.0e4, per_decade=24, **overrides):
        """Solve the master scenes (one per S on a log grid). ``s_min = 0.4``: a hand-over after
        the start happens before the rigid deformation peak, where ``St V > 0.4``."""
        numerics = resolve(accuracy, **overrides)
        eps_m = numerics.switch / rigid.HANDOVER_COEFF * (1.0 + 1e-9)  # hands over at its start
        n = int(round(per_decade * math.log10(s_max / s_min))) + 1
        s = np.geomspace(s_min, s_max, n)
        table = {k: np.empty(n) for k in (*_LOG, *_LIN)}
        for i, si in enumerate(s):
            c = collide(si, eps_m, accuracy=accuracy, save_profiles=False, **overrides)
            if not c.ok:
                raise RuntimeError(f"master scene S={si:g} failed: {c.message}")
            t_per_tau = eps_m**-0.4  # T = tau x0/x1
            for k in _LOG + ("v_r", "ln_x_e_x1", "x_min_x1", "energy_error", "dimple_depth_x1"):
                table[k][i] = getattr(c, k)
            for k in ("v_zero", "max_rebound", "max_deformation", "peak_force"):
                table[f"t_{k}"][i] = getattr(c, f"tau_{k}") * t_per_tau
        return cls(accuracy, tuple(sorted(overrides.items())), s, table)

    def __post_init__(self):
        splines = {}
        for name, y in self.table.items():
            finite = np.isfinite(y)
            if finite.sum() >= 4:
                values = np.log(y[finite]) if name in _LOG else y[finite]
                splines[name] = (finite, CubicSpline(np.log(self.s[finite]), values))
        object.__setattr__(self, "_splines", splines)

    def _interpolate(self, name, s_value):
        if name not in self._splines:
            return math.nan
        finite, spline = self._splines[name]
        i = int(np.searchsorted(self.s, s_value))
        if not finite[max(i - 1, 0): i + 1].all():
            return math.nan  # e.g. no rebound time below the critical S
        value = float(spline(math.log(s_value)))
        return math.exp(value) if name in _LOG else value

    def collide(self, St, eps) -> Collision:
        """A scene from the master curve; scenes off the curve are solved directly."""
        stokes, eps = validate_scene(St, eps)
        numerics = resolve(self.accuracy, **dict(self.overrides), save_profiles=False)
        x_start = eps**-0.4
        x_switch = rigid.handover_separation(x_start, stokes, numerics.switch)
        if x_switch is None or x_switch >= x_start:
            return collide(stokes, eps, accuracy=self.accuracy, save_profiles=False,
                           **dict(self.overrides))
        wall = time.perf_counter()
        v_s = float(rigid.velocity(x_switch, x_start, 1.0, stokes))
        t_s = float(rigid.elapsed_time(x_switch, x_start, 1.0, stokes))
        s_value = stokes * v_s
        if not self.s[0] <= s_value <= self.s[-1]:
            return collide(stokes, eps, accuracy=self.accuracy, save_profiles=False,
                           **dict(self.overrides))
        lam = v_s**0.4
        tau_per_t = eps**0.4

        def at(name):
            return self._interpolate(name, s_value)

        def tau(name):
            t = at(name)
            return (t_s + lam / v_s * t) * tau_per_t if math.isfinite(t) else math.nan

        v_r = max(0.0, v_s * at("v_r"))
        result = Collision(
            St=stokes, eps=eps, accuracy=self.accuracy, numerics=numerics, model="master",
            status="ok", message=f"master curve at S = St V_switch = {s_value:.6g}",
            v_r=v_r, h_m_x1=lam * at("h_m_x1"), h_m_approach_x1=lam * at("h_m_approach_x1"),
            ln_x_e_x1=math.log(lam) + at("ln_x_e_x1"), x_min_x1=lam * at("x_min_x1"),
            w0_max_x1=lam * at("w0_max_x1"), peak_force=v_s / lam * at("peak_force"),
            tau_v_zero=tau("t_v_zero") if math.isfinite(at("t_v_zero")) else math.inf,
            tau_max_rebound=tau("t_max_rebound") if v_r > 0 else math.nan,
            tau_max_deformation=tau("t_max_deformation"), tau_peak_force=tau("t_peak_force"),
            dimple_depth_x1=lam * at("dimple_depth_x1"), energy_error=at("energy_error"),
            tau_handover=t_s * tau_per_t)
        result.dimple = bool(result.dimple_depth_x1 > DIMPLE_DEPTH)
        include_rigid_peaks(result, x_start, x_switch)
        result.wall_s = time.perf_counter() - wall
        return result
