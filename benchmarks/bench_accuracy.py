"""Speed against accuracy, measured: what each preset buys.

1. Reference per panel scene: three resolutions (grid cells x2, time tolerance /8 per level, so
   both errors fall ~4x per level for a second-order scheme), Richardson-extrapolated with the
   observed order; the extrapolation's own error is estimated and reported.
2. The hand-over from the analytic rigid approach (``switch``) and the hand-back (``release``)
   are measured separately: each threshold is halved repeatedly at a fixed fine resolution and
   the limit threshold -> 0 is extrapolated; the reference is corrected to that limit.
3. Each preset and a few explicit resolutions over the panel: error against the reference and
   the median wall time per scene (one core), and which error source dominates.

``python benchmarks/bench_accuracy.py`` (about 10 minutes on 2 cores) writes
``benchmarks/accuracy.md``, ``accuracy.json`` and ``accuracy.png``.
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

import numpy as np

import harness

HERE = Path(__file__).parent
STOKES = (1.0, 2.5, 5.0, 10.0, 30.0, 100.0, 300.0)
EPS = (1e-2, 1e-5, 1e-8)
PANEL = [(st, ep) for ep in EPS for st in STOKES]
if "--quick" in sys.argv:  # smoke run of the script itself: two scenes, output to /tmp
    PANEL = [(5.0, 1e-5), (30.0, 1e-2)]
    HERE = Path("/tmp")
KEYS = ("v_r", "h_m_x1", "h_m_approach_x1", "ln_x_e_x1")
# reference levels: grid and time refined together; thresholds fixed at small values
# (BDF2, max_order 2, whose time error falls 4x per level as the grid's does)
# The references' grids: one grid each (no extrapolation), the axis refined to 0.1 of an inner
# cell, on the fine preset's other settings; the preset itself is a pair since solver 1.15.0
# (solver/extrapolation.py), so the levels name what they are. bench_cavitation.py,
# bench_piezoviscous.py and bench_extrapolation.py refine the same family.
SINGLE_GRID = dict(axis_ratio=0.1, extrapolate=False)
LEVELS = [dict(SINGLE_GRID, n_inner=64 * 2**k, stretch=1.0 + 0.2 / 2**k, max_rel=0.3 / 2**k,
               rtol=4e-5 / 8**k, max_order=2) for k in range(3)]
SWITCH_REF, RELEASE_REF = 0.0001, 0.00003125
SWITCHES = (0.0032, 0.0016, 0.0008, 0.0004, 0.0002, 0.0001)
RELEASES = (0.001, 0.0005, 0.00025, 0.000125, 0.0000625, 0.00003125)
STUDY = dict(LEVELS[1])  # resolution of the threshold studies
EXPLICIT = {"n_inner=32": dict(n_inner=32), "n_inner=48": dict(n_inner=48),
            "n_inner=96": dict(n_inner=96), "n_inner=96, rtol=1e-5": dict(n_inner=96, rtol=1e-5)}
TARGET = {"standard": 5e-3, "fine": 5e-4}
V_R_FLOOR = 0.05


def solve(args):
    stokes, eps, accuracy, overrides = args
    from solver import collide

    c = collide(stokes, eps, accuracy=accuracy, save_profiles=False, **overrides)
    out = {k: getattr(c, k) for k in KEYS}
    out.update(status=c.status, model=c.model, wall_s=c.wall_s, escaped=c.escaped)
    return out


def error(value, ref, key):
    """Relative error; for ln x_e the absolute error of the log (= relative error of x_e);
    v_r relative to max(v_r, V_R_FLOOR): a rebound weaker than 5 % of v0 is judged absolutely,
    or the relative error would blow up where v_r vanishes at the critical St."""
    if key == "ln_x_e_x1":
        return abs(value - ref)
    return abs(value - ref) / max(abs(ref), V_R_FLOOR if key == "v_r" else 1e-300)


def richardson(values):
    """Limit, observed order and error estimate from three values at ratio-2 refinements."""
    f0, f1, f2 = values
    d1, d2 = f1 - f0, f2 - f1
    order = math.log2(abs(d1 / d2)) if d2 != 0 and d1 != 0 else 2.0
    p = min(max(order, 1.0), 3.0)
    limit = f2 + d2 / (2**p - 1)
    return limit, order, abs(d2) / (2**p - 1)


def run(pool, jobs):
    return list(pool.map(solve, jobs, chunksize=1))


def references(pool, panel):
    """The converged reference of each scene of ``panel`` (``(St, eps)`` pairs) and what it rests
    on: three levels (``LEVELS``) Richardson-extrapolated with the observed order, corrected to
    both thresholds -> 0 (``SWITCHES``, ``RELEASES``). Returns the per-scene lists ``reference``,
    its estimated error, the observed orders and the threshold studies' errors."""
    base = dict(switch=SWITCH_REF, release=RELEASE_REF)
    print("reference levels ...", flush=True)
    levels = [run(pool, [(st, ep, "fine", {**base, **lv}) for st, ep in panel]) for lv in LEVELS]
    print("hand-over and release studies ...", flush=True)
    switch_runs = [run(pool, [(st, ep, "fine", {**STUDY, "switch": s, "release": RELEASE_REF})
                              for st, ep in panel]) for s in SWITCHES]
    release_runs = [run(pool, [(st, ep, "fine", {**STUDY, "switch": 0.005, "release": r})
                               for st, ep in panel]) for r in RELEASES]

    reference, ref_err, orders, switch_err, release_err = [], [], [], [], []
    for i, _ in enumerate(panel):
        ref, rerr, ordr, serr, lerr = {}, {}, {}, {}, {}
        for key in KEYS:
            if any(lv[i]["status"] != "ok" for lv in levels):
                ref[key] = rerr[key] = ordr[key] = math.nan
                continue
            limit, order, err = richardson([lv[i][key] for lv in levels])
            s_vals = [r[i][key] for r in switch_runs]
            s_lim = richardson(s_vals[-3:])[0]  # thresholds halve: threshold -> 0
            r_vals = [r[i][key] for r in release_runs]
            r_lim = richardson(r_vals[-3:])[0]
            # correct the grid/time limit (at SWITCH_REF, RELEASE_REF) to both thresholds -> 0
            # the levels ran at SWITCH_REF = SWITCHES[-1] and RELEASE_REF = RELEASES[-1]
            ref[key] = limit + (s_lim - s_vals[-1]) + (r_lim - r_vals[-1])
            rerr[key], ordr[key] = err, order
            serr[key] = {s: error(v, s_lim, key) for s, v in zip(SWITCHES, s_vals)}
            lerr[key] = {r: error(v, r_lim, key) for r, v in zip(RELEASES, r_vals)}
        reference.append(ref), ref_err.append(rerr), orders.append(ordr)
        switch_err.append(serr), release_err.append(lerr)
    return reference, ref_err, orders, switch_err, release_err


def main():
    t_start = time.perf_counter()
    load_start = harness.load_now()
    from solver import PRESETS, collide

    collide(5.0, 0.01)  # compile once before the workers load the cache
    results = {"panel": PANEL, "levels": LEVELS}
    with ProcessPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        reference, ref_err, orders, switch_err, release_err = references(pool, PANEL)

    # presets and explicit resolutions, timed one at a time on one core
    print("presets ...", flush=True)
    configs = {name: (name, {}) for name in PRESETS}
    configs.update({name: ("standard", kw) for name, kw in EXPLICIT.items()})
    table = {}
    for name, (preset, kw) in configs.items():
        rows = [solve((st, ep, preset, kw)) for st, ep in PANEL]
        errs = {k: [error(r[k], ref[k], k) if r["status"] == "ok" else math.inf
                    for r, ref in zip(rows, reference)] for k in KEYS}
        walls = [r["wall_s"] for r in rows]
        walls_30 = [r["wall_s"] for r, (st, _) in zip(rows, PANEL) if st <= 30 and r["model"] == "ehd"]
        numerics = PRESETS[preset].as_dict() | kw
        table[name] = dict(errors=errs, wall_median=statistics.median(walls),
                           wall_median_st30=statistics.median(walls_30), numerics=numerics,
                           status=[r["status"] for r in rows])
    # one-parameter fast path: master curve in S = St V_switch against direct standard solves
    print("master curve ...", flush=True)
    from solver.master import MasterCurve

    t = time.perf_counter()
    curve = MasterCurve.build("standard")
    build_s = time.perf_counter() - t
    direct = [solve((st, ep, "standard", {})) for st, ep in PANEL]
    master_rows = []
    for (st, ep), d, ref in zip(PANEL, direct, reference):
        c = curve.collide(st, ep)
        row = {k: getattr(c, k) for k in KEYS}
        master_rows.append(dict(model=c.model, wall_s=c.wall_s,
                                vs_direct={k: error(row[k], d[k], k) for k in KEYS},
                                vs_reference={k: error(row[k], ref[k], k) for k in KEYS},
                                direct_wall_s=d["wall_s"]))
    results["master"] = dict(build_s=build_s, points=len(curve.s), rows=master_rows)

    results.update(reference=reference, reference_error=ref_err, observed_order=orders,
                   switch_error=switch_err, release_error=release_err,
                   table=table, seconds=time.perf_counter() - t_start)
    results = _jsonable(results)  # the report reads what the JSON holds (string keys, None)
    results = harness.write_json(HERE / "accuracy.json", results, load_start)
    write_report(results)
    plot(results)
    print((HERE / "accuracy.md").read_text())


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _fmt(x):
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.1e}"


def write_report(res):
    from solver import PRESETS

    lines = ["# Speed against accuracy", "",
             "Generated by `python benchmarks/bench_accuracy.py` (`make bench-accuracy`); raw numbers "
             "in `accuracy.json`, plot in `accuracy.png`.", "",
             f"Panel: St in {list(STOKES)} x eps in {list(EPS)} ({len(PANEL)} scenes). Errors: "
             "relative for v_r (floor 0.05), h_m and h_m_approach; for x_e the absolute error of "
             "ln x_e (= relative error of x_e; x_e overflows a float at large St).", "",
             "## Reference", "",
             "Three levels (inner cells 64/128/256, rtol 4e-5/5e-6/6e-7, outer grid refined alike), "
             "Richardson-extrapolated with the observed order; thresholds extrapolated to zero "
             "separately (below). Largest estimated error of the reference itself, over the panel:", ""]
    for key in KEYS:
        errs = [r[key] / max(abs(ref[key]), V_R_FLOOR if key == "v_r" else 1e-300)
                if key != "ln_x_e_x1" else r[key]
                for r, ref in zip(res["reference_error"], res["reference"]) if r[key] is not None
                and math.isfinite(r[key])]
        ords = [o[key] for o in res["observed_order"] if o[key] is not None and math.isfinite(o[key])]
        lines.append(f"- {key}: {max(errs):.1e} (observed orders: median {statistics.median(ords):.2f})")
    lines += ["", "## Hand-over and release thresholds", "",
              "Error caused by the analytic rigid phases alone (fixed fine grid), against the "
              "extrapolated zero threshold; max over the panel (eps = 1e-2 scenes start coupled, "
              "so only the release matters there):", "",
              "| switch | " + " | ".join(KEYS) + " |", "|---" * (len(KEYS) + 1) + "|"]
    for s in SWITCHES:
        cells = [_fmt(max((e[k][str(s)] for e in res["switch_error"] if k in e and e[k]), default=None))
                 for k in KEYS]
        lines.append(f"| {s:g} | " + " | ".join(cells) + " |")
    lines += ["", "| release | " + " | ".join(KEYS) + " |", "|---" * (len(KEYS) + 1) + "|"]
    for r in RELEASES:
        cells = [_fmt(max((e[k][str(r)] for e in res["release_error"] if k in e and e[k]), default=None))
                 for k in KEYS]
        lines.append(f"| {r:g} | " + " | ".join(cells) + " |")
    lines += ["", "## Presets and explicit resolutions", "",
              "Max error over the panel and over St <= 30, median wall time per scene (one core, "
              "after compilation).", "",
              "| setting | v_r | h_m | h_m approach | x_e (ln) | max, St<=30 | median ms | median ms, St<=30 EHD |",
              "|---|---|---|---|---|---|---|---|"]
    for name, row in res["table"].items():
        e = row["errors"]
        low = max(max(v for v, (st, _) in zip(e[k], res["panel"]) if st <= 30) for k in KEYS)
        lines.append(f"| {name} | " + " | ".join(_fmt(max(e[k])) for k in KEYS)
                     + f" | {_fmt(low)} | {row['wall_median'] * 1e3:.1f} | "
                     f"{row['wall_median_st30'] * 1e3:.1f} |")
    lines += ["", "## Targets", ""]
    for preset, target in TARGET.items():
        e = res["table"][preset]["errors"]
        misses = [f"St={st:g}, eps={ep:g}: " + ", ".join(f"{k} {e[k][i]:.1e}" for k in KEYS
                                                         if e[k][i] > target)
                  for i, (st, ep) in enumerate(res["panel"]) if any(e[k][i] > target for k in KEYS)]
        lines.append(f"- `{preset}` (target {target:g}): " + ("met on every panel scene." if not misses
                                                               else f"missed on {len(misses)} of "
                                                               f"{len(res['panel'])}: " + "; ".join(misses)))
    lines += ["", "## Which error dominates", "",
              "Max over the panel of the total error, and of the parts caused by the hand-over "
              "(`switch`) and the hand-back (`release`) at the preset's thresholds (read off the "
              "threshold studies above, interpolated in log-log); the rest is grid and time error.",
              "", "| preset | part | " + " | ".join(KEYS) + " |", "|---|---" + "|---" * len(KEYS) + "|"]
    for preset in PRESETS:
        sw, rl = PRESETS[preset].switch, PRESETS[preset].release
        total = [max(res["table"][preset]["errors"][k]) for k in KEYS]
        hand = [_threshold_part(res["switch_error"], SWITCHES, sw, k) for k in KEYS]
        back = [_threshold_part(res["release_error"], RELEASES, rl, k) for k in KEYS]
        lines.append(f"| {preset} | total | " + " | ".join(map(_fmt, total)) + " |")
        lines.append(f"| | switch {sw:g} | " + " | ".join(map(_fmt, hand)) + " |")
        lines.append(f"| | release {rl:g} | " + " | ".join(map(_fmt, back)) + " |")
    m = res["master"]
    on = [r for r in m["rows"] if r["model"] == "master"]
    lines += ["", "## One-parameter fast path (master curve in S = St V_switch)", "",
              f"Built once for `standard`: {m['points']} coupled solves in {m['build_s']:.1f} s. "
              f"{len(on)} of {len(m['rows'])} panel scenes lie on the curve (hand-over after the "
              "start); the others (eps = 1e-2 starts coupled, rigid scenes) are solved directly.", "",
              "| | " + " | ".join(KEYS) + " |", "|---" * (len(KEYS) + 1) + "|"]
    for label, field in (("max error vs direct standard", "vs_direct"),
                         ("max error vs reference", "vs_reference")):
        lines.append(f"| {label} | " + " | ".join(
            _fmt(max(r[field][k] for r in on)) for k in KEYS) + " |")
    if on:
        speed = statistics.median(r["direct_wall_s"] for r in on) / statistics.median(
            r["wall_s"] for r in on)
        lines += ["", f"Median time per scene on the curve: "
                  f"{statistics.median(r['wall_s'] for r in on) * 1e3:.2f} ms against "
                  f"{statistics.median(r['direct_wall_s'] for r in on) * 1e3:.1f} ms direct "
                  f"({speed:.0f}x); it pays off once a sweep has more than about "
                  f"{m['build_s'] / statistics.median(r['direct_wall_s'] for r in on):.0f} scenes "
                  "that hand over after their start."]
    lines.append("")
    lines.append(f"Run time of this benchmark: {res['seconds'] / 60:.1f} min.")
    (HERE / "accuracy.md").write_text("\n".join(lines) + "\n")


def _threshold_part(study, thresholds, value, key):
    """Max over the panel of a threshold study's error at ``value`` (log-log interpolation,
    linear extrapolation in the threshold beyond the studied range: the error is first order)."""
    worst = 0.0
    for scene in study:
        if key not in scene or not scene[key]:
            continue
        errs = np.array([scene[key][str(t)] for t in thresholds], dtype=float)
        ts = np.array(thresholds)
        if value >= ts.max():
            e = errs[0] * value / ts[0]
        elif value <= ts.min():
            e = errs[-1] * value / ts[-1]
        else:
            good = errs > 0
            e = float(np.exp(np.interp(np.log(value), np.log(ts[good][::-1]),
                                       np.log(errs[good][::-1])))) if good.sum() > 1 else 0.0
        worst = max(worst, e)
    return worst


def plot(res):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for name, row in res["table"].items():
        worst = max(max(row["errors"][k]) for k in KEYS)
        low = max(max(v for v, (st, _) in zip(row["errors"][k], res["panel"]) if st <= 30)
                  for k in KEYS)
        ms = row["wall_median"] * 1e3
        marker = "o" if name in ("fast", "standard", "fine") else "s"
        ax.loglog([ms], [worst], marker, color="C0" if marker == "o" else "C1")
        ax.loglog([ms], [low], marker, mfc="none", color="C0" if marker == "o" else "C1")
        ax.annotate(name, (ms, worst), textcoords="offset points", xytext=(5, 3), fontsize=8)
    for target in TARGET.values():
        ax.axhline(target, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("median wall time per scene [ms] (one core)")
    ax.set_ylabel("max error over the panel (filled: all St, open: St <= 30)")
    ax.set_title("ehd-collision: accuracy against cost")
    fig.tight_layout()
    fig.savefig(HERE / "accuracy.png", dpi=120, metadata={"Software": None})


if __name__ == "__main__":
    sys.exit(main())
