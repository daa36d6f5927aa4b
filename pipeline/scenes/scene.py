"""A scene in physical units: two bodies and a fluid -> (St, eps), the scales of its solution.

A *scene* is what a user sees: "two 100 um sandstone grains meeting in water at 10 cm/s". From it
(docs/model.md, "Setting" and "The parameters"; all SI):

- reduced radius ``a = a1 a2 / (a1 + a2)`` and mass ``m = m1 m2 / (m1 + m2)``; a plane wall is
  ``a2 = m2 = inf``, so a sphere against a wall has ``a = a1``, ``m = m1``;
- elastic constant ``theta = (1 - nu1^2)/(pi E1) + (1 - nu2^2)/(pi E2)`` [1/Pa];
- film scale ``x1 = (4 theta mu a^1.5 v0)^(2/5)`` [m], Stokes number ``St = m v0 / (6 pi mu a^2)``,
  elasticity parameter ``eps = 4 theta mu v0 a^1.5 / x0^2.5 = (x1/x0)^(5/2)``;
- Reynolds number ``Re = rho_f v0 a / mu`` (the film's inertia relative to viscosity is
  ``Re x0/a``); bar sound speed of a solid ``c = sqrt(E / rho)``;
- with the pressure scale ``p* = mu a v0 / x1^2``: the cavitation number
  ``Pi = (p_amb - p_cav) / p*``, the piezoviscous number ``beta = alpha p*`` (alpha the fluid's
  ``pressure_viscosity``), the Roelands ``P_R = p_R / p*`` and the Dowson-Higginson ``c1 p*``,
  ``c2 p*`` (docs/scenes.md, "Pressure-dependent viscosity and density").

The solver works in the dimensionless variables of docs/model.md ("Scales"); results are converted back with
the scales ``x1`` (axial lengths), ``mu a v0 / x1^2`` (pressure), ``6 pi mu a^2 v0 / x1`` (force)
and ``x0 / v0`` (time: ``t = tau x0 / v0``).

The model is never applied silently outside its range: scenes whose St or eps fall outside what
the solver accepts are refused (``SceneError``, raised by ``Scene.physics`` with what to change).
Building a scene from a file is in :mod:`pipeline.scenes.scene_file`, the validity checks in
:mod:`pipeline.scenes.checks`, solving a scene in :mod:`pipeline.scenes.run`.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from solver.physics import Physics, codes

from ..errors import UsageError
from .materials import FluidProps, Solid
from .units import format_quantity

__all__ = ["SceneError", "Body", "Scene", "STANDARD_ATMOSPHERE", "CAVITATION_CHOICES",
           "ROUGHNESS_CHOICES",
           "VISCOSITY_CHOICES", "DENSITY_CHOICES"]

STANDARD_ATMOSPHERE = 101325.0  # Pa: the default ambient pressure of a scene (a liquid at sea level)
CAVITATION_CHOICES = Physics.group("cavitation").choices
ROUGHNESS_CHOICES = ("auto", "on", "off")
# The asperities' stiffness where the materials give no asperity data (docs/model.md, "Surface
# roughness"): the Greenwood-Williamson roughness parameter N sigma beta, 0.03-0.05 for most
# engineering surfaces (Greenwood & Williamson 1966), its mid value; and the summit radius
# beta = sigma / SUMMIT_ASPECT, an assumed aspect of the summits (not measured for these
# surfaces; the report shows what a 10x stiffer or softer layer changes)
GW_ROUGHNESS_PARAMETER = 0.04
SUMMIT_ASPECT = 0.01
# a scene's viscosity and density laws: "auto" is the automatic switch (run.run_scene), the
# others are forced; the laws are the solver's (solver.physics.codes), but a table, which a
# fluid does not ship
VISCOSITY_CHOICES = ("auto", *(law for law in codes("viscosity_law") if law != "table"))
DENSITY_CHOICES = ("auto", *codes("density_law"))


class SceneError(UsageError, ValueError):
    """A scene that cannot be built or solved (the message names the field or parameter)."""


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
    ambient_pressure: float = STANDARD_ATMOSPHERE  # Pa, absolute (default 1 atm)
    # absolute pressure at which the liquid cavitates [Pa]; None: the film cannot cavitate (a gas)
    # or nothing is known (a liquid without a vapour pressure): the classic film, unchecked
    cavitation_pressure: float | None = None
    cavitation_pressure_source: str = ""  # how it was set, for the report
    # the cavitation model: "auto" (classic, switched to the default model where the classic
    # tension would cross the floor: run.run_scene), or forced "off", "reynolds", "jfo"
    cavitation: str = "auto"
    # the viscosity law: "auto" (constant, switched to the fluid's law where alpha times the
    # classic peak pressure is not small: run.run_scene), or forced "constant", "barus",
    # "roelands"; the density law likewise: "auto", "constant", "dowson-higginson"
    viscosity_law: str = "auto"
    density_law: str = "auto"
    # surface roughness as physics: "auto" (smooth, switched on where the combined rms roughness
    # is not small against the smooth film's closest approach: run.run_scene), "on" or "off"
    asperity_contact: str = "auto"
    # the pair's dry coefficient of restitution (acts only where the asperities touch); 1: unknown
    e_dry: float = 1.0
    e_dry_source: str = ""  # where it came from, for the report
    # the outer-flow reading of e_far [m] (solver/far_field.py): where the outer approach starts
    # and where e_far reads the speeds; None: the defaults, 1 a and 0.1 a (docs/scenes.md)
    outer_start: float | None = None
    x_ref: float | None = None
    # the approach speed [m/s] at the outer start when the scene gave it (``v0`` is then mapped
    # from it through the outer flow, 0 when the outer flow stops the spheres before x0); None:
    # the scene gave v0 (docs/scenes.md, "The approach speed")
    approach_speed: float | None = None
    # how the approach speed was set: "given", or "settling (<law> drag, from 10 a)"
    approach_speed_source: str = ""
    # a settling approach's speed [m/s] at the outer start, on its motion with gravity
    # (trajectory.settling_arrival); None: the approach is the outer flow's alone
    settling_outer_start_speed: float | None = None

    def __post_init__(self):
        # a forced law the fluid has no constants for is refused here, before anything is solved
        self._viscosity_law(self.viscosity_law)
        self._density_law(self.density_law)
        # v0 as dataclasses.replace may give it (examples/scene_in_python.py): a string with
        # units read as the scene file's, a number of m/s; 0 only where the outer flow stops
        # the spheres (a bool was solved as 1 m/s, a negative speed was named as a negative St)
        if not (isinstance(self.v0, numbers.Real) and self.v0 == 0.0):  # 0: a stopped scene
            from .scene_file import _SPEED
            from .units import to_si

            object.__setattr__(self, "v0", to_si(self.v0, _SPEED, "v0"))
        else:
            object.__setattr__(self, "v0", 0.0)

    @property
    def stops_outside(self) -> bool:
        """True when the outer flow stops the spheres before they reach ``x0`` (an approach speed
        too slow for the outer resistance): they stick without a film collision."""
        return self.v0 <= 0.0

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
        return self.stokes_of(self.v0)

    def stokes_of(self, speed: float) -> float:
        """``m V / (6 pi mu a^2)``: the Stokes number of the speed ``V`` [m/s]."""
        a = self.reduced_radius
        return self.reduced_mass * speed / (6.0 * math.pi * self.fluid.viscosity * a * a)

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

    @property
    def Pi(self) -> float:
        """Cavitation number ``(p_amb - p_cav) / p*`` with ``p* = mu a v0 / x1^2``
        (``pressure_scale``); inf when the scene has no cavitation pressure."""
        if self.cavitation_pressure is None:
            return math.inf
        return (self.ambient_pressure - self.cavitation_pressure) / self.pressure_scale

    @property
    def beta(self) -> float | None:
        """Piezoviscous number ``alpha p*`` (alpha the fluid's ``pressure_viscosity``, ``p*`` the
        ``pressure_scale``); None when the fluid has no alpha."""
        alpha = self.fluid.pressure_viscosity
        return None if alpha is None else alpha * self.pressure_scale

    def _viscosity_law(self, law: str) -> str:
        """The law ``law`` stands for with this fluid: "auto" is the fluid's own law (the one the
        automatic switch turns on: "roelands" with Z and p_R, "barus" with alpha > 0, else
        "constant"); a forced law the fluid has no constants for raises SceneError."""
        if law not in VISCOSITY_CHOICES:
            raise SceneError(f"viscosity_law must be one of {list(VISCOSITY_CHOICES)}, got {law!r}")
        f = self.fluid
        alpha = f.pressure_viscosity
        if law == "auto":
            if not alpha:  # None (unknown) or 0 (no pressure dependence)
                return "constant"
            return "roelands" if f.has_roelands else "barus"
        if law in ("barus", "roelands"):
            if alpha is None:
                raise SceneError(f"viscosity_law = {law!r} needs the fluid's pressure-viscosity "
                                 f"coefficient, and the fluid {f.name!r} has none: give "
                                 "fluid.pressure_viscosity (e.g. '20 1/GPa', --pressure-viscosity)")
            if alpha == 0.0:
                raise SceneError(f"viscosity_law = {law!r} with pressure_viscosity = 0 (the "
                                 f"fluid {f.name!r}) is the constant viscosity: give "
                                 "fluid.pressure_viscosity > 0 or viscosity_law = 'constant'")
            if law == "roelands" and not f.has_roelands:
                raise SceneError(f"viscosity_law = 'roelands' needs the fluid's roelands_index "
                                 f"and roelands_pressure, and the fluid {f.name!r} has none: give "
                                 "both (e.g. fluid.roelands_index = 0.6, fluid.roelands_pressure "
                                 "= '196 MPa'), or viscosity_law = 'barus'")
        return law

    def _density_law(self, law: str) -> str:
        """The density law ``law`` stands for: "auto" is "dowson-higginson" where the fluid has
        its constants, else "constant"; a forced law without them raises SceneError."""
        if law not in DENSITY_CHOICES:
            raise SceneError(f"density_law must be one of {list(DENSITY_CHOICES)}, got {law!r}")
        has = self.fluid.has_dowson_higginson
        if law == "auto":
            return "dowson-higginson" if has else "constant"
        if law == "dowson-higginson" and not has:
            raise SceneError(f"density_law = 'dowson-higginson' needs the fluid's "
                             f"dowson_higginson_c1 and dowson_higginson_c2, and the fluid "
                             f"{self.fluid.name!r} has none: give both (e.g. "
                             "fluid.dowson_higginson_c1 = '0.6 1/GPa', fluid.dowson_higginson_c2 "
                             "= '1.7 1/GPa')")
        return law

    @property
    def roughness_rms(self) -> float | None:
        """The combined rms roughness ``sqrt(s1^2 + s2^2)`` of the bodies [m]; None when neither
        gives one (a body without a value counts as smooth)."""
        values = [b.solid.roughness for b in (self.body1, self.body2)]
        if all(v is None for v in values):
            return None
        return math.sqrt(sum(v * v for v in values if v is not None))

    @property
    def asperity_stiffness(self) -> float | None:
        """The dimensionless asperity stiffness ``k`` of the rough surfaces (docs/model.md,
        "Surface roughness"): ``(16/(3 pi)) (N sigma beta) sqrt(a/beta) x1/sigma`` with the
        Greenwood-Williamson parameter ``N sigma beta = GW_ROUGHNESS_PARAMETER`` and the summit
        radius ``beta = sigma / SUMMIT_ASPECT``; None without a roughness."""
        sigma = self.roughness_rms
        if not sigma:
            return None
        beta = sigma / SUMMIT_ASPECT
        return (16.0 / (3.0 * math.pi)) * GW_ROUGHNESS_PARAMETER \
            * math.sqrt(self.reduced_radius / beta) * self.x1 / sigma

    def physics(self, cavitation: str | None = None, viscosity_law: str | None = None,
                density_law: str | None = None, asperity_contact: str | None = None) -> Physics:
        """The scene's dimensionless groups: the one place a scene becomes solver input.

        ``cavitation`` is the model (default: the scene's own choice); "auto" is the solver's
        default model where the scene has a cavitation pressure (``Pi`` finite) and the classic
        film where it has none. ``viscosity_law`` and ``density_law`` likewise (default: the
        scene's own); "auto" is the fluid's own law (``_viscosity_law``, ``_density_law``),
        "constant" the classic film's. The automatic switches of a scene (classic first, the
        floor or the law only where the classic film needs them) are ``run.run_scene``'s: it
        asks for "off" and "constant" first. With "off" and a cavitation pressure, ``Pi`` is kept
        (finite) and ignored by the solver; a law's constants (``beta = alpha p*``, ``roelands_Z``,
        ``roelands_PR = p_R / p*``, ``dh_c1 = c1 p*``, ``dh_c2 = c2 p*``) are passed only with
        the law that uses them (with the constant viscosity ``beta`` is the solver's 0).

        ``asperity_contact`` "on" passes the bodies' combined rms roughness over ``x1`` with its
        asperity stiffness (``asperity_stiffness``); "off" and "auto" the smooth surfaces
        (``run.run_scene`` decides "auto"), and ``e_dry`` with the contact only (it acts only
        where the asperities touch: smooth surfaces keep the solver's 1, as the other groups of
        physics that is off keep their defaults).

        Raises SceneError when a group is outside what the solver accepts (the Physics' own
        range check; for a group above its range the message says what to change in the
        scene), or when a cavitation model is asked for a scene without a cavitation pressure,
        or a law for a fluid without its constants.
        """
        model = self.cavitation if cavitation is None else cavitation
        if model not in CAVITATION_CHOICES:
            raise SceneError(f"cavitation must be one of {list(CAVITATION_CHOICES)}, got {model!r}")
        if model in ("reynolds", "jfo") and self.cavitation_pressure is None:
            raise SceneError(f"cavitation = {model!r} needs a cavitation pressure, and this scene "
                             f"has none ({self.cavitation_pressure_source or 'not given'}): give "
                             "fluid.cavitation_pressure (a pressure, 'vapour' or 'gas-saturated') "
                             "or fluid.tensile_strength")
        visc = self._viscosity_law(self.viscosity_law if viscosity_law is None else viscosity_law)
        dens = self._density_law(self.density_law if density_law is None else density_law)
        f, p_star = self.fluid, self.pressure_scale
        values = {"St": self.stokes, "eps": self.eps, "Pi": self.Pi, "cavitation": model,
                  "viscosity_law": visc, "density_law": dens}
        if visc != "constant":
            values["beta"] = self.beta
        if visc == "roelands":
            values["roelands_Z"] = f.roelands_index
            values["roelands_PR"] = f.roelands_pressure / p_star
        if dens != "constant":
            values["dh_c1"] = f.dowson_higginson_c1 * p_star
            values["dh_c2"] = f.dowson_higginson_c2 * p_star
        rough = self.asperity_contact if asperity_contact is None else asperity_contact
        if rough not in ROUGHNESS_CHOICES:
            raise SceneError(f"asperity_contact must be one of {list(ROUGHNESS_CHOICES)}, got "
                             f"{rough!r}")
        if rough == "on":
            sigma = self.roughness_rms
            if not sigma:
                raise SceneError("asperity_contact = 'on' needs the bodies' rms roughness: give "
                                 "solid.roughness (e.g. '0.3 um') for at least one body")
            if sigma >= self.x0:
                raise SceneError(f"the combined rms roughness {format_quantity(sigma, 'm')} is "
                                 f"not below the starting gap x0 = {format_quantity(self.x0, 'm')}"
                                 ": start farther out (a larger x0 or x0_over_a)")
            values["roughness"] = sigma / self.x1
            values["asperity_stiffness"] = self.asperity_stiffness
            values["e_dry"] = self.e_dry
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

    # ---- the outer flow: how e_far reads the near-field result (solver/far_field.py) -----------
    @property
    def outer_geometry(self) -> str | None:
        """``"wall"``, ``"spheres"`` (two equal radii and masses) or ``"pair"`` (two free spheres
        of any radii and masses, solver/model/outer_flow.py ``pair_resistance``); a sphere over
        ``far_field.PAIR_RATIO_MAX`` times the other's radius is a wall to the outer flow (its
        series took minutes at 1e4 and did not converge at 1e6)."""
        if self.body2.wall:
            return "wall"
        if math.isclose(self.body1.radius, self.body2.radius, rel_tol=1e-9) and math.isclose(
                self.body1.mass, self.body2.mass, rel_tol=1e-9):
            return "spheres"
        from solver.far_field import pair_within_reach

        first, second = self._outer_bodies
        if not pair_within_reach(second.radius / first.radius):  # the larger sphere: a wall
            return "wall"
        return "pair"

    @property
    def outer_start_distance(self) -> float:
        """Where the outer approach starts [m] (default ``far_field.START_OVER_A`` a)."""
        from solver.far_field import START_OVER_A

        return START_OVER_A * self.reduced_radius if self.outer_start is None else self.outer_start

    @property
    def x_ref_distance(self) -> float:
        """Where e_far reads the speeds [m] (default ``far_field.X_REF_OVER_A`` a)."""
        from solver.far_field import X_REF_OVER_A

        return X_REF_OVER_A * self.reduced_radius if self.x_ref is None else self.x_ref

    @property
    def _outer_bodies(self):
        """The two bodies as the outer flow takes them: the sphere and the wall; of two spheres
        the smaller first (the "pair" outer flow measures the added mass on sphere 1's volume:
        with the larger first, a 2 cm glass sphere meeting a 100 um grain in water made ``phi``
        1.6e6, beyond what ``OuterFlow`` takes, and the scene was refused, solved with the
        bodies listed the other way round; the same collision either way, e_far to 1e-9)."""
        if not self.body2.wall and self.body2.radius < self.body1.radius:
            return self.body2, self.body1
        return self.body1, self.body2

    @property
    def density_ratio(self) -> float:
        """``phi``: the fluid mass the particle displaces over its mass, ``rho_f / rho_p``
        (wall: ``rho_f V1 / m1``; two spheres: ``rho_f V / (2 m)``, ``V`` the smaller sphere's
        volume, ``m`` the reduced mass); 0 without a fluid density (no added mass)."""
        rho_f = self.fluid.density
        if not rho_f:
            return 0.0
        first, second = self._outer_bodies
        volume = 4.0 / 3.0 * math.pi * first.radius**3
        share = 1.0 if self.outer_geometry == "wall" else 0.5
        return rho_f * volume * share / self.reduced_mass

    def outer_flow(self):
        """The ``solver.far_field.OuterFlow`` of the scene (``outer_geometry``)."""
        from solver.far_field import OuterFlow

        geometry = self.outer_geometry
        a = self.reduced_radius
        ratios = {}
        if geometry == "pair":
            first, second = self._outer_bodies
            ratios = {"radius_ratio": second.radius / first.radius,
                      "mass_ratio": second.mass / first.mass}
        return OuterFlow(geometry=geometry, x0_over_a=self.x0 / a,
                         x_ref_over_a=self.x_ref_distance / a,
                         start_over_a=self.outer_start_distance / a,
                         density_ratio=self.density_ratio, **ratios)

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
                    "roughness_m": s.roughness,
                    "source": s.source}
        f = self.fluid
        return {"body1": body(self.body1), "body2": body(self.body2),
                "fluid": {"name": f.name, "viscosity_Pa_s": f.viscosity,
                          "density_kg_per_m3": f.density, "vapour_pressure_Pa": f.vapour_pressure,
                          "mean_free_path_m": f.mean_free_path,
                          "ambient_pressure_Pa": self.ambient_pressure,
                          "cavitation_pressure_Pa": self.cavitation_pressure,
                          "cavitation_pressure_source": self.cavitation_pressure_source,
                          "pressure_viscosity_per_Pa": f.pressure_viscosity,
                          "roelands_index": f.roelands_index,
                          "roelands_pressure_Pa": f.roelands_pressure,
                          "dowson_higginson_c1_per_Pa": f.dowson_higginson_c1,
                          "dowson_higginson_c2_per_Pa": f.dowson_higginson_c2,
                          "source": f.source, "pressure_source": f.pressure_source},
                "v0_m_per_s": self.v0, "approach_speed_m_per_s": self.approach_speed,
                "approach_speed_source": self.approach_speed_source,
                "x0_m": self.x0}



def _eps_too_large(scene: Scene, eps: float) -> str:
    hi = Physics.group("eps").hi
    need = scene.x1 * hi ** -0.4
    return (f"eps = {eps:.3g} is outside the model's range (0, {hi:g}]: the start "
            f"x0 = {format_quantity(scene.x0, 'm')} is within the deformation scale x1 = "
            f"{format_quantity(scene.x1, 'm')}; start farther out (x0 >= "
            f"{format_quantity(need, 'm')})")


def _stokes_too_large(scene: Scene, stokes: float) -> str:
    speed = (f"the approach speed {format_quantity(scene.approach_speed, 'm/s')}, v0 = "
             if scene.approach_speed is not None else "v0 = ")
    return (f"St = {stokes:.4g} (from {speed}{format_quantity(scene.v0, 'm/s')}) is outside the "
            f"solver's range (0, {Physics.group('St').hi:g}]: viscous losses are negligible and "
            "the impact is close to dry Hertz contact; a slower speed or a smaller or lighter "
            "sphere is within it")


def _beta_too_large(scene: Scene, beta: float) -> str:
    return (f"beta = alpha p* = {beta:.4g} is outside the solver's range "
            f"[0, {Physics.group('beta').hi:g}] (alpha = "
            f"{format_quantity(scene.fluid.pressure_viscosity, '1/Pa')} of {scene.fluid.name}, "
            f"p* = {format_quantity(scene.pressure_scale, 'Pa')}): the viscosity would grow by "
            f"e^{beta:.3g} already at the pressure scale; solve the constant-viscosity film "
            "instead with viscosity_law = 'constant' (--viscosity-law constant)")


# group -> message for a scene whose group is above the solver's range (what to change)
_TOO_LARGE = {"eps": _eps_too_large, "St": _stokes_too_large, "beta": _beta_too_large}
