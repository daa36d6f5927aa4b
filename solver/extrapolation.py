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
error over 31 scenes below the 128-cell grid's). Left as the finer solve's, measured no better or
worse extrapolated: the lowest pressure ``p_min`` and the dimple's depth and time (extremes of
one cell's value, whose cell changes with the grid), the time of the peak force and the central
gap at the peak pressure (no better), the strain energy at the hand-over (the threshold's),
the cavity's size and onset (not measured); and the energy closure, which is the finer solve's
own. The profiles and series are the finer solve's; its counts are both solves'.
"""

from __future__ import annotations

import math

__all__ = ["EXTRAPOLATED", "IN_LOG", "COUNTS", "extrapolated", "combine"]

EXTRAPOLATED = ("v_r", "e_wet", "e_x0", "h_m_x1", "h_m_approach_x1", "ln_x_e_x1",
                "tau_max_deformation", "tau_v_zero", "tau_max_rebound", "peak_force", "p_max",
                "w0_max_x1", "x_min_x1")
# extrapolated in their logarithm (a ratio spanning decades; measured so: benchmarks/piezoviscous)
IN_LOG = ("viscosity_ratio_max_approach",)
# a speed that is 0 where the spheres stick: not smooth across the threshold, where one grid may
# rebound and the other not
STICKING = ("v_r", "e_wet", "e_x0")
LOG_MAX = math.log(1.7976931348623157e308)  # the largest double's logarithm
COUNTS = ("steps", "rejected_steps", "newton_iterations", "lu_factorizations",
          "higher_order_steps")


def extrapolated(fine: float, coarse: float) -> float:
    """``fine + (fine - coarse) / 3``: the leading grid error of a second-order solution removed
    (``coarse`` on half the cells)."""
    return fine + (fine - coarse) / 3.0


def combine(result, coarse) -> None:
    """``result`` (the finer solve) with its ``EXTRAPOLATED`` observables extrapolated against
    ``coarse`` (the solve on half the cells), in place, and both solves' counts. Each observable
    only where both values are finite, and a speed of ``STICKING`` only where both rebound;
    ``result.extrapolated`` says whether the pair was combined (both solves ok)."""
    for name in COUNTS:
        setattr(result, name, getattr(result, name) + getattr(coarse, name))
    if result.status != "ok" or coarse.status != "ok":
        return
    for name in EXTRAPOLATED:
        f, c = getattr(result, name), getattr(coarse, name)
        if not (math.isfinite(f) and math.isfinite(c)):
            continue
        if name in STICKING and not (f > 0.0 and c > 0.0):
            continue
        setattr(result, name, extrapolated(f, c))
    for name in IN_LOG:
        f, c = getattr(result, name), getattr(coarse, name)
        if f > 0.0 and c > 0.0 and math.isfinite(f) and math.isfinite(c):
            log_value = extrapolated(math.log(f), math.log(c))
            # beyond the double range it is inf, as a single solve reports it (observables.py)
            setattr(result, name, math.exp(log_value) if log_value < LOG_MAX else math.inf)
    # the whole collision's closest approach is at most the approach's
    result.h_m_x1 = min(result.h_m_x1, result.h_m_approach_x1)
    result.extrapolated = True
