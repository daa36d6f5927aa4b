"""Cold compile: what the first collision costs with an empty numba cache, per piece of physics,
and which compiled functions the time goes to (issue 30: under 20 s).

Each run is a fresh process with a fresh, empty cache folder (``EHD_CACHE_DIR``, docs/solver.md
"Compiled code") that imports ``solver`` and solves one collision (standard preset): the classic
film, a rough film, a JFO and a Reynolds cavity, a Barus liquid. Wall and CPU time (user + system)
of the whole process, the median of ``--repeat`` runs with their range. Inside the process,
numba's ``numba:compile`` events (``numba.core.event``) time every compilation; a compilation's
own time is its duration less that of the compilations it started (the functions it calls), so
the own times add up to the compile time. Only the first run of each case is attributed (the
table of the classic film's functions).

``--compare DIR`` times another checkout (e.g. ``git worktree add DIR COMMIT``) in the same run,
alternated with this one case by case (benchmarks/harness.py: rounds in a rotated order, both
run as ``python -S -P`` with this venv's packages), and shows it as the "before" columns with the
median of the per-round CPU ratios.

Usage: ``python benchmarks/bench_compile.py [--repeat N] [--compare DIR] [--cases NAME ...]
[--out FILE]`` (writes ``benchmarks/compile.md`` and ``compile.json``, with the provenance of
``benchmarks/harness.py``). About 40 s of CPU a run: 15 runs, 30 with ``--compare``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import tempfile
from pathlib import Path

import harness

REPO = Path(__file__).resolve().parent.parent
TARGET_S = 20.0  # a cold compile of what one collision needs, CPU seconds (issue 30)
CASES = {
    "classic": {"St": 10.0, "eps": 1e-3},
    "rough": {"St": 20.0, "eps": 1e-3, "roughness": 2.0},
    "jfo": {"St": 10.0, "eps": 1e-2, "Pi": 1e-3, "cavitation": "jfo"},
    "reynolds": {"St": 10.0, "eps": 1e-2, "Pi": 1e-3, "cavitation": "reynolds"},
    "barus": {"St": 10.0, "eps": 1e-3, "beta": 2.0},
}
TOP = 15  # functions shown in the attribution table

# The measured process: argv[1] the scene's fields (JSON), argv[2] where to write what compiled.
_CHILD = r"""
import json, sys, time
from numba.core import event

own, count, stack = {}, {}, []


def name(ev):
    f = ev.data["dispatcher"].py_func
    return f"{f.__module__}.{f.__qualname__}"


class Timer(event.Listener):
    def on_start(self, ev):
        stack.append([time.perf_counter(), 0.0])

    def on_end(self, ev):
        start, inner = stack.pop()
        took = time.perf_counter() - start
        key = name(ev)
        own[key] = own.get(key, 0.0) + took - inner
        count[key] = count.get(key, 0) + 1
        if stack:
            stack[-1][1] += took


event.register("numba:compile", Timer())
from solver import Physics, collide
result = collide(Physics(**json.loads(sys.argv[1])))
with open(sys.argv[2], "w") as out:
    json.dump({"status": result.status, "own_s": own, "specialisations": count}, out)
"""


def cold_run(fields: dict, env: dict, attribution: Path | None) -> dict:
    """Wall and CPU seconds of one process that solves ``fields`` with an empty cache; what it
    compiled goes to ``attribution`` (kept) or a temporary file."""
    with tempfile.TemporaryDirectory(prefix="ehd-bench-compile-") as tmp:
        out = attribution or Path(tmp) / "compiled.json"
        t = harness.time_process([sys.executable, "-S", "-P", "-c", _CHILD, json.dumps(fields),
                                  out], dict(env, EHD_CACHE_DIR=tmp))
        compiled = json.loads(out.read_text())
    return {**t, "status": compiled["status"], "compiled_s": sum(compiled["own_s"].values())}


def measure(cases: list[str], repeat: int, launches: dict, keep: Path) -> dict:
    """``{case: {label: [run, ...]}}``, the labels alternated in rounds; the first run of each
    case of the last label keeps its attribution in ``keep/<case>.json``."""
    out = {}
    last = list(launches)[-1]
    for case in cases:
        first = {label: True for label in launches}

        def side(label):
            def run():
                path = keep / f"{case}.json" if first[label] and label == last else None
                first[label] = False
                return cold_run(CASES[case], launches[label], path)
            return run
        out[case] = harness.alternate({label: side(label) for label in launches}, repeat,
                                      warmup=0)
    return out


def attribution(path: Path) -> dict:
    """The functions of one run, largest own compile time first, with their count of
    specialisations; numba's own (array allocation, strings, StructRef constructors) summed."""
    doc = json.loads(path.read_text())
    own, count = doc["own_s"], doc["specialisations"]
    solver = {k: v for k, v in own.items() if k.startswith("solver.")}
    return {"total_s": sum(own.values()), "functions": len(own),
            "specialisations": sum(count.values()),
            "solver_s": sum(solver.values()), "solver_functions": len(solver),
            "top": [[k, own[k], count[k]] for k in sorted(own, key=own.get, reverse=True)[:TOP]],
            "several": {k: n for k, n in count.items() if n > 1 and k.startswith("solver.")}}


def summary(runs: list[dict]) -> dict:
    wall = harness.spread([r["wall_s"] for r in runs])
    cpu = harness.spread([r["cpu_s"] for r in runs])
    return {"wall_s": wall, "cpu_s": cpu, "status": sorted({r["status"] for r in runs})}


def render(doc: dict) -> str:
    results, before = doc["results"], doc.get("before")
    lines = [
        "# Cold compile (`benchmarks/bench_compile.py`)", "",
        f"{harness.describe(doc)}. One collision (standard preset) in a fresh process with an "
        f"empty numba cache; median of {doc['repeat']} runs per case (range in brackets), CPU = "
        "user + system time of the process (import, compile, solve: the solve itself takes "
        "under 0.1 s). `python benchmarks/bench_compile.py` regenerates this file and "
        "`compile.json`.", "",
        "| case | wall [s] | CPU [s] |" + (" before: CPU [s] | CPU ratio (rounds) |"
                                          if before else ""),
        "|---|---:|---:|" + ("---:|---:|" if before else ""),
    ]
    for case, r in results.items():
        w, c = r["wall_s"], r["cpu_s"]
        row = (f"| {case} | {w['median']:.1f} [{w['min']:.1f}-{w['max']:.1f}] | "
               f"{c['median']:.1f} [{c['min']:.1f}-{c['max']:.1f}] |")
        if before:
            b, q = before[case]["cpu_s"], doc["ratio"][case]["ratio"]
            row += (f" {b['median']:.1f} [{b['min']:.1f}-{b['max']:.1f}] | {q['median']:.2f} "
                    f"({q['min']:.2f}-{q['max']:.2f}) |")
        lines.append(row)
    medians = {case: r["cpu_s"]["median"] for case, r in results.items()}
    over = [f"{case} {t:.1f} s" for case, t in medians.items() if t >= TARGET_S]
    lines += ["", f"Target (issue 30): a cold compile under {TARGET_S:g} s: "
              + ", ".join(f"{case} {t:.1f} s" for case, t in medians.items()) + " CPU ("
              + (f"not met: {', '.join(over)}" if over else "met") + ")."]
    if before:
        lines += ["", f"Before: {doc['before_source']}, alternated with this checkout case by "
                  "case in this run (the ratio is the median of the per-round CPU ratios)."]
    a = doc.get("attribution")
    if a:
        lines += [
            "", "## Where the classic collision's compile goes (one run)", "",
            f"numba compiled {a['functions']} functions in {a['specialisations']} "
            f"specialisations, {a['total_s']:.1f} s in all (wall, inside the process); the "
            f"solver's own {a['solver_functions']} functions {a['solver_s']:.1f} s, numba's "
            "library code (array allocation, StructRef constructors, min/max) the rest. A "
            "function's own time is its compile less that of the functions it calls. Only an "
            "entry (a function the solver calls from Python: `integrate` here) links in the "
            "code of every function below it and optimises and emits the whole (docs/solver.md, "
            "\"Compiled code\"), so its own time includes that; every other function's is its "
            "own code's.", "",
            "| function | own compile [s] | specialisations |", "|---|---:|---:|"]
        lines += [f"| `{name}` | {s:.2f} | {n} |" for name, s, n in a["top"]]
        several = ", ".join(f"`{k}` ({n})" for k, n in a["several"].items()) or "none"
        lines += ["", f"Solver functions compiled for more than one signature: {several}."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3, help="runs per case (default 3)")
    p.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    p.add_argument("--compare", default=None, metavar="DIR|COMMIT",
                   help="also time the checkout in DIR, or this repository's COMMIT checked out "
                        "in a temporary folder, alternated (shown as 'before')")
    p.add_argument("--out", default=str(REPO / "benchmarks" / "compile.md"),
                   help="markdown file for the table ('-': print only); the JSON goes beside it")
    args = p.parse_args(argv)
    load_start = harness.load_now()
    launches = {"this": harness.source_env(REPO)}
    with contextlib.ExitStack() as stack:
        if args.compare:
            before = Path(args.compare)
            if not (before / "solver").is_dir():  # not a checkout: a commit of this repository
                if not harness.resolve_commit(args.compare):
                    p.error(f"--compare {args.compare}: neither a checkout (no solver/ folder "
                            "in it) nor a commit of this repository")
                before = stack.enter_context(harness.checkout(args.compare))
            launches = {"before": harness.source_env(before), **launches}
        keep = stack.enter_context(tempfile.TemporaryDirectory(prefix="ehd-bench-compile-"))
        runs = measure(args.cases, args.repeat, launches, Path(keep))
        first = Path(keep) / "classic.json"
        found = attribution(first) if first.exists() else None
    doc = {"repeat": args.repeat, "target_s": TARGET_S, "source": str(REPO),
           "results": {case: summary(r["this"]) for case, r in runs.items()},
           "runs": runs, "attribution": found}
    if args.compare:
        commit, dirty = harness.commit_of(before)
        doc["before_source"] = (f"{args.compare} (solver {harness.solver_version(before)}, "
                                f"commit {commit[:7]}{' with changes' if dirty else ''})")
        doc["before"] = {case: summary(r["before"]) for case, r in runs.items()}
        doc["ratio"] = {case: harness.compare([x["cpu_s"] for x in r["this"]],
                                              [x["cpu_s"] for x in r["before"]])
                        for case, r in runs.items()}
    doc = harness.save_results(args.out, doc, load_start)
    harness.save_report(args.out, render(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
