"""Wall time of the default sweep (what ``make sweep`` runs), cold and with nothing to do.

Runs the two commands of ``make sweep`` (``ehd sweep sweeps/paper.toml`` and ``ehd figures``)
as subprocesses, but on a fresh store in a temporary folder (``--store``), so the project's own
``results/paper.zarr`` is never touched. Cases:

- empty store, numba cache warm (the target: <= 60 s on 2 cores), for each local executor;
- rerun with nothing to do (target: <= 5 s);
- empty store with an empty numba cache (what the very first run on a machine pays).

Usage: ``make bench-sweep`` (writes ``benchmarks/sweep.md`` and ``sweep.json``, with the provenance
of ``benchmarks/harness.py``) or
``python benchmarks/bench_sweep.py [--quick] [--out FILE]`` (``--quick``: sweeps/quick.toml).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness

REPO = Path(__file__).resolve().parent.parent
EHD = str(Path(sys.executable).parent / "ehd")


def _run(args, env) -> tuple[float, str]:
    t = time.perf_counter()
    proc = subprocess.run([EHD, *args], cwd=REPO, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if proc.returncode not in (0, 3):
        sys.exit(f"ehd {' '.join(args)} failed ({proc.returncode}):\n{proc.stderr}")
    return wall, proc.stdout


def make_sweep(sweep_file, store, figures, env, executor=None) -> dict:
    """The two steps of ``make sweep``; returns their wall times and the scene counts."""
    extra = ["--executor", executor] if executor else []
    t_sweep, out = _run(["sweep", sweep_file, "--store", str(store), *extra], env)
    t_fig, _ = _run(["figures", str(store), "--out", str(figures)], env)
    computed = 0
    for line in out.splitlines():
        if line.strip().startswith("runner"):
            computed = int(line.split(";")[1].split()[0])
    return {"sweep": t_sweep, "figures": t_fig, "total": t_sweep + t_fig, "computed": computed}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="benchmark sweeps/quick.toml instead")
    p.add_argument("--repeat", type=int, default=3, help="repeats of the nothing-to-do rerun")
    p.add_argument("--out", default=str(REPO / "benchmarks" / "sweep.md"),
                   help="markdown file for the table ('-': print only)")
    args = p.parse_args(argv)
    sweep_file = "sweeps/quick.toml" if args.quick else "sweeps/paper.toml"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    load_start = harness.load_now()
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-sweep-") as tmp:
        tmp = Path(tmp)
        # compile once into the documented cache (docs/solver.md), as any earlier run would have
        _run(["run", "--St", "5", "--eps", "0.01", "--accuracy", "fast"], env)
        for executor in ("processes", "threads"):
            store, figs = tmp / f"{executor}.zarr", tmp / f"fig-{executor}"
            cold = make_sweep(sweep_file, store, figs, env, executor)
            rows.append((f"empty store, numba cache warm, `--executor {executor}`", cold))
            if executor == "processes":  # the default of make sweep
                reruns = [make_sweep(sweep_file, store, figs, env) for _ in range(args.repeat)]
                med = {k: statistics.median(r[k] for r in reruns) for k in reruns[0]}
                med["total_range"] = [min(r["total"] for r in reruns),
                                      max(r["total"] for r in reruns)]
                rows.append((f"rerun, nothing to do (median of {args.repeat})", med))
            shutil.rmtree(store)
        fresh = {**env, "EHD_CACHE_DIR": str(tmp / "numba-cold")}  # wins over NUMBA_CACHE_DIR
        cold_compile = make_sweep(sweep_file, tmp / "cc.zarr", tmp / "fig-cc", fresh)
        rows.append(("empty store, empty numba cache (first run on a machine)", cold_compile))
    payload = {"sweep_file": sweep_file, "repeat": args.repeat,
               "cases": [{"case": name, **r} for name, r in rows]}
    doc = (harness.write_json(Path(args.out).with_suffix(".json"), payload, load_start)
           if args.out != "-" else {**payload, **harness.provenance(load_start)})
    lines = [
        f"# Sweep benchmark: `make sweep` on `{sweep_file}`",
        "",
        f"Measured by `benchmarks/bench_sweep.py`: {harness.describe(doc)}. Each row runs "
        "`ehd sweep` then `ehd figures` (the two steps of `make sweep`) as fresh processes on "
        "a temporary store; times in seconds (one run each, except the rerun: the median of "
        "its runs, their range in `sweep.json`), scenes/s counts the sweep step only.",
        "",
        "| case | sweep [s] | figures [s] | total [s] | scenes computed | scenes/s |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for name, r in rows:
        rate = f"{r['computed'] / r['sweep']:.1f}" if r["computed"] else "-"
        lines.append(f"| {name} | {r['sweep']:.1f} | {r['figures']:.1f} | {r['total']:.1f} | "
                     f"{r['computed']:.0f} | {rate} |")
    lines += ["", "Targets (issue 3): empty store with a warm numba cache <= 60 s; a rerun with "
              "nothing to do <= 5 s."]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out != "-":
        Path(args.out).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
