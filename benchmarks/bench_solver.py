"""Solver speed: median wall time per collision after compilation, per preset, and compile time.

Run ``make bench`` (single-threaded BLAS, as in the sweeps). Prints a Markdown table and writes
it to ``benchmarks/solver.md``. Each scene is solved ``REPEATS`` times in one process; the
median is quoted (machines are noisy). Compile time is measured in a fresh interpreter with an
empty numba cache (cold) and again with the cache it filled (warm: loading only).
"""

from __future__ import annotations

import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STOKES = (1.0, 5.0, 10.0, 30.0, 100.0)
EPS = (1e-2, 1e-6)
PRESETS = ("fast", "standard", "fine")
REPEATS = 5
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
    with tempfile.TemporaryDirectory() as cache:
        cold = first_call_seconds(cache)
        warm = first_call_seconds(cache)

    from solver import collide

    collide(5.0, 0.01, save_profiles=False)  # compile / load in this process
    rows = []
    for preset in PRESETS:
        for eps in EPS:
            for stokes in STOKES:
                collide(stokes, eps, accuracy=preset, save_profiles=False)  # build the grid
                walls, last = [], None
                for _ in range(REPEATS):
                    t = time.perf_counter()
                    last = collide(stokes, eps, accuracy=preset, save_profiles=False)
                    walls.append(time.perf_counter() - t)
                rows.append((preset, eps, stokes, last.model, last.status, last.steps,
                             statistics.median(walls)))

    lines = [
        "# Solver speed",
        "",
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; one scene"
        " at a time on one core (OPENBLAS_NUM_THREADS="
        f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}). Median of {REPEATS} runs after"
        " compilation. `python benchmarks/bench_solver.py` (or `make bench`) regenerates this file.",
        "",
        f"First call in a fresh process: {cold:.1f} s with an empty numba cache (compile), "
        f"{warm:.2f} s with a warm cache (load).",
        "",
        "| preset | eps | St | model | status | steps | median wall [ms] |",
        "|---|---|---|---|---|---|---|",
    ]
    for preset, eps, stokes, model, status, steps, wall in rows:
        lines.append(f"| {preset} | {eps:g} | {stokes:g} | {model} | {status} | {steps} | "
                     f"{wall * 1e3:.1f} |")
    lines += ["", "Median over the scenes with St <= 30 (the issue's target range):", "",
              "| preset | median [ms] | max [ms] |", "|---|---|---|"]
    for preset in PRESETS:
        sel = [r[6] for r in rows if r[0] == preset and r[2] <= 30 and r[3] == "ehd"]
        lines.append(f"| {preset} | {statistics.median(sel) * 1e3:.1f} | {max(sel) * 1e3:.1f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    OUT.write_text(text)


if __name__ == "__main__":
    main()
