"""Solving a scene: ``run_scene`` runs the solver and the validity checks, ``SceneResult`` in SI.

The solver works in the dimensionless variables of docs/model.md ("Scales"); results are converted
back with the scene's scales (``Scene.x1``, ``pressure_scale``, ``force_scale``, ``time_scale``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from solver import observables
from solver.physics import Physics

from .answer import answer, stopped_answer
from .checks import (Check, model_reason, outcome_checks, premise_checks, pressure_checks,
                     pressure_notes)
from .pieces import PIECES, QUANTITY_KEYS, REASON_KEYS, BaseFilm
from .scene import Scene

__all__ = ["SceneResult", "run_scene", "RESULT_KEYS", "SCALES", "scene_keys", "result_keys",
           "si_value", "check_solvable", "dem_restitution",
           "DEM_COUPLING", "stopped_result"]

# Keys of SceneResult.to_dict() (a contract for scripts using `ehd scene --json`, docs/scenes.md):
# the scene's own keys, then the SI keys of the observables (solver/observables.py, ``SceneKey``)
_SCENE_KEYS = (
    "title", "verdict", "e_for_dem", "e_for_dem_range", "e_for_cfd_dem", "e_for_cfd_dem_range",
    "range_drivers", "approach_speed_m_per_s", "inputs", "reduced_radius_m", "reduced_mass_kg",
    "theta_per_Pa", "effective_modulus_Pa", "x0_m", "x0_over_a", "x1_m", *Physics.names(), "Re",
    "Re_x0_over_a", "sound_speed_m_per_s", "wave_parameter", "model", "model_reason",
    *REASON_KEYS, "e_dry_source", *QUANTITY_KEYS, "status", "message", "x_ref_m",
    "x_ref_over_a", "outer_start_m", "outer_start_over_a", "outer_geometry", "density_ratio", "dem_restitution",
)
_LAST_KEYS = ("sensitivity", "warnings", "notes", "dimensionless")


def scene_keys() -> tuple:
    """``(Observable, SceneKey)`` of every SI key of ``ehd scene``, in the registry's order."""
    return tuple((o, k) for o in observables.OBSERVABLES for k in o.scene)


def result_keys() -> tuple:
    """The keys of ``SceneResult.to_dict`` as the registry declares them now."""
    return (*_SCENE_KEYS, *(k.key for _, k in scene_keys()), *_LAST_KEYS)


RESULT_KEYS = result_keys()

# The scene scales that make an observable SI (``SceneKey.scale``): the units of the
# dimensionless solution (docs/model.md, "Scales") in the scene's values, (scene, collision) -> SI
SCALES = {
    "1": lambda s, c: 1.0,
    "v0": lambda s, c: s.v0,
    "x1": lambda s, c: s.x1,
    "x0/v0": lambda s, c: s.time_scale,
    "sqrt(a x1)": lambda s, c: math.sqrt(s.reduced_radius * s.x1),
    "2 pi a x1^2": lambda s, c: 2.0 * math.pi * s.reduced_radius * s.x1**2,
    "6 pi mu a^2 v0 / x1": lambda s, c: s.force_scale,
    "mu a v0 / x1^2": lambda s, c: s.pressure_scale,
    "mu0": lambda s, c: s.fluid.viscosity,
    # the approach speed at x_ref, St_ref/St v0 (rigid.impact_stokes)
    "v(x_ref)": lambda s, c: c.St_ref / c.St * s.v0,
}


def si_value(o, key, scene: Scene, c, outer) -> object:
    """The value of ``key`` (a ``SceneKey`` of observable ``o``) for collision ``c`` of
    ``scene``: SI, non-finite as None, flags as bool or None (unknown)."""
    v = getattr(c, o.name)
    if key.outer and outer is None:
        return None
    if o.kind == "flag":
        return None if v is None else bool(v)
    if o.kind == "count":
        return int(v)
    scale = SCALES[key.scale or o.units](scene, c)
    factor = observables.si_unit(key.key)[1]
    if key.form:  # the observable is ln(quantity / scale)
        ln_si = float(v) + math.log(scale * factor)
        v = ln_si / math.log(10.0) if key.form == "log10" else (
            math.exp(ln_si) if ln_si < 700 else math.nan)
    else:
        v = float(v) * scale * factor
    return v if math.isfinite(v) else None


@dataclass
class SceneResult:
    """A solved scene: the dimensionless ``collision`` plus SI results and validity checks."""

    scene: Scene
    collision: object  # solver.Collision
    warnings: list[Check] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    peak_pressure: float = math.nan  # Pa
    min_pressure: float = math.nan  # Pa (negative: tension)
    # per piece of physics the scene switches (pieces.PIECES): which was used and why, one
    # sentence with numbers ({reason_key: sentence}; also attributes: result.<reason_key>)
    reasons: dict = field(default_factory=dict)
    # the result without each piece of physics the scene switched on (and with the asperity
    # stiffness 10x either way): {label: {"e_wet", "e_far", "v_r", "status"}}
    sensitivity: dict = field(default_factory=dict)
    outer: object = None  # the solver.far_field.OuterFlow e_far was read with (None: none)
    # the verdict and the e per code kind with their ranges (answer.answer); {} until computed
    answer: dict = field(default_factory=dict)

    def __getattr__(self, name):
        # each piece's reason as an attribute too (result.viscosity_reason, examples/)
        reasons = self.__dict__.get("reasons", {})
        if name in reasons:
            return reasons[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def to_dict(self) -> dict:
        """All results (keys ``RESULT_KEYS``), SI with the unit in the key, non-finite as None."""
        s, c = self.scene, self.collision

        def num(v):
            v = float(v)
            return v if math.isfinite(v) else None

        si = {k.key: si_value(o, k, s, c, self.outer) for o, k in scene_keys()}
        if s.settling_outer_start_speed is not None:  # gravity drives the approach
            si["outer_start_speed_m_per_s"] = s.settling_outer_start_speed
        out = {
            "title": s.title, **self.answer,
            # the speed at the outer start: given, or what arrives at x0 with v0
            "approach_speed_m_per_s": s.approach_speed if s.approach_speed is not None else
            si["outer_start_speed_m_per_s"],
            "inputs": s.inputs(),
            "reduced_radius_m": num(s.reduced_radius), "reduced_mass_kg": num(s.reduced_mass),
            "theta_per_Pa": s.theta, "effective_modulus_Pa": s.effective_modulus,
            "x0_m": s.x0, "x0_over_a": s.x0 / s.reduced_radius, "x1_m": s.x1,
            # the physics solved (Pi = inf, the classic film without a floor, is null as in
            # the solver's JSON)
            **{k: num(v) if isinstance(v, float) else v for k, v in c.physics.as_dict().items()},
            "Re": s.reynolds,
            "Re_x0_over_a": s.reynolds * s.x0 / s.reduced_radius,
            "sound_speed_m_per_s": s.sound_speed, "wave_parameter": s.wave_parameter,
            "model": c.model, "model_reason": model_reason(s, c),
            **{key: self.reasons.get(key, "") for key in REASON_KEYS},
            "e_dry_source": s.e_dry_source,
            **{key: value(s) for piece in PIECES for key, value in piece.quantities.items()},
            "status": c.status, "message": c.message,
            # where e_far reads the speeds (solver/far_field.py)
            "x_ref_m": s.x_ref_distance, "x_ref_over_a": s.x_ref_distance / s.reduced_radius,
            "outer_start_m": s.outer_start_distance,
            "outer_start_over_a": s.outer_start_distance / s.reduced_radius,
            "outer_geometry": s.outer_geometry,
            "density_ratio": self.outer.density_ratio if self.outer else s.density_ratio,
            "dem_restitution": dem_restitution(c.e_wet, c.e_far if self.outer else math.nan),
            **si,
            "sensitivity": self.sensitivity,
            "warnings": [w.as_dict() for w in self.warnings], "notes": list(self.notes),
            "dimensionless": c.to_dict(),
        }
        assert tuple(out) == result_keys()
        return out


# Which restitution a DEM code should take (docs/scenes.md, "The approach from far away"): the
# JSON's coupling -> (its label in the report, its kind in the one table of which e each kind of
# code realises, pipeline.dem.conventions.DEM_KINDS)
DEM_COUPLING = {"resolved_cfd_dem": ("resolved CFD-DEM", "cfd-dem"), "dry_dem": ("dry DEM", "dry")}


def dem_restitution(e_wet: float, e_far: float) -> dict:
    """``{coupling: {"code", "key", "value", "why"}}``: the restitution each kind of DEM code
    takes (``key`` names the result, ``value`` is it)."""
    from ..dem.conventions import DEM_KINDS

    values = {"e_wet": e_wet, "e_far": e_far}
    out = {}
    for coupling, (label, kind) in DEM_COUPLING.items():
        key = DEM_KINDS[kind].e_column
        v = float(values[key])
        out[coupling] = {"code": label, "key": key, "value": v if math.isfinite(v) else None,
                         "why": DEM_KINDS[kind].why}
    return out


def stopped_result(scene: Scene, ranges: bool = True) -> dict:
    """``SceneResult.to_dict`` of a scene whose outer flow stops the spheres before ``x0``
    (``Scene.stops_outside``): they stick without a film collision; nothing of the film is
    computed (its keys are null). ``ranges`` False: the ranges null (``--no-range``)."""
    outer = scene.outer_flow()
    a = scene.reduced_radius
    stop = outer.stopping_gap(scene.stokes_of(scene.approach_speed))
    out = dict.fromkeys(result_keys())
    out.update(
        title=scene.title, **stopped_answer(ranges), approach_speed_m_per_s=scene.approach_speed,
        inputs=scene.inputs(), reduced_radius_m=a, reduced_mass_kg=scene.reduced_mass,
        theta_per_Pa=scene.theta, effective_modulus_Pa=scene.effective_modulus, x0_m=scene.x0,
        x0_over_a=scene.x0 / a, status="ok",
        message=(f"the outer flow stops the spheres at a gap of {stop:.3g} a, before the film's "
                 f"start x0 = {scene.x0 / a:.3g} a: the approach speed "
                 f"{scene.approach_speed:.4g} m/s is too slow for the outer resistance, so they "
                 "stick without a film collision"),
        v_r=0.0, e_wet=0.0, e_far=0.0, x_ref_m=scene.x_ref_distance,
        x_ref_over_a=scene.x_ref_distance / a, outer_start_m=scene.outer_start_distance,
        outer_start_over_a=scene.outer_start_distance / a,
        outer_start_speed_m_per_s=(scene.approach_speed if scene.settling_outer_start_speed is None
                                   else scene.settling_outer_start_speed),
        outer_geometry=scene.outer_geometry,
        density_ratio=scene.density_ratio, sensitivity={}, warnings=[], notes=[])
    return out


def check_solvable(scene: Scene) -> Physics:
    """The scene's ``Physics``; SceneError, saying what to change, when a group lies outside
    the solver's range (``Scene.physics``)."""
    return scene.physics()


def run_scene(scene: Scene, accuracy: str = "standard", sensitivity_solves: bool = True,
              ranges: bool = False, **overrides) -> SceneResult:
    """Solve a scene and check it.

    The scene's automatic switches (each piece of ``pieces.PIECES`` whose field is "auto", the
    default) are decided on one first solve, the *base*: the classic film (each automatic piece
    at its ``base``), with whatever the scene forces. Each automatic piece asks that first film
    whether it needs the piece (``ScenePiece.switch``, the rules of ``checks.py``); if one fired,
    the scene is solved again with it ``on``. The ``SceneResult`` reasons say which film answered
    and why. A scene that forces everything (or whose fluid gives nothing to switch) is solved
    once.

    Parameters
    ----------
    scene : Scene
    accuracy : {"fast", "standard", "fine"}
        Solver preset.
    sensitivity_solves : bool
        Solve the scene again without each piece of physics it switched on (``sensitivity``);
        False skips those solves (sweeps of scenes, exports).
    ranges : bool
        Solve the scene again at the ends of each unknown (``answer.answer``: the ranges of
        ``e_for_dem`` and ``e_for_cfd_dem`` and their drivers, what ``ehd scene`` shows);
        False: the central values only, their ranges null.
    **overrides
        Numerical settings passed to ``solver.collide``. Profiles are not saved unless
        ``save_profiles=True`` (only the figures need them).

    Returns
    -------
    SceneResult
        ``collision.status`` tells whether the solve succeeded.
    """
    from solver import collide

    from ..environment import compile_notice

    if scene.stops_outside:  # no film collision to solve (a ZeroDivisionError before)
        if scene.approach_speed is None:  # v0 = 0 given (dataclasses.replace), not the outer flow's
            raise ValueError("v0 = 0: the spheres never reach x0, and there is no collision to "
                             "solve; give a positive v0 (a speed in m/s, or with its units)")
        raise ValueError(f"the outer flow stops the spheres before x0 (approach speed "
                         f"{scene.approach_speed:.4g} m/s): they stick without a film collision; "
                         "stopped_result(scene) gives the report ehd scene prints for it")
    outer = scene.outer_flow()
    auto = [p for p in PIECES if getattr(scene, p.field) == "auto"]
    # the automatic switches start from the classic film (docs/scenes.md, "Which model, and
    # why"), with what the scene forces
    base = scene.physics(**{p.field: p.base for p in auto})
    overrides = {"save_profiles": False,
                 **{k: v for k, v in overrides.items() if v is not None}, "outer": outer}
    compile_notice(physics=[base])  # one line when a solve is about to compile (a silent wait)
    c = collide(base, accuracy=accuracy, **overrides)
    first = BaseFilm.of(scene, c)
    final = scene.physics(**{p.field: p.on if p.switch(scene, first) else p.base for p in auto})
    if final != base:
        compile_notice(physics=[final])
        c = collide(final, accuracy=accuracy, **overrides)
    reasons = {p.reason_key: p.reason(scene, c.physics, first, p not in auto, base)
               for p in PIECES}
    sensitivity = _sensitivity(c, base, accuracy, overrides) if sensitivity_solves else {}
    result = SceneResult(scene=scene, collision=c, sensitivity=sensitivity, outer=outer,
                         reasons=reasons)
    _check(result, base, first.p_max)
    options = {k: v for k, v in overrides.items() if k not in ("outer", "save_profiles")}
    result.answer = answer(result, accuracy, options, ranges=ranges)
    return result


def _check(result: SceneResult, base, base_p_max) -> None:
    """The validity checks and notes of a solved scene, and its pressure extremes in Pa, into
    ``result`` (``base``: the film solved first, whose peak pressure ``base_p_max`` [Pa]
    decided the switches)."""
    scene, c = result.scene, result.collision
    warnings = premise_checks(scene)
    notes = []
    if c.ok:
        # the solver's extremes over the whole collision, rigid phases included
        p_star = scene.pressure_scale
        result.peak_pressure, result.min_pressure = c.p_max * p_star, c.p_min * p_star
        post, notes = outcome_checks(scene, c, result.peak_pressure, result.min_pressure)
        warnings += post
    warnings += pressure_checks(scene, base_p_max, base)
    notes += pressure_notes(scene, base_p_max, base)
    if scene.sound_speed is None:
        notes.append("elastic-wave check skipped: no density known for either solid")
    if result.outer.geometry == "pair":
        notes.append("e_far: two unequal spheres, their relative motion at zero momentum (the "
                     "drag on the pair's centre of mass left out; docs/model.md)")
    if scene.fluid.density is None:
        notes.append("e_far without added mass: the fluid has no density")
    result.warnings, result.notes = warnings, notes


def _sensitivity(c, base, accuracy, overrides) -> dict:
    """The scene's result without each piece of physics it switched on itself (one solve each),
    and each piece's further variants (``ScenePiece.variants``: its least known input either
    way): the spread a user should see beside the one number (docs/scenes.md, "Sensitivity")."""
    from solver import collide

    final = c.physics
    variants = {}
    for piece in PIECES:
        label, on, off = piece.without
        if on(final) and not on(base):
            variants[label] = final.replace(**off)
    for piece in PIECES:
        variants.update(piece.variants(final))
    from ..environment import compile_notice

    compile_notice(physics=list(variants.values()))
    out = {}
    for label, physics in variants.items():
        r = collide(physics, accuracy=accuracy, **overrides)
        e_far = float(r.e_far) if r.ok else math.nan
        out[label] = {"e_wet": float(r.e_wet) if r.ok else None,
                      "e_far": e_far if math.isfinite(e_far) else None,
                      "v_r": float(r.v_r) if r.ok else None, "status": r.status}
    return out
