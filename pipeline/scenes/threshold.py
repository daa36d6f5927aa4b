"""The sticking threshold of a scene's materials: the impact Stokes number (and speed, or size)
below which its spheres stick, found along the same path as ``ehd restitution`` (``v0``, the
approach speed or both radii times a factor; eps moves with them) by bisection between a
sticking and a rebounding scene. Sticking is read in the e of a kind of code: ``e_wet = 0`` (a
resolved CFD-DEM code: they never leave the lubrication region) or ``e_far = 0`` (a dry DEM
code: the outer flow stops them before they are back at ``x_ref``); a scene whose outer flow
stops the spheres before ``x0`` sticks in both.

``ehd restitution SCENE --threshold`` prints it (``--plot`` marks it); from Python::

    from pipeline.scenes.commands import load_scene
    from pipeline.scenes.threshold import sticking_threshold
    t = sticking_threshold(load_scene("examples/glass_beads_water.toml"))
    t.St_c, t.value, t.unit     # St_c, and the impact speed there in "m/s"
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Threshold", "SolveFailed", "sticking_threshold", "format_threshold", "RTOL"]

RTOL = 1e-3  # the bracket's final relative width: below the presets' errors on x_e near St_c
# (standard, on ln x_e: benchmarks/accuracy.md: 1.1 %), which decide whether a scene sticks


@dataclass(frozen=True)
class Threshold:
    """``St_c`` (the bracket's geometric middle) and the path's quantity there."""

    vary: str  # "v0", "approach_speed" or "radius"
    St_c: float | None  # None: no change from sticking to rebounding on the path (``note``)
    factor: float | None  # on the scene's v0, approach speed or radii
    value: float | None  # v0 [m/s], the approach speed [m/s] or body1's radius [m] at St_c
    unit: str
    bracket: tuple  # (sticking factor, rebounding factor)
    solves: int
    note: str = ""
    failed: bool = False  # a solve the bisection needed failed (``note`` says which and why)
    key: str = "e_wet"  # the e whose 0 is sticking: "e_wet" or "e_far"
    approach_speed: float | None = None  # the approach speed at St_c [m/s] (None: no outer flow)
    v0: float | None = None  # the speed at x0 at St_c [m/s]


class SolveFailed(ValueError):
    """A solve along the path failed (its status and message)."""


def sticks(result, key: str) -> bool:
    """Whether a solved path scene (a ``SceneResult``, or None: stopped before ``x0``) sticks
    in ``key``."""
    return result is None or getattr(result.collision, key) == 0.0


def _sticks(scene, vary, factor, accuracy, key):
    from pipeline.dem.export import scene_path

    from .run import run_scene
    from .scene import SceneError

    try:
        at = scene_path(scene, vary, [factor])[0]
        if at.stops_outside:
            return True
        r = run_scene(at, accuracy=accuracy, save_profiles=False, sensitivity_solves=False)
    except SceneError as exc:  # refused there (e.g. eps beyond 0.1 at a larger size)
        raise SolveFailed(f"the scene at {vary} x {factor:.4g} is refused: {exc}") from None
    if not r.collision.ok:
        raise SolveFailed(f"the solve at {vary} x {factor:.4g} failed ({r.collision.status}): "
                          f"{r.collision.message}")
    return sticks(r, key)


def sticking_threshold(scene, vary: str = "v0", accuracy: str = "standard", *,
                       start: float = 0.1, stop: float = 10.0, n: int = 9, results=None,
                       rtol: float = RTOL, key: str = "e_wet") -> Threshold:
    """Bisect the path ``scene_path(scene, vary, factors)`` for the change from sticking to
    rebounding.

    Parameters
    ----------
    scene : pipeline.scenes.scene.Scene
    vary : {"v0", "approach_speed", "radius"}
    start, stop, n : float, float, int
        The first bracket is looked for on ``n`` log-spaced factors in ``[start, stop]``
        (``ehd restitution``'s ``--from``, ``--to``, ``--n``).
    results : list of SceneResult, None or str, optional
        Those factors already solved, one entry each in order: its result, None for a scene
        stopped before ``x0``, or why it was skipped (``ehd restitution`` passes its path's).
    rtol : float
        Stop when the bracket's factors differ by less than this, relatively.
    key : {"e_wet", "e_far"}
        The e whose 0 is sticking (resolved CFD-DEM or dry DEM).

    Returns
    -------
    Threshold
        With ``St_c = None`` and a ``note`` when every scene on the path sticks or rebounds, or
        (``failed``) when a solve the bisection needed failed. A failed solve of the first
        ``n`` factors is left out of the search, as ``ehd restitution`` leaves it out of its
        table (a failed scene's ``e_wet`` says nothing about sticking).
    """
    import numpy as np

    from pipeline.dem.export import PATHS, path_value

    factors = [float(f) for f in np.geomspace(start, stop, n)]
    unit = PATHS[vary][1]
    outcome, solves = _outcome(scene, vary, factors, accuracy, key, results)
    common = dict(vary=vary, unit=unit, key=key)
    # the first rebounding factor after a sticking one
    change = next((i for i in range(1, len(outcome))
                   if outcome[i - 1][1] and not outcome[i][1]), None)
    if change is None:
        return Threshold(St_c=None, factor=None, value=None, bracket=(), solves=solves,
                         note=_no_change(outcome, vary, start, stop), **common)
    lo, hi = outcome[change - 1][0], outcome[change][0]
    while hi / lo - 1.0 > rtol:
        mid = math.sqrt(lo * hi)
        solves += 1
        try:
            stuck = _sticks(scene, vary, mid, accuracy, key)
        except SolveFailed as exc:
            return Threshold(St_c=None, factor=None, value=None, bracket=(lo, hi), solves=solves,
                             failed=True, note=f"between {vary} x {lo:.4g} (sticks) and x "
                                                f"{hi:.4g} (rebounds) {exc}", **common)
        lo, hi = (mid, hi) if stuck else (lo, mid)
    factor = math.sqrt(lo * hi)
    from pipeline.dem.export import scene_path

    at = scene_path(scene, vary, [factor])[0]
    approach = path_value(at, "approach_speed")
    return Threshold(St_c=at.stokes, factor=factor, value=path_value(at, vary),
                     bracket=(lo, hi), solves=solves, approach_speed=approach, v0=at.v0,
                     **common)


def _outcome(scene, vary, factors, accuracy, key, results):
    """``([(factor, sticks)], solves)`` of the path's factors in increasing order (St grows with
    v0 and with size, St ~ v0 a, whichever way the path ran): from ``results`` where it has an
    entry per factor (a skipped point, a str, and a failed solve left out), else solved here."""
    if results is not None and len(results) == len(factors):
        outcome = [(f, sticks(r, key)) for f, r in zip(factors, results)
                   if r is None or (not isinstance(r, str) and r.collision.ok)]
        return sorted(outcome), 0
    outcome = []
    for f in factors:
        try:
            outcome.append((f, _sticks(scene, vary, f, accuracy, key)))
        except SolveFailed:
            continue
    return sorted(outcome), len(factors)


def _no_change(outcome, vary, start, stop) -> str:
    """The note of a path without a change from sticking to rebounding: over the factors it
    solved, never more (``--n 1`` had claimed the whole of ``--from``/``--to``)."""
    if not outcome:
        return (f"every {vary} from {min(start, stop):g} to {max(start, stop):g} times the "
                "scene's failed to solve; change the scene or the path")
    stuck_all = [stuck for _, stuck in outcome]
    what = "rebound" if not any(stuck_all) else "stick" if all(stuck_all) else "alternate"
    lo, hi = outcome[0][0], outcome[-1][0]
    where = f"at {vary} x {lo:.4g}" if len(outcome) == 1 else \
        f"at every {vary} solved from {lo:.4g} to {hi:.4g} times the scene's"
    return f"the spheres {what} {where}; widen --from/--to, or more --n"


# the e a threshold is read in -> the code kind it is for
CODE_OF = {"e_wet": "resolved CFD-DEM", "e_far": "dry DEM"}


def format_threshold(t: Threshold) -> str:
    """One line for the command line."""
    head = f"sticking threshold in {t.key} ({CODE_OF[t.key]})"
    if t.failed:
        return f"{head}: not found: {t.note}"
    if t.St_c is None:
        return f"{head}: not on this path ({t.note})"
    from pipeline.dem.export import PATHS

    from .units import format_quantity

    approach = "" if t.approach_speed is None or t.vary == "approach_speed" else \
        f", approach speed {format_quantity(t.approach_speed, 'm/s')}"
    if t.v0 is not None and t.vary != "v0":  # the path moved v0 too (docs/scenes.md)
        approach = f", v0 {format_quantity(t.v0, 'm/s')}" + approach
    return (f"{head}: St_c = {t.St_c:.4g} ({PATHS[t.vary][0]} "
            f"{format_quantity(t.value, t.unit)}{approach}, {t.factor:.4g} x the scene's): below "
            f"it the spheres stick, above it they rebound (bisected to {RTOL:g} in {t.solves} "
            "solves)")
