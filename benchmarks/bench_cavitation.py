"""The cavitating film (Reynolds and JFO floors) next to the classic one: speed and accuracy per
preset, and the two cavitation models against each other.

1. Speed: median wall time per collision (one core, compiled code warm) of the classic film and
   of both floor models at Pi = 1e-4 (the liquid scenes) and Pi = 1e-2, on the same scenes and
   presets; and of the classic film with BDF2 throughout (``max_order=2``), the method a
   cavitating film steps with once its first cavity opens (docs/solver.md, "Orders above 2"):
   the ratio to it is at most the cost of the floor itself (the cavitating film takes the
   orders above 2 until then), and the ratio to the classic film is about that cost times the
   classic film's gain from the orders above 2.
2. Accuracy: per scene, a reference from three resolutions beyond the presets (grid cells x2 and
   time tolerance /8 per level, as benchmarks/bench_accuracy.py), Richardson-extrapolated with
   the observed order; each preset's error against it.

``python benchmarks/bench_cavitation.py`` (a few minutes on 2 cores) writes
``benchmarks/cavitation.md`` and ``cavitation.json``.
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
SPEED_SCENES = [(st, ep) for ep in (1e-2, 1e-6) for st in (5.0, 10.0, 30.0, 100.0)]
FLOORS = (math.inf, 1e-2, 1e-4)
MODELS = ("reynolds", "jfo")
PRESETS = ("fast", "standard", "fine")
REPEATS = 3
ACCURACY_SCENES = [(10.0, 1e-2, 1e-4), (30.0, 1e-6, 1e-4), (10.0, 1e-2, 1e-2), (100.0, 1e-4, 1e-3)]
KEYS = ("v_r", "h_m_x1", "ln_x_e_x1", "cavity_radius_max", "e_wet")
LEVELS = [dict(SINGLE_GRID, n_inner=64 * 2**k, stretch=1.0 + 0.2 / 2**k, max_rel=0.3 / 2**k,
               rtol=4e-5 / 8**k, switch=1e-4, release=3.125e-5) for k in range(3)]
if "--quick" in sys.argv:  # smoke run of the script itself
    SPEED_SCENES, ACCURACY_SCENES, REPEATS = SPEED_SCENES[:2], ACCURACY_SCENES[:1], 1
    HERE = Path("/tmp")


def _physics(st, eps, pi, model):
    from solver import Physics

    return Physics(St=st, eps=eps, Pi=pi, cavitation=model)


def timed(args):
    st, eps, pi, model, preset, max_order = args
    from solver import collide

    options = {} if max_order is None else {"max_order": max_order}
    collide(_physics(st, eps, pi, model), accuracy=preset, save_profiles=False,
            **options)  # grid, compile
    walls = []
    for _ in range(REPEATS):
        c = collide(_physics(st, eps, pi, model), accuracy=preset, save_profiles=False,
                    **options)
        walls.append(c.wall_s)
    return statistics.median(walls), c.status


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


def main():
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    t0 = time.time()
    load_start = harness.load_now()
    with ProcessPoolExecutor(2) as pool:
        pool.submit(timed, (5.0, 1e-2, 1e-4, "jfo", "fast", None)).result()  # compile once
        speed_jobs = [(st, ep, pi, model, pr, None) for pr in PRESETS for pi in FLOORS
                      for model in (MODELS if math.isfinite(pi) else ("off",))
                      for st, ep in SPEED_SCENES]
        speed_jobs += [(st, ep, math.inf, "off", pr, 2) for pr in PRESETS
                       for st, ep in SPEED_SCENES]
        speed = list(pool.map(timed, speed_jobs))
        cases = [(st, ep, pi, model) for st, ep, pi in ACCURACY_SCENES for model in MODELS]
        ref_jobs = [(*case, "fine", lv) for case in cases for lv in LEVELS]
        refs = list(pool.map(solve, ref_jobs))
        preset_jobs = [(*case, pr, {}) for case in cases for pr in PRESETS]
        presets = list(pool.map(solve, preset_jobs))
    res = {"speed": [], "accuracy": [], "seconds": 0.0}
    for (st, ep, pi, model, pr, max_order), (wall, status) in zip(speed_jobs, speed):
        res["speed"].append(dict(St=st, eps=ep, Pi=pi, model=model, preset=pr,
                                 max_order=max_order, wall_s=wall, status=status))
    for k, (st, ep, pi, model) in enumerate(cases):
        levels = refs[3 * k: 3 * k + 3]
        row = dict(St=st, eps=ep, Pi=pi, model=model, reference={}, order={}, ref_error={},
                   presets={})
        for key in KEYS:
            ref, order, err = richardson([lv[key] for lv in levels])
            row["reference"][key], row["order"][key], row["ref_error"][key] = ref, order, err
        for j, pr in enumerate(PRESETS):
            got = presets[3 * k + j]
            row["presets"][pr] = {key: abs(got[key] - row["reference"][key])
                                  / max(abs(row["reference"][key]), 1e-3) for key in KEYS}
            row["presets"][pr]["wall_s"] = got["wall_s"]
        res["accuracy"].append(row)
    res["seconds"] = time.time() - t0
    res = harness.write_json(HERE / "cavitation.json", res, load_start, default=str)
    write_report(res)


def write_report(res):
    lines = ["# Cavitation (Reynolds and JFO floors) next to the classic film", "",
             "`python benchmarks/bench_cavitation.py` regenerates this file (`make bench`). One "
             "scene at a time per core, compiled code warm, OPENBLAS_NUM_THREADS=1; median of "
             f"{REPEATS} runs.", "", "## Speed: median wall time per collision [ms]", "",
             "| preset | classic | Reynolds Pi = 1e-2 | Reynolds Pi = 1e-4 | JFO Pi = 1e-2 | "
             "JFO Pi = 1e-4 | Reynolds / classic (Pi = 1e-4) | JFO / classic (Pi = 1e-4) |",
             "|---|---|---|---|---|---|---|---|"]
    bdf2_rows = []
    for pr in PRESETS:
        def med(pi, model, max_order=None):
            return statistics.median(r["wall_s"] for r in res["speed"] if r["preset"] == pr
                                     and r["Pi"] == pi and r["model"] == model
                                     and r.get("max_order") == max_order)
        c = med(math.inf, "off")
        lines.append(f"| {pr} | {c * 1e3:.1f} | {med(1e-2, 'reynolds') * 1e3:.1f} | "
                     f"{med(1e-4, 'reynolds') * 1e3:.1f} | {med(1e-2, 'jfo') * 1e3:.1f} | "
                     f"{med(1e-4, 'jfo') * 1e3:.1f} | {med(1e-4, 'reynolds') / c:.2f} | "
                     f"{med(1e-4, 'jfo') / c:.2f} |")
        if any(r.get("max_order") == 2 for r in res["speed"]):
            c2 = med(math.inf, "off", 2)
            bdf2_rows.append(f"| {pr} | {c2 * 1e3:.1f} | {c2 / c:.2f} | "
                             f"{med(1e-4, 'reynolds') / c2:.2f} | {med(1e-4, 'jfo') / c2:.2f} |")
    if bdf2_rows:
        lines += ["", "The classic film with BDF2 throughout (`max_order=2`), the method a "
                  "cavitating film steps with from its first cavity on (docs/solver.md, \"Orders "
                  "above 2\"). A cavitating film takes the orders above 2 until then, so its ratio "
                  "to this film is at most the floor's own cost; its ratio to the classic film "
                  "(above) is about that cost times the classic film's gain from the orders above 2.",
                  "", "| preset | classic, BDF2 [ms] | classic BDF2 / classic | "
                  "Reynolds / classic BDF2 (Pi = 1e-4) | JFO / classic BDF2 (Pi = 1e-4) |",
                  "|---|---|---|---|---|", *bdf2_rows]
    bad = [r for r in res["speed"] if r["status"] != "ok"]
    lines += ["", f"Scenes: St in {{5, 10, 30, 100}} x eps in {{1e-2, 1e-6}}; "
              f"{len(bad)} of {len(res['speed'])} runs not ok.", "",
              "## Accuracy: relative error of each preset against a refined reference", "",
              "Reference: three levels beyond `fine` (cells x2, rtol /8 per level, switch 1e-4, "
              "release 3.1e-5), Richardson-extrapolated; `order` is the observed order, `ref err` "
              "the extrapolation's own correction. Errors relative to max(|ref|, 1e-3).", ""]
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
