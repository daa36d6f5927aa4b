"""The sticking threshold of a scene's materials: the impact Stokes number (and speed, or size)
below which its spheres stick (``e_wet = 0``: they never leave the lubrication region), found
along the same path as ``ehd restitution`` (``v0`` or both radii times a factor; eps moves with
them) by bisection between a sticking and a rebounding scene.

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
# (standard: 1.1 % on ln x_e, benchmarks/accuracy.md), which decide whether a scene sticks


@dataclass(frozen=True)
class Threshold:
    """``St_c`` (the bracket's geometric middle) and the path's quantity there."""

    vary: str  # "v0" or "radius"
    St_c: float | None  # None: no change from sticking to rebounding on the path (``note``)
    factor: float | None  # on the scene's v0 or radii
    value: float | None  # v0 [m/s] or body1's radius [m] at St_c
    unit: str
    bracket: tuple  # (sticking factor, rebounding factor)
    solves: int
    note: str = ""
    failed: bool = False  # a solve the bisection needed failed (``note`` says which and why)


class SolveFailed(ValueError):
    """A solve along the path failed (its status and message)."""


def _sticks(scene, vary, factor, accuracy):
    from pipeline.dem.export import scene_path

    from .run import run_scene

    r = run_scene(scene_path(scene, vary, [factor])[0], accuracy=accuracy, save_profiles=False,
                   sensitivity_solves=False)
    if not r.collision.ok:
        raise SolveFailed(f"the solve at {vary} x {factor:.4g} failed ({r.collision.status}): "
                          f"{r.collision.message}")
    return r.collision.e_wet == 0.0, r.scene.stokes


def sticking_threshold(scene, vary: str = "v0", accuracy: str = "standard", *,
                       start: float = 0.1, stop: float = 10.0, n: int = 9, results=None,
                       rtol: float = RTOL) -> Threshold:
    """Bisect the path ``scene_path(scene, vary, factors)`` for the change from sticking to
    rebounding.

    Parameters
    ----------
    scene : pipeline.scenes.scene.Scene
    vary : {"v0", "radius"}
    start, stop, n : float, float, int
        The first bracket is looked for on ``n`` log-spaced factors in ``[start, stop]``
        (``ehd restitution``'s ``--from``, ``--to``, ``--n``).
    results : list of SceneResult, optional
        Those factors already solved (in order; ``ehd restitution`` passes its rows).
    rtol : float
        Stop when the bracket's factors differ by less than this, relatively.

    Returns
    -------
    Threshold
        With ``St_c = None`` and a ``note`` when every scene on the path sticks or rebounds, or
        (``failed``) when a solve the bisection needed failed. A failed solve of the first
        ``n`` factors is left out of the search, as ``ehd restitution`` leaves it out of its
        table (a failed scene's ``e_wet`` says nothing about sticking).
    """
    import numpy as np

    factors = [float(f) for f in np.geomspace(start, stop, n)]
    solves = 0
    unit = "m/s" if vary == "v0" else "m"
    if results is not None and len(results) == n:
        outcome = [(f, r.collision.e_wet == 0.0) for f, r in zip(factors, results)
                   if r.collision.ok]
    else:
        outcome = []
        for f in factors:
            solves += 1
            try:
                outcome.append((f, _sticks(scene, vary, f, accuracy)[0]))
            except SolveFailed:
                continue
    base = scene.v0 if vary == "v0" else scene.body1.radius
    # St grows with v0 and with size (St ~ v0 a): the first rebounding factor after a sticking one
    change = next((i for i in range(1, len(outcome))
                   if outcome[i - 1][1] and not outcome[i][1]), None)
    if change is None:
        sticks = [stuck for _, stuck in outcome]
        what = "rebound" if not any(sticks) else "stick" if all(sticks) else "alternate"
        if not outcome:
            what = "fail to solve"
        return Threshold(vary, None, None, None, unit, (), solves,
                         note=f"the spheres {what} at every {vary} from {start:g} to {stop:g} "
                              f"times the scene's; widen --from/--to")
    lo, hi = outcome[change - 1][0], outcome[change][0]
    while hi / lo - 1.0 > rtol:
        mid = math.sqrt(lo * hi)
        solves += 1
        try:
            stuck, _ = _sticks(scene, vary, mid, accuracy)
        except SolveFailed as exc:
            return Threshold(vary, None, None, None, unit, (lo, hi), solves, failed=True,
                             note=f"between {vary} x {lo:.4g} (sticks) and x {hi:.4g} "
                                  f"(rebounds) {exc}")
        lo, hi = (mid, hi) if stuck else (lo, mid)
    factor = math.sqrt(lo * hi)
    from pipeline.dem.export import scene_path

    at = scene_path(scene, vary, [factor])[0]
    return Threshold(vary, at.stokes, factor, base * factor, unit, (lo, hi), solves)


def format_threshold(t: Threshold) -> str:
    """One line for the command line."""
    if t.failed:
        return f"sticking threshold: not found: {t.note}"
    if t.St_c is None:
        return f"sticking threshold: not on this path ({t.note})"
    from .units import format_quantity

    what = "impact speed v0" if t.vary == "v0" else "radius of body1"
    return (f"sticking threshold: St_c = {t.St_c:.4g} ({what} {format_quantity(t.value, t.unit)}"
            f", {t.factor:.4g} x the scene's): below it the spheres stick, above it they "
            f"rebound (bisected to {RTOL:g} in {t.solves} solves)")
