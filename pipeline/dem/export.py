"""Export rows (one per computed collision), fitted laws and ready-to-paste settings for DEM codes.

Rows come from a sweep store (dimensionless: no materials, ``St_exp = St`` as for a sphere on a
wall) or from scenes solved along a path (``scene_rows``). ``write_export`` writes
``restitution.csv``, ``restitution.json`` (fits per group, the LIGGGHTS calibration, the OpenFOAM
and YADE settings with their conventions) and one snippet file per group and code.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np

from solver import SOLVER_VERSION

from . import liggghts
from .conventions import CONVENTIONS, stokes_numbers
from .fits import LAWS

__all__ = ["CSV_FIELDS", "store_rows", "scene_rows", "scene_path", "write_export", "read_csv",
           "group_settings"]

CSV_FIELDS = (
    "group", "material1", "material2", "fluid", "radius1_m", "radius2_m", "density1_kg_m3",
    "density2_kg_m3", "youngs1_Pa", "youngs2_Pa", "poisson1", "poisson2", "viscosity_Pa_s",
    "fluid_density_kg_m3", "v0_m_s", *CONVENTIONS, "eps", "x_ref_x0", "e_wet", "sticks",
    "closest_approach_x1", "closest_approach_m", "peak_pressure", "peak_pressure_Pa",
    "roughness_m", "warning", "status", "solver_version",
)


def _blank():
    return {k: "" for k in CSV_FIELDS}


def store_rows(ds, density_ratio: float = 0.0) -> list[dict]:
    """One row per ok scene of a sweep store with (St, eps) axes; groups are the eps values."""
    solver_version = ds.attrs.get("solver_version", "")
    out = []
    st_values, eps_values = ds["St"].values, ds["eps"].values
    for eps in eps_values:
        sub = ds.sel(eps=eps)
        for st in st_values:
            cell = sub.sel(St=st)
            if int(cell["status"].values) != 1:
                continue
            row = _blank()
            row.update(stokes_numbers(float(st), rho_f=density_ratio))
            e = float(cell["e_wet"].values)
            row.update(group=f"eps={float(eps):.3g}", eps=float(eps), x_ref_x0=1.0, e_wet=e,
                       sticks=bool(e == 0.0),
                       closest_approach_x1=float(cell["h_m_x1"].values),
                       peak_pressure=float(cell["p_max"].values), status="ok",
                       solver_version=solver_version)
            out.append(row)
    return out


def scene_path(scene, vary: str, factors) -> list:
    """Scenes along a path: ``v0`` or the radii (and ``x0`` with them, keeping ``x0/a``) times
    each factor. eps moves along the path with v0 and size: that is the point."""
    scenes = []
    for f in factors:
        if vary == "v0":
            scenes.append(dataclasses.replace(scene, v0=scene.v0 * f))
        elif vary == "radius":
            b1 = dataclasses.replace(scene.body1, radius=scene.body1.radius * f)
            b2 = dataclasses.replace(scene.body2, radius=scene.body2.radius * f)
            scenes.append(dataclasses.replace(scene, body1=b1, body2=b2, x0=scene.x0 * f))
        else:
            raise ValueError(f"vary must be 'v0' or 'radius', got {vary!r}")
    return scenes


def scene_rows(results, group: str) -> list[dict]:
    """Rows of solved scenes (``pipeline.scenes.run.SceneResult``)."""
    out = []
    for r in results:
        s, c = r.scene, r.collision
        b1, b2 = s.body1, s.body2
        row = _blank()
        row.update(stokes_numbers(s.stokes, rho_p=b1.solid.density, d=2.0 * b1.radius, v0=s.v0,
                                  mu=s.fluid.viscosity, rho_f=s.fluid.density))
        rough = next((w for w in r.warnings if w.check == "roughness"), None)
        from pipeline.scenes.checks import combined_roughness
        sigma = combined_roughness(s)
        row.update(
            group=group, material1=b1.solid.name, material2=b2.solid.name, fluid=s.fluid.name,
            radius1_m=b1.radius, radius2_m=b2.radius, density1_kg_m3=b1.solid.density,
            density2_kg_m3=b2.solid.density if b2.solid.density is not None else "",
            youngs1_Pa=b1.solid.youngs_modulus, youngs2_Pa=b2.solid.youngs_modulus,
            poisson1=b1.solid.poisson_ratio, poisson2=b2.solid.poisson_ratio,
            viscosity_Pa_s=s.fluid.viscosity, fluid_density_kg_m3=s.fluid.density, v0_m_s=s.v0,
            eps=s.eps, x_ref_x0=c.x_ref_x0, e_wet=c.e_wet, sticks=bool(c.e_wet == 0.0),
            closest_approach_x1=c.h_m_x1, closest_approach_m=c.h_m_x1 * s.x1,
            peak_pressure=c.p_max, peak_pressure_Pa=r.peak_pressure,
            roughness_m="" if sigma is None else sigma,
            warning="" if rough is None else rough.message, status=c.status,
            solver_version=SOLVER_VERSION)
        out.append(row)
    return out


def _num(v):
    if v == "" or v is None:
        return math.nan
    return float(v)


def group_settings(rows: list[dict]) -> dict:
    """Fits on every convention, the LIGGGHTS calibration and the OpenFOAM / YADE settings of one
    group of rows. A group with fewer than 3 rebounding rows gets a note instead."""
    ok = [r for r in rows if r["status"] in ("ok", "start_deformed") and
          math.isfinite(_num(r["e_wet"]))]
    e = np.array([_num(r["e_wet"]) for r in ok])
    out = {"n": len(ok), "n_rebound": int(np.sum(e > 0)), "fits": {}}
    if out["n_rebound"] < 3:
        out["note"] = ("fewer than 3 rebounding collisions: no fit (use ehd restitution over a "
                       "range of speeds or sizes)")
        return out
    for conv in CONVENTIONS:
        st = np.array([_num(r[conv]) for r in ok])
        out["fits"][conv] = {law: fit(st, e, conv).as_dict() for law, fit in LAWS.items()}
    st = np.array([_num(r["St"]) for r in ok])
    exp_fit = out["fits"]["St"]["exponential"]
    plain = np.array([liggghts.replica_restitution(s, exp_fit["e_max"], exp_fit["c"])
                      for s in st[e > 0]])
    e_max, c, err, _ = liggghts.calibrate(st, e, exp_fit["e_max"], exp_fit["c"])
    out["liggghts"] = {
        "convention": "St", "MaximumRestitution": e_max, "CriticalStokes": c,
        "calibration_max_error": err,
        "uncalibrated_max_error": float(np.max(np.abs(plain - e[e > 0]))),
        "note": "CriticalStokes is the constant C of e = e_max exp(-C/St) with St from the "
                "instantaneous normal velocity; values calibrated against the replica "
                "(pipeline/dem/liggghts.py) so the realised e matches the model at impact",
    }
    fl = out["fits"]["St_L"]["exponential"]
    thr_l = out["fits"]["St_L"]["threshold"]
    st_stick_l = thr_l["c"]
    out["openfoam"] = {
        "model": "localInteractionHW (patchInteractionModel; StokesWallMPPIC library)",
        "convention": "St_L = (rho_p + rho_f/2) d Un / (9 mu)",
        "e": fl["e_max"], "coeffStc": fl["c"],
        "eCutoffLog": math.log(fl["e_max"]) - fl["c"] / st_stick_l if st_stick_l > 0 else None,
        "note": "eCutoffLog: ln e of the law at the sticking threshold St_L,c of the threshold "
                "fit; the version of the library read hard-codes a cut-off of -5.3 in its "
                "correct() and may ignore this entry",
    }
    ty = out["fits"]["St_yade"]["threshold"]
    out["yade"] = {
        "material": "ViscElMat(lubrication=True)",
        "convention": "St_yade = rho_p d v / mu (no factor 9)",
        "en": ty["e_max"], "roughnessScale_over_d": 0.5 * math.exp(-ty["c"]),
        "law": "e = en (1 - ln(d / (2 roughnessScale)) / St_yade): threshold St_yade,c = "
               "ln(d / (2 roughnessScale)), so roughnessScale = (d/2) exp(-St_yade,c)",
        "note": "the roughnessScale that reproduces the EHD threshold is far below any real "
                "roughness: it is a fitting constant of the rigid-lubrication law, not a surface "
                "property",
    }
    return out


def _first(rows, key):
    return next((r[key] for r in rows if r[key] != ""), "")


def _openfoam_text(s) -> str:
    o = s["openfoam"]
    cut = "" if o["eCutoffLog"] is None else f"\n                eCutoffLog {o['eCutoffLog']:.6g};"
    return f"""// ehd-collision wet restitution ({o['convention']}); constant/cloudProperties
patchInteractionModel localInteractionHW;

localInteractionHWCoeffs
{{
    patches
    (
        walls
        {{
            type       rebound;
            e          {o['e']:.6g};
            mu         0;
            rhoF       {o.get('rhoF', 1000.0):.6g};
            muP        {o.get('muP', 1e-3):.6g};
            coeffStc   {o['coeffStc']:.6g};{cut}
        }}
    );
}}
"""


def _yade_text(s, d=None) -> str:
    y = s["yade"]
    rough = (f"{y['roughnessScale_over_d'] * d:.6g}" if d else
             f"{y['roughnessScale_over_d']:.6g} * d  # d: particle diameter")
    return f"""# ehd-collision wet restitution for YADE ({y['convention']})
# {y['law']}
mat = O.materials.append(ViscElMat(en={y['en']:.6g}, lubrication=True,
                                   viscoDyn={y.get('viscoDyn', 1e-3):.6g},
                                   roughnessScale={rough}))
"""


def write_export(rows: list[dict], out_dir, source: str) -> list[Path]:
    """Write the CSV, the JSON and the per-group snippets into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "restitution.csv", out / "restitution.json"]
    with open(paths[0], "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    groups = {}
    for r in rows:
        groups.setdefault(r["group"], []).append(r)
    doc = {"source": source, "solver_version": SOLVER_VERSION,
           "conventions": {k: {"definition": d, "used_by": u} for k, (d, u) in CONVENTIONS.items()},
           "groups": {}}
    for name, grp in groups.items():
        s = group_settings(grp)
        doc["groups"][name] = s
        if "liggghts" not in s:
            continue
        mu = _num(_first(grp, "viscosity_Pa_s"))
        mu = 1e-3 if not math.isfinite(mu) else mu
        rho_f = _num(_first(grp, "fluid_density_kg_m3"))
        s["openfoam"].update(rhoF=1000.0 if not math.isfinite(rho_f) else rho_f, muP=mu)
        s["yade"]["viscoDyn"] = mu
        tag = re.sub(r"[^A-Za-z0-9.+-]+", "_", name).strip("_")
        mats = [m for m in dict.fromkeys([_first(grp, "material1") or "type1",
                                          _first(grp, "material2") or "type1"])]
        n = len(mats)
        lig = s["liggghts"]
        youngs = [_num(_first(grp, "youngs1_Pa")), _num(_first(grp, "youngs2_Pa"))][:n]
        poisson = [_num(_first(grp, "poisson1")), _num(_first(grp, "poisson2"))][:n]
        youngs = [y if math.isfinite(y) else 7e10 for y in youngs]
        poisson = [p if math.isfinite(p) else 0.25 for p in poisson]
        v_char = _num(_first(grp, "v0_m_s"))
        full = lambda v: [[v] * n for _ in range(n)]  # noqa: E731  (one pair: same value)
        text = liggghts.snippet(mats, full(lig["MaximumRestitution"]), full(lig["CriticalStokes"]),
                                full(mu), youngs, poisson, 1.0 if not math.isfinite(v_char) else v_char)
        d = 2.0 * _num(_first(grp, "radius1_m"))
        for fname, body in ((f"liggghts_{tag}.in", text), (f"openfoam_{tag}.txt", _openfoam_text(s)),
                            (f"yade_{tag}.py", _yade_text(s, d if math.isfinite(d) else None))):
            (out / fname).write_text(body)
            paths.append(out / fname)
    paths[1].write_text(json.dumps(doc, indent=2, default=_json_default))
    return paths


def _json_default(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, np.bool_):
        return bool(v)
    raise TypeError(type(v))


def read_csv(path) -> list[dict]:
    """The rows of ``restitution.csv`` back, numbers as floats (empty: ``""``)."""
    rows = []
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            for k, v in r.items():
                if k in ("sticks",):
                    r[k] = v == "True"
                elif v != "" and k not in ("group", "material1", "material2", "fluid", "warning",
                                            "status", "solver_version"):
                    r[k] = float(v)
            rows.append(r)
    return rows
