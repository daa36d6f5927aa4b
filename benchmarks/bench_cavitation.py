"""The cavitating film (Reynolds and JFO floors) next to the classic one: speed and accuracy per
preset, and the two cavitation models against each other.

1. Speed: CPU time per collision (one core, compiled code warm) of the classic film and of both
   floor models at Pi = 1e-4 (the liquid scenes) and Pi = 1e-2, on the same scenes and presets;
   and of the classic film with BDF2 throughout (``max_order=2``), the method a cavitating film
   steps with once its first cavity opens (docs/solver.md, "Orders above 2"): the ratio to it is
   at most the cost of the floor itself (the cavitating film takes the orders above 2 until
   then), and the ratio to the classic film is about that cost times the classic film's gain
   from the orders above 2. Every variant of one scene and preset is timed in one process, in
   rounds (each round solves each variant once, in a rotated order: harness.alternate), so a
   ratio is the median of per-round ratios, and the table gives the median of the scenes'
   ratios with their range.
2. Accuracy: per scene, a reference from three resolutions beyond the presets (grid cells x2 and
   time tolerance /8 per level, as benchmarks/bench_accuracy.py), Richardson-extrapolated with
   the observed order; each preset's error against it. The references are pinned in
   ``cavitation_references.json`` with the solver that computed them, so that a change of the
   numerics is measured against the same truth (they had been recomputed by the solver under
   test, so a change of the error control moved them too); ``--recompute-references``
   recomputes them, as a change of the model needs.

``python benchmarks/bench_cavitation.py [--recompute-references]`` (a few minutes on 2 cores)
writes ``benchmarks/cavitation.md`` and ``cavitation.json``.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import harness
from bench_accuracy import SINGLE_GRID  # the references' single grids

HERE = Path(__file__).parent
REFERENCES = HERE / "cavitation_references.json"
SPEED_SCENES = [(st, ep) for ep in (1e-2, 1e-6) for st in (5.0, 10.0, 30.0, 100.0)]
FLOORS = (1e-2, 1e-4)
MODELS = ("reynolds", "jfo")
PRESETS = ("fast", "standard", "fine")
REPEATS = 5
# the timed variants of a scene: (label, Pi, model, max_order); Pi inf: no floor
VARIANTS = [("classic", math.inf, "off", None), ("classic_bdf2", math.inf, "off", 2)] + [
    (f"{model}_{pi:g}", pi, model, None) for pi in FLOORS for model in MODELS]
ACCURACY_SCENES = [(10.0, 1e-2, 1e-4), (30.0, 1e-6, 1e-4), (10.0, 1e-2, 1e-2), (100.0, 1e-4, 1e-3)]
KEYS = ("v_r", "h_m_x1", "ln_x_e_x1", "cavity_radius_max", "e_wet")
LEVELS = [dict(SINGLE_GRID, n_inner=64 * 2**k, stretch=1.0 + 0.2 / 2**k, max_rel=0.3 / 2**k,
               rtol=4e-5 / 8**k, switch=1e-4, release=3.125e-5) for k in range(3)]
if "--quick" in sys.argv:  # smoke run of the script itself
    SPEED_SCENES, ACCURACY_SCENES, REPEATS = SPEED_SCENES[:2], ACCURACY_SCENES[:1], 1
    HERE = Path("/tmp")  # the pinned references are read where they are, never written


def _physics(st, eps, pi, model):
    from solver import Physics

    return Physics(St=st, eps=eps, Pi=pi, cavitation=model)


def timed(args):
    """CPU seconds per round of each variant of one scene at one preset, alternated
    (harness.alternate: a warm-up round, then ``REPEATS`` rounds in rotated orders); and the
    variants' statuses."""
    st, eps, preset = args
    from solver import collide

    status = {}

    def side(label, pi, model, max_order):
        physics = _physics(st, eps, pi, model)
        options = {} if max_order is None else {"max_order": max_order}

        def solve_once():
            status[label] = collide(physics, accuracy=preset, save_profiles=False,
                                    **options).status

        return lambda: harness.time_call(solve_once)

    runs = harness.alternate({v[0]: side(*v) for v in VARIANTS}, REPEATS)
    return {label: [r["cpu_s"] for r in rounds] for label, rounds in runs.items()}, status


def solve(args):
    st, eps, pi, model, preset, overrides = args
    from solver import collide

    c = collide(_physics(st, eps, pi, model), accuracy=preset, save_profiles=False, **overrides)
    return {k: float(getattr(c, k)) for k in KEYS} | {"status": c.status, "wall_s": c.wall_s}


def richardson(values):
    """Limit of three values at ratio-2 refinement, with the observed order and the estimate's
    own error (the last correction); NaN order when the differences do not shrink."""
    a, b, c = values
    d1, d2 = b - a, c - b
    if d2 == 0.0:
        return c, math.inf, 0.0
    ratio = d1 / d2
    if not ratio > 1.0:
        return c, math.nan, abs(d2)
    p = math.log2(ratio)
    corr = d2 / (2.0**p - 1.0)
    return c + corr, p, abs(corr)


def references(cases, pool):
    """The pinned references of ``cases`` (module docstring), recomputed (and pinned again) with
    ``--recompute-references`` or where the file lacks a case."""
    try:
        pinned = json.loads(REFERENCES.read_text()) if REFERENCES.exists() else {"cases": []}
        rows = {(r["St"], r["eps"], r["Pi"], r["model"]): r for r in pinned["cases"]}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise SystemExit(f"bench_cavitation: the pinned references {REFERENCES} are unreadable "
                         f"({type(exc).__name__}: {exc}); restore the file from git, or "
                         "recompute them with --recompute-references") from None
    if "--recompute-references" not in sys.argv and all(c in rows for c in cases):
        return pinned, [rows[c] for c in cases]
    ref_jobs = [(*case, "fine", lv) for case in cases for lv in LEVELS]
    levels = list(pool.map(solve, ref_jobs))
    fresh = []
    for k, (st, ep, pi, model) in enumerate(cases):
        row = dict(St=st, eps=ep, Pi=pi, model=model, reference={}, order={}, ref_error={})
        for key in KEYS:
            ref, order, err = richardson([lv[key] for lv in levels[3 * k: 3 * k + 3]])
            row["reference"][key], row["order"][key], row["ref_error"][key] = ref, order, err
        fresh.append(row)
    if HERE == REFERENCES.parent:  # not the --quick smoke run
        pinned = harness.write_json(REFERENCES, {"cases": fresh}, harness.load_now())
    return pinned, fresh


def main():
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    t0 = time.time()
    load_start = harness.load_now()
    cases = [(st, ep, pi, model) for st, ep, pi in ACCURACY_SCENES for model in MODELS]
    with ProcessPoolExecutor(2) as pool:
        pool.submit(solve, (5.0, 1e-2, 1e-4, "jfo", "fast", {})).result()  # compile once
        speed_jobs = [(st, ep, pr) for pr in PRESETS for st, ep in SPEED_SCENES]
        speed = list(pool.map(timed, speed_jobs))
        pinned, rows = references(cases, pool)
        preset_jobs = [(*case, pr, {}) for case in cases for pr in PRESETS]
        presets = list(pool.map(solve, preset_jobs))
    res = {"speed": [], "accuracy": [], "references": {k: pinned.get(k) for k in
                                                       ("solver_version", "commit", "date")},
           "seconds": 0.0}
    for (st, ep, pr), (cpu, status) in zip(speed_jobs, speed):
        res["speed"].append(dict(St=st, eps=ep, preset=pr, cpu_s=cpu, status=status))
    for k, ref_row in enumerate(rows):
        row = {**ref_row, "presets": {}}
        for j, pr in enumerate(PRESETS):
            got = presets[3 * k + j]
            row["presets"][pr] = {key: abs(got[key] - row["reference"][key])
                                  / max(abs(row["reference"][key]), 1e-3) for key in KEYS}
            row["presets"][pr]["wall_s"] = got["wall_s"]
        res["accuracy"].append(row)
    res["seconds"] = time.time() - t0
    res = harness.write_json(HERE / "cavitation.json", res, load_start, default=str)
    write_report(res)


def _ratio(res, preset, label, base):
    """The median over the speed scenes of each scene's median per-round ratio of ``label`` to
    ``base`` at ``preset``, and the range of the scenes' ratios."""
    per_scene = [statistics.median(harness.round_ratios(r["cpu_s"][label], r["cpu_s"][base]))
                 for r in res["speed"] if r["preset"] == preset]
    return statistics.median(per_scene), min(per_scene), max(per_scene)


def _ms(res, preset, label):
    """The median over the speed scenes of each scene's median CPU time of ``label`` [ms]."""
    return 1e3 * statistics.median(statistics.median(r["cpu_s"][label]) for r in res["speed"]
                                   if r["preset"] == preset)


def write_report(res):
    def ratio(pr, label, base):
        mid, lo, hi = _ratio(res, pr, label, base)
        return f"{mid:.2f} ({lo:.2f}-{hi:.2f})"

    lines = ["# Cavitation (Reynolds and JFO floors) next to the classic film", "",
             "`python benchmarks/bench_cavitation.py` regenerates this file (`make bench`). One "
             "scene at a time per core, compiled code warm, OPENBLAS_NUM_THREADS=1. Each scene "
             "and preset in one process, its variants alternated: a warm-up round, then "
             f"{REPEATS} rounds that solve each variant once, in a rotated order. A ratio is the "
             "median over the scenes of each scene's median per-round ratio, with the scenes' "
             "range; a time, the median over the scenes of each scene's median.", "",
             "## Speed: CPU time per collision [ms]", "",
             "| preset | classic | Reynolds Pi = 1e-2 | Reynolds Pi = 1e-4 | JFO Pi = 1e-2 | "
             "JFO Pi = 1e-4 | Reynolds / classic (Pi = 1e-4) | JFO / classic (Pi = 1e-4) |",
             "|---|---|---|---|---|---|---|---|"]
    bdf2_rows = []
    for pr in PRESETS:
        lines.append(f"| {pr} | {_ms(res, pr, 'classic'):.1f} | "
                     f"{_ms(res, pr, 'reynolds_0.01'):.1f} | {_ms(res, pr, 'reynolds_0.0001'):.1f} | "
                     f"{_ms(res, pr, 'jfo_0.01'):.1f} | {_ms(res, pr, 'jfo_0.0001'):.1f} | "
                     f"{ratio(pr, 'reynolds_0.0001', 'classic')} | "
                     f"{ratio(pr, 'jfo_0.0001', 'classic')} |")
        bdf2_rows.append(f"| {pr} | {_ms(res, pr, 'classic_bdf2'):.1f} | "
                         f"{ratio(pr, 'classic_bdf2', 'classic')} | "
                         f"{ratio(pr, 'reynolds_0.0001', 'classic_bdf2')} | "
                         f"{ratio(pr, 'jfo_0.0001', 'classic_bdf2')} |")
    lines += ["", "The classic film with BDF2 throughout (`max_order=2`), the method a "
              "cavitating film steps with from its first cavity on (docs/solver.md, \"Orders "
              "above 2\"). A cavitating film takes the orders above 2 until then, so its ratio "
              "to this film is at most the floor's own cost; its ratio to the classic film "
              "(above) is about that cost times the classic film's gain from the orders above 2.",
              "", "| preset | classic, BDF2 [ms] | classic BDF2 / classic | "
              "Reynolds / classic BDF2 (Pi = 1e-4) | JFO / classic BDF2 (Pi = 1e-4) |",
              "|---|---|---|---|---|", *bdf2_rows]
    widest = max(max(rounds) / min(rounds) for r in res["speed"]
                 for label in ("classic_bdf2", "reynolds_0.0001", "jfo_0.0001")
                 for rounds in [harness.round_ratios(r["cpu_s"][label], r["cpu_s"]["classic"])])
    lines += ["", f"Within one scene the rounds agree: the widest range of a scene's per-round "
              f"ratios to the classic film is a factor {widest:.2f} (largest over "
              "smallest); the ranges in the tables are the scenes' own differences (per scene: "
              "`cavitation.json`)."]
    runs = [status for r in res["speed"] for status in r["status"].values()]
    bad = sum(status != "ok" for status in runs)
    pinned = res["references"]
    lines += ["", f"Scenes: St in {{5, 10, 30, 100}} x eps in {{1e-2, 1e-6}}; "
              f"{bad} of {len(runs)} variants not ok.", "",
              "## Accuracy: relative error of each preset against a refined reference", "",
              "Reference: three levels beyond `fine` (cells x2, rtol /8 per level, switch 1e-4, "
              "release 3.1e-5), Richardson-extrapolated; `order` is the observed order, `ref err` "
              "the extrapolation's own correction. Errors relative to max(|ref|, 1e-3). The "
              "references are pinned in `cavitation_references.json`: computed by solver "
              f"{pinned.get('solver_version')} (commit {str(pinned.get('commit'))[:7]}, "
              f"{str(pinned.get('date'))[:10]}); `--recompute-references` recomputes them.", ""]
    head = ("| St | eps | Pi | model | quantity | reference | order | ref err | fast | standard "
            "| fine |")
    lines += [head, "|---" * 11 + "|"]
    for row in res["accuracy"]:
        for key in KEYS:
            p = row["presets"]
            lines.append(f"| {row['St']:g} | {row['eps']:g} | {row['Pi']:g} | {row['model']} | "
                         f"{key} | "
                         f"{row['reference'][key]:.6g} | {row['order'][key]:.2f} | "
                         f"{row['ref_error'][key]:.1e} | {p['fast'][key]:.1e} | "
                         f"{p['standard'][key]:.1e} | {p['fine'][key]:.1e} |")
    lines += ["", "## JFO against Reynolds (the references)", "",
              "| St | eps | Pi | quantity | Reynolds | JFO | JFO - Reynolds |", "|---" * 7 + "|"]
    refs = {(r["St"], r["eps"], r["Pi"], r["model"]): r["reference"] for r in res["accuracy"]}
    for st, ep, pi in ACCURACY_SCENES:
        for key in KEYS:
            a, b = refs[(st, ep, pi, "reynolds")][key], refs[(st, ep, pi, "jfo")][key]
            lines.append(f"| {st:g} | {ep:g} | {pi:g} | {key} | {a:.6g} | {b:.6g} | {b - a:+.3g} |")
    lines += ["", f"Run time of this benchmark: {res['seconds'] / 60:.1f} min.", ""]
    text = "\n".join(lines)
    (HERE / "cavitation.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
