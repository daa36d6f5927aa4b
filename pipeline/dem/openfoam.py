"""The OpenFOAM ``localInteractionHW`` patch interaction (a third-party library), its law and snippet.

The library is StokesWallMPPIC (J. Williams, github.com/jvwilliams23/StokesWallMPPIC, OpenFOAM-6;
Williams et al. 2022), built as ``$(FOAM_USER_LIBBIN)/libLocalInteractionModelHW`` and loaded by
``libs ("libLocalInteractionModelHW.so");`` in ``system/controlDict``. Its ``correct()``
(``src/LocalInteractionHW.C``, read for this module, not copied) applies, to a parcel hitting a
``rebound`` patch with ``coeffStc != 0``, at the impact normal velocity ``Un``:

    St_L = (rho_p + 0.5 rhoF) Un d / (9 muP),    ln e = ln(e) - coeffStc / St_L,

and sticks the parcel (``active = false``) when ``ln e < -5.3`` (hard-coded: the entry
``eCutoffLog`` is read, ``src/patchInteractionDataHW.C``, but this branch overwrites it). ``mu``
takes ``mu Ut`` off the tangential velocity. Entries default to 0 (``e`` to 1) when absent.
The law is applied once, at impact, in closed form: what it realises is ``law`` below exactly.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

__all__ = ["LIBRARY", "LIBS_LINE", "DICTIONARY", "STICK_LOG_E", "law", "calibrate", "snippet"]

LIBRARY = "StokesWallMPPIC (github.com/jvwilliams23/StokesWallMPPIC), libLocalInteractionModelHW.so"
LIBS_LINE = 'libs ("libLocalInteractionModelHW.so");'
DICTIONARY = "constant/kinematicCloudProperties, subModels"
STICK_LOG_E = -5.3  # the library's hard-coded sticking cut-off on ln e


def law(st_l, e_max, coeff_stc):
    """The e the library applies at ``St_L`` (0 where it sticks the parcel)."""
    st_l = np.asarray(st_l, float)
    with np.errstate(divide="ignore"):
        log_e = math.log(e_max) - coeff_stc / st_l
    return np.where(log_e < STICK_LOG_E, 0.0, np.exp(log_e))


def calibrate(st_l, e, e_max0, c0, weights=None, e_cap=1.0):
    """``(e, coeffStc)``, ``e <= e_cap`` (the pair's e_dry), that minimise the squared error of
    ``law`` over every row, sticking ones included (the fit of the rebounding rows alone leaves the library rebounding where the
    model sticks). Returns ``(e_max, coeffStc, max_abs_error)``."""
    st_l, e = np.asarray(st_l, float), np.asarray(e, float)
    w = np.ones_like(e) if weights is None else np.asarray(weights, float)

    def cost(p):
        if not (0.0 < p[0] <= e_cap and p[1] > 0.0):
            return np.inf
        return float(np.sum(w * (law(st_l, p[0], p[1]) - e) ** 2))

    best = None
    # the cut-off makes the cost piecewise smooth: a few starts between the fit's C and the C
    # that puts the cut-off at the model's threshold
    for scale in (1.0, 1.2, 1.5, 2.0):
        r = optimize.minimize(cost, [min(e_max0, e_cap), c0 * scale], method="Nelder-Mead",
                              options={"xatol": 1e-6, "fatol": 1e-12, "maxiter": 2000})
        if best is None or r.fun < best.fun:
            best = r
    em, c = float(best.x[0]), float(best.x[1])
    return em, c, float(np.max(np.abs(law(st_l, em, c) - e)))


def snippet(s: dict, *, store: bool, header: tuple = ()) -> str:
    """The controlDict line and the kinematicCloudProperties entries of group settings ``s``;
    ``header``: comment lines (without ``//``) after the title: the e realised, its physics."""
    head = "".join(f"// {line}\n" for line in header)
    o = s["openfoam"]
    rep = "  // REPLACE: " if store else "  // "
    if not store:
        rho_note = "the scene's fluid density, as in the fit's St_L"
    elif o["density_ratio"] == 0.0:
        rho_note = "keep 0: the fit's St_L has no added mass (--density-ratio 0)"
    else:
        rho_note = (f"REPLACE: {o['density_ratio']:.3g} (the export's rho_f/rho_p) x your "
                    "particle density, as in the fit's St_L")
    return f"""// ehd-collision wet restitution for OpenFOAM: patchInteractionModel localInteractionHW
{head}// Library: {LIBRARY} (third party; build it for your OpenFOAM).
// Law applied at impact: St_L = (rho_p + rhoF/2) Un d / (9 muP),  e = e exp(-coeffStc/St_L),
// the parcel sticks where ln e < -5.3 (hard-coded in the library: eCutoffLog is not used).
// Walls only (a patch interaction). Largest error of this law against the model, every row:
// {o['realised_max_error']:.3f} in e (JSON restitution.json: openfoam.realised_error_by_St).
//
// 1) system/controlDict:
{LIBS_LINE}
//
// 2) constant/kinematicCloudProperties, inside subModels {{ ... }}:
patchInteractionModel localInteractionHW;

localInteractionHWCoeffs
{{
    patches
    (
        walls   // REPLACE: your wall patch name(s), e.g. "wall.*"
        {{
            type       rebound;
            e          {o['e']:.6g};
            mu         0;{"  // REPLACE: tangential loss (mu Ut taken off); 0: none" if store else "  // tangential loss (mu Ut taken off): the model says nothing on it"}
            rhoF       {o['rhoF']:.6g};{"  // " + rho_note}
            muP        {o['muP']:.6g};{rep}fluid viscosity [Pa s]
            coeffStc   {o['coeffStc']:.6g};
        }}
    );
}}
"""
