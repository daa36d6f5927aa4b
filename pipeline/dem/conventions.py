"""Stokes-number conventions of the codes and experiments that take a wet restitution e(St).

Ours (``solver``): ``St = m v0 / (6 pi mu a^2)`` with the reduced mass and radius; LIGGGHTS' hooke
``viscous`` model uses the same definition with ``meff`` and ``reff`` (with a wall: the sphere's
mass and radius), so it is the same number for a sphere on a wall and for two spheres (but
LIGGGHTS uses the instantaneous normal velocity, see ``liggghts``).

The others depend on the geometry (``GEOMETRIES``):

- the experimenters' ``St_exp = rho_p d v0 / (9 mu)`` of body 1 (Joseph et al. 2001; Gondret et al.
  2002) equals ours for a sphere on a wall and is half of ours for two equal spheres (our St uses
  the reduced mass and radius);
- Legendre et al. (2006) add half the fluid's added mass, ``St_L = St_exp (1 + rho_f / (2 rho_p))``;
  the OpenFOAM ``localInteractionHW`` patch model computes that ``St_L`` (walls only);
- YADE's ``ViscElMat`` lubrication option (``Ip2_ViscElMat_ViscElMat_ViscElPhys``, yade
  2023.02a) uses ``<rho> (R1 + R2) |vn| / mu`` with ``<rho>`` the mean of the two materials'
  densities and a wall counted with the sphere's radius. The exported YADE snippet gives walls a
  material of density 0, so against a wall ``<rho> = rho_p / 2`` and the number is
  ``rho_p a v / mu``: with that, ``St_yade = 4.5 St`` for a sphere on a wall and for two equal
  spheres alike, and one YADE fit serves both.

A sweep store is dimensionless (no materials): its rows carry both geometries, ``St_exp``/``St_L``
for a sphere on a wall (as before) and ``St_exp_pair``/``St_L_pair`` for two equal spheres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["CONVENTIONS", "GEOMETRIES", "DEM_KINDS", "DemKind", "stokes_numbers",
           "store_stokes_numbers"]

GEOMETRIES = ("sphere-wall", "sphere-sphere", "either")  # "either": a store (dimensionless)

# name -> (definition, who uses it)
CONVENTIONS = {
    "St": ("m v0 / (6 pi mu a^2), reduced m and a (a wall: the sphere's m and a)",
           "this model; LIGGGHTS hooke viscous (both geometries)"),
    "St_exp": ("rho_p d v0 / (9 mu), body 1 (store: a sphere on a wall, = St)",
               "Joseph et al. 2001; Gondret et al. 2002"),
    "St_L": ("(rho_p + rho_f/2) d v0 / (9 mu), body 1 (store: a sphere on a wall)",
             "Legendre et al. 2006; OpenFOAM localInteractionHW (walls)"),
    "St_yade": ("<rho> (R1 + R2) v0 / mu, <rho> the mean of the two materials' densities, the "
                "exported wall material of density 0 (both geometries: 4.5 St for equal spheres "
                "and for a sphere on a wall)", "YADE ViscElMat lubrication"),
    "St_exp_pair": ("rho_p d v0 / (9 mu) of two equal spheres, v0 the approach speed = St / 2 "
                    "(stores only)", "Joseph et al. 2001 (two-sphere experiments)"),
    "St_L_pair": ("(rho_p + rho_f/2) d v0 / (9 mu) of two equal spheres (stores only)",
                  "Legendre et al. 2006"),
}


@dataclass(frozen=True)
class DemKind:
    """The kind of DEM code an export is for (``ehd export-dem --for``): which e its contact law
    realises and at which speed that law sees the collision.

    e_column
        The CSV column of the e the exported law realises.
    speed_column
        The CSV column of the impact speed the law is calibrated against [m/s]: the speed the
        code sees at contact (a store, dimensionless, leaves it empty; ``speed_ratio_column`` is
        the same speed over ``v0``).
    speed_ratio_column
        That speed over ``v0``; every Stokes number of the law (each convention is linear in the
        speed) is the row's times this ratio. ``None``: ``v0`` itself (ratio 1).
    code, why
        The kind of code in words, and why it takes this e.
    """

    name: str
    e_column: str
    speed_column: str
    speed_ratio_column: str | None
    code: str
    why: str


# One place for "which e, at which speed" (docs/pipeline.md, "DEM export"; docs/scenes.md, "The
# approach from far away"). A dry DEM code has no fluid force: its particle keeps the speed it
# approached with down to contact, so its contact law must turn the approach speed at the
# reading distance x_ref into the departure speed there (e_far, both speeds read at x_ref): the
# law is calibrated against the speed at x_ref on the way in, not v0 at x0 (which the outer flow
# has already slowed). A resolved CFD-DEM code's fluid brings the particle to x0 at v0 itself.
DEM_KINDS = {
    "dry": DemKind(
        "dry", "e_far", "v_ref_m_s", "v_ref_over_v0", "dry DEM (LIGGGHTS or YADE without fluid "
        "coupling)", "no fluid force in the code: the contact law carries the whole loss the "
        "fluid causes, both speeds read at the reading distance x_ref (e_far, the outer flow's "
        "Stokes resistance and added mass from x_ref to x0 and back included); the law sees the "
        "approach speed at x_ref (the export's v_ref_m_s), which the particle keeps down to "
        "contact there"),
    "cfd-dem": DemKind(
        "cfd-dem", "e_wet", "v0_m_s", None, "resolved CFD-DEM",
        "the CFD computes the fluid force on the particle down to near contact (x0), so the "
        "contact law carries only the loss inside x0 (e_wet) and sees the speed at x0, v0"),
}

_YADE_OVER_ST = 4.5  # rho_p a v / mu over m v / (6 pi mu a^2) with m = 4/3 pi a^3 rho_p: 9/2


def stokes_numbers(st, *, geometry, rho_p, d, v0, mu, rho_f=0.0, rho_2=None, d_2=None) -> dict:
    """Every convention for one collision of a scene: body 1 of density ``rho_p`` and diameter
    ``d`` against a wall (``geometry="sphere-wall"``) or a sphere of ``rho_2``, ``d_2``."""
    st_exp = rho_p * d * v0 / (9.0 * mu)
    if geometry == "sphere-wall":
        rho_mean, radii = 0.5 * rho_p, d  # the snippet's wall material has density 0
    elif geometry == "sphere-sphere":
        rho_mean, radii = 0.5 * (rho_p + rho_2), 0.5 * (d + d_2)
    else:
        raise ValueError(f"geometry must be sphere-wall or sphere-sphere, got {geometry!r}")
    return {"St": st, "St_exp": st_exp, "St_L": st_exp * (1.0 + 0.5 * rho_f / rho_p),
            "St_yade": rho_mean * radii * v0 / mu, "St_exp_pair": "", "St_L_pair": ""}


def store_stokes_numbers(st, density_ratio=0.0) -> dict:
    """Every convention for a dimensionless store row (geometry "either"): ``St_exp``/``St_L``
    for a sphere on a wall, ``..._pair`` for two equal spheres; ``density_ratio`` is
    ``rho_f / rho_p``."""
    added = 1.0 + 0.5 * density_ratio
    return {"St": st, "St_exp": st, "St_L": st * added, "St_yade": _YADE_OVER_ST * st,
            "St_exp_pair": 0.5 * st, "St_L_pair": 0.5 * st * added}


def st_ratio(row: dict, convention: str) -> float:
    """``St_convention / St`` of a row of ``stokes_numbers``."""
    return row[convention] / row["St"] if row["St"] > 0 else math.nan
