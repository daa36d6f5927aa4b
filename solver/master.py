"""One-parameter fast path: a master curve in ``S = St * V_switch``.

Where the coupled phase takes over from the analytic rigid approach, ``W(0)/X`` equals the
hand-over threshold and the state is ``(X_s, V_s)`` with ``X_s = (c V_s / switch)^(2/5)``.
Measured in the local film scale ``x1' = x1 V_s^(2/5)`` (the ``x1`` of a collision at speed
``V_s v0``) with velocities in ``V_s v0``, that state is the same for every scene, and the rest
of the collision depends on ``S = St V_s`` alone (docs/model.md, "Similarity"). So a table of coupled solutions
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

from .collision import (DIMPLE_DEPTH, Collision, check_energy, collide, include_rigid_peaks,
                        read_far)
from .model import rigid
from .observables import OBSERVABLES
from .physics import Physics
from .settings import resolve
from .shortcuts import plan

__all__ = ["MasterCurve"]

# what the curve carries (solver/observables.py: Observable.master): name -> (interpolation, scaling)
_CARRIED = {o.name: tuple(o.master.split()) for o in OBSERVABLES if o.master}


@dataclass(frozen=True)
class MasterCurve:
    """Coupled solutions started exactly at the hand-over, tabulated in ``S = St V_s``.

    Exact (to the hand-over's accuracy) for the classic film only: ``collide`` refuses other
    physics."""

    accuracy: str
    overrides: tuple  # sorted (name, value) pairs of numerical overrides
    s: np.ndarray  # (K,) tabulated S
    table: dict  # name -> (K,) values in the master scene's units (times: T' from the hand-over)

    @classmethod
    def build(cls, accuracy="standard", s_min=0.4, s_max=1.0e4, per_decade=24, **overrides):
        """Solve the master scenes (one per S on a log grid). ``s_min = 0.4``: a hand-over after
        the start happens before the rigid deformation peak, where ``St V > 0.4``."""
        numerics = resolve(accuracy, **overrides)
        eps_m = numerics.switch / rigid.HANDOVER_COEFF * (1.0 + 1e-9)  # hands over at its start
        n = int(round(per_decade * math.log10(s_max / s_min))) + 1
        s = np.geomspace(s_min, s_max, n)
        table = {k: np.empty(n) for k in _CARRIED}
        t_per_tau = eps_m**-0.4  # T = tau x0/x1
        for i, si in enumerate(s):
            c = collide(Physics(St=si, eps=eps_m), accuracy=accuracy, save_profiles=False,
                        **overrides)
            if not c.ok:
                raise RuntimeError(f"master scene S={si:g} failed: {c.message}")
            for k, (_, scaling) in _CARRIED.items():
                table[k][i] = getattr(c, k) * (t_per_tau if scaling == "time" else 1.0)
        return cls(accuracy, tuple(sorted(overrides.items())), s, table)

    def __post_init__(self):
        splines = {}
        for name, y in self.table.items():
            finite = np.isfinite(y)
            if finite.sum() >= 4:
                log = _CARRIED[name][0] == "log"
                values = np.log(y[finite]) if log else y[finite]
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
        return math.exp(value) if _CARRIED[name][0] == "log" else value

    def collide(self, physics, eps=None, *, x_ref_x0: float = 1.0, outer=None) -> Collision:
        """A scene from the master curve; classic scenes off the curve are solved directly.

        ``x_ref_x0`` is where ``e_wet`` is seen (``solver.collide``); on the curve ``e_wet`` is
        computed from the interpolated ``ln_x_e_x1`` (rigid.restitution_from_rest), which fixes the
        whole rigid departure. ``outer``: how ``e_far`` reads it (``solver.collide``).

        Raises
        ------
        ValueError
            ``physics`` is not the classic model: the curve would answer it with the wrong film.
        """
        if not isinstance(physics, Physics):
            physics = Physics(St=physics, eps=eps)
        if not plan(physics).classic:
            raise ValueError(f"the master curve holds the classic film only; solve {physics} "
                             "directly with solver.collide")
        numerics = resolve(self.accuracy, **dict(self.overrides), save_profiles=False)
        stokes, x_start = physics.St, physics.x_start
        x_switch = rigid.handover_separation(x_start, stokes, numerics.switch)
        if x_switch is None or x_switch >= x_start:
            return collide(physics, accuracy=self.accuracy, save_profiles=False,
                           x_ref_x0=x_ref_x0, outer=outer, **dict(self.overrides))
        wall = time.perf_counter()
        v_s = float(rigid.velocity(x_switch, x_start, 1.0, stokes))
        t_s = float(rigid.elapsed_time(x_switch, x_start, 1.0, stokes))
        s_value = stokes * v_s
        if not self.s[0] <= s_value <= self.s[-1]:
            return collide(physics, accuracy=self.accuracy, save_profiles=False,
                           x_ref_x0=x_ref_x0, outer=outer, **dict(self.overrides))
        lam = v_s**0.4
        tau_per_t = physics.tau_per_t
        # docs/model.md, "Similarity": how each quantity of the master scene scales to this one
        # (energies are relative to the kinetic energy, which is V_s^2 times the master scene's)
        scale = {"velocity": v_s, "length": lam, "force": v_s / lam, "pressure": v_s / lam**2,
                 "energy": v_s**2, "none": 1.0}
        values = {}
        for name, (_, scaling) in _CARRIED.items():
            y = self._interpolate(name, s_value)
            if scaling == "time":
                values[name] = (t_s + lam / v_s * y) * tau_per_t if math.isfinite(y) else math.nan
            elif scaling == "log_length":
                values[name] = math.log(lam) + y
            else:
                values[name] = scale[scaling] * y
        values["v_r"] = max(0.0, values["v_r"])
        if not math.isfinite(self._interpolate("tau_v_zero", s_value)):
            values["tau_v_zero"] = math.inf  # the master scene never stops: rigid creep
        if values["v_r"] <= 0.0:
            values["tau_max_rebound"] = math.nan
        result = Collision(
            physics=physics, accuracy=self.accuracy, numerics=numerics, model="master",
            status="ok", message=f"master curve at S = St V_switch = {s_value:.6g}",
            tau_handover=t_s * tau_per_t, **values)
        result.dimple = bool(result.dimple_depth_x1 > DIMPLE_DEPTH)
        result.extrapolated = numerics.extrapolate  # the tabulated solves were pairs
        result.x_ref_x0 = x_ref_x0
        result.e_wet = rigid.restitution_from_rest(values["ln_x_e_x1"], physics,
                                                   x_ref_x0 * x_start)
        result.e_x0 = rigid.restitution_from_rest(values["ln_x_e_x1"], physics, x_start)
        read_far(result, outer)
        include_rigid_peaks(result, rigid.approach_peaks(x_start, stokes, x_switch))
        # not carried by the curve: the approach's pressure peak lies in its coupled phase
        result.p_max_approach = result.h_axis_at_peak_pressure_x1 = math.nan
        result.viscosity_ratio_max_approach = 1.0  # the classic film
        check_energy(result)
        result.wall_s = time.perf_counter() - wall
        return result
