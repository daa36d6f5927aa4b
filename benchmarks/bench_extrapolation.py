"""Two grids, one answer: Richardson extrapolation of a collision's observables across a grid and
the same grid with half the cells (issue 30, item 3: a higher order in space where it pays; the
fine preset since solver 1.15.0, solver/extrapolation.py).

The film's discretisation is second order in space (benchmarks/accuracy.md: observed orders
1.95-1.99, median over the panel), so its grid error falls 4x when the cells halve. A pair of
solves, one on the grid ``h`` and one on ``Numerics.halved()`` (half the inner cells, the outer
cells growing twice as fast and twice as wide, the axis refined alike; the time tolerance, the
orders and the rigid phases' thresholds the same), combined as ``f_h + (f_h - f_2h) / 3``,
cancels that error's leading term; what both solves share (the time error at one tolerance, the
thresholds' error) passes through as it is in ``f_h``. ``|f_h - f_2h| / 3`` is also an estimate
of the grid error of ``f_h`` alone, shown beside its measured error.

Measured against converged references:

- the classic film: the accuracy panel's (benchmarks/accuracy.json, 21 scenes) and a hold-out
  panel's, computed here the same way (``bench_accuracy.references``: three levels to 256 inner
  cells, thresholds extrapolated to 0) on 10 scenes at St and eps that no setting here was
  chosen on. The fine preset's pair (80 inner cells, the axis at 0.05 of a cell, with 40) was
  chosen on the accuracy panel among four settings; the hold-out panel checks that it
  generalises. Every float observable of the registry is also compared on both panels against
  references from the same three levels (without the thresholds' correction);
- the other films: the stored references of benchmarks/cavitation.json (JFO, Reynolds) and
  benchmarks/piezoviscous.json (Barus), and references computed here from the three levels for
  rough surfaces and slip.

Time: every candidate solves the classic accuracy panel once per round, the candidates
alternated (``harness.alternate``, one core); the ratio to the fine preset of solver 1.14 (128
inner cells, one grid) is the median of the per-round ratios, with their spread; the other films
alike, the two fine presets only.

``python benchmarks/bench_extrapolation.py [--rounds 5] [--quick]`` (about 4 minutes) writes
``benchmarks/extrapolation.md`` and ``extrapolation.json`` (``--quick``: two scenes per panel,
two rounds, to /tmp).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict
from pathlib import Path

import harness
from bench_accuracy import LEVELS, RELEASE_REF, SWITCH_REF, error, references, richardson

HERE = Path(__file__).parent
KEYS = ("v_r", "h_m_x1", "h_m_approach_x1", "ln_x_e_x1")  # the accuracy table's
HOLDOUT = [(st, ep) for ep in (1e-3, 1e-6) for st in (3.0, 7.0, 20.0, 50.0, 150.0)]
# the fine preset of solvers 1.12-1.14: one grid of 128 inner cells
FINE_1_14 = dict(n_inner=128, axis_ratio=0.1, stretch=1.1, max_rel=0.2, extrapolate=False)
# name: (preset, overrides)
CANDIDATES = {
    "fast": ("fast", {}),
    "standard": ("standard", {}),
    "fine 1.14 (128 cells)": ("fine", FINE_1_14),
    "80 cells alone": ("fine", dict(extrapolate=False)),
    "standard pair": ("standard", dict(extrapolate=True)),
    "fine (80 + 40 cells)": ("fine", {}),
    "128 + 64 cells": ("fine", dict(FINE_1_14, extrapolate=True)),
}
BASE, NEW = "fine 1.14 (128 cells)", "fine (80 + 40 cells)"
# rough surfaces and slip: (St, eps, Physics fields), references computed here
OTHER = [(10.0, 1e-4, dict(roughness=0.5)), (30.0, 1e-4, dict(roughness=0.3)),
         (10.0, 1e-4, dict(roughness=0.5, e_dry=0.8)), (10.0, 1e-4, dict(slip_length=0.5)),
         (100.0, 1e-4, dict(slip_length=0.2))]
OTHER_KEYS = ("v_r", "h_m_x1", "ln_x_e_x1", "e_wet")
# the other films' speeds relative to at least 0.05, as benchmarks/accuracy.md measures v_r
SPEED_FLOOR = 0.05


def numerics(name):
    from solver.settings import resolve

    preset, overrides = CANDIDATES[name]
    return resolve(preset, **overrides)


def solve(args):
    """One collision's observables (``keys``; all float observables for ``"all"``)."""
    scene, preset, overrides, keys = args
    from solver import Physics, collide
    from solver.observables import OBSERVABLES

    st, ep, fields = scene if len(scene) == 3 else (*scene, {})
    c = collide(Physics(St=st, eps=ep, **fields), accuracy=preset, save_profiles=False,
                **overrides)
    if keys == "all":  # not the wall time, nor the energy closure (a check, not a limit)
        keys = [o.name for o in OBSERVABLES if o.kind == "float"
                and o.name not in ("wall_s", "energy_error")]
    # ln_viscosity_ratio: the log of the peak viscosity ratio, as benchmarks/piezoviscous.md
    out = {k: math.log(c.viscosity_ratio_max_approach) if k == "ln_viscosity_ratio"
           else float(getattr(c, k)) for k in keys}
    return {**out, "status": c.status}


def _as_overrides(n):
    return {k: v for k, v in asdict(n).items() if k != "save_profiles"}


def runs(pool, scenes, name, keys=KEYS):
    """The candidate's values per scene, and for a pair its finer and coarser solves alone."""
    preset, overrides = CANDIDATES[name]
    values = list(pool.map(solve, [(s, preset, overrides, keys) for s in scenes], chunksize=1))
    n = numerics(name)
    if not n.extrapolate:
        return values, None, None
    single = _as_overrides(n) | {"extrapolate": False}
    fine = list(pool.map(solve, [(s, preset, single, keys) for s in scenes], chunksize=1))
    coarse = list(pool.map(solve, [(s, preset, _as_overrides(n.halved()), keys) for s in scenes],
                           chunksize=1))
    return values, fine, coarse


def panel_errors(pool, panel, reference):
    """Per candidate: each observable's error per scene against ``reference``, and for a pair
    the finer solve's own error and its estimate ``|f_h - f_2h| / 3``."""
    out = {}
    for name in CANDIDATES:
        print(f"  {name} ...", flush=True)
        values, fine, coarse = runs(pool, panel, name)
        row = {"errors": {k: [error(v[k], r[k], k) for v, r in zip(values, reference)]
                          for k in KEYS}}
        if fine is not None:
            row["fine_errors"] = {k: [error(f[k], r[k], k) for f, r in zip(fine, reference)]
                                  for k in KEYS}
            row["estimates"] = {k: [error(f[k] + abs(f[k] - c[k]) / 3.0, f[k], k)
                                    for f, c in zip(fine, coarse)] for k in KEYS}
        out[name] = row
    return out


def level_references(pool, scenes, keys):
    """References from the three levels of bench_accuracy.py (grid and time refined together,
    thresholds at ``SWITCH_REF``, ``RELEASE_REF``), Richardson-extrapolated with the observed
    order: ``{key: [(reference, its estimated error) per scene]}`` (NaN where a level is not
    finite)."""
    base = dict(switch=SWITCH_REF, release=RELEASE_REF)
    levels = [list(pool.map(solve, [(s, "fine", {**base, **lv}, keys) for s in scenes],
                            chunksize=1)) for lv in LEVELS]
    keys = [k for k in levels[0][0] if k != "status"]
    out = {}
    for k in keys:
        out[k] = []
        for i in range(len(scenes)):
            vals = [lv[i][k] for lv in levels]
            ok = all(math.isfinite(v) for v in vals) and all(
                lv[i]["status"] == "ok" for lv in levels)
            limit, _, err = richardson(vals) if ok else (math.nan, math.nan, math.nan)
            out[k].append((limit, err))
    return out


def _relative(value, ref, key, speed_floor=1e-3):
    """The error of a float observable: absolute for a logarithm, else relative to ``|ref|``
    with a floor of 1e-3, ``speed_floor`` for the speeds ``v_r`` and ``e_wet``."""
    if key.startswith("ln_"):
        return abs(value - ref)
    return abs(value - ref) / max(abs(ref), speed_floor if key in ("v_r", "e_wet") else 1e-3)


def every_observable(pool, scenes):
    """Each float observable's largest and median error over ``scenes`` (classic film), the fine
    preset of 1.14 against the pair, with the references' own largest error."""
    refs = level_references(pool, scenes, "all")
    old = list(pool.map(solve, [(s, "fine", FINE_1_14, "all") for s in scenes], chunksize=1))
    new = list(pool.map(solve, [(s, "fine", {}, "all") for s in scenes], chunksize=1))
    out = {}
    for k, ref in refs.items():
        rows = [(r, e, a[k], b[k]) for (r, e), a, b in zip(ref, old, new)
                if all(math.isfinite(x) for x in (r, a[k], b[k]))]
        if not rows:
            continue
        e_old = [_relative(a, r, k) for r, _, a, _ in rows]
        e_new = [_relative(b, r, k) for r, _, _, b in rows]
        out[k] = {"n": len(rows), "old_max": max(e_old), "old_median": statistics.median(e_old),
                  "new_max": max(e_new), "new_median": statistics.median(e_new),
                  "ref_error": max(_relative(r + e, r, k) for r, e, _, _ in rows)}
    return out


def other_films(pool, quick):
    """The two fine presets against the references of the other films: each family's largest
    error per observable."""
    cav = json.loads((HERE / "cavitation.json").read_text())["accuracy"]
    piezo = json.loads((HERE / "piezoviscous.json").read_text())["accuracy"]
    families = {
        "cavitation (JFO, Reynolds)": (
            [(r["St"], r["eps"], dict(Pi=r["Pi"], cavitation=r["model"])) for r in cav],
            [r["reference"] for r in cav], OTHER_KEYS),
        "Barus (beta 2, 5)": (
            [(r["St"], r["eps"], dict(beta=r["beta"])) for r in piezo if r["beta"] > 0.0],
            [r["reference"] for r in piezo if r["beta"] > 0.0],
            (*OTHER_KEYS, "ln_viscosity_ratio")),
    }
    scenes = OTHER[:2] if quick else OTHER
    refs = level_references(pool, scenes, OTHER_KEYS)
    families["rough surfaces, slip"] = (
        scenes, [{k: refs[k][i][0] for k in OTHER_KEYS} for i in range(len(scenes))], OTHER_KEYS)
    out = {}
    for family, (fam_scenes, fam_refs, keys) in families.items():
        if quick:
            fam_scenes, fam_refs = fam_scenes[:2], fam_refs[:2]
        print(f"  {family} ...", flush=True)
        row = {"scenes": fam_scenes}
        for name in (BASE, NEW):
            preset, overrides = CANDIDATES[name]
            values = list(pool.map(solve, [(s, preset, overrides, keys) for s in fam_scenes],
                                   chunksize=1))
            row[name] = {k: max(_relative(v[k], r[k], k, SPEED_FLOOR)
                                 for v, r in zip(values, fam_refs))
                         for k in keys}
        out[family] = row
    return out


def cpu_rounds(scenes, names, rounds):
    """Each candidate's CPU seconds for ``scenes``, per round, alternated in this process."""
    from solver import Physics, collide

    def side(name):
        preset, overrides = CANDIDATES[name]

        def run():
            for st, ep, *fields in scenes:
                collide(Physics(St=st, eps=ep, **(fields[0] if fields else {})), accuracy=preset,
                        save_profiles=False, **overrides)
        return lambda: harness.time_call(run)

    times = harness.alternate({name: side(name) for name in names}, rounds)
    base = [t["cpu_s"] for t in times[BASE]]
    return {name: {"cpu_s": [t["cpu_s"] for t in runs],
                   "ratio": harness.compare([t["cpu_s"] for t in runs], base)["ratio"]}
            for name, runs in times.items()}


def _fmt(x):
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.1e}"


def _largest(errors, panel, stokes_max=math.inf):
    return max(max(e for e, (st, _) in zip(errors[k], panel) if st <= stokes_max) for k in KEYS)


def _cost_rows(cpu):
    rows = ["| candidate | CPU [s] | / fine of 1.14 |", "|---|---:|---:|"]
    for name, t in cpu.items():
        r = t["ratio"]
        rows.append(f"| {name} | {statistics.median(t['cpu_s']):.2f} | {r['median']:.2f} "
                    f"[{r['min']:.2f}-{r['max']:.2f}] |")
    return rows


def render_panels(res) -> list[str]:
    lines = []
    for panel_name in ("accuracy", "holdout"):
        p = res[panel_name]
        panel = [tuple(x) for x in p["panel"]]
        ref_err = max(max(r[k] for r in p["reference_error"] if r[k] is not None) for k in KEYS)
        title = ("Classic film, accuracy panel (benchmarks/accuracy.json's 21 references)"
                 if panel_name == "accuracy" else
                 f"Classic film, hold-out panel ({len(panel)} scenes: St "
                 f"{sorted({st for st, _ in panel})} x eps {sorted({ep for _, ep in panel})}, "
                 "references computed in this run)")
        lines += [f"## {title}", "",
                  f"Largest error of the reference itself (estimated): {ref_err:.1e}; errors "
                  "below it are not resolved.", "",
                  "| candidate | v_r | h_m | h_m approach | x_e (ln) | max, St<=30 |",
                  "|---|---|---|---|---|---|"]
        for name, row in p["candidates"].items():
            e = row["errors"]
            lines.append(f"| {name} | " + " | ".join(_fmt(max(e[k])) for k in KEYS)
                         + f" | {_fmt(_largest(e, panel, 30.0))} |")
        lines.append("")
    return lines


def render_estimates(res) -> list[str]:
    lines = ["## The pair's error estimate", "",
             "`|f_h - f_2h|/3` against the measured error of the finer solve `f_h` alone, over "
             "both classic panels: the median of their ratio (measured / estimated) per "
             "observable, and how many of the scenes' measured errors exceed twice the estimate "
             "(where the grid error is not the leading one: the time tolerance or the "
             "thresholds, which the estimate does not see, or a grid not yet in its asymptotic "
             "range).", "", "| pair | " + " | ".join(KEYS) + " |", "|---" * (len(KEYS) + 1) + "|"]
    for name, row in res["accuracy"]["candidates"].items():
        if "estimates" not in row:
            continue
        cells = []
        for k in KEYS:
            pairs = [(m, s) for panel_name in ("accuracy", "holdout")
                     for m, s in zip(res[panel_name]["candidates"][name]["fine_errors"][k],
                                     res[panel_name]["candidates"][name]["estimates"][k])
                     if s > 0.0 or m > 0.0]
            ratios = [m / s for m, s in pairs if s > 0.0]
            over = sum(m > 2.0 * s for m, s in pairs)
            cells.append(f"{statistics.median(ratios):.2f} ({over} of {len(pairs)} > 2x)")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines + [""]


def render(res) -> str:
    lines = ["# Two grids, one answer: Richardson extrapolation of the observables", "",
             harness.describe(res), "",
             "Generated by `python benchmarks/bench_extrapolation.py`. A pair solves a scene on "
             "its grid and on the same grid with half the cells (the time tolerance, orders and "
             "thresholds the same) and reports `f_h + (f_h - f_2h)/3` (solver/extrapolation.py): "
             "the grid error of a second-order discretisation falls 4x when the cells halve, so "
             "its leading term cancels; the time and threshold errors of `f_h` pass through. The "
             "fine preset is such a pair since solver 1.15.0 (80 inner cells, the axis refined to "
             "0.05 of a cell, and 40); `fine 1.14` is the single 128-cell grid it replaced. Errors "
             "as in benchmarks/accuracy.md: relative for v_r (floor 0.05), h_m and h_m_approach; "
             "absolute in ln x_e.", ""]
    lines += render_panels(res)
    lines += ["## Cost", "",
              "CPU time of the classic accuracy panel "
              f"({len(res['accuracy']['panel'])} scenes) per candidate, {res['rounds']} rounds "
              "alternated in one process (one core); the ratio is the median of the per-round "
              "ratios [their range].", "",
              *_cost_rows(res["cpu"]), "",
              f"The other films' scenes below ({res['other_scenes']} scenes), alike:", "",
              *_cost_rows(res["cpu_other"]), ""]
    lines += render_estimates(res)
    lines += ["## Every observable (classic film)", "",
              "Each float observable against references from the three levels of "
              "bench_accuracy.py (thresholds at 1e-4 and 3.1e-5, not extrapolated to 0), over "
              "both classic panels: the largest and the median error of the fine preset of 1.14 "
              "and of the pair (solver/extrapolation.py extrapolates those marked; the others "
              "are the pair's finer solve's). Relative (floor 1e-3), absolute for a logarithm.",
              "", "| observable | scenes | 1.14 max | 1.14 median | pair max | pair median | "
              "reference's error | extrapolated |", "|---|---:|---|---|---|---|---|---|"]
    from solver.extrapolation import EXTRAPOLATED

    for k, r in res["every_observable"].items():
        # the derived ones follow their extrapolated source (x_e from ln x_e, e_far from e_x0)
        marked = "yes" if k in EXTRAPOLATED or k in ("h_m_x0", "h_m_approach_x0", "x_e_x1",
                                                      "x_e_x0", "ln_x_e_x0", "e_far") else ""
        lines.append(f"| {k} | {r['n']} | {_fmt(r['old_max'])} | {_fmt(r['old_median'])} | "
                     f"{_fmt(r['new_max'])} | {_fmt(r['new_median'])} | {_fmt(r['ref_error'])} | "
                     f"{marked} |")
    lines += ["", "## Other films", "",
              "Largest error per family against its references (benchmarks/cavitation.json, "
              "piezoviscous.json; rough surfaces and slip: the three levels, computed here), "
              "relative with a floor of 0.05 for the speeds, absolute for the logarithms.", ""]
    for family, row in res["other"].items():
        keys = list(row[BASE])
        lines += [f"### {family} ({len(row['scenes'])} scenes)", "",
                  "| candidate | " + " | ".join(keys) + " |", "|---" * (len(keys) + 1) + "|"]
        for name in (BASE, NEW):
            lines.append(f"| {name} | " + " | ".join(_fmt(row[name][k]) for k in keys) + " |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--quick", action="store_true",
                        help="two scenes per panel, two rounds, output to /tmp (a smoke run)")
    args = parser.parse_args(argv)
    out = Path("/tmp") if args.quick else HERE
    stored = json.loads((HERE / "accuracy.json").read_text())
    # the panel the stored references belong to (bench_accuracy.py's PANEL, whose --quick
    # replaces it with a two-scene panel of its own)
    accuracy_panel, holdout, rounds = [tuple(x) for x in stored["panel"]], HOLDOUT, args.rounds
    accuracy_ref = {"reference": stored["reference"], "reference_error": stored["reference_error"]}
    if args.quick:
        keep = [0, 10]
        accuracy_panel = [accuracy_panel[i] for i in keep]
        accuracy_ref = {key: [v[i] for i in keep] for key, v in accuracy_ref.items()}
        holdout, rounds = HOLDOUT[:2], 2
    load_start = harness.load_now()
    from solver import collide

    collide(5.0, 0.01)  # compile once before the workers load the cache
    res = {"rounds": rounds, "candidates": {name: {"preset": preset, "overrides": ov}
                                            for name, (preset, ov) in CANDIDATES.items()}}
    with ProcessPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        print("hold-out references ...", flush=True)
        reference, ref_err = references(pool, holdout)[:2]
        res["holdout"] = {"panel": holdout, "reference": reference, "reference_error": ref_err}
        res["accuracy"] = {"panel": accuracy_panel, **accuracy_ref}
        for panel_name in ("accuracy", "holdout"):
            print(f"{panel_name} panel ...", flush=True)
            p = res[panel_name]
            p["candidates"] = panel_errors(pool, [tuple(x) for x in p["panel"]], p["reference"])
        print("every observable ...", flush=True)
        res["every_observable"] = every_observable(pool, [*accuracy_panel, *holdout])
        print("other films ...", flush=True)
        res["other"] = other_films(pool, args.quick)
    print("cost ...", flush=True)
    res["cpu"] = cpu_rounds(accuracy_panel, list(CANDIDATES), rounds)
    other_scenes = [tuple(s) for row in res["other"].values() for s in row["scenes"]]
    res["other_scenes"] = len(other_scenes)
    res["cpu_other"] = cpu_rounds(other_scenes, [BASE, NEW], max(2, rounds - 2))
    res = harness.write_json(out / "extrapolation.json", res, load_start)
    text = render(res)
    (out / "extrapolation.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
