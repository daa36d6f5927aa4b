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
import resource
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


def _run(args, env, usage=None) -> tuple[float, str]:
    """Run ``ehd ARGS``; its wall time and stdout. ``usage``: a dict that gets the CPU seconds
    of the process tree (``cpu``: the command and every process it started and waited for)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    proc = subprocess.run([EHD, *args], cwd=REPO, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if usage is not None:
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        usage["cpu"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
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


def executors(sweep_file, tmp: Path, env, rounds: int) -> dict:
    """The sweep step on an empty store per executor (the default, ``serial``, ``processes``),
    alternated in each round; per round the default's CPU less serial's [s] and its wall time
    over serial's. Returns the medians, their ranges and every round."""
    kinds = ("default", "serial", "processes")
    per_round = []
    for k in range(rounds):
        got = {}
        for kind in kinds:
            store = tmp / f"ex-{kind}-{k}.zarr"
            usage = {}
            extra = [] if kind == "default" else ["--executor", kind]
            wall, _ = _run(["sweep", sweep_file, "--store", str(store), *extra], env, usage)
            got[kind] = {"wall": wall, "cpu": usage["cpu"]}
            shutil.rmtree(store)
        per_round.append(got)
    out = {"rounds": per_round}
    for other in ("serial", "processes"):
        extra_cpu = [r["default"]["cpu"] - r[other]["cpu"] for r in per_round]
        wall_ratio = [r["default"]["wall"] / r[other]["wall"] for r in per_round]
        out[other] = {"extra_cpu_median": statistics.median(extra_cpu),
                      "extra_cpu_range": [min(extra_cpu), max(extra_cpu)],
                      "wall_ratio_median": statistics.median(wall_ratio),
                      "wall_ratio_range": [min(wall_ratio), max(wall_ratio)]}
    for kind in kinds:
        out[f"{kind}_cpu_median"] = statistics.median(r[kind]["cpu"] for r in per_round)
        out[f"{kind}_wall_median"] = statistics.median(r[kind]["wall"] for r in per_round)
    return out


def _executor_lines(ex: dict, rounds: int) -> list[str]:
    lines = ["", f"## Executors (the sweep step, alternated, {rounds} rounds)", "",
             "CPU of the process tree (the command and every process it started). Per round: "
             "the default's CPU less the other's, and its wall time over the other's; medians "
             "with the rounds' range.", "",
             "| executor | CPU median [s] | wall median [s] |", "|---|---:|---:|"]
    for kind in ("default", "serial", "processes"):
        lines.append(f"| {kind} | {ex[f'{kind}_cpu_median']:.1f} | "
                     f"{ex[f'{kind}_wall_median']:.1f} |")
    lines += ["", "| default against | CPU more [s], median (range) | wall ratio, median (range) |",
              "|---|---:|---:|"]
    for other in ("serial", "processes"):
        r = ex[other]
        lines.append(f"| `{other}` | {r['extra_cpu_median']:+.1f} "
                     f"({r['extra_cpu_range'][0]:+.1f} to {r['extra_cpu_range'][1]:+.1f}) | "
                     f"{r['wall_ratio_median']:.2f} ({r['wall_ratio_range'][0]:.2f}-"
                     f"{r['wall_ratio_range'][1]:.2f}) |")
    lines += ["", "Target (issue 30): the default at most 2 s of CPU more than `serial` and "
              "faster in wall time on 2 idle cores."]
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="benchmark sweeps/quick.toml instead")
    p.add_argument("--repeat", type=int, default=3, help="repeats of the nothing-to-do rerun")
    p.add_argument("--rounds", type=int, default=3,
                   help="alternated rounds of the executors' comparison (0: skip it)")
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
        for executor in ("auto", "processes"):
            store, figs = tmp / f"{executor}.zarr", tmp / f"fig-{executor}"
            cold = make_sweep(sweep_file, store, figs, env, executor)
            rows.append((f"empty store, numba cache warm, `--executor {executor}`", cold))
            if executor == "auto":  # the default of make sweep
                reruns = [make_sweep(sweep_file, store, figs, env) for _ in range(args.repeat)]
                med = {k: statistics.median(r[k] for r in reruns) for k in reruns[0]}
                med["total_range"] = [min(r["total"] for r in reruns),
                                      max(r["total"] for r in reruns)]
                rows.append((f"rerun, nothing to do (median of {args.repeat})", med))
            shutil.rmtree(store)
        fresh = {**env, "EHD_CACHE_DIR": str(tmp / "numba-cold")}  # wins over NUMBA_CACHE_DIR
        cold_compile = make_sweep(sweep_file, tmp / "cc.zarr", tmp / "fig-cc", fresh)
        rows.append(("empty store, empty numba cache (first run on a machine)", cold_compile))
        ex = executors(sweep_file, tmp, env, args.rounds) if args.rounds > 0 else None
    payload = {"sweep_file": sweep_file, "repeat": args.repeat,
               "cases": [{"case": name, **r} for name, r in rows], "executors": ex}
    doc = harness.save_results(args.out, payload, load_start)
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
    if ex is not None:
        lines += _executor_lines(ex, args.rounds)
    harness.save_report(args.out, "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
