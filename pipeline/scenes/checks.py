"""Validity checks of a scene: every premise of the model that a scene strains, with its number.

Each premise is reported as a ``Check`` carrying the number that triggered it and its threshold
(``THRESHOLDS``); ``premise_checks`` needs only the scene, ``outcome_checks`` the solution.
``model_reason`` says why the rigid or the EHD model answered, ``cavitation_reason`` which film
model (classic or with a cavitation floor) answered and why, ``viscosity_reason`` and
``density_reason`` which viscosity and density laws and why; ``cavitation_crosses``,
``viscosity_switch`` and ``density_switch`` are the automatic switches of ``run.run_scene``
(thresholds ``VISCOSITY_SWITCH``, ``DENSITY_SWITCH``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.model import rigid

from .scene import Scene
from .units import format_quantity

__all__ = ["Check", "premise_checks", "outcome_checks", "THRESHOLDS", "model_reason",
           "roughness_check", "roughness_reason", "contact_switch", "combined_roughness", "cavitation_crosses", "cavitation_reason",
           "physics_label", "cavitation_label", "gas", "VISCOSITY_SWITCH", "DENSITY_SWITCH",
           "viscosity_switch", "density_switch", "density_rise", "viscosity_reason",
           "density_reason", "pressure_notes", "pressure_checks", "per_gpa",
           "law_viscosity_ratio", "ALPHA_KNOWN_LIQUID"]

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

# The automatic switches of the pressure-dependent viscosity and density (run.run_scene), read at
# the peak pressure p_peak of the classic film (the solver's p_max times p*):
# - viscosity: alpha p_peak >= 0.1, i.e. the viscosity there exceeds mu0 by more than
#   exp(0.1) - 1 = 10.5 %. That is above the few-% accuracy of the solver's own presets (the
#   standard preset's largest errors over the St, eps panel, benchmarks/accuracy.md: 1.3e-3 on
#   v_r, 1.1e-2 on h_m, 1.9e-2 on h_m on approach), so below it the constant viscosity is as good as the solve, and
#   above it the viscosity law can move the results by more than the solver's own error;
VISCOSITY_SWITCH = 0.1
# - density (fluids with Dowson-Higginson constants): the density rise at p_peak,
#   c1 p / (1 + c2 p), above 1 %. The film conserves the liquid content rho h, so a density rise
#   of delta thins the compressed film by about delta: at 1 % that is the standard preset's own
#   error on h_m (1.1e-2, as above). The fluids that have the constants (mineral oils,
#   alpha = 20-42 1/GPa) have switched the viscosity on long before (1 % needs p ~ 17 MPa,
#   alpha p ~ 0.5 there), so the density law costs no extra solve.
DENSITY_SWITCH = 0.01


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
    if p_cav is not None and c.physics.cavitation == "off" and absolute < p_cav:
        # only where the film was solved without the floor: asked for (cavitation = "off"), or
        # the switch, decided on the classic film, kept it off while the film solved (with a
        # pressure-dependent viscosity) pulls harder
        why = ("cavitation = 'off' solved the film without it" if scene.cavitation == "off" else
               "the cavitation switch, decided on the classic film's tension, left the floor off; "
               "force it with cavitation = 'jfo'")
        out.append(Check("cavitation", absolute, p_cav, (
            f"the film tension brings the absolute pressure to {_crossing(scene, p_min)}, "
            f"below the cavitation pressure {format_quantity(p_cav, 'Pa')} "
            f"({scene.cavitation_pressure_source}): the liquid would cavitate, and {why}")))
    elif p_cav is None and gas(scene) and absolute < 0.0:
        out.append(Check("gas_tension", absolute, 0.0, (
            f"the film tension brings the gas's absolute pressure to {_crossing(scene, p_min)}, "
            "below zero, which a gas cannot carry: the gas's compressibility is not modelled")))
    elif p_cav is None and not gas(scene) and p_min < 0.0:
        notes.append(f"cavitation not checked: {scene.cavitation_pressure_source}; the film "
                     f"tension reaches {format_quantity(p_min, 'Pa')}")
    rough = roughness_check(scene, c) if c.physics.smooth else None
    if rough is not None:  # the smooth film was kept (asperity_contact = "off")
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
    return scene.fluid.gas


def _crossing(scene: Scene, p_min: float) -> str:
    return (f"{format_quantity(scene.ambient_pressure + p_min, 'Pa')} (ambient "
            f"{format_quantity(scene.ambient_pressure, 'Pa')} + min film pressure "
            f"{format_quantity(p_min, 'Pa')})")


def cavitation_crosses(scene: Scene, p_min: float | None) -> bool:
    """True when the classic film's lowest pressure ``p_min`` [Pa, gauge; None: not known]
    brings the absolute pressure below the scene's cavitation pressure: the automatic switch."""
    p_cav = scene.cavitation_pressure
    return p_cav is not None and p_min is not None and scene.ambient_pressure + p_min < p_cav


def cavitation_label(physics) -> str:
    """The film model as to cavitation: "classic film" (no floor, and nothing else switched on),
    "no cavitation floor" (no floor, a pressure-dependent law on) or "jfo cavitation at
    Pi = ..."."""
    if physics.cavitation == "off":
        # the contact is reported on its own line (roughness_reason)
        return "classic film" if physics.replace(roughness=0.0).classic else "no cavitation floor"
    return f"{physics.cavitation} cavitation at Pi = {physics.Pi:.3g}"


def viscosity_label(physics) -> str:
    """"constant viscosity", "barus viscosity at beta = ..." or "roelands viscosity at beta = ...
    (Z = ..., P_R = ...)"."""
    law = physics.viscosity_law
    if law == "constant":
        return "constant viscosity"
    label = f"{law} viscosity at beta = {physics.beta:.3g}"
    if law == "roelands":
        label += f" (Z = {physics.roelands_Z:.3g}, P_R = {physics.roelands_PR:.3g})"
    return label


def density_label(physics) -> str:
    """"constant density" or "dowson-higginson density (c1 p* = ..., c2 p* = ...)"."""
    if physics.density_law == "constant":
        return "constant density"
    return (f"{physics.density_law} density (c1 p* = {physics.dh_c1:.3g}, c2 p* = "
            f"{physics.dh_c2:.3g})")


def physics_label(physics) -> str:
    """The film physics used: "classic film", or what is switched on, e.g. "jfo cavitation at
    Pi = ..., barus viscosity at beta = ..."."""
    if physics.classic:
        return "classic film"
    parts = [] if physics.cavitation == "off" else [cavitation_label(physics)]
    if physics.viscosity_law != "constant":
        parts.append(viscosity_label(physics))
    if physics.density_law != "constant":
        parts.append(density_label(physics))
    if not physics.smooth:
        parts.append(f"asperity contact at roughness {physics.roughness:.3g} x1")
    return ", ".join(parts)


def _first_film(base) -> str:
    """The film the switches were decided on (``base``: the first solve's physics)."""
    return "the classic film" if base.classic else f"the first solve ({physics_label(base)})"


def cavitation_reason(scene: Scene, physics, base_p_min: float | None, *, forced: bool,
                      base=None) -> str:
    """Which film model answered (``cavitation_label``) and why, in one sentence with numbers.

    ``base_p_min`` is the lowest pressure [Pa, gauge] of the film solved first without the floor
    (``base``, default: the classic film; None: not solved or failed); ``forced``: the model
    was asked for (``cavitation`` not "auto").
    """
    label, p_cav = cavitation_label(physics), scene.cavitation_pressure
    floor = ("" if p_cav is None else f"the cavitation pressure {format_quantity(p_cav, 'Pa')} "
             f"({scene.cavitation_pressure_source})")
    film = "classic film" if base is None or base.classic else "film without the floor"
    if forced:
        why = f"{label}, as asked for (cavitation = {scene.cavitation!r})"
        return why + (f"; {floor}" if floor and physics.cavitation != "off" else "")
    if p_cav is None:
        return f"{label}: {scene.cavitation_pressure_source}, so the film is not switched"
    if base_p_min is None:
        return f"{label}: the solve of the {film} failed, so the cavitation switch was not decided"
    if physics.cavitation == "off":
        return (f"{label}: the film's lowest absolute pressure, "
                f"{_crossing(scene, base_p_min)}, stays above {floor}")
    return (f"{label}: the {film}'s tension would bring the absolute pressure to "
            f"{_crossing(scene, base_p_min)}, below {floor}, so the film is solved with the "
            f"floor p >= p_cav (P >= -Pi, Pi = (p_amb - p_cav) / p* with p* = "
            f"{format_quantity(scene.pressure_scale, 'Pa')})")


# ---- pressure-dependent viscosity and density ------------------------------------------------
def viscosity_switch(scene: Scene, p_peak: float | None) -> bool:
    """True when ``alpha p_peak >= VISCOSITY_SWITCH`` (``p_peak`` [Pa, gauge] the classic film's
    peak pressure; None: not known): the automatic switch to the fluid's viscosity law."""
    alpha = scene.fluid.pressure_viscosity
    return bool(alpha) and p_peak is not None and alpha * p_peak >= VISCOSITY_SWITCH


def density_rise(scene: Scene, p: float) -> float | None:
    """The fluid's Dowson-Higginson density rise ``c1 p / (1 + c2 p)`` at the gauge pressure
    ``p`` [Pa] (None: no constants)."""
    f = scene.fluid
    if not f.has_dowson_higginson:
        return None
    p = max(p, 0.0)  # the rise under compression (in tension it is below c1 * 0.01 p*)
    return f.dowson_higginson_c1 * p / (1.0 + f.dowson_higginson_c2 * p)


def density_switch(scene: Scene, p_peak: float | None) -> bool:
    """True when the Dowson-Higginson density rise at the classic film's peak pressure
    ``p_peak`` [Pa] exceeds ``DENSITY_SWITCH``: the automatic switch to that law."""
    rise = None if p_peak is None else density_rise(scene, p_peak)
    return rise is not None and rise > DENSITY_SWITCH


def per_gpa(value: float | None) -> str:
    """A coefficient in 1/Pa shown in 1/GPa, the unit of the tables (``'5.9 1/GPa'``)."""
    return "-" if value is None else f"{value * 1e9:.3g} 1/GPa"


def law_viscosity_ratio(scene: Scene, law: str, p: float) -> float:
    """``mu/mu0`` of the fluid's ``law`` ("barus" or "roelands") at the gauge pressure ``p``
    [Pa]: ``exp(alpha p)``, or Roelands' ``exp((alpha p_R / Z)((1 + p/p_R)^Z - 1))`` with the
    same slope alpha at ``p = 0`` (solver.physics, ``roelands_Z``)."""
    f = scene.fluid
    alpha = f.pressure_viscosity
    if law == "roelands":
        z, p_r = f.roelands_index, f.roelands_pressure
        return math.exp(alpha * p_r / z * ((1.0 + p / p_r) ** z - 1.0))
    return math.exp(alpha * p)


def _alpha_text(scene: Scene) -> str:
    return f"alpha = {per_gpa(scene.fluid.pressure_viscosity)} for {scene.fluid.name}"


def viscosity_reason(scene: Scene, physics, base_p_max: float | None, *, forced: bool,
                     base=None) -> str:
    """Which viscosity law answered (``viscosity_label``) and why, in one sentence with numbers.

    ``base_p_max`` is the peak pressure [Pa, gauge] of the film solved first with the constant
    viscosity (``base``, default: the classic film; None: not solved or failed); ``forced``: the
    law was asked for (``viscosity_law`` not "auto").
    """
    label, f = viscosity_label(physics), scene.fluid
    alpha, p_star = f.pressure_viscosity, scene.pressure_scale
    if forced:
        why = f"{label}, as asked for (viscosity_law = {scene.viscosity_law!r})"
        if alpha:
            why += (f"; {_alpha_text(scene)}, beta = alpha p* with p* = "
                    f"{format_quantity(p_star, 'Pa')}")
        return why
    if alpha is None:
        return (f"{label}: {f.name} has no pressure-viscosity coefficient (fluid."
                "pressure_viscosity), so 0 is assumed and the viscosity law is not switched (the "
                "range of ehd scene spans 0 to 20 1/GPa)")
    if alpha == 0.0:
        return (f"{label}: the pressure-viscosity coefficient of {f.name} is 0, so the viscosity "
                "does not depend on the pressure")
    film = _first_film(base) if base is not None else "the classic film"
    if base_p_max is None:
        return f"{label}: the solve of {film} failed, so the viscosity switch was not decided"
    ap = alpha * base_p_max
    at = (f"alpha p_peak = {ap:.3g} at the peak pressure {format_quantity(base_p_max, 'Pa')} of "
          f"{film} ({_alpha_text(scene)})")
    if physics.viscosity_law == "constant":
        return (f"{label}: {at}, below {VISCOSITY_SWITCH:g} (the Barus viscosity there would "
                f"be {math.expm1(ap):.2%} above mu0)")
    name = physics.viscosity_law
    law = ("mu = mu0 exp(alpha p)" if name == "barus" else
           f"the Roelands law (Z = {f.roelands_index:.3g}, p_R = "
           f"{format_quantity(f.roelands_pressure, 'Pa')}, slope alpha at p = 0)")
    ratio = law_viscosity_ratio(scene, name, base_p_max)
    return (f"{label}: {at}, at least {VISCOSITY_SWITCH:g} (the {name.capitalize()} viscosity "
            f"there would be {ratio:.3g} mu0), so the film is solved with {law}, beta = alpha p* "
            f"with p* = {format_quantity(p_star, 'Pa')}")


def density_reason(scene: Scene, physics, base_p_max: float | None, *, forced: bool,
                   base=None) -> str:
    """Which density law answered (``density_label``) and why, in one sentence with numbers
    (arguments as ``viscosity_reason``)."""
    label, f = density_label(physics), scene.fluid
    if forced:
        return f"{label}, as asked for (density_law = {scene.density_law!r})"
    if f.gas:
        return (f"{label}: {f.name} is a gas, whose density follows its pressure (ideal gas), "
                "which the model does not have (the gas_tension check says where it matters)")
    if not f.has_dowson_higginson:
        return (f"{label}: {f.name} has no Dowson-Higginson constants (fluid."
                "dowson_higginson_c1, _c2), so the density law is not switched")
    film = _first_film(base) if base is not None else "the classic film"
    if base_p_max is None:
        return f"{label}: the solve of {film} failed, so the density switch was not decided"
    rise = density_rise(scene, base_p_max)
    at = (f"the Dowson-Higginson density of {f.name} (c1 = {per_gpa(f.dowson_higginson_c1)}, "
          f"c2 = {per_gpa(f.dowson_higginson_c2)}) rises by {rise:.2%} at the peak pressure "
          f"{format_quantity(base_p_max, 'Pa')} of {film}")
    if physics.density_law == "constant":
        return f"{label}: {at}, not above {DENSITY_SWITCH:.0%}"
    return (f"{label}: {at}, above {DENSITY_SWITCH:.0%}, so the film is solved with rho/rho0 = "
            f"1 + c1 p / (1 + c2 p)")


# A liquid without a pressure-viscosity coefficient: the smallest alpha of a liquid with a known,
# nonzero one in the shipped table (glycerol, 5.9 1/GPa; mineral oils 20-42 1/GPa, Stachowiak &
# Batchelor, Table 2.3). Where the alpha at which the viscosity switch would fire is at or below
# it, a liquid like those would need the pressure-dependent viscosity: a warning; above it (the
# peak pressure is low) a note.
ALPHA_KNOWN_LIQUID = 5.9e-9  # 1/Pa


def _alpha_needed(p_peak: float) -> float:
    """The pressure-viscosity coefficient [1/Pa] from which the switch fires at ``p_peak``."""
    return VISCOSITY_SWITCH / p_peak


def pressure_checks(scene: Scene, p_peak: float | None, base=None) -> list[Check]:
    """The ``pressure_viscosity`` warning: the liquid has no alpha, and at the peak pressure
    ``p_peak`` [Pa] of the film solved first (``base``) the viscosity would matter from an alpha
    at or below ``ALPHA_KNOWN_LIQUID`` on (the switch's own criterion, ``VISCOSITY_SWITCH``)."""
    f = scene.fluid
    if f.gas or f.pressure_viscosity is not None or p_peak is None or p_peak <= 0.0:
        return []
    need = _alpha_needed(p_peak)
    if need > ALPHA_KNOWN_LIQUID:
        return []
    film = _first_film(base) if base is not None else "the classic film"
    return [Check("pressure_viscosity", need, ALPHA_KNOWN_LIQUID, (
        f"{f.name} has no pressure-viscosity coefficient, and at the peak pressure "
        f"{format_quantity(p_peak, 'Pa')} of {film} the viscosity would change the collision "
        f"from alpha = {per_gpa(need)} on (alpha p_peak >= {VISCOSITY_SWITCH:g}), below the "
        f"{per_gpa(ALPHA_KNOWN_LIQUID)} of glycerol (mineral oils: 20-42 1/GPa): this result "
        "keeps the viscosity constant; give fluid.pressure_viscosity"))]


def pressure_notes(scene: Scene, p_peak: float | None, base=None) -> list[str]:
    """Notes where a liquid's pressure dependence is not known: no alpha (with the alpha from
    which the switch would fire at the peak pressure ``p_peak`` [Pa] of the film solved first,
    ``base``, default the classic film), unless that alpha is small enough for the warning of
    ``pressure_checks``; no Dowson-Higginson constants."""
    f, notes = scene.fluid, []
    if f.gas or p_peak is None or p_peak <= 0.0:
        return notes
    film = _first_film(base) if base is not None else "the classic film"
    peak = f"the peak pressure {format_quantity(p_peak, 'Pa')} of {film}"
    if f.pressure_viscosity is None and not pressure_checks(scene, p_peak, base):
        need = per_gpa(_alpha_needed(p_peak))
        notes.append(f"pressure-dependent viscosity not checked: {f.name} has no "
                     f"pressure_viscosity; at {peak} it would matter from alpha = {need} on "
                     f"(alpha p_peak >= {VISCOSITY_SWITCH:g}; mineral oils: 20-42 1/GPa); give "
                     "fluid.pressure_viscosity")
    if not f.has_dowson_higginson:
        notes.append(f"pressure-dependent density not checked: {f.name} has no Dowson-Higginson "
                     f"constants ({peak}); give fluid.dowson_higginson_c1 and "
                     "fluid.dowson_higginson_c2")
    return notes


def combined_roughness(scene: Scene) -> float | None:
    """``sqrt(s1^2 + s2^2)`` of the bodies' rms roughness [m]; None when neither gives one (a body
    without a value counts as smooth)."""
    return scene.roughness_rms


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


def contact_switch(scene: Scene, c) -> bool:
    """True when the smooth solve ``c`` says the asperities decide (``roughness_check``) and the
    contact can be modelled from the scene's start: the roughness lies inside the starting gap
    ``x0`` (a rougher pair touches before the start: the smooth film is kept, and
    ``roughness_reason`` says to start farther out)."""
    sigma = combined_roughness(scene)
    return bool(c.ok and roughness_check(scene, c) is not None and sigma < scene.x0)


def roughness_reason(scene: Scene, physics, base_h_m, forced: bool) -> str:
    """One sentence: whether the asperities' contact acts in ``physics`` and why (the rule:
    switched on where the combined rms roughness exceeds ``THRESHOLDS["roughness"]`` of the
    smooth film's closest approach ``base_h_m`` [m]), with the dry restitution it carries."""
    sigma = combined_roughness(scene)
    e_dry = f"; e_dry = {scene.e_dry:g} ({scene.e_dry_source})"
    if not physics.smooth:
        how = "forced on (asperity_contact = 'on')" if forced else (
            f"switched on: rms roughness {format_quantity(sigma, 'm')} is "
            f"{sigma / base_h_m:.3g} times the smooth film's closest approach "
            f"{format_quantity(base_h_m, 'm')} (> {THRESHOLDS['roughness']:.3g})")
        return (f"asperity contact {how}; asperity stiffness k = {physics.asperity_stiffness:.3g}"
                f" (Greenwood-Williamson, docs/model.md){e_dry}")
    if forced:
        return "smooth surfaces (asperity_contact = 'off')"
    if sigma is None:
        return "smooth surfaces: neither body gives an rms roughness"
    if base_h_m is None:
        return "smooth surfaces: the smooth film was not solved"
    if sigma >= scene.x0 and sigma > THRESHOLDS["roughness"] * base_h_m:
        return (f"smooth surfaces kept: the rms roughness {format_quantity(sigma, 'm')} is not "
                f"below the starting gap x0 = {format_quantity(scene.x0, 'm')}, so the asperities "
                "touch before the modelled collision starts: start farther out (a larger x0 or "
                "x0_over_a) to model the contact")
    return (f"smooth surfaces: rms roughness {format_quantity(sigma, 'm')} is only "
            f"{sigma / base_h_m:.3g} times the smooth film's closest approach "
            f"(<= {THRESHOLDS['roughness']:.3g})")


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
