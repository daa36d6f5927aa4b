"""The speed suite (``make bench``): this checkout against a baseline commit, alternated in one run.

Figures (each a CPU time and a wall time, per run):

- start-up: ``python -c "import argparse"`` (the same interpreter on both sides: a control, it
  should never move), ``ehd --help``, ``ehd sweep --help``, ``ehd run`` of one fast scene (start,
  loading the compiled kernels, one solve), and the no-op ``make sweep`` (``ehd sweep
  sweeps/paper.toml`` on a complete store plus ``ehd figures`` on an up-to-date folder; each side
  builds its own store first, about a minute each);
- solver: one collision at each preset (classic film), with a cavitating film (JFO, Pi 1e-3), a
  piezoviscous one (Barus, beta 2) and a rough one (roughness 0.5, asperity stiffness 20), solved
  in one process per side with compiled code and grids warm.

Each figure is measured in rounds: every round runs it once on each side, the order of the sides
rotated from round to round, after one warm-up round (``benchmarks/harness.py``). Quoted: each
side's median, the median of the per-round ratios (this / baseline) with their range, and
whether the figure moved (every round's CPU-time ratio on the same side of 1 and the median off 1
by more than 3 %; otherwise the change is within the spread the rounds measured; the wall time is
shown, not judged: on a shared machine it depends on what else runs). Both sides run with this venv's packages, as
``python -S -P -m pipeline.cli`` (start-up) or a solver process (``PYTHONPATH`` = the checkout),
the baseline exported from git (``git archive``) and this checkout mirrored as it is (uncommitted
changes included) into ``<cache root>/numba/bench-suite`` (docs/solver.md; ``make clean-cache``
removes it), where their compiled kernels and paper stores stay between runs: the first run with
a new baseline compiles it (both sides at once) and builds its store, later ones only what
changed.

The baseline: ``--baseline REF`` (``make bench BASELINE=REF``); by default the commit of the stored
result ``benchmarks/speed.json``, the run the committed figures come from. Comparing a commit with
itself is the suite's noise check: every figure should read "no".

Usage: ``make bench`` or ``python benchmarks/suite.py [--baseline REF] [--rounds N] [--no-noop]
[--quick] [--out FILE]``; writes ``benchmarks/speed.md`` and ``speed.json`` (``--quick``: five
rounds, no no-op sweep, into /tmp).
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import harness

HERE = Path(__file__).resolve().parent
STORED = HERE / "speed.json"
ROUNDS = 7
# name: (St, eps, Physics fields beyond St and eps, preset)
SOLVES = {
    "collide fast St 10 eps 1e-2": (10.0, 1e-2, {}, "fast"),
    "collide standard St 10 eps 1e-4": (10.0, 1e-4, {}, "standard"),
    "collide fine St 30 eps 1e-6": (30.0, 1e-6, {}, "fine"),
    "collide standard JFO Pi 1e-3 St 10 eps 1e-4": (10.0, 1e-4, dict(Pi=1e-3, cavitation="jfo"),
                                                    "standard"),
    "collide standard Barus beta 2 St 10 eps 1e-4": (10.0, 1e-4, dict(beta=2.0), "standard"),
    "collide standard rough 0.5/20 St 30 eps 1e-4": (30.0, 1e-4, dict(
        roughness=0.5, asperity_stiffness=20.0, e_dry=0.97), "standard"),
}
MOVED = {"slower", "faster"}
COUNTS = ("status", "steps", "newton", "lu", "rejected_steps")


def default_baseline() -> str:
    if STORED.exists():
        commit = json.loads(STORED.read_text()).get("commit")
        if commit and commit != harness.NOT_RECORDED:
            return commit
    return "HEAD"


def resolve(ref: str) -> str:
    sha = harness.resolve_commit(ref)
    if not sha:
        sys.exit(f"error: baseline {ref!r} is not a commit of this repository; "
                 "pass one with --baseline REF (make bench BASELINE=REF)")
    return sha


def startup_sides(trees: dict[str, Path], keep: Path, cache: str, noop: bool) -> dict[str, dict]:
    """``{figure: {side: callable}}`` of the start-up figures (each side's paper store and
    figures kept in ``keep`` between runs)."""
    launches = {}
    for side, tree in trees.items():
        argv, env = harness.cli_launch(tree)
        env.update(EHD_CACHE_DIR=cache, NUMBA_CACHE_DIR=cache)
        env.pop("PYTHONDONTWRITEBYTECODE", None)  # as after pip install: .pyc files written
        launches[side] = (argv, env, tree)

    def run(side, *args, ok=(0,)):
        argv, env, tree = launches[side]
        return lambda: harness.time_process([*argv, *args], env, cwd=tree, ok=ok)

    figures = {
        "python -c 'import argparse'": {s: (lambda s=s: harness.time_process(
            [sys.executable, "-c", "import argparse"], launches[s][1])) for s in trees},
        "ehd --help": {s: run(s, "--help") for s in trees},
        "ehd sweep --help": {s: run(s, "sweep", "--help") for s in trees},
        "ehd run --St 5 --eps 0.01 --accuracy fast": {
            s: run(s, "run", "--St", "5", "--eps", "0.01", "--accuracy", "fast") for s in trees},
    }
    if noop:
        noop_sides = {}
        for side, tree in trees.items():
            store, figs = keep / f"paper-{side}.zarr", keep / f"figures-{side}"
            sweep = run(side, "sweep", str(tree / "sweeps" / "paper.toml"), "--store", str(store),
                        ok=(0, 3))
            draw = run(side, "figures", str(store), "--out", str(figs))
            print(f"the paper store of {side}: completing it (the first time: about a minute)",
                  flush=True)
            try:
                sweep(), draw()
            except RuntimeError:  # e.g. an earlier side's store this solver does not take
                shutil.rmtree(store, ignore_errors=True)
                shutil.rmtree(figs, ignore_errors=True)
                sweep(), draw()

            def both(sweep=sweep, draw=draw):
                a, b = sweep(), draw()
                return {k: a[k] + b[k] for k in a}
            noop_sides[side] = both
        figures["no-op make sweep (ehd sweep + ehd figures)"] = noop_sides
    return figures


def solver_sides(workers: dict[str, harness.SolverProcess], name: str, errors: dict,
                 counts: dict) -> dict:
    st, eps, fields, preset = SOLVES[name]

    def measure(side):
        def once():
            got = workers[side].solve(st, eps, fields, preset)
            if "error" in got:
                raise RuntimeError(got["error"])
            counts.setdefault(name, {})[side] = {k: got.get(k) for k in COUNTS}
            return {"cpu_s": got["cpu_s"][0], "wall_s": got["wall_s"][0]}
        return once
    return {side: measure(side) for side in workers}


def measure_all(trees: dict[str, Path], keep: Path, rounds: int, noop: bool) -> dict:
    # one cache for both: numba keeps kernels apart by source path, the solver by source hash
    cache = str(keep / "cache")
    figures, errors, counts = {}, {}, {}

    def record(name, group, sides):
        try:
            runs = harness.alternate(sides, rounds)
        except RuntimeError as exc:
            errors[name] = str(exc).splitlines()[-1][:300]
            print(f"{name}: not compared ({errors[name]})", flush=True)
            return
        figures[name] = {"group": group, **harness.compare_runs(runs["this"], runs["baseline"])}
        if name in counts:
            figures[name]["counts"] = counts[name]
        c = figures[name]["cpu_s"]
        print(f"{name}: CPU ratio {c['ratio']['median']:.2f} ({c['ratio']['min']:.2f}-"
              f"{c['ratio']['max']:.2f}), moved: {c['moved']}", flush=True)

    workers = {side: harness.SolverProcess(tree, cache) for side, tree in trees.items()}
    try:
        print("compiling both sides' solvers (at once)", flush=True)
        harness.SolverProcess.compile_all(workers.values())
        core = harness.SolverProcess.pin_together(workers.values())
        for name in SOLVES:
            record(name, "solver", solver_sides(workers, name, errors, counts))
    finally:
        for w in workers.values():
            w.close()
    for name, sides in startup_sides(trees, keep, cache, noop).items():
        record(name, "startup", sides)
    return {"figures": figures, "errors": errors, "pinned_core": core}


def render(doc: dict) -> str:
    base = doc["baseline"]
    moved = [f"{n} ({f['cpu_s']['moved']}, {f['cpu_s']['ratio']['median']:.2f}x in CPU time)"
             for n, f in doc["figures"].items() if f["cpu_s"]["moved"] in MOVED]
    lines = [
        "# Speed suite (`make bench`, `benchmarks/suite.py`)", "",
        f"This checkout: {harness.describe(doc)}.", "",
        f"Baseline: `{base['ref']}` = commit {base['commit'][:7]} (solver "
        f"{base['solver_version']}), exported from git and measured in the same run, both sides "
        f"from folders alike (benchmarks/README.md): {doc['rounds']} rounds after one warm-up round, each round running every figure "
        "once on each side in a rotated order. Ratios are this / baseline, the median of the "
        "per-round ratios, with their range; a figure moved when every round's CPU-time ratio "
        "lies on the same side of 1 and their median is off 1 by more than "
        f"{harness.TOLERANCE:.0%}. CPU is the user + system time of the process (start-up: of "
        "the child process; solver: of the solve); the wall time, which on a shared machine "
        "depends on what else runs, is shown beside it and judges nothing.", "",
        *harness.figure_rows(doc["figures"]), "",
        ("Moved beyond the rounds' spread: " + "; ".join(moved) + "." if moved else
         "No figure moved beyond the spread of its rounds."),
    ]
    if doc["errors"]:
        lines += ["", "Not compared (a side could not run it): " + "; ".join(
            f"{n}: {e}" for n, e in doc["errors"].items())]
    counted = {n: f["counts"] for n, f in doc["figures"].items() if "counts" in f}
    if counted:
        lines += ["", "Counts of the last solve (status, steps, Newton iterations, LU "
                  "factorisations, rejected steps; they differ when a change alters the "
                  "numerics):", "", "| figure | this | baseline |", "|---|---|---|"]
        for n, c in counted.items():
            cells = ["/".join(str(c[s].get(k)) for k in COUNTS) if s in c else "-"
                     for s in ("this", "baseline")]
            lines.append(f"| {n} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", default=None,
                   help="commit to compare with (default: the commit of benchmarks/speed.json)")
    p.add_argument("--rounds", type=int, default=ROUNDS, help=f"rounds (default {ROUNDS})")
    p.add_argument("--no-noop", action="store_true",
                   help="skip the no-op make sweep (saves building two paper stores)")
    p.add_argument("--quick", action="store_true",
                   help="smoke run: 5 rounds, no no-op make sweep, written to /tmp")
    p.add_argument("--out", default=None, help="markdown file (default benchmarks/speed.md); "
                   "the JSON goes beside it")
    args = p.parse_args(argv)
    if args.quick:
        args.rounds, args.no_noop = harness.MIN_ROUNDS, True
    out = Path(args.out) if args.out else (
        Path(tempfile.gettempdir()) / "speed.md" if args.quick else HERE / "speed.md")
    ref = args.baseline or default_baseline()
    sha = resolve(ref)
    load_start = harness.load_now()
    keep = harness.bench_folder()
    for old in keep.glob("commit-*"):  # earlier baselines' trees (their kernels stay cached)
        if old.name != f"commit-{sha}":
            shutil.rmtree(old, ignore_errors=True)
    trees = {"this": harness.sync_worktree(keep / "this"),
             "baseline": harness.export_commit(sha, keep / f"commit-{sha}")}
    result = measure_all(trees, keep, args.rounds, not args.no_noop)
    payload = {"baseline": {"ref": ref, "commit": sha,
                            "solver_version": harness.solver_version(commit=sha)},
               "rounds": args.rounds, **result,
               "moved": [n for n, f in result["figures"].items()
                         if f["cpu_s"]["moved"] in MOVED]}
    doc = harness.write_json(out.with_suffix(".json"), payload, load_start)
    text = render(doc)
    out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
