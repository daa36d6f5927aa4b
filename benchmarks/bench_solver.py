"""Solver speed: median wall time per collision after compilation, per preset, and compile time.

``python benchmarks/bench_solver.py`` (single-threaded BLAS, as in the sweeps; a few minutes)
prints a Markdown table and writes it to ``benchmarks/solver.md``, the numbers to ``solver.json``
(with the provenance of ``benchmarks/harness.py``). Each scene is solved ``REPEATS`` times in one
process; the median is quoted with the range of the runs (machines are noisy). Compile time is
measured in a fresh interpreter with an empty numba cache (cold) and again with the cache it
filled (warm: loading only). Against another commit, alternated: ``make bench``
(``benchmarks/suite.py``).
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import harness

STOKES = (1.0, 5.0, 10.0, 30.0, 100.0)
EPS = (1e-2, 1e-6)
PRESETS = ("fast", "standard", "fine")
REPEATS = 5
WARM_REPEATS = 5  # fresh processes loading from the filled cache (one alone gave 0.49-0.72 s on this
# shared machine within an hour)
OUT = Path(__file__).with_name("solver.md")

_FIRST_CALL = (
    "import time; t = time.perf_counter(); from solver import collide; "
    "collide(5.0, 0.01, save_profiles=False); print(time.perf_counter() - t)")


def first_call_seconds(cache_dir: str) -> float:
    env = dict(os.environ, EHD_CACHE_DIR=cache_dir)  # the solver's cache root, first in order
    out = subprocess.run([sys.executable, "-c", _FIRST_CALL], env=env, capture_output=True,
                         text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    load_start = harness.load_now()
    with tempfile.TemporaryDirectory() as cache:
        cold = first_call_seconds(cache)
        warm_runs = [first_call_seconds(cache) for _ in range(WARM_REPEATS)]
        warm = statistics.median(warm_runs)

    from solver import collide

    collide(5.0, 0.01, save_profiles=False)  # compile / load in this process
    rows = []
    for preset in PRESETS:
        for eps in EPS:
            for stokes in STOKES:
                collide(stokes, eps, accuracy=preset, save_profiles=False)  # build the grid
                last = {}

                def once():
                    last["c"] = collide(stokes, eps, accuracy=preset, save_profiles=False)
                runs = [harness.time_call(once) for _ in range(REPEATS)]
                c = last["c"]
                rows.append((preset, eps, stokes, c.model, c.status, c.steps,
                             harness.spread([r["wall_s"] for r in runs]),
                             harness.spread([r["cpu_s"] for r in runs])))

    doc = harness.write_json(OUT.with_suffix(".json"), {
        "repeats": REPEATS, "first_call_s": {"empty_cache": cold, "warm_cache": warm,
                                             "warm_cache_runs": warm_runs},
        "scenes": [{"preset": preset, "eps": eps, "St": stokes, "model": model, "status": status,
                    "steps": steps, "wall_s": wall, "cpu_s": cpu}
                   for preset, eps, stokes, model, status, steps, wall, cpu in rows]}, load_start)
    lines = [
        "# Solver speed",
        "",
        f"{harness.describe(doc)}; one scene at a time on one core. Median of {REPEATS} runs after"
        " compilation, with the range of their wall time, and their CPU time (on a shared"
        " machine the steadier measure; the wall time includes waiting for a core)."
        " `python benchmarks/bench_solver.py` regenerates this file and `solver.json`.",
        "",
        f"First call in a fresh process: {cold:.1f} s with an empty numba cache (compile), "
        f"{warm:.2f} s with a warm cache (load; median of {WARM_REPEATS} processes, "
        f"{min(warm_runs):.2f}-{max(warm_runs):.2f}).",
        "",
        "| preset | eps | St | model | status | steps | median wall [ms] | range [ms] | "
        "median CPU [ms] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for preset, eps, stokes, model, status, steps, wall, cpu in rows:
        lines.append(f"| {preset} | {eps:g} | {stokes:g} | {model} | {status} | {steps} | "
                     f"{wall['median'] * 1e3:.1f} | {wall['min'] * 1e3:.1f}-"
                     f"{wall['max'] * 1e3:.1f} | {cpu['median'] * 1e3:.1f} |")
    lines += ["", "Median over the scenes with St <= 30 (the issue's target range):", "",
              "| preset | median wall [ms] | max wall [ms] | median CPU [ms] | max CPU [ms] |",
              "|---|---|---|---|---|"]
    for preset in PRESETS:
        sel = [r for r in rows if r[0] == preset and r[2] <= 30 and r[3] == "ehd"]
        wall, cpu = [r[6]["median"] for r in sel], [r[7]["median"] for r in sel]
        lines.append(f"| {preset} | {statistics.median(wall) * 1e3:.1f} | "
                     f"{max(wall) * 1e3:.1f} | {statistics.median(cpu) * 1e3:.1f} | "
                     f"{max(cpu) * 1e3:.1f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    OUT.write_text(text)


if __name__ == "__main__":
    main()
