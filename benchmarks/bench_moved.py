"""What moved against an earlier release: the largest change per observable, per preset, over the
accuracy table's panel, beside each side's error against the converged reference.

Both solvers answer the panel of ``bench_accuracy.py`` (St 1-300 x eps 1e-2, 1e-5, 1e-8, the
classic film) at each preset (fast, standard, fine), each in a process of its own with its own
numba cache, the reference commit checked out into a temporary folder (``git worktree``). A
change is measured as the accuracy table measures an error (``bench_accuracy.error``: relative,
``v_r`` against max(v_r, 0.05), ``ln x_e`` absolute), the earlier release's value standing for
the reference. The errors are against the converged reference of ``benchmarks/accuracy.json``
(not recomputed here): a change is within the preset's stated error where it is no larger than
the larger of the two sides' stated errors (each side's largest over the panel, the accuracy
table's row; issue 30: "the
largest change per observable against 1.8.0, within each preset's stated error"). A change can
exceed both where the two versions err on either side of the reference.

``python benchmarks/bench_moved.py [--ref COMMIT] [--out FILE]`` (default ``057d67b``, solver
1.8.0; about a minute on 2 cores, two cold compiles included) writes ``benchmarks/moved_1.8.0.md`` and its
``.json``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import harness
from bench_accuracy import KEYS, PANEL, error

HERE = Path(__file__).parent
ROOT = HERE.parent
PRESETS = ("fast", "standard", "fine")

# one process per side: every (St, eps, preset) of argv[1] (JSON), the observables of each
_SIDE = r"""
import json, sys
from solver import collide
out = []
for st, eps, preset in json.loads(sys.argv[1]):
    c = collide(st, eps, accuracy=preset, save_profiles=False)
    out.append({"status": c.status, **{k: getattr(c, k) for k in json.loads(sys.argv[2])}})
print(json.dumps(out))
"""


def solve_sides(trees: dict[str, Path], jobs: list, tmp: Path) -> dict[str, list[dict]]:
    """Each side's answers to ``jobs``, the sides solving at once (one process each)."""
    procs = {}
    for name, tree in trees.items():
        env = harness.source_env(tree)
        env.update(EHD_CACHE_DIR=str(tmp / f"cache-{name}"), NUMBA_CACHE_DIR=str(tmp / name))
        procs[name] = subprocess.Popen([sys.executable, "-c", _SIDE, json.dumps(jobs),
                                        json.dumps(KEYS)], cwd=tree, env=env,
                                       stdout=subprocess.PIPE, text=True)
    answers = {}
    for name, proc in procs.items():
        out, _ = proc.communicate()
        if proc.returncode != 0:
            raise RuntimeError(f"the {name} side failed (exit {proc.returncode}; its error above)")
        answers[name] = json.loads(out)
    return answers


def largest_changes(jobs, answers, reference) -> dict:
    """Per preset and observable: the largest change (and its scene) and, there, each side's
    error against the converged reference; each side's largest error over the panel (its
    stated error, the accuracy table's row); how many scenes are as close to the reference now
    or closer; and the scenes whose change exceeds both stated errors."""
    rows = {}
    for (st, eps, preset), new, old in zip(jobs, answers["new"], answers["old"]):
        ref = reference[PANEL.index((st, eps))]
        for key in KEYS:
            row = rows.setdefault(preset, {}).setdefault(key, {
                "change": -1.0, "stated_new": 0.0, "stated_old": 0.0, "closer": 0,
                "compared": 0, "scenes": []})
            if new["status"] != "ok" or old["status"] != "ok":
                row.setdefault("not_ok", []).append([st, eps, old["status"], new["status"]])
                continue
            change = error(new[key], old[key], key)
            err_new, err_old = error(new[key], ref[key], key), error(old[key], ref[key], key)
            row["scenes"].append([st, eps, change, err_old, err_new])
            row["stated_new"] = max(row["stated_new"], err_new)
            row["stated_old"] = max(row["stated_old"], err_old)
            row["compared"] += 1
            row["closer"] += err_new <= err_old
            if change > row["change"]:
                row.update(change=change, St=st, eps=eps, err_new=err_new, err_old=err_old)
    for preset_rows in rows.values():
        for row in preset_rows.values():
            bound = max(row["stated_new"], row["stated_old"])
            row["beyond"] = [x for x in row["scenes"] if x[2] > bound]
    return rows


def report(doc: dict) -> str:
    ref = doc["ref"]
    old = ref["solver_version"]
    lines = [f"# What moved against solver {old} (`benchmarks/bench_moved.py`)",
             "", harness.describe(doc), "",
             f"The classic film, the accuracy table's panel (St 1-300 x eps 1e-2, 1e-5, 1e-8: "
             f"{len(PANEL)} scenes), solved by this checkout and by commit {ref['commit'][:7]} "
             f"(solver {old}). A change is measured as the accuracy table "
             "measures an error (relative; `v_r` against max(v_r, 0.05); `ln x_e` absolute). "
             "Errors are against the converged reference of `benchmarks/accuracy.json`: at the "
             "scene of the largest change, and the largest over the panel (each version's stated "
             "error, its row of the accuracy table). `python benchmarks/bench_moved.py` "
             "regenerates this file and its JSON.", "",
             f"| preset | observable | largest change | at St, eps | error {old} there | error "
             f"now there | stated error {old} | stated error now | scenes as close now or "
             "closer |",
             "|---|---|---:|---|---:|---:|---:|---:|---:|"]
    beyond = []
    for preset, rows in doc["changes"].items():
        for key, r in rows.items():
            where = f"{r['St']:g}, {r['eps']:g}" if "St" in r else "-"
            lines.append(f"| {preset} | `{key}` | {r['change']:.1e} | {where} | "
                         f"{r.get('err_old', float('nan')):.1e} | "
                         f"{r.get('err_new', float('nan')):.1e} | {r['stated_old']:.1e} | "
                         f"{r['stated_new']:.1e} | {r['closer']} of {r['compared']} |")
            beyond += [f"{preset} `{key}` St {st:g}, eps {eps:g}: {c:.1e} ({e_old:.1e} then, "
                       f"{e_new:.1e} now)" for st, eps, c, e_old, e_new in r["beyond"]]
    lines.append("")
    if beyond:
        lines.append(f"Changes larger than both stated errors ({len(beyond)}; a change can be, "
                     "where the two versions err on either side of the reference, up to the "
                     "sum of their errors): " + "; ".join(beyond) + ".")
    else:
        lines.append("No change is larger than both versions' stated errors.")
    not_ok = {(p, tuple(x)) for p, rows in doc["changes"].items() for r in rows.values()
              for x in r.get("not_ok", [])}
    lines.append("")
    if not_ok:
        lines.append("Not compared (a side did not end ok): " + "; ".join(
            f"{p} St {st:g} eps {eps:g} ({old} then, {new} now)"
            for p, (st, eps, old, new) in sorted(not_ok)))
    else:
        lines.append("Every scene ended ok on both sides.")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ref", default="057d67b", help="the earlier release (default: 057d67b, "
                                                         "solver 1.8.0)")
    parser.add_argument("--out", default=None, help="the report (the JSON beside it; default: "
                                                    "benchmarks/moved_<version>.md)")
    args = parser.parse_args()
    if not harness.resolve_commit(args.ref):  # fail before the runs, not after them
        parser.error(f"--ref {args.ref}: not a commit of this repository")
    version = harness.solver_version(commit=args.ref)
    out = Path(args.out) if args.out else HERE / f"moved_{version}.md"
    if not out.parent.is_dir():  # fail before the runs, not after them
        parser.error(f"--out {out}: its folder does not exist")
    reference = json.loads((HERE / "accuracy.json").read_text())
    if [tuple(p) for p in reference["panel"]] != PANEL:
        parser.error("benchmarks/accuracy.json holds another panel: run bench_accuracy.py first")
    jobs = [(st, eps, preset) for preset in PRESETS for st, eps in PANEL]
    load_start = harness.load_now()
    with tempfile.TemporaryDirectory() as tmp, harness.checkout(args.ref) as old_tree:
        answers = solve_sides({"old": old_tree, "new": ROOT}, jobs, Path(tmp))
    doc = harness.write_json(out.with_suffix(".json"), {
        "ref": {"ref": args.ref, "commit": harness.resolve_commit(args.ref),
                "solver_version": version},
        "reference_from": {"file": "benchmarks/accuracy.json",
                           "solver_version": reference["solver_version"],
                           "commit": reference["commit"]},
        "jobs": jobs, "answers": answers,
        "changes": largest_changes(jobs, answers, reference["reference"])}, load_start)
    harness.save_report(str(out), report(doc))


if __name__ == "__main__":
    main()
