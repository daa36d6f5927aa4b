"""The pressure-dependent liquid (issue 11) next to the classic film: speed and accuracy per preset,
and where its time goes.

1. Speed: median wall time per collision (one core, compiled code and grids warm) of the classic
   film (beta = 0) and of the piezoviscous film (Barus at beta 1, 2, 5, 10; Barus with the
   Dowson-Higginson density and Roelands at beta 5) on the same scenes and presets. Each scene's
   variants run one after the other, their order rotated from repeat to repeat, so that a
   variant and its classic counterpart see the same machine load; ratios are taken per scene
   (variant / classic at the same St, eps and preset). Process CPU time is recorded next to the
   wall time (less sensitive to other processes on the machine). Steps, rejected steps, LU
   factorisations and Newton iterations show where the cost goes.
2. Where the time goes (standard preset, St 10, eps 1e-4): the counters and CPU time per phase of
   the coupled solve, measured by re-running the scene truncated at the phase boundaries
   (``max_steps``: the truncated run is the full run's prefix); the cost of one LU
   factorisation and of one Newton iteration at the same film state for both liquids; and the
   same scenes with the law applied in tension (``viscosity_in_tension="law"``), which removes
   the kink of the compression-only law at P = 0.
3. Accuracy: per scene, a reference from three resolutions beyond the presets (grid cells x2 and
   time tolerance /8 per level, switch 1e-4, release 3.125e-5, as benchmarks/bench_cavitation.py),
   Richardson-extrapolated with the observed order; the thresholds' share of the reference is
   estimated by halving both at the middle level. Each preset's error against it, for the
   piezoviscous scenes and the classic film at the same St.

``python benchmarks/bench_piezoviscous.py`` (about 7 minutes on one core) writes
``benchmarks/piezoviscous.md`` and ``piezoviscous.json``. Everything runs in this one process,
one scene at a time. ``--report`` rewrites the .md from the .json without solving; ``--quick``
is a smoke run of the script (output in /tmp).
"""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import harness
from bench_accuracy import SINGLE_GRID  # the references' single grids
from bench_cavitation import richardson  # the same extrapolation as the cavitation bench

HERE = Path(__file__).parent
PRESETS = ("fast", "standard", "fine")
REPEATS = 3
TARGET_RATIO = 2.0
# name -> (label, Physics fields beyond St and eps)
VARIANTS = {
    "classic": ("classic (beta 0)", {}),
    "barus-1": ("Barus beta 1", dict(beta=1.0)),
    "barus-2": ("Barus beta 2", dict(beta=2.0)),
    "barus-5": ("Barus beta 5", dict(beta=5.0)),
    "barus-10": ("Barus beta 10", dict(beta=10.0)),
    "barus-dh-5": ("Barus + Dowson-Higginson beta 5",
                   dict(beta=5.0, density_law="dowson-higginson")),
    "roelands-5": ("Roelands beta 5", dict(beta=5.0, viscosity_law="roelands")),
}
PIEZO = [v for v in VARIANTS if v != "classic"]
STOKES = (3.0, 10.0, 30.0, 100.0)
# eps = 1e-4 with every variant; eps = 1e-2 (coupled from the start) with a subset, to keep the
# fine preset's share of the run time within the budget
SPEED_SCENES = [(st, 1e-4, tuple(VARIANTS)) for st in STOKES] + \
               [(st, 1e-2, ("classic", "barus-2", "barus-5")) for st in STOKES]
PROFILE_SCENE = (10.0, 1e-4)
PROFILE_VARIANTS = ("classic", "barus-2", "barus-5")
UNLOADED = 0.01  # P_max below which the film no longer carries compression (profile phases)
ACCURACY_SCENES = [(st, 1e-4, b) for st in (10.0, 100.0) for b in (0.0, 2.0, 5.0)]
KEYS = ("v_r", "h_m_x1", "ln_x_e_x1", "e_wet", "ln_viscosity_ratio")
# how each error is measured: relative with a floor, or absolute (logarithms)
FLOORS = {"v_r": 0.05, "h_m_x1": 1e-300, "e_wet": 0.05}
LEVELS = [dict(SINGLE_GRID, n_inner=64 * 2**k, stretch=1.0 + 0.2 / 2**k, max_rel=0.3 / 2**k,
               rtol=4e-5 / 8**k, switch=1e-4, release=3.125e-5) for k in range(3)]
HALVED = dict(LEVELS[1], switch=LEVELS[1]["switch"] / 2, release=LEVELS[1]["release"] / 2)
if "--quick" in sys.argv:  # smoke run of the script itself
    STOKES = (10.0,)
    SPEED_SCENES = [(10.0, 1e-4, ("classic", "barus-2", "barus-5"))]
    PRESETS, REPEATS = ("fast", "standard"), 1
    ACCURACY_SCENES = [(10.0, 1e-4, 2.0)]
    LEVELS = [dict(lv, n_inner=lv["n_inner"] // 2, rtol=lv["rtol"] * 8) for lv in LEVELS]
    HALVED = dict(LEVELS[1], switch=LEVELS[1]["switch"] / 2, release=LEVELS[1]["release"] / 2)
    HERE = Path("/tmp")


def physics(st, eps, variant=None, **fields):
    from solver import Physics

    return Physics(St=st, eps=eps, **(VARIANTS[variant][1] if variant else {}), **fields)


def run(ph, preset, **overrides):
    """One collision, with its wall time (the solver's own) and this process's CPU time."""
    from solver import collide

    cpu = time.process_time()
    c = collide(ph, accuracy=preset, save_profiles=False, **overrides)
    return c, time.process_time() - cpu


def counters(c):
    return dict(steps=c.steps, rejected=c.rejected_steps, lu=c.lu_factorizations,
                newton=c.newton_iterations)


# ---- 1. speed ------------------------------------------------------------------------------------
def warm(preset):
    """Compile (first call) and build this preset's grids (cached per resolution and extent)."""
    from solver.collision import handover_separation, scene_grid
    from solver.settings import resolve

    numerics = resolve(preset)
    for st, eps, variants in SPEED_SCENES:
        for v in variants:
            x_switch = handover_separation(physics(st, eps, v), numerics)
            if x_switch is not None:
                scene_grid(st, x_switch, numerics)
    for v in VARIANTS:
        run(physics(*PROFILE_SCENE, v), preset)


def speed():
    rows = {}
    for preset in PRESETS:
        warm(preset)
        for r in range(REPEATS):
            for st, eps, variants in SPEED_SCENES:
                k = r % len(variants)
                for v in variants[k:] + variants[:k]:  # rotated: no variant always runs first
                    c, cpu = run(physics(st, eps, v), preset)
                    row = rows.setdefault((preset, st, eps, v), dict(
                        preset=preset, St=st, eps=eps, variant=v, wall_s=[], cpu_s=[]))
                    row["wall_s"].append(c.wall_s)
                    row["cpu_s"].append(cpu)
                    row.update(counters(c), status=c.status, message=c.message, model=c.model,
                               v_r=c.v_r,
                               energy_error=c.energy_error,
                               viscosity_ratio=c.viscosity_ratio_max_approach)
            print(f"speed {preset} repeat {r + 1}/{REPEATS} done", flush=True)
    out = []
    for row in rows.values():
        row["wall_median"] = statistics.median(row["wall_s"])
        row["cpu_median"] = statistics.median(row["cpu_s"])
        out.append(row)
    return out


# ---- 2. where the time goes ----------------------------------------------------------------------
def phases(c):
    """Boundaries (accepted-step counts) of the coupled solve's phases, from its series: the
    approach to V = 0, the rebound up to the largest pressure after it, the unloading until
    P_max < UNLOADED, and the rest up to the release."""
    s = c.series
    m = s["phase"] == 1
    v, p = s["V"][m], s["P_max"][m]
    end = len(v) - 1
    i_v = int(np.argmax(v <= 0.0)) if np.any(v <= 0.0) else end
    i_p = i_v + int(np.argmax(p[i_v:]))
    low = np.nonzero(p[i_p:] < UNLOADED)[0]
    i_low = i_p + int(low[0]) if low.size else end
    return [0, i_v, i_p, i_low, end]


PHASE_NAMES = ("approach to V = 0", "rebound to the peak pressure",
               f"peak to unloaded film (P_max < {UNLOADED:g})", "unloaded film to release")


def profile():
    """Counters and CPU time per phase, by truncated re-runs (max_steps = a boundary)."""
    st, eps = PROFILE_SCENE
    out = {}
    for v in PROFILE_VARIANTS:
        ph = physics(st, eps, v)
        full, _ = run(ph, "standard")
        s = full.series
        m = s["phase"] == 1
        tau, p, vel = s["tau"][m], s["P_max"][m], s["V"][m]
        bounds = phases(full)
        cumulative = [dict(steps=0, rejected=0, lu=0, newton=0, cpu=0.0)]
        for b in bounds[1:]:
            cpus, last = [], None
            for _ in range(REPEATS):
                # the last boundary is the full run (its end is the release, not max_steps)
                c, cpu = run(ph, "standard", **({} if b == bounds[-1] else
                                                {"max_steps": max(b, 10)}))
                cpus.append(cpu)
                last = c
            cumulative.append(counters(last) | {"cpu": statistics.median(cpus)})
        segments = []
        for j, name in enumerate(PHASE_NAMES):
            a, b = bounds[j], bounds[j + 1]
            d = {k: cumulative[j + 1][k] - cumulative[j][k] for k in cumulative[0]}
            dtau = np.diff(tau[a:b + 1])
            segments.append(dict(
                phase=name, first_step=a, last_step=b, tau=(float(tau[a]), float(tau[b])),
                **d, dtau_median=float(np.median(dtau)) if dtau.size else math.nan,
                dtau_min=float(dtau.min()) if dtau.size else math.nan,
                p_max_start=float(p[a]), p_max_peak=float(p[a:b + 1].max()),
                v_end=float(vel[b])))
        rebound = np.diff(tau[bounds[1]:bounds[3] + 1])  # V = 0 to the unloaded film
        out[v] = dict(totals=counters(full), cpu=cumulative[-1]["cpu"], segments=segments,
                      p_max=float(full.p_max), dtau_rebound_median=float(np.median(rebound)))
        print(f"profile {v} done", flush=True)
    # the same scenes with the law applied in tension (smooth at P = 0)
    law = {}
    for v in PROFILE_VARIANTS[1:]:
        cpus, c = [], None
        for _ in range(REPEATS):
            c, cpu = run(physics(st, eps, v, viscosity_in_tension="law"), "standard")
            cpus.append(cpu)
        law[v] = counters(c) | {"cpu": statistics.median(cpus), "v_r": c.v_r}
    return dict(scene=dict(St=st, eps=eps, preset="standard"), variants=out, law_in_tension=law,
                lens=lens(), per_operation=per_operation())


def lens():
    """The loaded region of the piezoviscous film over the rebound: its radius and peak."""
    from solver import collide

    st, eps = PROFILE_SCENE
    c = collide(physics(st, eps, "barus-5"), accuracy="standard")
    bounds = phases(c)
    rows = []
    for k in np.linspace(bounds[1], bounds[2], 5).astype(int):
        p = c.pressure[k]
        loaded = c.radius[p > 1.0]
        rows.append(dict(step=int(k), tau=float(c.profile_tau[k]), X=float(c.profile_x[k]),
                         p_max=float(p.max()), r_p_max=float(c.radius[int(np.argmax(p))]),
                         r_loaded=float(loaded.max()) if loaded.size else 0.0))
    return rows


def per_operation():
    """Cost of one LU factorisation (Jacobian + LU) and of one Newton iteration (residual, LU
    solve, gap) at one film state (mid-rebound of the beta 5 scene), with the classic and the
    piezoviscous physics: the same kernels the time loop calls."""
    from solver import collide
    from solver.collision import handover_separation, scene_grid
    from solver.integration.linalg import lu_factor, lu_solve
    from solver.model.film import face_fluxes, gap, jacobian, residual
    from solver.model.state import Coupling, Step
    from solver.settings import resolve

    st, eps = PROFILE_SCENE
    ph = physics(st, eps, "barus-5")
    numerics = resolve("standard")
    c = collide(ph, accuracy="standard")
    bounds = phases(c)
    k = (bounds[1] + bounds[2]) // 2
    p, x = np.ascontiguousarray(c.pressure[k]), float(c.profile_x[k])
    g = scene_grid(st, handover_separation(ph, numerics), numerics)
    n = g.s.size
    theta, active = np.ones(n - 1), np.zeros(n - 1, dtype=np.bool_)
    w, h, q, res = np.empty(n), np.empty(n), np.empty(n - 1), np.empty(n + 2)
    jac, dres_dh, piv = np.empty((n + 2, n + 2)), np.empty((n, 3)), np.empty(n + 2, dtype=np.int32)
    gap(g.s, g.influence, x, p, w, h)
    c_hist, bh, v = h.copy(), 1e-4, float(c.series["V"][c.series["phase"] == 1][k])
    nodes, step = g.nodes(), Step(bh, c_hist, x, v)
    smooth = Coupling(g.influence, np.ones(n), g.force_weight, 0.0, np.empty(0))

    def factorise(phys):
        jacobian(nodes, phys, bh, p, theta, h, active, smooth, jac, dres_dh)
        lu_factor(jac, piv)

    def newton(phys):
        face_fluxes(nodes, p, h, phys, q)
        residual(nodes, phys, step, x, v, p, theta, h, q, res)
        lu_solve(jac, piv, res)
        gap(g.s, g.influence, x, p, w, h)

    out = dict(nodes=n, step=k, p_max=float(p.max()))
    for name, phys in (("classic", physics(st, eps).as_array()), ("barus-5", ph.as_array())):
        for label, f in (("lu", factorise), ("newton", newton)):
            f(phys)
            batches = []
            for _ in range(15):
                t = time.process_time()
                for _ in range(200):
                    f(phys)
                batches.append((time.process_time() - t) / 200)
            out[f"{name}_{label}_us"] = min(batches) * 1e6  # the least disturbed batch
    return out


# ---- 3. accuracy ---------------------------------------------------------------------------------
def values(c):
    out = {k: float(getattr(c, k)) for k in KEYS if k != "ln_viscosity_ratio"}
    out["ln_viscosity_ratio"] = math.log(c.viscosity_ratio_max_approach)
    return out | {"status": c.status, "steps": c.steps}


def error(value, ref, key):
    """Relative error (v_r and e_wet relative to max(|ref|, 0.05), as benchmarks/accuracy.md
    does for v_r); for the logarithms ln x_e and ln(mu/mu0) the absolute error (= relative error
    of x_e and of the viscosity ratio)."""
    if key in FLOORS:
        return abs(value - ref) / max(abs(ref), FLOORS[key])
    return abs(value - ref)


def accuracy():
    from solver.collision import handover_separation
    from solver.settings import resolve

    rows = []
    for st, eps, beta in ACCURACY_SCENES:
        ph = physics(st, eps, beta=beta)
        levels = [values(run(ph, "fine", **lv)[0]) for lv in LEVELS]
        at_start = all(handover_separation(ph, resolve("fine", **lv)) == ph.x_start
                       for lv in LEVELS + [HALVED])
        halved = values(run(ph, "fine", **HALVED)[0])
        row = dict(St=st, eps=eps, beta=beta, handover_at_start=at_start, reference={}, order={},
                   ref_error={},
                   threshold={}, levels=levels, presets={},
                   status=[lv["status"] for lv in levels] + [halved["status"]])
        for key in KEYS:
            ref, order, err = richardson([lv[key] for lv in levels])
            row["reference"][key], row["order"][key] = ref, order
            row["ref_error"][key] = error(ref + err, ref, key)
            row["threshold"][key] = error(halved[key], levels[1][key], key)
        for pr in PRESETS:
            got = values(run(ph, pr)[0])
            row["presets"][pr] = {k: error(got[k], row["reference"][k], k) for k in KEYS}
            row["presets"][pr]["status"] = got["status"]
        rows.append(row)
        print(f"accuracy St {st:g} beta {beta:g} done", flush=True)
    return rows


# ---- the report ----------------------------------------------------------------------------------
def main():
    if "--report" in sys.argv:  # the report again from the stored numbers, no solving
        write_report(json.loads((HERE / "piezoviscous.json").read_text()))
        return
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    t0 = time.time()
    load_start = os.getloadavg()
    res = dict(machine=f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
               blas_threads=os.environ.get("OPENBLAS_NUM_THREADS"), repeats=REPEATS)
    res["speed"] = speed()
    res["profile"] = profile()
    res["accuracy"] = accuracy()
    res["seconds"] = time.time() - t0
    res["load_average"] = dict(start=load_start, end=os.getloadavg())
    harness.write_json(HERE / "piezoviscous.json", _jsonable(res),
                       [round(x, 2) for x in load_start])
    write_report(res)


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):  # NaN and inf stay (json writes NaN, Infinity)
        return obj.item()
    return obj


def ratios(speed, preset, variant, key="wall_median"):
    """Per-scene ratio variant / classic at the same St, eps and preset, over the scenes where
    both runs are ok (a failed run's time says nothing about the model's cost)."""
    base = {(r["St"], r["eps"]): r[key] for r in speed
            if r["preset"] == preset and r["variant"] == "classic" and r["status"] == "ok"}
    return [r[key] / base[(r["St"], r["eps"])] for r in speed
            if r["preset"] == preset and r["variant"] == variant and r["status"] == "ok"
            and (r["St"], r["eps"]) in base]


def _rows(speed, preset, variant):
    return [r for r in speed if r["preset"] == preset and r["variant"] == variant]


def _order(x):
    return f"{x:.2f}"


def _fmt(x):
    return "-" if x is None or not math.isfinite(x) else f"{x:.1e}"


def write_report(res):
    speed = res["speed"]
    lines = [
        "# The pressure-dependent liquid next to the classic film", "",
        "`python benchmarks/bench_piezoviscous.py` regenerates this file and `piezoviscous.json` "
        f"(`make bench`). {res['machine']}; one scene at a time in one process, "
        f"OPENBLAS_NUM_THREADS={res['blas_threads']}, compiled code and grids warm; median of "
        f"{REPEATS} runs. Each scene's variants run back to back in rotated order, so a ratio "
        "compares runs under the same machine load. Load average during the run: "
        f"{res['load_average']['start'][0]:.1f} at the start, {res['load_average']['end'][0]:.1f} "
        "at the end (other processes were running: the wall times carry their noise; the CPU-time "
        "ratios beside them are less sensitive to it).", "",
        "Scenes: " + "; ".join(
            f"eps = {eps:g}, St in {{"
            + ", ".join(f"{st:g}" for st, e, _ in SPEED_SCENES if e == eps)
            + "}: " + ", ".join(VARIANTS[v][0] for v in next(vs for _, e, vs in SPEED_SCENES
                                                           if e == eps))
            for eps in dict.fromkeys(e for _, e, _ in SPEED_SCENES))
        + ". The other variants at eps = 1e-2 are left out to bound the run time (the fine "
        "preset is most of it).", "",
        f"## Target: within {TARGET_RATIO:g}x of the classic model at the same preset", ""]
    verdict = []
    for pr in PRESETS:
        allr = [x for v in PIEZO for x in ratios(speed, pr, v)]
        if not allr:
            continue
        ok = [v for v in PIEZO if ratios(speed, pr, v)
              and statistics.median(ratios(speed, pr, v)) <= TARGET_RATIO]
        within = sum(x <= TARGET_RATIO for x in allr)
        verdict.append(
            f"- `{pr}`: **{'met' if statistics.median(allr) <= TARGET_RATIO else 'not met'}** "
            f"over all piezoviscous runs (median per-scene ratio {statistics.median(allr):.2f}, "
            f"max {max(allr):.1f}; {within} of {len(allr)} scene-variant pairs within "
            f"{TARGET_RATIO:g}x). Variants whose median ratio is within {TARGET_RATIO:g}x: "
            + (", ".join(VARIANTS[v][0] for v in ok) if ok else "none") + ".")
    lines += verdict + ["",
                        "The ratio is taken per scene (piezoviscous / classic wall time at the "
                        "same St, eps and preset); the tables give its median over the scenes "
                        "and, in parentheses, its largest value.", "",
                        "## Speed: ratio piezoviscous / classic per preset (wall time)", "",
                        "| preset | classic median [ms] | " + " | ".join(VARIANTS[v][0]
                                                                          for v in PIEZO) + " |",
                        "|---|---|" + "---|" * len(PIEZO)]
    for pr in PRESETS:
        base = [r["wall_median"] for r in _rows(speed, pr, "classic")]
        if not base:
            continue
        cells = []
        for v in PIEZO:
            rr = ratios(speed, pr, v)
            cells.append(f"{statistics.median(rr):.2f} ({max(rr):.1f})" if rr else "-")
        lines.append(f"| {pr} | {statistics.median(base) * 1e3:.1f} | " + " | ".join(cells) + " |")
    lines += ["", "Same, process CPU time:", "",
              "| preset | classic median [ms] | " + " | ".join(VARIANTS[v][0] for v in PIEZO)
              + " |", "|---|---|" + "---|" * len(PIEZO)]
    for pr in PRESETS:
        base = [r["cpu_median"] for r in _rows(speed, pr, "classic")]
        if not base:
            continue
        cells = []
        for v in PIEZO:
            rr = ratios(speed, pr, v, "cpu_median")
            cells.append(f"{statistics.median(rr):.2f} ({max(rr):.1f})" if rr else "-")
        lines.append(f"| {pr} | {statistics.median(base) * 1e3:.1f} | " + " | ".join(cells) + " |")
    lines += ["", "## Speed per scene: median wall time [ms] and counters", "",
              "Counters are deterministic (steps accepted / rejected, LU factorisations, Newton "
              "iterations); per St at eps = 1e-4, then eps = 1e-2.", "",
              "| preset | variant | eps | " + " | ".join(f"St {s:g} ms" for s in STOKES)
              + " | steps (median over St) | rejected | LU | Newton | LU / step | Newton / step |",
              "|---|---|---|" + "---|" * len(STOKES) + "---|---|---|---|---|---|"]
    for pr in PRESETS:
        for eps in (1e-4, 1e-2):
            for v in VARIANTS:
                rows = [r for r in _rows(speed, pr, v) if r["eps"] == eps]
                if not rows:
                    continue
                by_st = {r["St"]: r for r in rows}
                times = " | ".join(f"{by_st[s]['wall_median'] * 1e3:.1f}"
                                   + ("" if by_st[s]["status"] == "ok"
                                      else f" ({by_st[s]['status']})")
                                   if s in by_st else "-" for s in STOKES)
                med = {k: statistics.median(r[k] for r in rows)
                       for k in ("steps", "rejected", "lu", "newton")}
                lu_step = statistics.median(r["lu"] / max(r["steps"], 1) for r in rows)
                nw_step = statistics.median(r["newton"] / max(r["steps"], 1) for r in rows)
                lines.append(f"| {pr} | {VARIANTS[v][0]} | {eps:g} | {times} | "
                             f"{med['steps']:.0f} | "
                             f"{med['rejected']:.0f} | {med['lu']:.0f} | {med['newton']:.0f} | "
                             f"{lu_step:.2f} | {nw_step:.2f} |")
    bad = [r for r in speed if r["status"] != "ok"]
    lines += ["", f"{len(bad)} of {len(speed)} scene-variant-preset runs not ok (left out of the "
              "ratios)" + (": " + "; ".join(f"{r['preset']} {VARIANTS[r['variant']][0]}: "
                                           f"{r.get('message', r['status'])}" for r in bad)
                           if bad else "") + "."]
    lines += where_the_time_goes(res["profile"])
    lines += accuracy_report(res["accuracy"])
    lines += ["", f"Run time of this benchmark: {res['seconds'] / 60:.1f} min.", ""]
    text = "\n".join(lines)
    (HERE / "piezoviscous.md").write_text(text)
    print(text)


def _per_step(segment):
    return segment["cpu"] / max(segment["steps"], 1)


def where_the_time_goes(prof):
    sc, var = prof["scene"], prof["variants"]
    c, b5 = var["classic"], var["barus-5"]
    ct, bt = c["totals"], b5["totals"]
    op = prof["per_operation"]
    seg, cs = b5["segments"], c["segments"]
    cpu_total = sum(s["cpu"] for s in seg)
    rej_total = sum(s["rejected"] for s in seg)
    rebound, collapse = seg[1], seg[2]
    lens = prof["lens"]
    law = prof["law_in_tension"]
    b2 = var["barus-2"]
    lines = ["", f"## Where the time goes ({sc['preset']}, St {sc['St']:g}, eps {sc['eps']:g})", "",
             "Phases of the coupled solve, from its series; counters and CPU time per phase by "
             "re-running the scene truncated at each boundary (`max_steps`; CPU median of "
             f"{REPEATS}). dtau: step size in tau = v0 t / x0.", "",
             "| variant | phase | steps | rejected | LU | Newton | CPU [ms] | LU / step | "
             "Newton / step | median dtau | min dtau | P_max in phase |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for v, row in var.items():
        for s in row["segments"]:
            n = max(s["steps"], 1)
            lines.append(f"| {VARIANTS[v][0]} | {s['phase']} | {s['steps']} | {s['rejected']} | "
                         f"{s['lu']} | {s['newton']} | {max(s['cpu'], 0.0) * 1e3:.0f} | "
                         f"{s['lu'] / n:.2f} | "
                         f"{s['newton'] / n:.2f} | {_fmt(s['dtau_median'])} | "
                         f"{_fmt(s['dtau_min'])} | {s['p_max_peak']:.3g} |")
        t = row["totals"]
        lines.append(f"| {VARIANTS[v][0]} | **total** | {t['steps']} | {t['rejected']} | "
                     f"{t['lu']} | "
                     f"{t['newton']} | {row['cpu'] * 1e3:.0f} | {t['lu'] / t['steps']:.2f} | "
                     f"{t['newton'] / t['steps']:.2f} | | | {row['p_max']:.3g} |")
    lines += ["", "The loaded region (P > 1) of the beta 5 film during the rebound (standard):", "",
              "| step | tau | X | P_max | at R | loaded to R |", "|---|---|---|---|---|---|"]
    for r in lens:
        lines.append(f"| {r['step']} | {r['tau']:.4f} | {r['X']:+.3f} | {r['p_max']:.3g} | "
                     f"{r['r_p_max']:.3f} | {r['r_loaded']:.3f} |")
    lines += ["", "With the law applied in tension too (`viscosity_in_tension=\"law\"`: smooth at "
              "P = 0), same scene:", "",
              "| variant | steps | rejected | LU | Newton | CPU [ms] | CPU / classic |",
              "|---|---|---|---|---|---|---|"]
    for v, r in law.items():
        lines.append(f"| {VARIANTS[v][0]}, law in tension | {r['steps']} | {r['rejected']} | "
                     f"{r['lu']} | {r['newton']} | {r['cpu'] * 1e3:.0f} | "
                     f"{r['cpu'] / c['cpu']:.2f} |")
    for v in law:
        t = var[v]["totals"]
        lines.append(f"| {VARIANTS[v][0]} (compression only, the default) | {t['steps']} | "
                     f"{t['rejected']} | {t['lu']} | {t['newton']} | {var[v]['cpu'] * 1e3:.0f} | "
                     f"{var[v]['cpu'] / c['cpu']:.2f} |")
    lines += ["", f"One LU factorisation (Jacobian + LU, {op['nodes']} nodes) costs "
              f"{op['classic_lu_us']:.0f} us with the classic physics and "
              f"{op['barus-5_lu_us']:.0f} us with Barus beta 5; one Newton iteration (residual, "
              f"LU solve, gap) "
              f"{op['classic_newton_us']:.0f} and {op['barus-5_newton_us']:.0f} us (same film "
              f"state: step {op['step']} of the beta 5 run, P_max {op['p_max']:.3g}; best of 15 "
              f"batches of 200 calls).", "",
              "Findings:", "",
              f"- The cost is in the counts more than in the pressure-dependent terms: per "
              f"operation Barus beta 5 costs {op['barus-5_lu_us'] / op['classic_lu_us']:.1f}x "
              f"(LU) and {op['barus-5_newton_us'] / op['classic_newton_us']:.1f}x (Newton "
              f"iteration) the classic film's (above), while it takes {bt['steps']} steps "
              f"({bt['steps'] / ct['steps']:.1f}x classic), {bt['rejected']} rejected "
              f"(classic {ct['rejected']}), {bt['lu']} LU factorisations "
              f"({bt['lu'] / ct['lu']:.1f}x; {bt['lu'] / bt['steps']:.2f} per step against "
              f"{ct['lu'] / ct['steps']:.2f}) and {bt['newton']} Newton iterations "
              f"({bt['newton'] / ct['newton']:.1f}x; {bt['newton'] / bt['steps']:.1f} per step "
              f"against {ct['newton'] / ct['steps']:.1f}): CPU {b5['cpu'] / c['cpu']:.1f}x. "
              f"Counts times unit costs: Newton iterations "
              f"{bt['newton'] * op['barus-5_newton_us'] / 1e3:.0f} ms and LU "
              f"{bt['lu'] * op['barus-5_lu_us'] / 1e3:.0f} ms of its {b5['cpu'] * 1e3:.0f} ms "
              f"(classic {ct['newton'] * op['classic_newton_us'] / 1e3:.0f} and "
              f"{ct['lu'] * op['classic_lu_us'] / 1e3:.0f} of {c['cpu'] * 1e3:.0f} ms).",
              f"- {rebound['cpu'] / cpu_total:.0%} of the CPU time, {rebound['steps']} of the "
              f"{bt['steps']} steps and {rebound['rejected']} of the {rej_total} rejections fall "
              f"in the rebound before the pressure peaks: the compressed, glassy region at the "
              f"axis does not drain while the spheres separate; it shrinks from R = "
              f"{lens[0]['r_loaded']:.2f} to {lens[-1]['r_loaded']:.3f} and its peak pressure "
              f"climbs from {rebound['p_max_start']:.3g} to {rebound['p_max_peak']:.3g} (beta P = "
              f"{5 * rebound['p_max_peak']:.0f}). Steps there are {rebound['dtau_median']:.1e} "
              f"(median; the classic film's from V = 0 to its unloading: "
              f"{c['dtau_rebound_median']:.1e}).",
              f"- The lens then collapses: from its peak to an unloaded film takes "
              f"{collapse['steps']} steps over dtau = "
              f"{collapse['tau'][1] - collapse['tau'][0]:.1e}, "
              f"the smallest {collapse['dtau_min']:.1e}. The approach takes {seg[0]['steps']} "
              f"steps and {seg[0]['cpu'] * 1e3:.0f} ms (classic {cs[0]['steps']}, "
              f"{cs[0]['cpu'] * 1e3:.0f} ms), the unloaded tail {seg[3]['steps']} steps and "
              f"{seg[3]['cpu'] * 1e3:.0f} ms (classic {cs[3]['steps']}, {cs[3]['cpu'] * 1e3:.0f} "
              f"ms): CPU per step {_per_step(seg[0]) / _per_step(cs[0]):.1f}x and "
              f"{_per_step(seg[3]) / _per_step(cs[3]):.1f}x the classic's (Newton iterations "
              f"{op['barus-5_newton_us'] / op['classic_newton_us']:.1f}x dearer, and more of "
              f"them per step in the approach).",
              f"- At beta 2 there is no lens to speak of (steps {b2['totals']['steps']} against "
              f"{ct['steps']}), {b2['totals']['rejected']} rejected steps and "
              f"{b2['totals']['lu']} LU factorisations. The compression-only law (the default "
              f"`viscosity_in_tension=\"ambient\"`) has a kink at P = 0, which the unloading "
              f"film crosses cell by cell; those cells' pressure errors leave the step's norm "
              f"(docs/solver.md, \"Kinks of the laws\"). Read in tension as well (smooth), the "
              f"same scene takes {law['barus-2']['rejected']} rejected and {law['barus-2']['lu']} LU "
              f"({law['barus-2']['cpu'] / c['cpu']:.1f}x classic CPU instead of "
              f"{b2['cpu'] / c['cpu']:.1f}x); at beta 5 the lens dominates "
              f"({law['barus-5']['rejected']} rejected without the kink, "
              f"{bt['rejected']} with it)."]
    return lines


def notes(rows):
    """What the reader needs to read the accuracy table, from the numbers themselves."""
    out = []
    start = [r for r in rows if r.get("handover_at_start")]
    if len(start) == len(rows):
        out.append("Every accuracy scene's reference levels hand over to the coupled solve at the "
                   "start x0 (the switch is not reached on the rigid path before it), so "
                   "`thresholds` measures the release alone.")
    zero = [r for r in rows if r["reference"]["e_wet"] == 0.0]
    if zero:
        out.append("e_wet is exactly 0 where the spheres stop short of x0 (x_e < x0): "
                   + ", ".join(f"St {r['St']:g} beta {r['beta']:g}" for r in zero) + ".")
    orders = [r["order"]["ln_viscosity_ratio"] for r in rows if r["beta"] > 0]
    finite = [o for o in orders if math.isfinite(o)]
    out.append("The viscosity ratio is read at the approach's largest pressure over the accepted "
               "steps, a sampled maximum; its observed orders: "
               + ", ".join(_order(o) for o in orders)
               + (f" (min {min(finite):.2f}, max {max(finite):.2f})." if finite else "."))
    return " ".join(out)


def accuracy_report(rows):
    lines = ["", "## Accuracy: error of each preset against a refined reference", "",
             "Reference: three levels beyond `fine` (inner cells 64/128/256, rtol "
             "4e-5/5e-6/6.25e-7, outer grid refined alike, switch 1e-4, release 3.125e-5), "
             "Richardson-extrapolated "
             "(as benchmarks/cavitation.md); `order` is the observed order, `ref err` the "
             "extrapolation's own correction, `thresholds` the change at the middle level when "
             "switch and release are halved (the reference's share of the hand-over and release "
             "error, not extrapolated away). Errors: relative for h_m; relative to max(|ref|, "
             "0.05) for v_r and e_wet; absolute for ln x_e and ln(mu/mu0) at the approach's "
             "pressure peak (= relative errors of x_e and of the viscosity ratio).", "",
             notes(rows), "",
             "### Largest error per preset (eps = 1e-4, St 10 and 100)", "",
             "| preset | film | " + " | ".join(KEYS) + " |", "|---|---|" + "---|" * len(KEYS)]
    presets = [p for p in PRESETS if p in rows[0]["presets"]]
    groups = [("piezoviscous (beta 2, 5)", [r for r in rows if r["beta"] > 0]),
              ("classic (beta 0)", [r for r in rows if r["beta"] == 0])]
    for pr in presets:
        for name, sel in groups:
            if not sel:
                continue
            cells = []
            for k in KEYS:
                if k == "ln_viscosity_ratio" and name.startswith("classic"):
                    cells.append("-")
                    continue
                cells.append(_fmt(max(r["presets"][pr][k] for r in sel)))
            lines.append(f"| {pr} | {name} | " + " | ".join(cells) + " |")
    lines += ["", "### Per scene", "",
              "| St | beta | quantity | reference | order | ref err | thresholds | "
              + " | ".join(presets) + " |", "|---" * (7 + len(presets)) + "|"]
    for row in rows:
        for k in KEYS:
            if k == "ln_viscosity_ratio" and row["beta"] == 0:
                continue
            p = row["presets"]
            lines.append(f"| {row['St']:g} | {row['beta']:g} | {k} | {row['reference'][k]:.6g} | "
                         f"{_order(row['order'][k])} | {_fmt(row['ref_error'][k])} | "
                         f"{_fmt(row['threshold'][k])} | "
                         + " | ".join(_fmt(p[pr][k]) for pr in presets) + " |")
    bad = [r for r in rows if any(s != "ok" for s in r["status"])
           or any(r["presets"][pr]["status"] != "ok" for pr in presets)]
    lines += ["", f"{len(bad)} of {len(rows)} accuracy scenes had a run that was not ok."]
    return lines


if __name__ == "__main__":
    main()
