"""This solver against an earlier release, and its new physics against its classic film: time per
collision, alternated scene by scene in one run so that both sides share the machine's load.

- Against a reference commit (default ``bfedd7c``, solver 1.2.0, the last release before the
  film's terms grew laws): the classic film at the standard preset on St 2-300 x eps 1e-2-1e-6.
  The reference is checked out from this repository's history into a temporary folder (``git
  worktree``) and solved in a process of its own with its own numba cache; each scene is solved
  ``REPEATS`` rounds, each solving it once on each side in a rotated order, and the median of the
  per-round ratios is reported with their range and the step, Newton and LU counts of both (the
  target, issue 16: at most 0.75x).
- The new physics against the classic film of this solver, same preset and scenes (eps 1e-4,
  St 10 and 30): JFO and Reynolds floors at Pi = 1e-3, Barus at beta 1, 2 and 5.

``python benchmarks/bench_versus.py [--ref COMMIT] [--accuracy PRESET] [--out FILE] [--quick]``
(a few minutes) writes ``benchmarks/versus.md`` and ``versus.json`` (``--quick``: a smoke run into
/tmp). Against the previous state of the code rather than a fixed release: ``make bench``
(``benchmarks/suite.py``).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

import harness

HERE = Path(__file__).parent
ROOT = HERE.parent
STOKES = (2.0, 5.0, 10.0, 30.0, 100.0, 300.0)
EPS = (1e-2, 1e-4, 1e-6)
REPEATS = 5
PHYSICS = {  # name: Physics fields beyond St, eps
    "classic": {},
    "jfo Pi 1e-3": {"Pi": 1e-3, "cavitation": "jfo"},
    "reynolds Pi 1e-3": {"Pi": 1e-3, "cavitation": "reynolds"},
    "barus beta 1": {"beta": 1.0},
    "barus beta 2": {"beta": 2.0},
    "barus beta 5": {"beta": 5.0},
}
PHYSICS_SCENES = ((10.0, 1e-4), (30.0, 1e-4))
COUNTS = ("status", "steps", "newton", "lu", "v_r")

def _side(proc: harness.SolverProcess, st, eps, fields=None, last: dict | None = None,
          accuracy="standard"):
    """One solve of the scene by ``proc``: its CPU and wall seconds (counters kept in ``last``)."""
    def once():
        got = proc.solve(st, eps, fields, accuracy)
        if "error" in got:
            raise RuntimeError(f"St {st:g} eps {eps:g} {fields or ''}: {got['error']}")
        if last is not None:
            last.update(got)
        return {"cpu_s": got["cpu_s"][0], "wall_s": got["wall_s"][0]}
    return once


def _row(runs, a: str, b: str, last: dict) -> dict:
    """Per-round ratios a / b in wall and CPU time, with the counters of both sides."""
    cmp = harness.compare_runs(runs[a], runs[b])
    return {"wall": cmp["wall_s"], "cpu": cmp["cpu_s"], "ratio": cmp["wall_s"]["ratio"]["median"],
            "cpu_ratio": cmp["cpu_s"]["ratio"]["median"],
            **{side: {k: last[side][k] for k in COUNTS} for side in (a, b)}}


def versus_reference(old: harness.SolverProcess, new: harness.SolverProcess, scenes,
                     repeats, accuracy="standard") -> list[dict]:
    rows = []
    for st, eps in scenes:
        last = {"old": {}, "new": {}}
        runs = harness.alternate({"old": _side(old, st, eps, last=last["old"], accuracy=accuracy),
                                  "new": _side(new, st, eps, last=last["new"], accuracy=accuracy)},
                                 repeats)
        rows.append({"St": st, "eps": eps, **_row(runs, "new", "old", last)})
        print(f"St {st:g} eps {eps:g}: {rows[-1]['wall']['this']['median'] * 1e3:.1f} ms "
              f"against {rows[-1]['wall']['baseline']['median'] * 1e3:.1f} ms "
              f"({rows[-1]['ratio']:.2f}x)", flush=True)
    return rows


def physics_against_classic(proc: harness.SolverProcess, scenes, repeats) -> list[dict]:
    rows = []
    for st, eps in scenes:
        for name, fields in PHYSICS.items():
            if name == "classic":
                continue
            last = {"classic": {}, "other": {}}
            runs = harness.alternate({"classic": _side(proc, st, eps, last=last["classic"]),
                                      "other": _side(proc, st, eps, fields, last["other"])},
                                     repeats)
            rows.append({"St": st, "eps": eps, "physics": name,
                         **_row(runs, "other", "classic", last)})
            print(f"{name} St {st:g}: {rows[-1]['ratio']:.2f}x the classic film", flush=True)
    return rows


def report(ref, versus, physics, repeats, doc, accuracy="standard") -> str:
    ratios = [r["ratio"] for r in versus]
    cpu_ratios = [r["cpu_ratio"] for r in versus]

    def spread(r):
        return f"{r['wall']['ratio']['min']:.2f}-{r['wall']['ratio']['max']:.2f}"

    lines = [
        "# This solver against an earlier release, and its physics against its classic film",
        "",
        f"{harness.describe(doc)}; one scene at a time per process. Per scene, {repeats} rounds "
        "after a warm-up round, each solving the scene once on each side in a rotated order "
        "(benchmarks/harness.py); a ratio is the median of the per-round ratios, with their "
        "range. `python benchmarks/bench_versus.py` regenerates this file and `versus.json`.",
        "",
        f"## Classic film, {accuracy} preset: against commit {ref}",
        "",
        f"Median over {len(ratios)} scenes of the per-scene ratio (this / reference): "
        f"**{statistics.median(ratios):.2f}x** in wall time (scenes {min(ratios):.2f}-"
        f"{max(ratios):.2f}x), {statistics.median(cpu_ratios):.2f}x in CPU time (scenes "
        f"{min(cpu_ratios):.2f}-{max(cpu_ratios):.2f}x). The targets: issue 16, against "
        "solver 1.2.0 (bfedd7c) at the standard preset, at most 0.75x; issue 30, against "
        "solver 1.8.0 (057d67b) in CPU time, at most 0.5x at the standard preset and 0.35x at "
        "the fine one.",
        "",
        "| St | eps | this [ms] | reference [ms] | ratio | rounds' ratios | steps | Newton | LU | "
        "steps ref | Newton ref | LU ref |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in versus:
        o, n = r["old"], r["new"]
        lines.append(f"| {r['St']:g} | {r['eps']:g} | {r['wall']['this']['median'] * 1e3:.1f} | "
                     f"{r['wall']['baseline']['median'] * 1e3:.1f} | {r['ratio']:.2f} | "
                     f"{spread(r)} | {n['steps']} | {n['newton']} | "
                     f"{n['lu']} | {o['steps']} | {o['newton']} | {o['lu']} |")
    lines += ["", "## New physics against the classic film (standard preset)", "",
              "| physics | St | eps | time [ms] | classic [ms] | ratio | rounds' ratios | steps | "
              "Newton | LU | classic steps | classic LU |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in physics:
        c, o = r["classic"], r["other"]
        lines.append(f"| {r['physics']} | {r['St']:g} | {r['eps']:g} | "
                     f"{r['wall']['this']['median'] * 1e3:.1f} | "
                     f"{r['wall']['baseline']['median'] * 1e3:.1f} | {r['ratio']:.2f} | "
                     f"{spread(r)} | {o['steps']} | {o['newton']} | "
                     f"{o['lu']} | {c['steps']} | {c['lu']} |")
    by_name = {}
    for r in physics:
        by_name.setdefault(r["physics"], []).append(r["ratio"])
    lines += ["", "| physics | median ratio |", "|---|---|"]
    lines += [f"| {k} | {statistics.median(v):.2f} |" for k, v in by_name.items()]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ref", default="bfedd7c", help="reference commit (default: bfedd7c)")
    parser.add_argument("--accuracy", default="standard", choices=("fast", "standard", "fine"),
                        help="the preset of the classic film against the reference (default: "
                             "standard; the physics against the classic film: always standard)")
    parser.add_argument("--out", default=str(HERE / "versus.md"),
                        help="the report (the JSON beside it; default: benchmarks/versus.md)")
    parser.add_argument("--quick", action="store_true",
                        help="two scenes, the fewest rounds that can say 'moved', into /tmp")
    args = parser.parse_args()
    if not Path(args.out).parent.is_dir():  # fail before the runs, not after them
        parser.error(f"--out {args.out}: its folder does not exist")
    scenes = [(st, eps) for eps in EPS for st in STOKES]
    repeats, out = REPEATS, Path(args.out)
    physics_scenes = PHYSICS_SCENES
    if args.quick:
        scenes, physics_scenes, repeats = scenes[2:4], PHYSICS_SCENES[:1], harness.MIN_ROUNDS
        out = Path(tempfile.gettempdir()) / "versus.md"
    load_start = harness.load_now()
    with tempfile.TemporaryDirectory() as tmp, harness.checkout(args.ref) as old_tree, \
            harness.SolverProcess(old_tree, str(Path(tmp) / "cache-ref")) as old, \
            harness.SolverProcess(ROOT, str(Path(tmp) / "cache-new")) as new:
        harness.SolverProcess.compile_all([old, new])
        core = harness.SolverProcess.pin_together([old, new])
        versus = versus_reference(old, new, scenes, repeats, args.accuracy)
        physics = physics_against_classic(new, physics_scenes, repeats)
    doc = harness.write_json(out.with_suffix(".json"), {
        "accuracy": args.accuracy,
        "reference": {"ref": args.ref, "commit": harness.resolve_commit(args.ref),
                      "solver_version": harness.solver_version(commit=args.ref)},
        "rounds": repeats, "pinned_core": core, "versus": versus, "physics": physics},
        load_start)
    text = report(args.ref, versus, physics, repeats, doc, args.accuracy)
    print(text)
    out.write_text(text)


if __name__ == "__main__":
    main()
