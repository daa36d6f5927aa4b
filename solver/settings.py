"""Accuracy presets: every numerical choice of a scene, checked (the physics is solver/physics.py).

A preset fixes every numerical choice that can change an answer: the radial grid (cells across
the uniform inner region, stretch of the outer cells, how far the grid reaches), the time-step
tolerance, and the two thresholds that decide where the analytic rigid solution is used
(``switch``: W(0)/X at which the coupled solution takes over on approach; ``release``: max|W|/X
below which it hands back on the way out).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace

__all__ = ["Numerics", "PRESETS", "resolve"]


@dataclass(frozen=True)
class Numerics:
    """Numerical settings of one scene (all dimensionless)."""

    n_inner: int  # cells across the inner (contact) region of the grid
    axis_ratio: float  # cell size at the axis relative to the inner region's
    axis_extent: float  # refined zone near the axis, as a fraction of the inner radius
    stretch: float  # growth factor of successive outer cells
    outer_extent: float  # grid end, in units of the inner region's radius
    max_rel: float  # largest outer cell relative to its radius
    inner_factor: float  # inner radius = inner_factor * max(Hertz contact radius, 2)
    rtol: float  # local error tolerance of the time stepping
    switch: float  # W(0)/X at which the rigid approach hands over to the coupled solution
    release: float  # max|W|/X below which the departing spheres are rigid again
    max_steps: int  # step budget: a scene that needs more fails with status "max_steps"
    save_profiles: bool = True  # keep P(R), W(R) at every step (sweeps switch this off)
    # highest order of the BDF time stepping, 1-5 (integration/stepper.py); 2 is BDF2, above it
    # the loop chooses each step's order (a film on rough surfaces stays at 2, a cavitating one
    # from its first cavity on: model/step.py, smooth_in_time and smooth_from_now)
    max_order: int = 2
    # the time tolerance where the order may rise above 2 (max_order > 2, a film smooth in
    # time) is rtol times this; a film that stays at BDF2 keeps rtol
    high_order_rtol_factor: float = 1.0
    # solve the scene on this grid and on ``halved()`` and report the observables whose grid
    # error is smooth extrapolated, f + (f - f_half)/3 (solver/extrapolation.py)
    extrapolate: bool = False

    def as_dict(self) -> dict:
        return asdict(self)

    def halved(self) -> "Numerics":
        """The same settings on the grid with half the cells: half the inner cells, the outer
        cells growing twice as fast (``stretch - 1`` doubled) and twice as wide (``max_rel``), as
        the reference levels of benchmarks/bench_accuracy.py refine; the axis cells stay the same
        fraction of an inner cell. The time tolerance, orders and thresholds stay: their errors
        are the same in both solves."""
        return replace(self, n_inner=self.n_inner // 2, stretch=1.0 + 2.0 * (self.stretch - 1.0),
                       max_rel=2.0 * self.max_rel, extrapolate=False)


PRESETS = {
    # chosen from the accuracy study in benchmarks/accuracy.md (errors and times per preset).
    # Orders up to 5 where the film is smooth in time, at 4 times the BDF2 tolerance: of the
    # factors 3, 4 and 6 tried, the largest at which every preset's largest errors in the
    # accuracy table (over the panel and over St <= 30) stay at or below those of BDF2 at rtol,
    # the presets of solver 1.11.0 (with 6, fast's h_m rose from 2.34e-2 to 2.59e-2; standard and
    # fine stayed below at 6, but one factor holds for every preset). rtol stays the tolerance of
    # the films that stay at BDF2 (cavitation floor, rough surfaces): their results do not move
    "fast": Numerics(n_inner=32, axis_ratio=0.1, axis_extent=0.25, stretch=1.25, outer_extent=30.0,
                     max_rel=0.3, inner_factor=1.2, rtol=3e-4, switch=0.01, release=0.003,
                     max_steps=20000, max_order=5, high_order_rtol_factor=4.0),
    "standard": Numerics(n_inner=64, axis_ratio=0.1, axis_extent=0.25, stretch=1.2,
                         outer_extent=30.0, max_rel=0.3, inner_factor=1.2, rtol=5e-5, switch=0.001,
                         release=0.0003, max_steps=50000, max_order=5,
                         high_order_rtol_factor=4.0),
    # A pair since solver 1.15.0: the film on 80 inner cells (the axis refined to 0.05 of a
    # cell) and on 40, extrapolated (``extrapolate``; benchmarks/extrapolation.md): every error
    # of the accuracy table below the single 128-cell grid's of solver 1.14 on both panels
    # there, at 0.62x its CPU time; the fine preset's tolerance and thresholds as before
    "fine": Numerics(n_inner=80, axis_ratio=0.05, axis_extent=0.25, stretch=1.16,
                     outer_extent=30.0, max_rel=0.3, inner_factor=1.2, rtol=1e-5, switch=0.0002,
                     release=0.00005, max_steps=200000, max_order=5, high_order_rtol_factor=4.0,
                     extrapolate=True),
}

_BOUNDS = {
    "n_inner": (4, 2000),
    "axis_ratio": (0.01, 1.0),
    "axis_extent": (0.0, 1.0),
    "stretch": (1.0, 2.0),
    "outer_extent": (5.0, 1e4),
    "max_rel": (0.01, 1.0),
    "inner_factor": (0.5, 10.0),
    "rtol": (1e-10, 0.1),
    "switch": (1e-12, 1.0),
    "release": (1e-13, 1.0),
    "max_steps": (10, 10**8),
    "max_order": (0, 5),
    "high_order_rtol_factor": (0.0, 100.0),
}
# the settings that count something (n_inner, max_steps, max_order): whole numbers
_WHOLE = {f.name for f in fields(Numerics) if f.type == "int"}


def _check_number(name, value, lo, hi, *, open_lo=True):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    ok_lo = v > lo if open_lo else v >= lo
    if not ok_lo or v > hi:
        lb = "(" if open_lo else "["
        raise ValueError(f"{name} = {value!r} is outside its valid range {lb}{lo:g}, {hi:g}]")
    return v


def _check_halves(numerics: Numerics) -> None:
    """``extrapolate`` pairs the grid with ``halved()``: that grid must be within ``_BOUNDS``
    and exactly half (an even ``n_inner``)."""
    half = numerics.halved()
    n_lo, stretch_hi, rel_hi = _BOUNDS["n_inner"][0], _BOUNDS["stretch"][1], _BOUNDS["max_rel"][1]
    if (numerics.n_inner % 2 or half.n_inner <= n_lo or half.stretch > stretch_hi
            or half.max_rel > rel_hi):
        raise ValueError(
            "extrapolate pairs the grid with the same grid at half its cells (n_inner/2, stretch "
            f"- 1 and max_rel doubled): n_inner must be even and at least {2 * (n_lo + 1)}, "
            f"stretch at most {1.0 + (stretch_hi - 1.0) / 2:g} and max_rel at most "
            f"{rel_hi / 2:g} (got {numerics.n_inner}, {numerics.stretch:g}, "
            f"{numerics.max_rel:g})")


# the settings that shape the radial grid (integration/radii.py: reference_radii's arguments)
_GRID = ("n_inner", "axis_ratio", "axis_extent", "stretch", "outer_extent", "max_rel")


def resolve(accuracy: str = "standard", **overrides) -> Numerics:
    """The preset ``accuracy`` with explicit overrides applied and checked."""
    import numpy as np

    from .physics import is_real_number

    if not isinstance(accuracy, str) or accuracy not in PRESETS:
        raise ValueError(f"accuracy must be one of {sorted(PRESETS)}, got {accuracy!r}")
    numerics = PRESETS[accuracy]
    clean = {}
    for name, value in overrides.items():
        if value is None:
            continue
        if name in ("save_profiles", "extrapolate"):  # from a sweep file too: "no" is not False
            if not isinstance(value, (bool, np.bool_)):  # numpy's too
                raise ValueError(f"{name} must be true or false, got {value!r}")
            clean[name] = bool(value)
            continue
        if name not in _BOUNDS:
            valid = sorted([*_BOUNDS, "save_profiles", "extrapolate"])
            raise ValueError(f"unknown numerical setting {name!r}; valid settings: {valid}")
        if not is_real_number(value):
            # true is 1 and "1e-4" a number to float(): max_order = true ran BDF1 unannounced
            raise ValueError(f"{name} must be a number, got {value!r}")
        lo, hi = _BOUNDS[name]
        v = _check_number(name, value, lo, hi, open_lo=name not in ("stretch",))
        if name in _WHOLE:
            if v != int(v):
                raise ValueError(f"{name} must be a whole number, got {value!r}")
            v = int(v)
        clean[name] = v
    numerics = replace(numerics, **clean)
    if numerics.extrapolate:
        _check_halves(numerics)
    if numerics.release >= numerics.switch:
        raise ValueError(
            f"release ({numerics.release:g}) must be smaller than switch ({numerics.switch:g}): "
            "the coupled solution hands back only once the deformation has relaxed below the "
            "level at which it took over"
        )
    if clean.keys() & set(_GRID):  # the grid these settings make (a preset's is known fine)
        from .integration.radii import reference_radii

        reference_radii(*(getattr(numerics, name) for name in _GRID))
    return numerics
