"""Validity checks of a scene: every premise of the model that a scene strains, with its number.

Each premise is reported as a ``Check`` carrying the number that triggered it and its threshold
(``THRESHOLDS``); ``premise_checks`` needs only the scene, ``outcome_checks`` the solution.
``model_reason`` says why the rigid or the EHD model answered, ``cavitation_reason`` which film
model (classic or with a cavitation floor) answered and why; ``cavitation_crosses`` is the
automatic switch of ``run.run_scene``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.model import rigid

from .scene import Scene
from .units import format_quantity

__all__ = ["Check", "premise_checks", "outcome_checks", "THRESHOLDS", "model_reason",
           "roughness_check", "combined_roughness", "cavitation_crosses", "cavitation_reason",
           "physics_label", "gas"]

# Thresholds of the validity checks (each check warns when its number exceeds the threshold).
THRESHOLDS = {
    # w(0)/x0 at the start is 3 pi^2 eps / (4 sqrt 2) = 5.23 eps (docs/model.md, "Small deformation"). Above 0.05, the
    # level at which the classic scheme stops trusting the rigid solution, the spheres would
    # already be deformed where the model assumes they are not: eps > 0.05 / 5.23 = 0.0096.
    "eps": rigid.eps_for_start_deformation(0.05),
    # Lubrication theory keeps the leading order in x/a; the outer-flow and curvature corrections
    # to the film force are of relative size O(x0/a) (up to logs), so 5% of a as the start.
    "x0_over_a": 0.05,
    # Fluid inertia in a squeeze film relative to viscous stress is Re x0/a (docs/model.md, "Setting", neglects
    # it); 0.1 keeps the neglected term at the 10% level at the start, and smaller afterwards.
    "Re_x0_over_a": 0.1,
    # Quasi-static elasticity: the sound transit time over the Hertz contact time scales as
    # (v0/c)^(1/5). At 0.25 (v0/c = 1e-3) Hunter's estimate of the energy radiated as elastic
    # waves, 1.04 (v0/c)^(3/5), is already 2% of the impact energy.
    "wave_parameter": 0.25,
    # Smooth surfaces: the combined rms roughness sigma = sqrt(s1^2 + s2^2) against the closest
    # approach h_m the smooth model predicts. Summits of a Gaussian surface stand about 3 sigma
    # above its mean plane, so from sigma/h_m = 1/3 on the asperities touch before the film
    # reaches h_m: contact mechanics, not the film, decides the collision.
    "roughness": 1.0 / 3.0,
}


@dataclass(frozen=True)
class Check:
    """One validity warning: which premise, the number that triggered it, and the threshold."""

    check: str
    value: float
    threshold: float
    message: str

    def as_dict(self) -> dict:
        return {"check": self.check, "value": self.value, "threshold": self.threshold,
                "message": self.message}


def premise_checks(scene: Scene) -> list[Check]:
    """Checks that need only the scene: eps, x0/a, fluid inertia, elastic waves."""
    out = []
    eps, a = scene.eps, scene.reduced_radius
    t = THRESHOLDS["eps"]
    if eps > t:
        out.append(Check("eps", eps, t, (
            f"eps = {eps:.3g} is not small (> {t:.3g}): the spheres are already deformed by "
            f"w(0)/x0 = {rigid.start_deformation_ratio(eps):.3g} at the start x0 = "
            f"{format_quantity(scene.x0, 'm')}, which the model takes as undeformed; start "
            "farther out (larger x0)")))
    ratio = scene.x0 / a
    t = THRESHOLDS["x0_over_a"]
    if ratio > t:
        out.append(Check("x0_over_a", ratio, t, (
            f"x0/a = {ratio:.3g} is not small (> {t:g}): lubrication theory neglects corrections "
            "of relative size x0/a to the film force at the start")))
    inertia = scene.reynolds * ratio
    t = THRESHOLDS["Re_x0_over_a"]
    if inertia > t:
        out.append(Check("Re_x0_over_a", inertia, t, (
            f"Re x0/a = {inertia:.3g} is not small (> {t:g}; Re = rho_f v0 a / mu = "
            f"{scene.reynolds:.3g}): fluid inertia in the film, neglected by the model, matters")))
    wave = scene.wave_parameter
    t = THRESHOLDS["wave_parameter"]
    if wave is not None and wave > t:
        out.append(Check("wave_parameter", wave, t, (
            f"(v0/c)^(1/5) = {wave:.3g} is not small (> {t:g}; c = sqrt(E/rho) = "
            f"{scene.sound_speed:.4g} m/s): elastic waves carry away energy the quasi-static "
            "model does not see")))
    return out


def outcome_checks(scene: Scene, c, p_max: float, p_min: float) -> tuple[list[Check], list[str]]:
    """Checks that need the solution: yield, cavitation, roughness, gas mean free path. Returns
    ``(warnings, notes)``; ``p_max``, ``p_min`` in Pa (gauge, relative to ambient)."""
    out, notes = [], []
    for body in (scene.body1, scene.body2):
        y = body.solid.yield_strength
        if y is not None and p_max > y:
            out.append(Check(f"yield_{body.label}", p_max, y, (
                f"peak film pressure {format_quantity(p_max, 'Pa')} exceeds the yield strength "
                f"{format_quantity(y, 'Pa')} of "
                f"{body.label} ({body.solid.name}): plastic deformation is not modelled")))
    p_cav, absolute = scene.cavitation_pressure, scene.ambient_pressure + p_min
    if p_cav is not None and c.physics.classic and absolute < p_cav:
        # only where the classic film was asked for (cavitation = "off"): else the scene
        # switched the floor on (run.run_scene)
        out.append(Check("cavitation", absolute, p_cav, (
            f"the film tension brings the absolute pressure to {_crossing(scene, p_min)}, "
            f"below the cavitation pressure {format_quantity(p_cav, 'Pa')} "
            f"({scene.cavitation_pressure_source}): the liquid would cavitate, and "
            "cavitation = 'off' solved the film without it")))
    elif p_cav is None and gas(scene) and absolute < 0.0:
        out.append(Check("gas_tension", absolute, 0.0, (
            f"the film tension brings the gas's absolute pressure to {_crossing(scene, p_min)}, "
            "below zero, which a gas cannot carry: the gas's compressibility is not modelled")))
    elif p_cav is None and not gas(scene) and p_min < 0.0:
        notes.append(f"cavitation not checked: {scene.cavitation_pressure_source}; the film "
                     f"tension reaches {format_quantity(p_min, 'Pa')}")
    rough = roughness_check(scene, c)
    if rough is not None:
        out.append(rough)
    lam = scene.fluid.mean_free_path
    if lam is not None and math.isfinite(c.h_m_x1):
        h_m = c.h_m_x1 * scene.x1
        if h_m < lam:
            out.append(Check("mean_free_path", h_m, lam, (
                f"closest approach {format_quantity(h_m, 'm')} is below the gas mean free "
                f"path {format_quantity(lam, 'm')} (Knudsen number {lam / h_m:.3g}): continuum lubrication "
                "is not valid")))
    return out, notes


def gas(scene: Scene) -> bool:
    """The fluid is a gas: it has a mean free path (the fluids table gives one to gases only)."""
    return scene.fluid.mean_free_path is not None


def _crossing(scene: Scene, p_min: float) -> str:
    return (f"{format_quantity(scene.ambient_pressure + p_min, 'Pa')} (ambient "
            f"{format_quantity(scene.ambient_pressure, 'Pa')} + min film pressure "
            f"{format_quantity(p_min, 'Pa')})")


def cavitation_crosses(scene: Scene, p_min: float | None) -> bool:
    """True when the classic film's lowest pressure ``p_min`` [Pa, gauge; None: not known]
    brings the absolute pressure below the scene's cavitation pressure: the automatic switch."""
    p_cav = scene.cavitation_pressure
    return p_cav is not None and p_min is not None and scene.ambient_pressure + p_min < p_cav


def physics_label(physics) -> str:
    """The film model used: "classic film" or "reynolds cavitation at Pi = ..."."""
    if physics.classic:
        return "classic film"
    return f"{physics.cavitation} cavitation at Pi = {physics.Pi:.3g}"


def cavitation_reason(scene: Scene, physics, classic_p_min: float | None, *,
                      forced: bool) -> str:
    """Which film model answered (``physics_label``) and why, in one sentence with numbers.

    ``classic_p_min`` is the classic film's lowest pressure [Pa, gauge] (None: the classic film
    was not solved or failed); ``forced``: the model was asked for (``cavitation`` not "auto").
    """
    label, p_cav = physics_label(physics), scene.cavitation_pressure
    floor = ("" if p_cav is None else f"the cavitation pressure {format_quantity(p_cav, 'Pa')} "
             f"({scene.cavitation_pressure_source})")
    if forced:
        why = f"{label}, as asked for (cavitation = {scene.cavitation!r})"
        return why + (f"; {floor}" if floor and not physics.classic else "")
    if p_cav is None:
        return f"{label}: {scene.cavitation_pressure_source}, so the film is not switched"
    if classic_p_min is None:
        return f"{label}: the classic solve failed, so the cavitation switch was not decided"
    if physics.classic:
        return (f"{label}: the film's lowest absolute pressure, "
                f"{_crossing(scene, classic_p_min)}, stays above {floor}")
    return (f"{label}: the classic film's tension would bring the absolute pressure to "
            f"{_crossing(scene, classic_p_min)}, below {floor}, so the film is solved with the "
            f"floor p >= p_cav (P >= -Pi, Pi = (p_amb - p_cav) / p* with p* = "
            f"{format_quantity(scene.pressure_scale, 'Pa')})")


def combined_roughness(scene: Scene) -> float | None:
    """``sqrt(s1^2 + s2^2)`` of the bodies' rms roughness [m]; None when neither gives one (a body
    without a value counts as smooth)."""
    values = [b.solid.roughness for b in (scene.body1, scene.body2)]
    if all(v is None for v in values):
        return None
    return math.sqrt(sum(v * v for v in values if v is not None))


def roughness_check(scene: Scene, c) -> Check | None:
    """The roughness warning, or None: fires when the combined rms roughness is not small against
    the smooth model's closest approach ``h_m`` (``THRESHOLDS["roughness"]``)."""
    sigma = combined_roughness(scene)
    if sigma is None or not math.isfinite(c.h_m_x1):
        return None
    h_m = c.h_m_x1 * scene.x1
    ratio = sigma / h_m
    t = THRESHOLDS["roughness"]
    if ratio <= t:
        return None
    return Check("roughness", ratio, t, (
        f"rms roughness {format_quantity(sigma, 'm')} is {ratio:.3g} times the closest approach "
        f"{format_quantity(h_m, 'm')} of the smooth model (> {t:.3g}): the asperities touch "
        "before the film gets that thin, so contact mechanics, not the film, decides this "
        "collision (its restitution included)"))


def _fmt_log(log_value: float) -> str:
    """Format ``exp(log_value)``, also when it overflows a float."""
    if log_value < 700.0:
        return f"{math.exp(log_value):.3g}"
    return f"10^{log_value / math.log(10.0):.0f}"


def model_reason(scene: Scene, c) -> str:
    """Why the scene needed the rigid or the EHD model, in one sentence with numbers."""
    physics, switch = c.physics, c.numerics.switch
    peak = _fmt_log(rigid.log_peak_deformation_ratio(physics.x_start, physics.St))
    if c.model == "rigid":
        # the rigid path from (x0, V = 1) comes to rest at x0 exp(-St)
        rest = scene.x1 * math.exp(rigid.rest_separation(physics.x_start, 1.0, physics.St))
        return (f"rigid: along the rigid-sphere path the central deformation peaks at "
                f"w(0)/x = {peak}, below the hand-over level {switch:g}, so the exact rigid "
                f"solution holds; the spheres creep to rest at x0 exp(-St) = "
                f"{format_quantity(rest, 'm')} "
                "without rebounding")
    phase = np.asarray(c.series["phase"])
    coupled = np.asarray(c.series["X"])[phase == 1]
    where = f" at x = {format_quantity(coupled[0] * scene.x1, 'm')}" if coupled.size else ""
    return (f"EHD: along the rigid-sphere path w(0)/x would reach {peak} (hand-over level "
            f"{switch:g}); it reaches that level{where}, where the coupled elastic-film solution "
            "takes over")
