"""Stokes-number conventions of the codes and experiments that take a wet restitution e(St).

Ours (``solver``): ``St = m v0 / (6 pi mu a^2)`` with the reduced mass and radius; LIGGGHTS' hooke
``viscous`` model uses the same definition with ``meff`` and ``reff`` (but the instantaneous normal
velocity, see ``liggghts``). For a sphere of diameter ``d`` on a wall it equals the experimenters'
``rho_p d v / (9 mu)`` (Joseph et al. 2001; Gondret et al. 2002); for two spheres the experimenters'
number is that of the moving sphere, ours the reduced one (twice as large for equal spheres).
Legendre et al. (2006) add half the fluid's added mass, ``St_L = St_exp (1 + rho_f / (2 rho_p))``;
the OpenFOAM ``localInteractionHW`` patch model computes that same ``St_L``. YADE's ``ViscElMat``
lubrication option uses ``rho_p d v / mu`` (no factor 9).
"""

from __future__ import annotations

import math

__all__ = ["CONVENTIONS", "stokes_numbers"]

# name -> (definition, who uses it)
CONVENTIONS = {
    "St": ("m v0 / (6 pi mu a^2), reduced m and a", "this model; LIGGGHTS hooke viscous"),
    "St_exp": ("rho_p d v0 / (9 mu), body 1", "Joseph et al. 2001; Gondret et al. 2002"),
    "St_L": ("(rho_p + rho_f/2) d v0 / (9 mu), body 1", "Legendre et al. 2006; OpenFOAM "
             "localInteractionHW"),
    "St_yade": ("rho_p d v0 / mu, body 1", "YADE ViscElMat lubrication"),
}


def stokes_numbers(st, *, rho_p=None, d=None, v0=None, mu=None, rho_f=0.0) -> dict:
    """Every convention of ``CONVENTIONS`` for one collision. With the body-1 quantities
    (``rho_p``, diameter ``d``, ``v0``, ``mu``) the experimenters' number is computed from them;
    without (a dimensionless sweep) the collision is taken as a sphere on a wall, where
    ``St_exp = St``; ``rho_f`` then enters as the density ratio ``rho_f / rho_p`` only."""
    if rho_p is not None and d is not None and mu is not None and v0 is not None:
        st_exp = rho_p * d * v0 / (9.0 * mu)
        ratio = rho_f / rho_p
    else:
        st_exp = st
        ratio = rho_f  # given as the density ratio rho_f / rho_p
    return {"St": st, "St_exp": st_exp, "St_L": st_exp * (1.0 + 0.5 * ratio),
            "St_yade": 9.0 * st_exp}


def st_ratio(row: dict, convention: str) -> float:
    """``St_convention / St`` of a row of ``stokes_numbers``."""
    return row[convention] / row["St"] if row["St"] > 0 else math.nan
