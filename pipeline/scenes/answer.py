"""One answer per kind of code, with its range: the verdict, the e a dry DEM code and a resolved
CFD-DEM code take, and how far each moves over what the scene does not know.

docs/scenes.md, "The answer and its range". The solved scene gives the central values
(``e_for_dem`` is ``e_far``, ``e_for_cfd_dem`` is ``e_wet``: ``CODE_KINDS``, from the one table
of which e each kind of code realises, ``pipeline.dem.conventions.DEM_KINDS``). Each *unknown* the
scene leaves open is a driver: the scene solved again (``run_scene`` with its automatic
switches, no sensitivity) at the unknown's low and high end, one unknown at a time:

- ``roughness``: each body whose roughness is not given as a value (none known, or a surface
  class: ``materials.ROUGHNESS_CLASSES``) at its band's low and high end;
- ``cavitation onset``: a liquid's cavitation pressure between gas-saturated (the ambient
  pressure, Pi = 0) and full tension (the classic film, no floor);
- ``pressure-viscosity``: a liquid without a pressure-viscosity coefficient at
  ``ALPHA_UNKNOWN_HIGH`` (the automatic switch decides whether it matters);
- ``asperity stiffness`` (a rough scene): 10x stiffer and softer, the sensitivity's solves
  (``run._sensitivity``: the least known input of the asperity contact), not solved again;
- ``reading distance`` (``e_for_dem`` only, no solve): ``e_far`` read from the same collision
  at ``READING_BAND_OVER_A``, the distances experiments and DEM calibrations read speeds at.

A range is the envelope of the central value and the drivers' values; a driver's ``share`` is
its span over the sum of the drivers' spans (of ``e_for_dem``; of ``e_for_cfd_dem`` where there
is no ``e_far``). The drivers are one at a time,
not combined: two unknowns at their worst together can go beyond the range.

``answer_lines`` writes the answer as the first lines of ``ehd scene``'s report.
"""

from __future__ import annotations

import dataclasses
import math

from ..dem.conventions import DEM_KINDS
from .materials import ROUGHNESS_CLASSES
from .pieces import STIFFNESS_LABELS
from .trajectory import ON_TRAJECTORY
from .units import format_quantity

__all__ = ["ALPHA_UNKNOWN_HIGH", "READING_BAND_OVER_A", "CODE_KINDS", "SOLVED_UNKNOWNS", "answer",
           "stopped_answer", "answer_lines"]

# The high end of a liquid's unknown pressure-viscosity coefficient [1/Pa]: 20 1/GPa, the lowest
# of the mineral oils in Stachowiak & Batchelor, Engineering Tribology, Table 2.3 (20-42 1/GPa;
# checks.ALPHA_KNOWN_LIQUID): a liquid that is not an oil lies below it (glycerol 5.9 1/GPa,
# water 0, the materials table), an oil should give its own; the low end is 0 (the constant
# viscosity, what the scene solves).
ALPHA_UNKNOWN_HIGH = 20e-9
# Where a speed is read [x/a]: from 3 x0 (0.03 a) to one radius out, where a settling sphere has
# not yet slowed (the outer start's default); e_far's default reading is 0.1 a
READING_BAND_OVER_A = (0.03, 1.0)
# the JSON key of each kind of code's e -> the result it takes (docs/scenes.md, "The approach from
# far away")
CODE_KINDS = {"e_for_dem": DEM_KINDS["dry"].e_column,
              "e_for_cfd_dem": DEM_KINDS["cfd-dem"].e_column}


def _value(v):
    return None if v is None or not math.isfinite(v) else float(v)


def _solved(result) -> dict:
    """``{"e_for_dem", "e_for_cfd_dem", "status"}`` of a ``SceneResult``."""
    c = result.collision
    if not c.ok:
        return {**dict.fromkeys(CODE_KINDS), "status": c.status}
    return {**{key: _value(float(getattr(c, column))) for key, column in CODE_KINDS.items()},
            "status": "ok"}


def _body_solid(scene, label, **changes):
    body = getattr(scene, label)
    return dataclasses.replace(body, solid=dataclasses.replace(body.solid, **changes))


def _roughness_variants(scene):
    """``(what, [(end, scene)])`` over the bodies whose roughness is not a given value (none
    known: the "unknown" band; a surface class: its band), each at its band's low and high end."""
    bodies = [(b, b.solid.roughness_class or "unknown") for b in (scene.body1, scene.body2)
              if b.solid.roughness is None or b.solid.roughness_class]
    if not bodies:
        return None
    what = "; ".join(f"{b.label} ({b.solid.name}) {cls}: "
                     f"{format_quantity(ROUGHNESS_CLASSES[cls][0], 'm')} to "
                     f"{format_quantity(ROUGHNESS_CLASSES[cls][1], 'm')} rms" for b, cls in bodies)
    ends = []
    for end, label in enumerate(("low", "high")):
        changed = {b.label: _body_solid(scene, b.label, roughness=ROUGHNESS_CLASSES[cls][end])
                   for b, cls in bodies}
        variant = dataclasses.replace(scene, **changed)
        sigma = variant.roughness_rms
        if sigma is not None and sigma >= scene.x0:  # the contact cannot start inside x0
            variant = (f"not solved: the rms roughness {format_quantity(sigma, 'm')} is not "
                       f"below the film's start x0 = {format_quantity(scene.x0, 'm')}")
        ends.append((label, variant))
    return what, ends


def _cavitation_variants(scene):
    if scene.cavitation_pressure is None or scene.cavitation != "auto":
        return None
    return ("the liquid's cavitation pressure: gas-saturated (the ambient pressure) to full "
            "tension (no floor)",
            [("gas-saturated", dataclasses.replace(
                scene, cavitation_pressure=scene.ambient_pressure,
                cavitation_pressure_source="gas-saturated (the range's low end)")),
             ("full tension", dataclasses.replace(scene, cavitation="off"))])


def _alpha_variants(scene):
    f = scene.fluid
    if f.gas or f.pressure_viscosity is not None \
            or scene.viscosity_law != "auto":
        return None
    fluid = dataclasses.replace(f, pressure_viscosity=ALPHA_UNKNOWN_HIGH)
    return (f"the liquid's pressure-viscosity coefficient, not given: 0 (as solved) to "
            f"{ALPHA_UNKNOWN_HIGH * 1e9:g} 1/GPa",
            [("alpha high", dataclasses.replace(scene, fluid=fluid))])


_VARIANTS = (("roughness", _roughness_variants), ("cavitation onset", _cavitation_variants),
             ("pressure-viscosity", _alpha_variants))
# the unknowns the range solves again (the others are read from solves already made)
SOLVED_UNKNOWNS = tuple(name for name, _ in _VARIANTS)




def _stiffness_driver(result):
    """The asperity layer 10x stiffer and softer, from the sensitivity's solves (None: not a
    rough scene, or no sensitivity solved)."""
    rows = [result.sensitivity[k] for k in STIFFNESS_LABELS if k in result.sensitivity]
    if not rows:
        return None
    central = _solved(result)
    failed = [f"{k}: {r['status']}" for k, r in zip(STIFFNESS_LABELS, rows) if r["status"] != "ok"]
    return {"unknown": "asperity stiffness",
            "detail": "the asperity layer's stiffness 10x stiffer to 10x softer",
            "e_for_dem": _envelope(central["e_for_dem"], [r["e_far"] for r in rows]),
            "e_for_cfd_dem": _envelope(central["e_for_cfd_dem"], [r["e_wet"] for r in rows]),
            "status": "ok" if not failed else "failed (" + ", ".join(failed) + ")"}


def _reading_driver(result):
    """``e_far`` read from the same collision at the ends of ``READING_BAND_OVER_A``."""
    outer, c = result.outer, result.collision
    if outer is None or not c.ok:
        return None
    lo = max(READING_BAND_OVER_A[0], outer.x0_over_a)
    hi = min(READING_BAND_OVER_A[1], outer.start_over_a)
    values = [dataclasses.replace(outer, x_ref_over_a=x).restitution(
        float(c.e_x0), c.physics.St) for x in (lo, hi)]
    return {"unknown": "reading distance",
            "detail": f"where the speeds are read: {lo:g} a to {hi:g} a (as solved: "
                      f"{outer.x_ref_over_a:g} a)",
            "e_for_dem": [min(values), max(values)], "e_for_cfd_dem": None, "status": "ok"}


def _solve(run_scene, scene, accuracy, solve_options) -> dict:
    """``_solved`` of one variant; a variant outside what the scene layer accepts (a roughness
    above x0, say) is a driver end that could not be solved, with the reason."""
    if isinstance(scene, str):  # an end that cannot be solved, with its reason
        return {"e_for_dem": None, "e_for_cfd_dem": None, "status": scene}
    try:
        result = run_scene(scene, accuracy, sensitivity_solves=False, **(solve_options or {}))
    except ValueError as exc:
        return {"e_for_dem": None, "e_for_cfd_dem": None, "status": f"not solved: {exc}"}
    return _solved(result)


def _envelope(central, values):
    finite = [v for v in [central, *values] if v is not None]
    return [min(finite), max(finite)] if finite else None


def answer(result, accuracy: str = "standard", solve_options: dict | None = None, *,
           ranges: bool = True) -> dict:
    """The verdict, the e per code kind with its range and the range's drivers of a solved scene
    (``run.SceneResult``); ``solve_options`` as ``run_scene``'s overrides. ``ranges`` False: the
    central values only (ranges of one point, no drivers)."""
    from .run import run_scene

    central = _solved(result)
    drivers = []
    if result.collision.ok and ranges:
        for name, variants in _VARIANTS:
            found = variants(result.scene)
            if found is None:
                continue
            what, ends = found
            solved = [_solve(run_scene, s, accuracy, solve_options) for _, s in ends]
            failed = [f"{end}: {r['status']}" for (end, _), r in zip(ends, solved)
                      if r["status"] != "ok"]
            drivers.append({
                "unknown": name, "detail": what,
                **{key: _envelope(central[key], [r[key] for r in solved])
                   for key in CODE_KINDS},
                "status": "ok" if not failed else "failed (" + ", ".join(failed) + ")"})
        stiffness = _stiffness_driver(result)
        if stiffness is not None:
            drivers.append(stiffness)
        reading = _reading_driver(result)
        if reading is not None:
            drivers.append(reading)
    return _assemble(central, drivers, computed=result.collision.ok and ranges)


def _assemble(central, drivers, computed=True) -> dict:
    # the shares of e_for_dem's range; of e_for_cfd_dem's where there is no e_far
    key = "e_for_dem" if central["e_for_dem"] is not None else "e_for_cfd_dem"
    spans = [(d[key][1] - d[key][0]) if d[key] else 0.0 for d in drivers]
    total = sum(spans)
    for d, span in zip(drivers, spans):
        d["share"] = span / total if total > 0.0 else 0.0
    out = {}
    shown = central["e_for_dem"] if central["e_for_dem"] is not None else central["e_for_cfd_dem"]
    out["verdict"] = None if shown is None else ("rebounds" if shown > 0.0 else "sticks")
    for key in CODE_KINDS:
        out[key] = central[key]
        ends = [v for d in drivers if d[key] for v in d[key]]
        out[f"{key}_range"] = None if central[key] is None else _envelope(central[key], ends)
        if not computed:
            out[f"{key}_range"] = None
    out["range_drivers"] = drivers
    return out


def stopped_answer(ranges: bool = True) -> dict:
    """The answer of a scene whose outer flow stops the spheres before ``x0``: they stick,
    whatever the unknowns (ranges of one point; null when not asked for)."""
    span = [0.0, 0.0] if ranges else None
    return {"verdict": "sticks", "e_for_dem": 0.0, "e_for_dem_range": span,
            "e_for_cfd_dem": 0.0, "e_for_cfd_dem_range": span, "range_drivers": []}


# the report's first lines: the label of each kind of code's e (the result it takes: CODE_KINDS)
_CODE_LABELS = {"e_for_dem": "e for a dry DEM code",
                "e_for_cfd_dem": "e for a resolved CFD-DEM code"}


def _e3(value) -> str:
    """An e for the report: 3 decimals, or 2 significant digits where those would show a
    rebound as 0.000."""
    return f"{value:.2g}" if 0.0 < value < 0.0005 else f"{value:.3f}"


def _e_lines(d: dict) -> list[str]:
    """The e per code kind with its range, and which unknowns make the range."""
    lines = []
    for key, result in CODE_KINDS.items():
        label = _CODE_LABELS[key]
        value, span = d[key], d[f"{key}_range"]
        if value is None:
            lines.append(f"{label} ({result}): not computed")
            continue
        spread = "" if span is None else f", range {_e3(span[0])} to {_e3(span[1])}" + (
            " (no unknown moves it)" if span[0] == span[1] else "")
        lines.append(f"{label} ({result}): {_e3(value)}{spread}")
    shares = [f"{r['unknown']} {100 * r['share']:.0f} %" for r in d["range_drivers"]
              if r["share"] > 0.0]
    if shares:
        code = "dry DEM" if d["e_for_dem"] is not None else "resolved CFD-DEM"
        lines.append(f"  range of the {code} e from: {', '.join(shares)} (one at a time; "
                     "range_drivers in --json)")
    return lines


def answer_lines(d: dict) -> list[str]:
    """The report's first lines: the verdict, the e per code kind with its range and drivers,
    and the two speeds (docs/scenes.md, "The answer and its range")."""
    if d["verdict"] is None:
        lines = ["verdict: none (the solve failed; see below)"]
    else:
        lines = [f"verdict: the spheres "
                 f"{d['verdict'].replace('sticks', 'stick').replace('rebounds', 'rebound')}"]
        lines += _e_lines(d)
    approach = d["approach_speed_m_per_s"]
    source = d["inputs"]["approach_speed_source"] or ""
    given = d["inputs"]["approach_speed_m_per_s"] is not None
    if source.startswith("settling"):
        where, how = f"far out, {source}", "through the settling motion"
    elif source == ON_TRAJECTORY:
        where = f"at the outer start {d['outer_start_over_a']:.3g} a (on {source})"
        how = "what the release arrives with"
    else:
        where = (f"at the outer start {d['outer_start_over_a']:.3g} a "
                 f"({'given' if given else 'what arrives at x0 with v0'})")
        how = "through the outer flow" if given else "given"
    if approach is None and source == ON_TRAJECTORY:  # released inside the outer start
        where = f"(released inside the outer start {d['outer_start_over_a']:.3g} a)"
    approach = "-" if approach is None else format_quantity(approach, "m/s")
    lines.append(f"speeds: approach {approach} {where}, "
                 f"v0 {format_quantity(d['inputs']['v0_m_per_s'], 'm/s')} at x0 = "
                 f"{d['x0_over_a']:.3g} a ({how})")
    return lines
