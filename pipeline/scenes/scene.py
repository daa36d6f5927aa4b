"""A scene in physical units: two bodies and a fluid -> (St, eps), validity checks, results in SI.

A *scene* is what a user sees: "two 100 um sandstone grains meeting in water at 10 cm/s". From it
(docs/model.md, "Setting" and "The parameters"; all SI):

- reduced radius ``a = a1 a2 / (a1 + a2)`` and mass ``m = m1 m2 / (m1 + m2)``; a plane wall is
  ``a2 = m2 = inf``, so a sphere against a wall has ``a = a1``, ``m = m1``;
- elastic constant ``theta = (1 - nu1^2)/(pi E1) + (1 - nu2^2)/(pi E2)`` [1/Pa];
- film scale ``x1 = (4 theta mu a^1.5 v0)^(2/5)`` [m], Stokes number ``St = m v0 / (6 pi mu a^2)``,
  elasticity parameter ``eps = 4 theta mu v0 a^1.5 / x0^2.5 = (x1/x0)^(5/2)``;
- Reynolds number ``Re = rho_f v0 a / mu`` (the film's inertia relative to viscosity is
  ``Re x0/a``); bar sound speed of a solid ``c = sqrt(E / rho)``.

The solver works in the dimensionless variables of docs/model.md ("Scales"); results are converted back with
the scales ``x1`` (axial lengths), ``mu a v0 / x1^2`` (pressure), ``6 pi mu a^2 v0 / x1`` (force)
and ``x0 / v0`` (time: ``t = tau x0 / v0``).

The model is never applied silently outside its range: scenes whose St or eps fall outside what
the solver accepts are refused (``SceneError``), and every premise that a scene strains is
reported as a ``Check`` carrying the number that triggered it (thresholds below).

No file I/O here: ``scene_from_dict`` takes an already-parsed TOML document.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from solver.model import rigid
from solver.physics import Physics

from .materials import FLUID_FIELDS, SOLID_FIELDS, FluidProps, MaterialTable, Solid
from .units import FieldSpec, format_quantity, to_si

__all__ = [
    "SceneError", "Body", "Scene", "Check", "SceneResult", "scene_from_dict", "run_scene",
    "premise_checks", "outcome_checks", "THRESHOLDS", "RESULT_KEYS",
    "DEFAULT_X0_OVER_A", "model_reason", "check_solvable",
]


class SceneError(ValueError):
    """A scene that cannot be built or solved (the message names the field or parameter)."""


DEFAULT_X0_OVER_A = 0.01  # docs/model.md "Setting": the close stage starts at x0 ~ 0.01 a

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
}

# Keys of SceneResult.to_dict() (a contract for scripts using `ehd scene --json`; see docs/scenes.md)
RESULT_KEYS = (
    "title", "inputs", "reduced_radius_m", "reduced_mass_kg", "theta_per_Pa", "effective_modulus_Pa",
    "x0_m", "x0_over_a", "x1_m", *Physics.names(), "Re", "Re_x0_over_a", "sound_speed_m_per_s",
    "wave_parameter", "model", "model_reason", "status", "message", "v_r",
    "rebound_speed_m_per_s", "closest_approach_nm", "closest_approach_on_approach_nm",
    "equilibrium_separation_m", "log10_equilibrium_separation_m", "escaped", "time_to_stop_s",
    "time_of_max_rebound_s", "peak_force_N", "peak_pressure_Pa", "min_pressure_Pa",
    "max_central_deformation_nm", "min_separation_nm", "dimple", "dimple_depth_nm",
    "warnings", "notes", "dimensionless",
)

_LENGTH = FieldSpec("[length]", "50 um", hi_open=False, si_unit="m")  # radius: inf = plane wall
_SPEED = FieldSpec("[length] / [time]", "10 cm/s", si_unit="m/s")
_GAP = FieldSpec("[length]", "500 nm", si_unit="m")
_RATIO = FieldSpec("", "0.01")
_PRESSURE = FieldSpec("[pressure]", "101.325 kPa", si_unit="Pa")

_TOP_KEYS = ("title", "v0", "x0", "x0_over_a", "body1", "body2", "fluid", "materials", "fluids")
_BODY_KEYS = ("material", "radius", "wall", *SOLID_FIELDS)
_FLUID_KEYS = ("name", "ambient_pressure", *FLUID_FIELDS)


@dataclass(frozen=True)
class Body:
    """One of the two colliding bodies: a sphere of ``radius`` [m], or a plane wall (inf)."""

    label: str  # "body1" / "body2"
    radius: float
    solid: Solid

    @property
    def wall(self) -> bool:
        return math.isinf(self.radius)

    @property
    def mass(self) -> float:
        """``rho 4/3 pi a^3`` [kg]; inf for a wall."""
        if self.wall:
            return math.inf
        return self.solid.density * 4.0 / 3.0 * math.pi * self.radius**3


def _reduced(u, v):
    """``u v / (u + v)`` with ``inf`` allowed for one of them (a wall)."""
    return 1.0 / (1.0 / u + 1.0 / v)


@dataclass(frozen=True)
class Scene:
    """Two bodies, a fluid, the approach speed ``v0`` [m/s] and the starting gap ``x0`` [m]."""

    title: str
    body1: Body
    body2: Body
    fluid: FluidProps
    v0: float
    x0: float
    ambient_pressure: float | None = None  # Pa, absolute; enables the cavitation check

    # ---- derived numbers (SI), docs/model.md---------------------------------------------------
    @property
    def reduced_radius(self) -> float:
        return _reduced(self.body1.radius, self.body2.radius)

    @property
    def reduced_mass(self) -> float:
        return _reduced(self.body1.mass, self.body2.mass)

    @property
    def theta(self) -> float:
        """``(1 - nu1^2)/(pi E1) + (1 - nu2^2)/(pi E2)`` [1/Pa]."""
        return self.body1.solid.compliance + self.body2.solid.compliance

    @property
    def effective_modulus(self) -> float:
        """``E* = 1 / (pi theta)`` [Pa]."""
        return 1.0 / (math.pi * self.theta)

    @property
    def x1(self) -> float:
        """Film scale once deformation matters, ``(4 theta mu a^1.5 v0)^(2/5)`` [m]."""
        a = self.reduced_radius
        return (4.0 * self.theta * self.fluid.viscosity * a**1.5 * self.v0) ** 0.4

    @property
    def stokes(self) -> float:
        """``St = m v0 / (6 pi mu a^2)``."""
        a = self.reduced_radius
        return self.reduced_mass * self.v0 / (6.0 * math.pi * self.fluid.viscosity * a * a)

    @property
    def eps(self) -> float:
        """``eps = 4 theta mu v0 a^1.5 / x0^2.5``."""
        a = self.reduced_radius
        return 4.0 * self.theta * self.fluid.viscosity * self.v0 * a**1.5 / self.x0**2.5

    @property
    def reynolds(self) -> float:
        """``Re = rho_f v0 a / mu`` (reduced radius)."""
        return self.fluid.density * self.v0 * self.reduced_radius / self.fluid.viscosity

    @property
    def sound_speed(self) -> float | None:
        """Slowest bar wave speed ``sqrt(E/rho)`` of the two solids [m/s] (None if unknown)."""
        speeds = [b.solid.sound_speed for b in (self.body1, self.body2)
                  if b.solid.sound_speed is not None]
        return min(speeds) if speeds else None

    @property
    def wave_parameter(self) -> float | None:
        """``(v0/c)^(1/5)``: elastic-wave transit time over the Hertz contact time (scaling)."""
        c = self.sound_speed
        return None if c is None else (self.v0 / c) ** 0.2

    def physics(self) -> Physics:
        """The scene's dimensionless groups: the one place a scene becomes solver input.

        Raises SceneError when a group is outside what the solver accepts (the Physics' own
        range check); for a group above its range the message says what to change in the scene.
        """
        values = {"St": self.stokes, "eps": self.eps}
        try:
            return Physics(**values)
        except ValueError as exc:
            for name, value in values.items():
                try:
                    Physics.group(name).check(value)
                except ValueError:
                    if name in _TOO_LARGE and value > Physics.group(name).hi:
                        raise SceneError(_TOO_LARGE[name](self, value)) from None
                    break
            raise SceneError(f"the scene is outside the solver's range: {exc}") from None

    # ---- scales of the dimensionless solution -----------------------------------------------
    @property
    def pressure_scale(self) -> float:
        """``mu a v0 / x1^2`` [Pa]."""
        return self.fluid.viscosity * self.reduced_radius * self.v0 / self.x1**2

    @property
    def force_scale(self) -> float:
        """``6 pi mu a^2 v0 / x1`` [N]."""
        a = self.reduced_radius
        return 6.0 * math.pi * self.fluid.viscosity * a * a * self.v0 / self.x1

    @property
    def time_scale(self) -> float:
        """``x0 / v0`` [s]: physical time ``t = tau x0 / v0``."""
        return self.x0 / self.v0

    def inputs(self) -> dict:
        """The resolved inputs in SI (what was actually used), for the report and ``--json``."""
        def body(b):
            s = b.solid
            return {"material": s.name, "wall": b.wall,
                    "radius_m": None if b.wall else b.radius,
                    "mass_kg": None if b.wall else b.mass,
                    "youngs_modulus_Pa": s.youngs_modulus, "poisson_ratio": s.poisson_ratio,
                    "density_kg_per_m3": s.density, "yield_strength_Pa": s.yield_strength,
                    "source": s.source}
        f = self.fluid
        return {"body1": body(self.body1), "body2": body(self.body2),
                "fluid": {"name": f.name, "viscosity_Pa_s": f.viscosity,
                          "density_kg_per_m3": f.density, "vapour_pressure_Pa": f.vapour_pressure,
                          "mean_free_path_m": f.mean_free_path,
                          "ambient_pressure_Pa": self.ambient_pressure, "source": f.source},
                "v0_m_per_s": self.v0, "x0_m": self.x0}


# ---- building a scene from a parsed TOML document ---------------------------------------------
def _check_keys(raw, valid, where):
    if not isinstance(raw, dict):
        raise SceneError(f"{where} must be a table (e.g. [{where}])")
    unknown = sorted(set(raw) - set(valid))
    if unknown:
        raise SceneError(f"{where}: unknown field(s) {unknown}; valid fields: {sorted(valid)}")


def _body(data, label, table: MaterialTable) -> Body:
    if label not in data:
        raise SceneError(f"missing the table [{label}]: give a radius and a material "
                         "(or youngs_modulus, poisson_ratio and density)")
    raw = data[label]
    _check_keys(raw, _BODY_KEYS, label)
    wall = raw.get("wall", False)
    if not isinstance(wall, bool):
        raise SceneError(f"{label}.wall must be true or false, got {wall!r}")
    if "radius" in raw:
        r = raw["radius"]
        if isinstance(r, str) and r.strip().lower() in ("inf", "infinity"):
            r = math.inf
        radius = to_si(r, _LENGTH, f"{label}.radius")
        if wall and not math.isinf(radius):
            raise SceneError(f"{label}: wall = true but radius = {raw['radius']!r}; a plane wall "
                             "has an infinite radius (leave radius out)")
    elif wall:
        radius = math.inf
    else:
        raise SceneError(f"{label}: missing the field 'radius' (e.g. radius = '50 um'; "
                         "or wall = true for a plane wall)")
    base = None
    if "material" in raw:
        if not isinstance(raw["material"], str):
            raise SceneError(f"{label}.material must be a name, got {raw['material']!r}")
        base = table.solid(raw["material"], f"{label}.material")
    # a plane wall needs no density (its mass is infinite)
    optional = {"density"} if math.isinf(radius) else set()
    values, name, source = _properties(raw, SOLID_FIELDS, base, label, "material", optional)
    solid = Solid(name=name, source=source, description=base.description if base else "", **values)
    return Body(label=label, radius=radius, solid=solid)


def _properties(raw, fields, base, label, kind, optional=frozenset()):
    """Field values of a solid or fluid: given in ``raw``, else from the named ``base`` entry,
    else None for optional fields; returns ``(values, name, source)``."""
    values = {}
    for field_name, (spec, required) in fields.items():
        if field_name in raw:
            values[field_name] = to_si(raw[field_name], spec, f"{label}.{field_name}")
        elif base is not None:
            values[field_name] = getattr(base, field_name)
        elif required and field_name not in optional:
            raise SceneError(f"{label}: missing the field '{field_name}' (e.g. {field_name} = "
                             f"'{spec.example}'), or name a {kind} = '...'")
        else:
            values[field_name] = None
    overridden = sorted(set(raw) & set(fields))
    if base is None:
        return values, "custom", "given in the scene"
    name = base.name + (f" (with {', '.join(overridden)} given)" if overridden else "")
    source = base.source + ("; overrides given in the scene" if overridden else "")
    return values, name, source


def _fluid(data, table: MaterialTable):
    if "fluid" not in data:
        raise SceneError("missing the table [fluid]: give name = 'water' (or viscosity and density)")
    raw = data["fluid"]
    _check_keys(raw, _FLUID_KEYS, "fluid")
    base = None
    if "name" in raw:
        if not isinstance(raw["name"], str):
            raise SceneError(f"fluid.name must be a name, got {raw['name']!r}")
        base = table.fluid(raw["name"], "fluid.name")
    values, name, source = _properties(raw, FLUID_FIELDS, base, "fluid", "fluid")
    fluid = FluidProps(name=name, source=source, description=base.description if base else "",
                       **values)
    ambient = None
    if "ambient_pressure" in raw:
        ambient = to_si(raw["ambient_pressure"], _PRESSURE, "fluid.ambient_pressure")
    return fluid, ambient


def scene_from_dict(data: dict, table: MaterialTable) -> Scene:
    """Build a ``Scene`` from a parsed scene document (see docs/scenes.md for the format).

    Parameters
    ----------
    data : dict
        Top-level keys ``title``, ``v0``, ``x0`` or ``x0_over_a``, tables ``body1``, ``body2``,
        ``fluid`` (and optionally ``materials`` / ``fluids``, already merged into ``table``).
    table : MaterialTable
        Named materials and fluids.

    Raises
    ------
    SceneError, ValueError
        With a message naming the offending field and its valid range.
    """
    _check_keys(data, _TOP_KEYS, "scene")
    body1 = _body(data, "body1", table)
    body2 = _body(data, "body2", table)
    if body1.wall and body2.wall:
        raise SceneError("body1 and body2 are both plane walls; at least one must be a sphere")
    if body1.wall:  # keep the sphere first: a wall is body2 by convention
        body1, body2 = Body("body1", body2.radius, body2.solid), Body("body2", body1.radius,
                                                                        body1.solid)
    fluid, ambient = _fluid(data, table)
    if "v0" not in data:
        raise SceneError("missing the field 'v0' (approach speed, e.g. v0 = '10 cm/s')")
    v0 = to_si(data["v0"], _SPEED, "v0")
    a = _reduced(body1.radius, body2.radius)
    if "x0" in data and "x0_over_a" in data:
        raise SceneError("give either x0 (a length) or x0_over_a (a ratio), not both")
    if "x0" in data:
        x0 = to_si(data["x0"], _GAP, "x0")
    elif "x0_over_a" in data:
        x0 = to_si(data["x0_over_a"], _RATIO, "x0_over_a") * a
    else:
        x0 = DEFAULT_X0_OVER_A * a
    title = data.get("title", "")
    if not isinstance(title, str):
        raise SceneError(f"title must be a string, got {title!r}")
    return Scene(title=title, body1=body1, body2=body2, fluid=fluid, v0=v0, x0=x0,
                 ambient_pressure=ambient)


# ---- validity checks ---------------------------------------------------------------------------
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
    """Checks that need the solution: yield, cavitation, gas mean free path. Returns
    ``(warnings, notes)``; ``p_max``, ``p_min`` in Pa (gauge, relative to ambient)."""
    out, notes = [], []
    for body in (scene.body1, scene.body2):
        y = body.solid.yield_strength
        if y is not None and p_max > y:
            out.append(Check(f"yield_{body.label}", p_max, y, (
                f"peak film pressure {format_quantity(p_max, 'Pa')} exceeds the yield strength "
                f"{format_quantity(y, 'Pa')} of "
                f"{body.label} ({body.solid.name}): plastic deformation is not modelled")))
    if scene.ambient_pressure is not None:
        pv = scene.fluid.vapour_pressure
        if pv is None:
            notes.append("cavitation check skipped: the fluid has no vapour_pressure")
        else:
            absolute = scene.ambient_pressure + p_min
            if absolute < pv:
                out.append(Check("cavitation", absolute, pv, (
                    "the film tension brings the absolute pressure to "
                    f"{format_quantity(absolute, 'Pa')} (ambient "
                    f"{format_quantity(scene.ambient_pressure, 'Pa')} + min film pressure "
                    f"{format_quantity(p_min, 'Pa')}), below the vapour pressure "
                    f"{format_quantity(pv, 'Pa')}: cavitation is not modelled")))
    elif p_min < 0.0 and scene.fluid.vapour_pressure is not None:
        notes.append("cavitation not checked: give fluid.ambient_pressure to check the film "
                     f"tension ({p_min:.3g} Pa) against the vapour pressure")
    lam = scene.fluid.mean_free_path
    if lam is not None and math.isfinite(c.h_m_x1):
        h_m = c.h_m_x1 * scene.x1
        if h_m < lam:
            out.append(Check("mean_free_path", h_m, lam, (
                f"closest approach {format_quantity(h_m, 'm')} is below the gas mean free "
                f"path {format_quantity(lam, 'm')} (Knudsen number {lam / h_m:.3g}): continuum lubrication "
                "is not valid")))
    return out, notes


def _fmt_log(log_value: float) -> str:
    """Format ``exp(log_value)``, also when it overflows a float."""
    if log_value < 700.0:
        return f"{math.exp(log_value):.3g}"
    return f"10^{log_value / math.log(10.0):.0f}"


def model_reason(scene: Scene, c) -> str:
    """Why the scene needed the rigid or the EHD model, in one sentence with numbers."""
    physics, switch = scene.physics(), c.numerics.switch
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


# ---- running a scene ---------------------------------------------------------------------------
@dataclass
class SceneResult:
    """A solved scene: the dimensionless ``collision`` plus SI results and validity checks."""

    scene: Scene
    collision: object  # solver.Collision
    warnings: list[Check] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    peak_pressure: float = math.nan  # Pa
    min_pressure: float = math.nan  # Pa (negative: tension)

    def to_dict(self) -> dict:
        """All results (keys ``RESULT_KEYS``), SI with the unit in the key, non-finite as None."""
        s, c = self.scene, self.collision
        x1, x0 = s.x1, s.x0

        def num(v):
            v = float(v)
            return v if math.isfinite(v) else None

        ln_xe_m = c.ln_x_e_x1 + math.log(x1)
        out = {
            "title": s.title, "inputs": s.inputs(),
            "reduced_radius_m": num(s.reduced_radius), "reduced_mass_kg": num(s.reduced_mass),
            "theta_per_Pa": s.theta, "effective_modulus_Pa": s.effective_modulus,
            "x0_m": x0, "x0_over_a": x0 / s.reduced_radius, "x1_m": x1,
            **s.physics().as_dict(), "Re": s.reynolds,
            "Re_x0_over_a": s.reynolds * x0 / s.reduced_radius,
            "sound_speed_m_per_s": s.sound_speed, "wave_parameter": s.wave_parameter,
            "model": c.model, "model_reason": model_reason(s, c),
            "status": c.status, "message": c.message,
            "v_r": num(c.v_r), "rebound_speed_m_per_s": num(c.v_r * s.v0),
            "closest_approach_nm": num(c.h_m_x1 * x1 * 1e9),
            "closest_approach_on_approach_nm": num(c.h_m_approach_x1 * x1 * 1e9),
            "equilibrium_separation_m": num(math.exp(ln_xe_m)) if ln_xe_m < 700 else None,
            "log10_equilibrium_separation_m": num(ln_xe_m / math.log(10.0)),
            "escaped": bool(c.escaped),
            "time_to_stop_s": num(c.tau_v_zero * s.time_scale),
            "time_of_max_rebound_s": num(c.tau_max_rebound * s.time_scale),
            "peak_force_N": num(c.peak_force * s.force_scale),
            "peak_pressure_Pa": num(self.peak_pressure), "min_pressure_Pa": num(self.min_pressure),
            "max_central_deformation_nm": num(c.w0_max_x1 * x1 * 1e9),
            "min_separation_nm": num(c.x_min_x1 * x1 * 1e9),
            "dimple": bool(c.dimple), "dimple_depth_nm": num(c.dimple_depth_x1 * x1 * 1e9),
            "warnings": [w.as_dict() for w in self.warnings], "notes": list(self.notes),
            "dimensionless": c.to_dict(),
        }
        assert tuple(out) == RESULT_KEYS
        return out


def check_solvable(scene: Scene) -> Physics:
    """The scene's ``Physics``; SceneError, saying what to change, when a group lies outside
    the solver's range (``Scene.physics``)."""
    return scene.physics()


def _eps_too_large(scene: Scene, eps: float) -> str:
    hi = Physics.group("eps").hi
    need = scene.x1 * hi ** -0.4
    return (f"eps = {eps:.3g} is outside the model's range (0, {hi:g}]: the start "
            f"x0 = {format_quantity(scene.x0, 'm')} is within the deformation scale x1 = "
            f"{format_quantity(scene.x1, 'm')}; start farther out (x0 >= "
            f"{format_quantity(need, 'm')})")


def _stokes_too_large(scene: Scene, stokes: float) -> str:
    return (f"St = {stokes:.4g} is outside the solver's range (0, {Physics.group('St').hi:g}]: "
            "viscous losses are negligible and the impact is close to dry Hertz contact")


# group -> message for a scene whose group is above the solver's range (what to change)
_TOO_LARGE = {"eps": _eps_too_large, "St": _stokes_too_large}


def run_scene(scene: Scene, accuracy: str = "standard", **overrides) -> SceneResult:
    """Solve a scene and check it.

    Parameters
    ----------
    scene : Scene
    accuracy : {"fast", "standard", "fine"}
        Solver preset.
    **overrides
        Numerical settings passed to ``solver.collide``. Profiles are not saved unless
        ``save_profiles=True`` (only the figures need them).

    Returns
    -------
    SceneResult
        ``collision.status`` tells whether the solve succeeded.
    """
    from solver import collide

    physics = check_solvable(scene)
    overrides = {k: v for k, v in overrides.items() if v is not None}
    overrides.setdefault("save_profiles", False)
    c = collide(physics, accuracy=accuracy, **overrides)
    warnings = premise_checks(scene)
    notes = []
    p_max = p_min = math.nan
    if c.ok:
        # the solver's extremes over the whole collision, rigid phases included
        p_max, p_min = c.p_max * scene.pressure_scale, c.p_min * scene.pressure_scale
        post, notes = outcome_checks(scene, c, p_max, p_min)
        warnings += post
    if scene.sound_speed is None:
        notes.append("elastic-wave check skipped: no density known for either solid")
    return SceneResult(scene=scene, collision=c, warnings=warnings, notes=notes,
                       peak_pressure=p_max, min_pressure=p_min)
