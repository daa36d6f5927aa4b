"""Two grids, one answer: a scene's observables from its grid and the grid with half the cells,
Richardson-extrapolated (``Numerics.extrapolate``, the fine preset since solver 1.15.0).

The film's discretisation is second order in space (benchmarks/accuracy.md: observed orders
1.95-1.99, median over the panel), so an observable's grid error falls 4x when the cells halve
(``Numerics.halved``), and ``f + (f - f_half) / 3`` cancels its leading term. What both solves
share, the time error at one tolerance and the rigid phases' thresholds, passes through as it is
in ``f``. Measured against converged references (benchmarks/extrapolation.md): on 80 inner cells
paired with 40, every error of the accuracy table fell below the single 128-cell grid's, on the
accuracy panel and on a hold-out panel, for the classic film, both cavitation floors, Barus films,
rough surfaces and slip, at 0.62x the CPU time.

``EXTRAPOLATED`` are the observables whose grid error was measured smooth (each one's largest
error over 31 scenes below the 128-cell grid's), and the approach's peak pressure
``p_max_approach``, from which the caller derives the peak viscosity and ``solidified`` as a
single solve does (collision.py). Left as the finer solve's, measured no better or worse
extrapolated: the lowest pressure ``p_min`` and the dimple's depth and time (extremes of one
cell's value, whose cell changes with the grid), the time of the peak force and the central gap
at the peak pressure (no better), the strain energy at the hand-over (the threshold's), the
cavity's size and onset (not measured); and the energy closure, which is the finer solve's own.
The profiles and series are the finer solve's; its counts are both solves'.

Observables that change regime at a threshold are not smooth across it, and a pair may straddle
it (one grid rebounds, the other not): each is extrapolated only where the finer solve, the
coarser one and the extrapolation agree on its regime, and with it its ``GROUPS`` (a rebound's
speed and time; the departure's ``x_e``, ``e_wet`` and ``e_x0``, whose regimes are tied: a
sphere that passes back out through ``x_ref`` departs with ``e_wet > 0``; the approach's closest
gap and the time the spheres stop, or creep to rest). Elsewhere the finer solve's values stay.
"""

from __future__ import annotations

import math

from .observables import OBSERVABLES

__all__ = ["EXTRAPOLATED", "GROUPS", "COUNTS", "extrapolated", "combine"]

EXTRAPOLATED = ("v_r", "tau_max_rebound", "e_wet", "e_x0", "ln_x_e_x1", "h_m_x1",
                "h_m_approach_x1", "tau_v_zero", "tau_max_deformation", "peak_force", "p_max",
                "p_max_approach", "w0_max_x1", "x_min_x1")
# extrapolated together or not at all (the others each alone)
GROUPS = (("v_r", "tau_max_rebound"), ("ln_x_e_x1", "e_wet", "e_x0"),
          ("h_m_approach_x1", "tau_v_zero"))
# the order combine walks them: each group, then each other observable alone
_UNITS = (*GROUPS, *((name,) for name in EXTRAPOLATED
                     if not any(name in group for group in GROUPS)))
# the cost counters, which a pair sums
COUNTS = tuple(o.name for o in OBSERVABLES if o.kind == "count")


def extrapolated(fine: float, coarse: float) -> float:
    """``fine + (fine - coarse) / 3``: the leading grid error of a second-order solution removed
    (``coarse`` on half the cells)."""
    return fine + (fine - coarse) / 3.0


def _thresholds(result, name):
    """Where ``name`` changes regime: ``x_e`` beyond ``x0`` (escaped) and beyond ``x_ref``
    (``e_wet > 0``); every other observable at 0 (a speed that is 0 where the spheres stick,
    ``x_min`` below 0 where the solids overlap)."""
    if name == "ln_x_e_x1":
        return (math.log(result.x0_over_x1), math.log(result.x_ref_x0 * result.x0_over_x1))
    return (0.0,)


def _regime(value, thresholds):
    return (math.isfinite(value), *(value > t for t in thresholds))


def combine(result, coarse) -> bool:
    """``result`` (the finer solve) with its ``EXTRAPOLATED`` observables extrapolated against
    ``coarse`` (the solve on half the cells), in place, where ``_regime`` allows, and both
    solves' counts; ``result.extrapolated`` and the return value say whether the pair was
    combined (both solves ok). The invariants of a single solve hold after it: the closest
    approach at most the approach's and at most ``x_e``, ``x_min`` at most ``x_e``, ``p_max`` at
    least the approach's peak."""
    for name in COUNTS:
        setattr(result, name, getattr(result, name) + getattr(coarse, name))
    if result.status != "ok" or coarse.status != "ok":
        return False
    for group in _UNITS:
        new, agree = {}, True
        for member in group:
            f, c = getattr(result, member), getattr(coarse, member)
            e = extrapolated(f, c) if math.isfinite(f) and math.isfinite(c) else f
            t = _thresholds(result, member)
            agree = agree and _regime(f, t) == _regime(c, t) == _regime(e, t)
            new[member] = e
        if agree:
            for member, value in new.items():
                setattr(result, member, value)
    result.h_m_x1 = min(result.h_m_x1, result.h_m_approach_x1, result.x_e_x1)
    result.x_min_x1 = min(result.x_min_x1, result.x_e_x1)
    result.p_max = max(result.p_max, result.p_max_approach)
    result.extrapolated = True
    return True
