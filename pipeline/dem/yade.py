"""YADE's ``ViscElMat`` lubrication option (yade 2023.02a), its law and snippet.

``Ip2_ViscElMat_ViscElMat_ViscElPhys`` (``pkg/dem/ViscoelasticPM.cpp``, read for this module, not
copied) sets, when a contact is created and both materials have ``lubrication=True`` (only in its
``young``/``en`` branch: no ``tc``, ``kn``, ``cn`` given):

    St = <rho> |vn| (R1 + R2) / <viscoDyn>,   en' = max(1e-3, <en> (1 + ln(<roughnessScale> / ((R1 + R2)/2)) / St)),

``<.>`` the mean of the two materials, ``vn`` the normal relative velocity then (the impact
speed), a wall counted with the sphere's radius; then a linear dashpot ``cn`` with that
restitution for the pair's reduced mass (Newton iteration to 1 % relative) and ``kn`` the harmonic
mean of ``2 young R`` of the two bodies. So

- the law is the threshold law ``e = en (1 - St_c / St)`` with ``St_c = ln(a / roughnessScale)``,
  ``a = (R1 + R2)/2``: ``roughnessScale = a exp(-St_c)``, a fitting constant far below any real
  roughness;
- YADE never sticks: ``e >= 1e-3`` (``E_FLOOR``);
- a body of mass 0 (a wall) is counted with the other body's mass, so the reduced mass is half the
  sphere's and the dashpot too weak (measured: e 0.05-0.1 too high against a wall); the snippet
  gives walls a mass 1e6 times the sphere's (reduced mass = the sphere's to 1e-6);
- ``<rho>`` averages the wall material's density in: the snippet's wall material has density 0
  (conventions: ``St_yade`` is then 4.5 St for both geometries);
- facet walls (``geom.facetBox``, meshes) enter the law through ``Ig2_Facet_Sphere_ScGeom`` as a
  sphere of radius 2R (measured in yade 2023.02a: e 0.27 too high in the issue's export, 0.32 on
  the glass wall of tests/test_dem_programs.py): the snippet states ``utils.wall`` only and its
  block 2 stops a run that has facets.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["E_FLOOR", "WALL_MASS_FACTOR", "law", "snippet"]

E_FLOOR = 1e-3
WALL_MASS_FACTOR = 1e6


def law(st_yade, en, st_c):
    """The e YADE applies at ``St_yade`` (threshold law, floored at ``E_FLOOR``)."""
    st_yade = np.asarray(st_yade, float)
    return np.maximum(E_FLOOR, en * (1.0 - st_c / st_yade))


def _dt(v, pair, steps) -> float:
    mass = 4.0 / 3.0 * math.pi * v["radius"] ** 3 * v["density"]
    return math.pi * math.sqrt((0.5 if pair else 1.0) * mass / (v["young"] * v["radius"])) / steps


def _title(y: dict, geometry: str, walls: bool, second: bool, header: tuple) -> list[str]:
    """The snippet's opening comments: title, ``header``, where to paste, engines, law, error."""
    return [
        "# ==== ehd-collision wet restitution for YADE 2023.02a: ViscElMat lubrication ====",
        *(f"# {line}" for line in header),
        f"# Geometry: {'sphere-wall and sphere-sphere' if geometry == 'either' else geometry}."
        " BLOCK 1 before the bodies; bodies: sphere(..., material=ehd_mat)"
        + (" and the second sphere material=ehd_mat2" if second else "")
        + (", walls: wall(..., material=ehd_wall_mat)" if walls else "") + ".",
        *(["# Walls: utils.wall only. Facets (geom.facetBox, meshes) enter the lubrication law as a",
           "# sphere of radius 2R and realise e up to 0.3 too high: block 2 stops a run that has them."]
          if walls else []),
        "# Engines: InteractionLoop([Ig2_Sphere_Sphere_ScGeom()" + (", Ig2_Wall_Sphere_ScGeom()" if walls else "")
        + "], [Ip2_ViscElMat_ViscElMat_ViscElPhys()], [Law2_ScGeom_ViscElPhys_Basic()]).",
        f"# Law at impact: e = max(1e-3, en (1 - ln(a/roughnessScale) / St_yade)), {y['convention']}.",
        f"# YADE never sticks (e >= 1e-3). Largest error against the model, every row: "
        f"{y['realised_max_error']:.3f} in e (restitution.json: yade.realised_error_by_St).",
    ]


def snippet(y: dict, *, geometry: str, values: dict, placeholders: bool, steps: int,
            header: tuple = ()) -> str:
    """Two blocks: the materials and time step (before the bodies) and, where walls occur, the
    wall mass (after them). ``values``: density, radius, young, poisson, viscosity (the scene's,
    or example values marked REPLACE for a store). ``header``: comment lines (without ``#``)
    after the title: the e realised, its physics."""
    rep = "  # REPLACE: " if placeholders else "  # the scene's "
    walls = geometry in ("sphere-wall", "either")
    pair = geometry in ("sphere-sphere", "either")
    v = values
    lines = [
        *_title(y, geometry, walls, "radius2" in v, header),
        "# ---- BLOCK 1 ----",
        "import math",
        f"ehd_density = {v['density']:.6g}{rep}particle density [kg/m^3]",
        f"ehd_radius = {v['radius']:.6g}{rep}particle radius [m]"
        + (" (equal spheres)" if pair and placeholders else ""),
        f"ehd_young = {v['young']:.6g}{rep}Young's modulus [Pa] (kn = 2 young R: the contact time, not e)",
        f"ehd_poisson = {v['poisson']:.6g}{rep}Poisson's ratio (tangential stiffness only)",
        f"ehd_viscosity = {v['viscosity']:.6g}{rep}fluid viscosity [Pa s] (enters St_yade)",
        "ehd_friction_angle = 0.5  # REPLACE: your friction angle [rad] (no effect head-on)",
        f"ehd_en = {y['en']:.6g}",
    ]
    second = "radius2" in v  # two spheres of different size or material: a second material
    if second:
        lines += [
            f"ehd_density2 = {v['density2']:.6g}  # the scene's second sphere's density [kg/m^3]",
            f"ehd_radius2 = {v['radius2']:.6g}  # the scene's second sphere's radius [m]",
            f"ehd_young2 = {v['young2']:.6g}  # the scene's second sphere's Young's modulus [Pa]",
            f"ehd_poisson2 = {v['poisson2']:.6g}  # the scene's second sphere's Poisson's ratio",
            "ehd_a = 0.5 * (ehd_radius + ehd_radius2)  # YADE's (R1 + R2)/2",
        ]
    else:
        lines.append("ehd_a = ehd_radius  # YADE's (R1 + R2)/2 (a wall counts with the sphere's R)")
    lines += [
        f"ehd_roughness = ehd_a * math.exp(-{y['st_c']:.6g})  # a exp(-St_c): a fitting constant",
        "ehd_mat = O.materials.append(ViscElMat(young=ehd_young, poisson=ehd_poisson, "
        "density=ehd_density, frictionAngle=ehd_friction_angle, en=ehd_en, lubrication=True, "
        "viscoDyn=ehd_viscosity, roughnessScale=ehd_roughness, label='ehd'))",
    ]
    if second:
        lines.append(
            "ehd_mat2 = O.materials.append(ViscElMat(young=ehd_young2, poisson=ehd_poisson2, "
            "density=ehd_density2, frictionAngle=ehd_friction_angle, en=ehd_en, lubrication=True, "
            "viscoDyn=ehd_viscosity, roughnessScale=ehd_roughness, label='ehd2'))  # sphere 2")
    if walls:
        lines.append(
            "# walls: density 0 (YADE averages the densities in St), the rest as the spheres'")
        lines.append(
            "ehd_wall_mat = O.materials.append(ViscElMat(young=ehd_young, poisson=ehd_poisson, "
            "density=0.0, frictionAngle=ehd_friction_angle, en=ehd_en, lubrication=True, "
            "viscoDyn=ehd_viscosity, roughnessScale=ehd_roughness, label='ehd_wall'))")
    lines.append("ehd_mass = 4.0 / 3.0 * math.pi * ehd_radius**3 * ehd_density")
    if second:
        lines += [
            "ehd_mass2 = 4.0 / 3.0 * math.pi * ehd_radius2**3 * ehd_density2",
            "# time step: at most 1/%d of the contact time pi sqrt(m_red / kn)," % steps,
            "# kn = 1 / (1/(2 young R1) + 1/(2 young2 R2))",
            "ehd_dt_max = math.pi * math.sqrt(ehd_mass * ehd_mass2 / (ehd_mass + ehd_mass2) / "
            f"(1.0 / (0.5 / (ehd_young * ehd_radius) + 0.5 / (ehd_young2 * ehd_radius2)))) / {steps}",
        ]
    else:
        lines += [
            "# time step: at most 1/%d of the contact time pi sqrt(m_red / kn), kn = young R;" % steps,
            "# " + ("the shorter of the geometries (two equal spheres: m_red = m/2; a wall: m)"
                    if pair and walls else "m_red = m/2 (two equal spheres)" if pair
                    else "m_red = m (the wall's mass is set in block 2)"),
            f"ehd_dt_max = math.pi * math.sqrt({'0.5 * ' if pair else ''}ehd_mass / (ehd_young * ehd_radius)) / {steps}"
            f"  # {_dt(v, pair, steps):.3g} s with the values above",
        ]
    lines.append("# set O.dt = ehd_dt_max or smaller")
    return "\n".join(lines + (_WALL_BLOCK if walls else [])) + "\n"


# block 2 (walls only): the walls' mass, and a stop where facets would realise too high an e
_WALL_BLOCK = [
    "# ---- BLOCK 2, after the bodies (before O.run) ----",
    "# YADE counts a massless wall with the sphere's mass (e ~0.1 too high): give walls a",
    f"# mass {WALL_MASS_FACTOR:.0e} times the sphere's (they stay fixed; only the contact law sees it)",
    "for ehd_b in O.bodies:",
    "    if isinstance(ehd_b.shape, Facet):",
    "        raise RuntimeError('ehd-collision: facet walls realise e up to 0.3 too high "
    "with this law; use utils.wall')",
    "    if not isinstance(ehd_b.shape, Sphere) and ehd_b.state.mass == 0:",
    f"        ehd_b.state.mass = {WALL_MASS_FACTOR:.0e} * ehd_mass",
]
