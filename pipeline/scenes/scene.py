"""A scene in physical units: two bodies and a fluid -> (St, eps), the scales of its solution.

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
the solver accepts are refused (``SceneError``, raised by ``Scene.physics`` with what to change).
Building a scene from a file is in :mod:`pipeline.scenes.scene_file`, the validity checks in
:mod:`pipeline.scenes.checks`, solving a scene in :mod:`pipeline.scenes.run`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from solver.physics import Physics

from ..errors import UsageError
from .materials import FluidProps, Solid
from .units import format_quantity

__all__ = ["SceneError", "Body", "Scene", "STANDARD_ATMOSPHERE", "CAVITATION_CHOICES"]

STANDARD_ATMOSPHERE = 101325.0  # Pa: the default ambient pressure of a scene (a liquid at sea level)
CAVITATION_CHOICES = ("auto", "off", "reynolds", "jfo")


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

    @property
    def Pi(self) -> float:
        """Cavitation number ``(p_amb - p_cav) / p*`` with ``p* = mu a v0 / x1^2``
        (``pressure_scale``); inf when the scene has no cavitation pressure."""
        if self.cavitation_pressure is None:
            return math.inf
        return (self.ambient_pressure - self.cavitation_pressure) / self.pressure_scale

    def physics(self, cavitation: str | None = None) -> Physics:
        """The scene's dimensionless groups: the one place a scene becomes solver input.

        ``cavitation`` is the model (default: the scene's own choice); "auto" is the solver's
        default model where the scene has a cavitation pressure (``Pi`` finite) and the classic
        film where it has none. The automatic switch of a scene (classic first, the floor only
        where the classic tension crosses it) is ``run.run_scene``'s: it asks for "off" first.
        With "off" and a cavitation pressure, ``Pi`` is kept (finite) and ignored by the solver.

        Raises SceneError when a group is outside what the solver accepts (the Physics' own
        range check; for a group above its range the message says what to change in the
        scene), or when a cavitation model is asked for a scene without a cavitation pressure.
        """
        model = self.cavitation if cavitation is None else cavitation
        if model not in CAVITATION_CHOICES:
            raise SceneError(f"cavitation must be one of {list(CAVITATION_CHOICES)}, got {model!r}")
        if model in ("reynolds", "jfo") and self.cavitation_pressure is None:
            raise SceneError(f"cavitation = {model!r} needs a cavitation pressure, and this scene "
                             f"has none ({self.cavitation_pressure_source or 'not given'}): give "
                             "fluid.cavitation_pressure (a pressure, 'vapour' or 'gas-saturated') "
                             "or fluid.tensile_strength")
        values = {"St": self.stokes, "eps": self.eps, "Pi": self.Pi, "cavitation": model}
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
                          "source": f.source},
                "v0_m_per_s": self.v0, "x0_m": self.x0}



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
