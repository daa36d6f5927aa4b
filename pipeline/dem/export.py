"""Export rows (one per computed collision), fitted laws and ready-to-paste settings for DEM codes.

Rows come from a sweep store (dimensionless: no materials; both geometries, ``conventions``) or
from scenes solved along a path (``scene_rows``: the scene's geometry and materials).
``export_files`` computes everything (fits, calibrations, the error each code realises) and only
then ``write_files`` writes ``restitution.csv``, ``restitution.json`` and the snippets, each to a
temporary name renamed into place: an interrupted or failed export leaves no partial file.

Snippets per group (``<tag>`` from the group name):

- ``liggghts_<tag>.in``: pair style and properties; ``liggghts_<tag>_wall.in``: the wall line
  (stores and sphere-wall scenes);
- ``yade_<tag>.py``: materials and time step, and the wall-mass block where walls occur;
- ``openfoam_<tag>.txt``: ``localInteractionHW`` (walls only: stores and sphere-wall scenes).

A store's snippets carry example values (glass in water) marked ``REPLACE``; a scene's carry the
scene's values, and only what the model does not know (friction, wall position) is marked.

Which e the laws realise, and at which speed, is the export's ``kind`` (``--for``;
``conventions.DEM_KINDS``): dry DEM ``e_far`` at the approach speed at ``x_ref``, resolved
CFD-DEM ``e_wet`` at ``v0``. Every JSON group and snippet header names it, the film physics of
the rows and their validity (``validity``); no law's e_max exceeds the pair's ``e_dry``.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import re
import sys
import time
from pathlib import Path

import numpy as np

from solver import SOLVER_VERSION

from . import liggghts, openfoam, yade
from .conventions import CONVENTIONS, DEM_KINDS, store_stokes_numbers, stokes_numbers
from .fits import LAWS
from solver.far_field import DEFAULT as FAR_DEFAULT

__all__ = ["CSV_FIELDS", "store_rows", "scene_rows", "scene_path", "PATHS", "approach_speed_of",
           "path_value", "write_export", "read_csv",
           "group_settings", "export_files", "write_files", "progress_to_stderr", "ST_BANDS",
           "PLACEHOLDERS", "ref_speed_ratio", "realised_physics", "validity", "snippet_header",
           "InvalidExport", "missing_e", "store_groups", "store_row", "check_stokes"]

# the files every export writes (``export_files``; its snippets' names come with its groups)
EXPORT_FILES = CSV_NAME, JSON_NAME = ("restitution.csv", "restitution.json")
CSV_FIELDS = (
    "group", "geometry", "material1", "material2", "fluid", "radius1_m", "radius2_m",
    "density1_kg_m3", "density2_kg_m3", "youngs1_Pa", "youngs2_Pa", "poisson1", "poisson2",
    "viscosity_Pa_s", "fluid_density_kg_m3", "v0_m_s", *CONVENTIONS, "eps", "x_ref_x0", "e_wet",
    "e_far", "x_ref_over_a", "v_ref_over_v0", "v_ref_m_s", "approach_speed_m_s", "sticks", "closest_approach_x1", "closest_approach_m", "peak_pressure", "peak_pressure_Pa",
    "roughness_m", "warning", "warning_checks", "status", "solver_version", "e_dry", "physics",
    "role",
)
# role: "fit" (fitted and calibrated on, when inside --fit-range) or "check" (solved between the
# rows and at the ends of --fit-range only to measure the law there: never fitted on)

# Edges of the St bands (ours) the realised errors are reported in: the threshold region, the
# steep rise, the tail, and beyond the paper's range.
ST_BANDS = (0.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, math.inf)

# Example values of a store's snippets (dimensionless store: no materials), each marked REPLACE:
# soda-lime glass beads of 100 um radius in water (the materials table's glass and water).
PLACEHOLDERS = {"density": 2500.0, "radius": 1e-4, "young": 7e10, "poisson": 0.25,
                "viscosity": 1e-3, "v_char": 0.1}


def _blank():
    return {k: "" for k in CSV_FIELDS}


def store_rows(ds, density_ratio: float = 0.0) -> list[dict]:
    """One row per ok scene of a sweep store with (St, eps) axes; groups are the eps values
    (and the values of any further axis, e.g. ``eps=0.0001 Pi=0.1``)."""
    solver_version = ds.attrs.get("solver_version", "")
    extra = [d for d in ds["status"].dims if d not in ("eps", "St")]
    # whole arrays at once (a .sel per cell took 16 s for 448 scenes)
    # e_far: stores made before it existed lack it (the column stays empty)
    grid = {k: np.asarray(ds[k].transpose("eps", "St", *extra).values)
            for k in ("status", "e_wet", "e_far", "h_m_x1", "p_max") if k in ds}
    out = []
    for label, physics, idx in store_groups(ds):
        for i, eps in enumerate(ds["eps"].values):
            for j, st in enumerate(ds["St"].values):
                cell = (i, j, *idx)
                if int(grid["status"][cell]) != 1:
                    continue
                record = {k: float(grid[k][cell]) for k in grid if k != "status"}
                out.append(store_row(float(st), float(eps), label, physics, record,
                                     solver_version, density_ratio))
    return out


def store_groups(ds):
    """``(label, physics, index)`` per value of the axes beyond St and eps: the label that
    follows ``eps=...`` in a group's name, the fixed and axis physics, the axes' indices."""
    import itertools

    fixed = dict(ds.attrs.get("fixed_physics", {}))
    extra = [d for d in ds["status"].dims if d not in ("eps", "St")]
    for idx in itertools.product(*(range(ds.sizes[d]) for d in extra)):
        label = "".join(f" {d}={float(ds[d].values[i]):.3g}" for d, i in zip(extra, idx))
        yield label, {**fixed, **{d: float(ds[d].values[i]) for d, i in zip(extra, idx)}}, idx


def store_row(st: float, eps: float, label: str, physics: dict, record: dict,
              solver_version: str, density_ratio: float, role: str = "fit") -> dict:
    """The row of one finished store scene (or one solved like it, ``role`` "check"):
    ``record`` holds its ``e_wet``, ``h_m_x1``, ``p_max`` and, where read, ``e_far``."""
    row = _blank()
    row.update(store_stokes_numbers(st, density_ratio))
    e = record["e_wet"]
    far = record.get("e_far", math.nan)
    e_far = far if math.isfinite(far) else ""
    row.update(group=f"eps={eps:.3g}{label}", geometry="either", eps=eps, x_ref_x0=1.0,
               e_wet=e, sticks=bool(e == 0.0), e_far=e_far,
               v_ref_over_v0="" if e_far == "" else ref_speed_ratio(FAR_DEFAULT, st),
               e_dry=float(physics.get("e_dry", 1.0)), physics=_store_physics(physics),
               role=role,
               # a sweep reads e_far with solver.far_field.DEFAULT
               x_ref_over_a=FAR_DEFAULT.x_ref_over_a if "e_far" in record else "",
               closest_approach_x1=record["h_m_x1"], peak_pressure=record["p_max"],
               status="ok", solver_version=solver_version)
    return row


def check_stokes(st, lo: float, hi: float) -> list[float]:
    """Where a law fitted on rows at ``st`` (our St) inside ``[lo, hi]`` is checked besides
    them: the range's ends (unless a row is there; ``lo`` 0 has none) and halfway (geometric)
    between neighbouring rows inside it."""
    st = sorted(st)
    ends = [x for x in (lo, hi) if x > 0.0 and math.isfinite(x)
            and min(abs(x / y - 1.0) for y in st) > 1e-6]
    mids = [math.sqrt(a * b) for a, b in zip(st[:-1], st[1:]) if lo <= math.sqrt(a * b) <= hi]
    return sorted(set(ends + mids))


def missing_e(rows: list[dict], kind: str) -> list[dict]:
    """The finished rows that lack the e ``kind`` realises (``e_far``: rows made before it)."""
    col = DEM_KINDS[kind].e_column
    return [r for r in rows if r["status"] in ("ok", "start_deformed") and r[col] == ""
            and math.isfinite(_num(r["e_wet"]))]


def _store_physics(physics: dict) -> str:
    """The store's physics in words: what it fixed or varied beyond St and eps."""
    given = ", ".join(f"{k} = {v}" for k, v in sorted(physics.items()) if k not in ("St", "eps"))
    return "store physics: " + (given or "the classic film (nothing else switched on)")


def physics_kind(physics) -> str:
    """The film physics a row was solved with, in words without its numbers (a path's rows
    share it where the numbers differ): "classic film" or e.g. "jfo cavitation, asperity
    contact" (``pipeline.scenes.checks.physics_label`` gives the numbers)."""
    parts = [] if physics.cavitation == "off" else [f"{physics.cavitation} cavitation"]
    parts += [f"{law} {name}" for name, law in (("viscosity", physics.viscosity_law),
                                                 ("density", physics.density_law))
              if law != "constant"]
    if not physics.smooth:
        parts.append("asperity contact (losses e_dry where the surfaces touch)")
    return ", ".join(parts) or "classic film"


def ref_speed_ratio(outer, stokes: float) -> float:
    """The approach speed at the reading distance ``x_ref`` over ``v0``: what arrives at ``x0``
    with ``v0`` after the outer flow (``outer``, a ``solver.far_field.OuterFlow``) from
    ``x_ref`` (``OuterFlow.approach_speed`` with the outer start at ``x_ref``). The speed a
    dry DEM code sees at contact (``conventions.DEM_KINDS``)."""
    if outer.x_ref_over_a <= outer.x0_over_a:
        return 1.0
    return dataclasses.replace(outer, start_over_a=outer.x_ref_over_a).approach_speed(stokes)


def scene_path(scene, vary: str, factors) -> list:
    """Scenes along a path: ``v0``, the approach speed or the radii (and ``x0``, the outer start
    and ``x_ref`` with them, keeping their ratios to ``a``) times each factor. eps moves along
    the path with the speed and size: that is the point. A scene given its approach speed keeps
    it along a path in size (``v0`` mapped again: ``scene_file.at_approach_speed``); a settling
    scene settles at its own speed at each size, and has no path in speed (refused: its speed
    mapped through the outer flow without gravity was wrong, 2.9 m/s for a ball that settles at
    23 mm/s)."""
    from pipeline.scenes.scene_file import at_approach_speed, at_settling

    settling = scene.approach_speed_source.startswith("settling")
    if vary != "radius" and settling:
        from pipeline.scenes.scene import SceneError

        raise SceneError(f"the scene settles at its own speed (approach_speed = 'settling'): "
                         f"it has no path in {vary}; vary its size (--vary radius), or give the "
                         "scene a v0 or an approach speed to move along")
    if vary == "v0" and scene.stops_outside:
        from pipeline.scenes.scene import SceneError

        raise SceneError("the scene's v0 is 0: its approach speed is too slow for the outer flow "
                         "to reach x0, so every v0 along the path would be 0; vary the approach "
                         "speed instead (--vary approach_speed)")
    scenes = []
    for f in map(float, factors):  # a numpy number would show as np.float64(...) in a refusal
        if vary == "v0":
            scenes.append(dataclasses.replace(scene, v0=scene.v0 * f, approach_speed=None))
        elif vary == "approach_speed":
            scenes.append(at_approach_speed(scene, approach_speed_of(scene) * f))
        elif vary == "radius":
            b1 = dataclasses.replace(scene.body1, radius=scene.body1.radius * f)
            b2 = dataclasses.replace(scene.body2, radius=scene.body2.radius * f)
            # the outer start and x_ref scale with the radii too (None: their defaults in a)
            outer = {k: None if getattr(scene, k) is None else getattr(scene, k) * f
                     for k in ("outer_start", "x_ref")}
            scaled = dataclasses.replace(scene, body1=b1, body2=b2, x0=scene.x0 * f, **outer)
            if settling:  # settles at its own speed
                scaled = at_settling(scaled)
            elif scene.approach_speed is not None:
                scaled = at_approach_speed(scaled, scene.approach_speed)
            scenes.append(scaled)
        else:
            raise ValueError(f"vary must be one of {list(PATHS)}, got {vary!r}")
    return scenes


# what can move along a path (``ehd restitution --vary``) -> what the path's axis shows
PATHS = {"v0": ("impact speed v0", "m/s"), "approach_speed": ("approach speed", "m/s"),
         "radius": ("radius of body1", "m")}


def approach_speed_of(scene) -> float:
    """The scene's approach speed at the outer start [m/s]: given, or what arrives at ``x0``
    with its ``v0`` (``OuterFlow.approach_speed``)."""
    if scene.approach_speed is not None:
        return scene.approach_speed
    return scene.outer_flow().approach_speed(scene.stokes) * scene.v0


def path_value(scene, vary: str) -> float:
    """The path's quantity of a scene [SI]: ``v0``, the approach speed, or body1's radius."""
    if vary == "radius":
        return scene.body1.radius
    return scene.v0 if vary == "v0" else approach_speed_of(scene)


def scene_rows(results, group: str, role: str = "fit") -> list[dict]:
    """Rows of solved scenes (``pipeline.scenes.run.SceneResult``), each with every validity
    warning of its scene (yield, fluid inertia, roughness, ...). ``role``: "fit" or "check"
    (``CSV_FIELDS``)."""
    from pipeline.scenes.checks import combined_roughness

    out = []
    for r in results:
        s, c = r.scene, r.collision
        b1, b2 = s.body1, s.body2
        geometry = "sphere-wall" if b2.wall else "sphere-sphere"
        row = _blank()
        row.update(stokes_numbers(s.stokes, geometry=geometry, rho_p=b1.solid.density,
                                  d=2.0 * b1.radius, v0=s.v0, mu=s.fluid.viscosity,
                                  rho_f=s.fluid.density,
                                  rho_2=None if b2.wall else b2.solid.density,
                                  d_2=None if b2.wall else 2.0 * b2.radius))
        sigma = combined_roughness(s)
        far = r.outer is not None and math.isfinite(c.e_far)
        ratio = ref_speed_ratio(r.outer, s.stokes) if far else ""
        row.update(
            group=group, geometry=geometry, material1=b1.solid.name, material2=b2.solid.name,
            fluid=s.fluid.name, radius1_m=b1.radius, radius2_m="" if b2.wall else b2.radius,
            density1_kg_m3=b1.solid.density,
            density2_kg_m3=b2.solid.density if b2.solid.density is not None else "",
            youngs1_Pa=b1.solid.youngs_modulus, youngs2_Pa=b2.solid.youngs_modulus,
            poisson1=b1.solid.poisson_ratio, poisson2=b2.solid.poisson_ratio,
            viscosity_Pa_s=s.fluid.viscosity, fluid_density_kg_m3=s.fluid.density, v0_m_s=s.v0,
            eps=s.eps, x_ref_x0=c.x_ref_x0, e_wet=c.e_wet, sticks=bool(c.e_wet == 0.0),
            e_far=c.e_far if far else "",
            x_ref_over_a=c.x_ref_over_a if r.outer is not None else "",
            v_ref_over_v0=ratio, v_ref_m_s=ratio * s.v0 if far else "",
            approach_speed_m_s=approach_speed_of(s) if r.outer is not None else "",
            closest_approach_x1=c.h_m_x1, closest_approach_m=c.h_m_x1 * s.x1,
            peak_pressure=c.p_max, peak_pressure_Pa=r.peak_pressure,
            roughness_m="" if sigma is None else sigma,
            warning="; ".join(w.message for w in r.warnings),
            warning_checks=" ".join(w.check for w in r.warnings), status=c.status,
            solver_version=SOLVER_VERSION, e_dry=s.e_dry,
            physics=physics_kind(c.physics),
            role=role)
        out.append(row)
    return out


def _num(v):
    if v == "" or v is None:
        return math.nan
    return float(v)


def _by_band(st, realised, e) -> list[dict]:
    """Largest ``|realised - e|`` per band of our St (``ST_BANDS``)."""
    out = []
    for lo, hi in zip(ST_BANDS[:-1], ST_BANDS[1:]):
        m = (st >= lo) & (st < hi)
        if m.any():
            out.append({"St_from": lo, "St_to": hi if math.isfinite(hi) else None,
                        "n": int(m.sum()), "n_model_sticks": int(np.sum(e[m] == 0.0)),
                        "max_error": float(np.max(np.abs(realised[m] - e[m])))})
    return out


def _realised(st, realised, e, fit_mask) -> dict:
    return {"realised_max_error": float(np.max(np.abs(realised - e))),
            "realised_max_error_fit_range": float(np.max(np.abs(realised[fit_mask] - e[fit_mask]))),
            "realised_error_by_St": _by_band(st, realised, e)}


def realised_physics(rows: list[dict], kind) -> dict:
    """What the law of a group realises and the physics behind it (every JSON block and
    snippet header says it): ``kind`` a ``conventions.DemKind``."""
    labels = {}
    for r in rows:
        labels.setdefault(r["physics"] or "not recorded", []).append(_num(r["St"]))
    film = "; ".join(f"{p} (rows at St {min(st):.3g}-{max(st):.3g})" if len(labels) > 1 else p
                     for p, st in labels.items())
    e_dry = _e_cap(rows)
    x_ref = _first(rows, "x_ref_over_a")
    outer = (f"; outer flow from x_ref = {x_ref:.3g} a (exact Stokes resistance"
             + (", added mass)" if _num(_first(rows, "fluid_density_kg_m3")) > 0 else ")")
             if kind.e_column == "e_far" and x_ref != "" else "")
    return {"for": kind.name, "code": kind.code, "e_realised": kind.e_column,
            "speed_column": kind.speed_column, "speed_over_v0_column": kind.speed_ratio_column,
            "why": kind.why, "physics": film + outer, "e_dry": e_dry}


def _e_cap(rows) -> float:
    """The pair's dry restitution (1 where none is known): no law's e_max above it."""
    values = [_num(r["e_dry"]) for r in rows if r["e_dry"] != ""]
    return min(values) if values else 1.0


def validity(rows: list[dict]) -> dict:
    """The validity checks the group's rows fail: ``n_rows``, ``n_rows_with_warnings``,
    ``checks`` ({name: rows}), and ``every_row_fails`` (the fit rows all carry a warning: the
    export is refused unless asked, ``--allow-invalid``)."""
    checks = {}
    for r in rows:
        for name in r["warning_checks"].split():
            checks[name] = checks.get(name, 0) + 1
    failing = [r for r in rows if r["warning_checks"]]
    fit_rows = [r for r in rows if r["role"] != "check"]
    every = bool(fit_rows) and all(r["warning_checks"] for r in fit_rows)
    return {"n_rows": len(rows), "n_rows_with_warnings": len(failing), "checks": checks,
            "every_row_fails": every,
            "summary": ("valid: no row fails a validity check" if not failing else
                        f"{'INVALID: every row fails' if every else f'{len(failing)} of {len(rows)} rows fail'}"
                        f" validity checks ({', '.join(sorted(checks))}; restitution.csv "
                        "warning): the model does not hold there")}


def group_settings(rows: list[dict], fit_range=None, kind="dry") -> dict:
    """Fits on every convention, the LIGGGHTS calibration, the OpenFOAM and YADE settings of one
    group of rows, each with the error its code realises against the model (every row, sticking
    ones included, check rows too, and per St band). ``kind``: ``conventions.DEM_KINDS`` key,
    which e (``e_realised``) is fitted at which speed (every Stokes number times the row's
    ``speed_over_v0_column``). ``fit_range``: ``(St_lo, St_hi)`` (ours, at v0) of the rows the
    fits and calibrations use (where the user's collisions are; never the "check" rows); errors
    are reported on every row regardless. A group with fewer than 3 rebounding rows in the
    range gets a note."""
    dem = DEM_KINDS[kind]
    ok = [r for r in rows if r["status"] in ("ok", "start_deformed") and
          math.isfinite(_num(r[dem.e_column]))]
    e = np.array([_num(r[dem.e_column]) for r in ok])
    st_v0 = np.array([_num(r["St"]) for r in ok])
    speed = np.array([1.0 if dem.speed_ratio_column is None else _num(r[dem.speed_ratio_column])
                      for r in ok])
    st = st_v0 * speed  # our St at the speed the code sees at contact
    lo, hi = fit_range if fit_range else (0.0, math.inf)
    fit_mask = (st_v0 >= lo) & (st_v0 <= hi) & np.array([r["role"] != "check" for r in ok],
                                                         dtype=bool)
    range_mask = (st_v0 >= lo) & (st_v0 <= hi)
    geometry = ok[0]["geometry"] if ok else ""
    if kind == "dry" and geometry == "either":
        geometry = "sphere-wall"  # a store reads e_far for a sphere and a wall (FAR_DEFAULT)
    out = {"n": len(ok), "n_rebound": int(np.sum(e > 0)), "geometry": geometry,
           "realises": realised_physics(ok or rows, dem), "validity": validity(rows),
           "n_check_rows": int(sum(r["role"] == "check" for r in ok)), "fits": {}}
    if fit_range:
        n_check = int((range_mask & ~fit_mask).sum())
        out["fit_range"] = {
            "St_from": lo, "St_to": hi, "n": int(fit_mask.sum()), "n_check": n_check,
            "between_rows": (f"checked: {n_check} scenes solved between the fitted rows and at "
                             "the range's ends (CSV role 'check', never fitted) are in every "
                             "realised error" if n_check else
                             "not checked: no point of the range lies between two rows or at "
                             "an end without a row")}
    if int(np.sum(e[fit_mask] > 0)) < 3:
        out["note"] = ("fewer than 3 rebounding collisions" + (" in --fit-range" if fit_range else "")
                       + ": no fit (use ehd restitution over a range of speeds or sizes)")
        return out
    cap = out["realises"]["e_dry"]
    values = {conv: np.array([_num(r[conv]) for r in ok]) * speed for conv in CONVENTIONS}
    for conv, x in values.items():
        if np.all(np.isfinite(x)):
            out["fits"][conv] = {law: fit(x[fit_mask], e[fit_mask], conv, cap).as_dict()
                                 for law, fit in LAWS.items()}
    tag = {"e_realised": dem.e_column, "speed_column": dem.speed_column}
    out["liggghts"] = {**tag, **_liggghts_block(out, st, e, fit_mask, range_mask, cap)}
    if geometry in ("sphere-wall", "either"):
        out["openfoam"] = {**tag, **_openfoam_block(out, values["St_L"], st, e, fit_mask,
                                                   range_mask, cap)}
    out["yade"] = {**tag, **_yade_block(out, values["St_yade"], st, e, range_mask)}
    return out


def _liggghts_block(out, st, e, fit_mask, range_mask, cap) -> dict:
    """LIGGGHTS: the law never sticks; calibrated on the rebounding rows of the range."""
    ef, em = st[fit_mask], e[fit_mask]
    exp_fit = out["fits"]["St"]["exponential"]
    plain = liggghts.replica_many(ef[em > 0], exp_fit["e_max"], exp_fit["c"])
    ls_e, ls_c, _, _ = liggghts.calibrate(ef, em, exp_fit["e_max"], exp_fit["c"], e_cap=cap)
    ls_realised = liggghts.replica_many(st, ls_e, ls_c)
    # refined to the smallest largest error over the range (sticking rows included): that is
    # what the JSON states, and near the threshold the least-squares pair leaves it 20-30 %
    # larger (measured on the paper store: 0.051-0.100 against 0.043-0.077)
    mm_e, mm_c, _ = liggghts.calibrate_minimax(ef, em, ls_e, ls_c, e_cap=cap)
    mm_realised = liggghts.replica_many(st, mm_e, mm_c)
    use_mm = (np.max(np.abs(mm_realised - e)[fit_mask])
              < np.max(np.abs(ls_realised - e)[fit_mask]))
    e_max, c, realised = (mm_e, mm_c, mm_realised) if use_mm else (ls_e, ls_c, ls_realised)
    rebound = fit_mask & (e > 0)
    return {
        "convention": "St", "geometry": "both (meff, reff: a wall counts as infinite)",
        "MaximumRestitution": e_max, "CriticalStokes": c, "MaximumRestitution_cap": cap,
        "calibration": "minimax" if use_mm else "least_squares",
        "calibration_max_error": float(np.max(np.abs(realised - e)[rebound])),
        "uncalibrated_max_error": float(np.max(np.abs(plain - em[em > 0]))),
        "least_squares": {"MaximumRestitution": ls_e, "CriticalStokes": ls_c,
                          **_realised(st, ls_realised, e, range_mask)},
        **_realised(st, realised, e, range_mask),
        "limitForce": "off: with limitForce on the normal force is never attractive, the "
                      "dashpot cannot hold the spheres and collisions the model says stick "
                      "rebound (liggghts.replica_restitution(limit_force=True); e 0.24 measured "
                      "in LIGGGHTS 3.8.0)",
        "steps_per_contact": liggghts.STEPS_PER_CONTACT,
        "time_step_error_measured": liggghts.TIME_STEP_ERROR,
        "note": "CriticalStokes is the constant C of e = e_max exp(-C/St) with St from the "
                "instantaneous normal velocity; values calibrated against the replica "
                "(pipeline/dem/liggghts.py) so the realised e matches the model at impact: "
                "least squares over the rebounding rows, then (calibration: minimax) the pair "
                "of smallest largest error over every row of the range; MaximumRestitution "
                "at most MaximumRestitution_cap (the pair's e_dry). "
                "calibration_max_error: rebounding rows of the fit; realised_max_error: every "
                "row, check rows between the fitted ones included, where the model sticks too "
                "(the law never sticks). Needs dt <= "
                "tc/steps_per_contact, at which LIGGGHTS 3.8.0 was measured to differ from the "
                "replica by up to time_step_error_measured (tests/test_dem_programs.py).",
    }


def _openfoam_block(out, st_l, st, e, fit_mask, range_mask, cap) -> dict:
    """OpenFOAM localInteractionHW: a patch (wall) model, on St_L."""
    em = e[fit_mask]
    fl = out["fits"]["St_L"]["exponential"]
    thr_l = out["fits"]["St_L"]["threshold"]
    fit_law = openfoam.law(st_l, fl["e_max"], fl["c"])
    ce, cc, _ = openfoam.calibrate(st_l[fit_mask], em, fl["e_max"], fl["c"], e_cap=cap)
    cal_law = openfoam.law(st_l, ce, cc)
    fit_err = float(np.max(np.abs(fit_law[fit_mask] - em)))
    cal_err = float(np.max(np.abs(cal_law[fit_mask] - em)))
    use_cal = cal_err < fit_err
    chosen = (ce, cc, cal_law) if use_cal else (fl["e_max"], fl["c"], fit_law)
    return {
        "model": "localInteractionHW (patchInteractionModel)",
        "library": openfoam.LIBRARY, "libs": openfoam.LIBS_LINE,
        "dictionary": openfoam.DICTIONARY, "geometry": "sphere-wall (patches only)",
        "convention": "St_L = (rho_p + rho_f/2) d Un / (9 mu)",
        "e": chosen[0], "coeffStc": chosen[1],
        "values_from": "calibrated" if use_cal else "fit",
        "fit": {"e": fl["e_max"], "coeffStc": fl["c"], **_realised(st, fit_law, e, range_mask)},
        "calibrated": {"e": ce, "coeffStc": cc, **_realised(st, cal_law, e, range_mask)},
        **_realised(st, chosen[2], e, range_mask),
        "sticks_below_St_L": chosen[1] / (math.log(chosen[0]) - openfoam.STICK_LOG_E),
        "model_sticks_below_St_L": thr_l["c"],
        "eCutoffLog": openfoam.STICK_LOG_E,
        "note": "e and coeffStc: the exponential fit on St_L, or (values_from: calibrated) "
                "the pair that minimises the squared error of the law the library applies "
                "(with its sticking cut-off ln e < -5.3, hard-coded; eCutoffLog is read "
                "but unused) over every row, sticking ones included; e at most the pair's "
                "e_dry. rhoF must be the "
                "fluid density of St_L's fit: the scene's; for a store, density_ratio "
                "times the particle density",
    }


def _yade_block(out, st_yade, st, e, range_mask) -> dict:
    """YADE ViscElMat lubrication: the threshold law on St_yade, floored at 1e-3."""
    ty = out["fits"]["St_yade"]["threshold"]
    return {
        "material": "ViscElMat(lubrication=True)",
        "convention": "St_yade = <rho> (R1 + R2) vn / mu (YADE's; walls of density 0: 4.5 St)",
        "geometry": "both (the wall material has density 0 and walls get a mass)",
        "walls": "utils.wall only: facets (geom.facetBox, meshes) enter the lubrication law as a "
                 "sphere of radius 2R and realise e up to 0.3 too high; the snippet's block 2 "
                 "stops a run that has facets",
        "en": ty["e_max"], "st_c": ty["c"], "roughnessScale_over_d": 0.5 * math.exp(-ty["c"]),
        "law": "e = max(1e-3, en (1 - ln(a / roughnessScale) / St_yade)), a = (R1 + R2)/2: "
               "threshold St_yade,c = ln(a / roughnessScale), so roughnessScale = a exp(-St_c)",
        "e_floor": yade.E_FLOOR, "wall_mass_factor": yade.WALL_MASS_FACTOR,
        **_realised(st, yade.law(st_yade, ty["e_max"], ty["c"]), e, range_mask),
        "steps_per_contact": liggghts.STEPS_PER_CONTACT,
        "note": "the roughnessScale that reproduces the EHD threshold is far below any real "
                "roughness: a fitting constant of the rigid-lubrication law, not a surface "
                "property. YADE never sticks (e >= 1e-3). A massless wall would be counted with "
                "the sphere's mass (e ~0.1 too high): the snippet gives walls a mass; en at most "
                "the pair's e_dry",
    }


def _first(rows, key):
    return next((r[key] for r in rows if r[key] != ""), "")


def _scene_values(grp) -> dict:
    """Materials, sizes and time steps of a scene group (all rows share them but v0)."""
    f = {k: _num(_first(grp, k)) for k in ("radius1_m", "radius2_m", "density1_kg_m3",
                                           "density2_kg_m3", "youngs1_Pa", "youngs2_Pa",
                                           "poisson1", "poisson2", "viscosity_Pa_s",
                                           "fluid_density_kg_m3")}
    wall = grp[0]["geometry"] == "sphere-wall"
    a1, rho1 = f["radius1_m"], f["density1_kg_m3"]
    m1 = 4.0 / 3.0 * math.pi * a1**3 * rho1
    if wall:
        meff, reff = m1, a1
    else:
        m2 = 4.0 / 3.0 * math.pi * f["radius2_m"] ** 3 * f["density2_kg_m3"]
        meff, reff = m1 * m2 / (m1 + m2), a1 * f["radius2_m"] / (a1 + f["radius2_m"])
    v0 = float(np.median([_num(r["v0_m_s"]) for r in grp]))
    v_char = max(v0, liggghts.MIN_CHARACTERISTIC_VELOCITY)
    yeff = liggghts.effective_modulus(f["youngs1_Pa"], f["poisson1"], f["youngs2_Pa"],
                                      f["poisson2"])
    tc = liggghts.contact_time(meff, reff, yeff, v_char)
    # YADE: kn = 1/(1/(2 young1 R1) + 1/(2 young2 R2)) (a wall: the sphere's R and, in the
    # snippet, its young), the wall given a mass: m_red = m1
    a_yade = a1 if wall else 0.5 * (a1 + f["radius2_m"])
    if wall:
        kn_yade = f["youngs1_Pa"] * a1
    else:
        kn_yade = 1.0 / (0.5 / (f["youngs1_Pa"] * a1) + 0.5 / (f["youngs2_Pa"] * f["radius2_m"]))
    tc_yade = math.pi * math.sqrt(meff / kn_yade)
    return {**f, "v0": v0, "v_char": v_char, "wall": wall, "a_yade": a_yade,
            "tc": tc, "dt_max": tc / liggghts.STEPS_PER_CONTACT,
            "tc_yade": tc_yade, "dt_max_yade": tc_yade / liggghts.STEPS_PER_CONTACT}


def _tag(name):
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", name).strip("_")


def snippet_header(s: dict) -> tuple:
    """Comment lines (no comment marker) every snippet of group settings ``s`` opens with: the e
    its law realises, at which speed, the physics behind it, and the validity of the rows."""
    import textwrap

    r, v = s["realises"], s["validity"]
    text = [f"Realises {r['e_realised']} for a {r['code']}: {r['why']}.",
            f"The law sees the impact speed of restitution.csv column {r['speed_column']} (its St "
            "is the row's St times " + (r["speed_over_v0_column"] or "1") + ").",
            f"Physics behind it: {r['physics']}; e_dry {r['e_dry']:g} (no e_max above it).",
            f"Validity: {v['summary']}."]
    if v["every_row_fails"]:
        text.append("Exported with --allow-invalid: do not trust these values.")
    return tuple(line for t in text for line in textwrap.wrap(t, 94))


def _snippets(name, grp, s, store: bool, density_ratio: float) -> dict:
    """{file name: text} of one group, and the time steps into ``s``."""
    tag = _tag(name)
    header = snippet_header(s)
    geometry = s["geometry"]
    walls = geometry in ("sphere-wall", "either")
    lig = s["liggghts"]
    files = {}
    if store:
        p = PLACEHOLDERS
        types = ["particles (and walls)"]
        lig_text = liggghts.snippet(lig, types=types, placeholders=True, header=header, values={
            "youngs": [p["young"]], "poisson": [p["poisson"]], "viscosity": p["viscosity"],
            "v_char": p["v_char"], "density": p["density"], "radius": p["radius"]})
        wall_type = 1
        yv = {"density": p["density"], "radius": p["radius"], "young": p["young"],
              "poisson": p["poisson"], "viscosity": p["viscosity"]}
        s["openfoam"].update(rhoF=density_ratio * p["density"], muP=p["viscosity"],
                             density_ratio=density_ratio)
    else:
        v = _scene_values(grp)
        mats = list(dict.fromkeys([_first(grp, "material1"), _first(grp, "material2")]))
        n = len(mats)
        lig_text = liggghts.snippet(lig, types=mats, placeholders=False, header=header, values={
            "youngs": [v["youngs1_Pa"], v["youngs2_Pa"]][:n],
            "poisson": [v["poisson1"], v["poisson2"]][:n], "viscosity": v["viscosity_Pa_s"],
            "v_char": v["v0"], "dt_max": v["dt_max"]})
        wall_type = n
        lig.update(contact_time_s=v["tc"], time_step_max_s=v["dt_max"],
                   characteristicVelocity=v["v_char"], atom_types=mats)
        s["yade"].update(contact_time_s=v["tc_yade"], time_step_max_s=v["dt_max_yade"],
                         roughnessScale_m=v["a_yade"] * math.exp(-s["yade"]["st_c"]),
                         viscoDyn=v["viscosity_Pa_s"])
        yv = {"density": v["density1_kg_m3"], "radius": v["radius1_m"], "young": v["youngs1_Pa"],
              "poisson": v["poisson1"], "viscosity": v["viscosity_Pa_s"]}
        if not v["wall"] and (v["radius2_m"], v["density2_kg_m3"], v["youngs2_Pa"],
                              v["poisson2"]) != (v["radius1_m"], v["density1_kg_m3"],
                                                 v["youngs1_Pa"], v["poisson1"]):
            yv.update(radius2=v["radius2_m"], density2=v["density2_kg_m3"],
                      young2=v["youngs2_Pa"], poisson2=v["poisson2"])
        if walls:
            s["openfoam"].update(rhoF=v["fluid_density_kg_m3"], muP=v["viscosity_Pa_s"])
    if store:
        lig["atom_types"] = types
    files[f"liggghts_{tag}.in"] = lig_text
    if walls:
        files[f"liggghts_{tag}_wall.in"] = liggghts.wall_snippet(wall_type, placeholders=store,
                                                                 header=header)
        files[f"openfoam_{tag}.txt"] = openfoam.snippet(s, store=store, header=header)
    files[f"yade_{tag}.py"] = yade.snippet(s["yade"], geometry=geometry, values=yv,
                                           placeholders=store, steps=liggghts.STEPS_PER_CONTACT,
                                           header=header)
    return files


def progress_to_stderr(command: str):
    """A ``progress`` callback printing ``<command>: <line>`` on stderr (stdout keeps results)."""
    def progress(msg):
        print(f"{command}: {msg}", file=sys.stderr, flush=True)
    return progress


class InvalidExport(ValueError):
    """Every fit row of a group fails a validity check and ``allow_invalid`` was not given."""


def export_files(rows: list[dict], source: str, *, fit_range=None, density_ratio=0.0,
                 progress=None, kind="dry", allow_invalid=False) -> dict:
    """Everything an export writes, as ``{file name: text}`` (nothing written yet).
    ``progress``: called with a line per group when there are several. ``kind``: which e the
    laws realise (``conventions.DEM_KINDS``). Raises ``InvalidExport`` (nothing computed is
    lost: nothing was written) when a group's fit rows all fail validity checks, unless
    ``allow_invalid``."""
    groups = {}
    for r in rows:
        groups.setdefault(r["group"], []).append(r)
    store = all(r["geometry"] == "either" for r in rows)
    doc = {"source": source, "solver_version": SOLVER_VERSION, "for": kind,
           "e_realised": DEM_KINDS[kind].e_column, "speed_column": DEM_KINDS[kind].speed_column,
           "conventions": {k: {"definition": d, "used_by": u} for k, (d, u) in CONVENTIONS.items()},
           "st_bands": [b if math.isfinite(b) else None for b in ST_BANDS],
           "groups": {}}
    if store:
        doc["density_ratio"] = density_ratio
        doc["placeholders"] = PLACEHOLDERS
    files = {}
    t0 = time.perf_counter()
    for k, (name, grp) in enumerate(groups.items()):
        s = group_settings(grp, fit_range, kind)
        if s["validity"]["every_row_fails"] and not allow_invalid:
            raise InvalidExport(f"group {name}: {s['validity']['summary']}")
        doc["groups"][name] = s
        if "liggghts" in s:
            files.update(_snippets(name, grp, s, store, density_ratio))
        if progress and len(groups) > 1:
            done = "fitted and calibrated" if "liggghts" in s else "not fitted (see its note)"
            progress(f"group {name} ({k + 1}/{len(groups)}) {done}, "
                     f"{time.perf_counter() - t0:.1f} s")
    buf = _csv_text(rows)
    return {CSV_NAME: buf, JSON_NAME: json.dumps(doc, indent=2, default=_json_default), **files}


def _csv_text(rows) -> str:
    import io

    fh = io.StringIO(newline="")
    w = csv.DictWriter(fh, fieldnames=CSV_FIELDS)
    w.writeheader()
    for r in rows:
        w.writerow(r)
    return fh.getvalue()


# the snippet files an export writes (``_snippets``), and the word their first line carries
SNIPPETS = ("liggghts_*.in", "yade_*.py", "openfoam_*.txt")
SNIPPET_MARK = "ehd-collision"


def write_files(files: dict, out_dir) -> tuple[list[Path], list[Path]]:
    """Write ``files`` into ``out_dir``: each to a hidden temporary name first, all renamed into
    place only once every one is written (a failure leaves no partial or half-new export:
    ``pipeline.writes.write_all``). Then the snippets of an earlier export in ``out_dir`` that
    this one does not write are removed (``stale_snippets``): beside the new CSV they would
    give laws fitted to rows it no longer holds. Returns ``(paths written, paths removed)``."""
    from ..writes import write_all

    out = Path(out_dir)
    written = write_all({out / name: text for name, text in files.items()},
                        f"--out {out_dir}")
    stale = stale_snippets(out, files)
    for path in stale:
        path.unlink(missing_ok=True)
    return written, stale


def stale_snippets(out: Path, keep) -> list[Path]:
    """The snippet files in ``out`` that an export wrote (their first line names ehd-collision)
    and that ``keep`` (this export's names) does not hold; anyone else's file is left alone."""
    stale = []
    for pattern in SNIPPETS:
        for path in sorted(out.glob(pattern)):
            if path.name in keep or path.is_symlink() or not path.is_file():
                continue
            try:
                with open(path, encoding="utf-8", errors="replace") as fh:
                    first = fh.readline(200)
            except OSError:
                continue
            if SNIPPET_MARK in first:
                stale.append(path)
    return stale


def write_export(rows: list[dict], out_dir, source: str, *, fit_range=None, density_ratio=0.0,
                 progress=None, kind="dry", allow_invalid=False) -> tuple[list[Path], list[Path]]:
    """Compute the export of ``rows`` and write it into ``out_dir`` (``write_files``)."""
    return write_files(export_files(rows, source, fit_range=fit_range,
                                    density_ratio=density_ratio, progress=progress, kind=kind,
                                    allow_invalid=allow_invalid), out_dir)


def _json_default(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, np.bool_):
        return bool(v)
    raise TypeError(type(v))


def read_csv(path) -> list[dict]:
    """The rows of ``restitution.csv`` back, numbers as floats (empty: ``""``)."""
    text_fields = ("group", "geometry", "material1", "material2", "fluid", "warning",
                   "warning_checks", "status", "solver_version", "physics", "role")
    rows = []
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            for k, v in r.items():
                if k in ("sticks",):
                    r[k] = v == "True"
                elif v != "" and k not in text_fields:
                    r[k] = float(v)
            rows.append(r)
    return rows
