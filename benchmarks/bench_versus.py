"""This solver against an earlier release, and its new physics against its classic film: time per
collision, alternated scene by scene in one run so that both sides share the machine's load.

- Against a reference commit (default ``bfedd7c``, solver 1.2.0, the last release before the
  film's terms grew laws): the classic film at the standard preset on St 2-300 x eps 1e-2-1e-6.
  The reference is checked out from this repository's history into a temporary folder (``git
  worktree``) and solved in a process of its own with its own numba cache; each scene is solved
  ``REPEATS`` times on each side, alternately, and the per-scene ratio of medians is reported
  with the step, Newton and LU counts of both (the target, issue 16: at most 0.75x).
- The new physics against the classic film of this solver, same preset and scenes (eps 1e-4,
  St 10 and 30): JFO and Reynolds floors at Pi = 1e-3, Barus at beta 1, 2 and 5.

``python benchmarks/bench_versus.py [--ref COMMIT] [--quick]`` (a few minutes) writes
``benchmarks/versus.md`` (``--quick``: a smoke run into /tmp).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

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

# The worker: reads one JSON request a line ({"St", "eps", "fields"}), solves it REPEATS times and
# answers the median wall time and the counters. Runs in the checkout it is started in, so the
# same text serves the reference (whose collide takes St, eps) and this solver (which also takes
# a Physics).
_WORKER = r"""
import json, statistics, sys, time
from solver import collide
try:
    from solver import Physics
except ImportError:
    Physics = None
repeats = int(sys.argv[1])
for line in sys.stdin:
    req = json.loads(line)
    if req["fields"]:
        scene = (Physics(St=req["St"], eps=req["eps"], **req["fields"]),)
    else:
        scene = (req["St"], req["eps"])
    c = collide(*scene, accuracy="standard", save_profiles=False)  # grid, compile
    walls = []
    for _ in range(repeats):
        t = time.perf_counter()
        c = collide(*scene, accuracy="standard", save_profiles=False)
        walls.append(time.perf_counter() - t)
    print(json.dumps({"wall": statistics.median(walls), "status": c.status, "steps": c.steps,
                      "newton": c.newton_iterations, "lu": c.lu_factorizations,
                      "v_r": c.v_r}), flush=True)
"""


class Side:
    """A solver in a process of its own, answering one scene at a time."""

    def __init__(self, checkout: Path, cache: str, repeats: int):
        env = dict(os.environ, PYTHONPATH=str(checkout), NUMBA_CACHE_DIR=cache,
                   EHD_CACHE_DIR=cache, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
        self.proc = subprocess.Popen([sys.executable, "-c", _WORKER, str(repeats)], cwd=checkout,
                                     env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True)

    def solve(self, st, eps, fields=None) -> dict:
        self.proc.stdin.write(json.dumps({"St": st, "eps": eps, "fields": fields or {}}) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError("the solver process ended (see its error above)")
        return json.loads(line)

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def versus_reference(ref: str, scenes, repeats) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        old_tree = Path(tmp) / "reference"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q",
                        str(old_tree), ref], check=True)
        try:
            old = Side(old_tree, str(Path(tmp) / "cache-ref"), repeats)
            new = Side(ROOT, str(Path(tmp) / "cache-new"), repeats)
            for k, (st, eps) in enumerate(scenes):
                # alternate which side goes first, so neither always follows the other
                first, second = (old, new) if k % 2 == 0 else (new, old)
                a = first.solve(st, eps)
                b = second.solve(st, eps)
                o, n = (a, b) if first is old else (b, a)
                rows.append({"St": st, "eps": eps, "old": o, "new": n,
                             "ratio": n["wall"] / o["wall"]})
                print(f"St {st:g} eps {eps:g}: {n['wall'] * 1e3:.1f} ms against "
                      f"{o['wall'] * 1e3:.1f} ms ({rows[-1]['ratio']:.2f}x)", flush=True)
            old.close()
            new.close()
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(old_tree)], check=False)
    return rows


def physics_against_classic(scenes, repeats) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        side = Side(ROOT, str(Path(tmp) / "cache"), repeats)
        for st, eps in scenes:
            for name, fields in PHYSICS.items():
                if name == "classic":
                    continue
                classic = side.solve(st, eps)  # alternated with each variant
                other = side.solve(st, eps, fields)
                rows.append({"St": st, "eps": eps, "physics": name, "classic": classic,
                             "other": other, "ratio": other["wall"] / classic["wall"]})
                print(f"{name} St {st:g}: {rows[-1]['ratio']:.2f}x the classic film", flush=True)
        side.close()
    return rows


def report(ref, versus, physics, repeats) -> str:
    ratios = [r["ratio"] for r in versus]
    lines = [
        "# This solver against an earlier release, and its physics against its classic film",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, one scene at a time per process"
        f" (OPENBLAS_NUM_THREADS=1); median of {repeats} solves per scene and side, the two sides"
        " alternated scene by scene in one run. `python benchmarks/bench_versus.py` regenerates"
        " this file.",
        "",
        f"## Classic film, standard preset: against commit {ref}",
        "",
        f"Median ratio (this / reference) over {len(ratios)} scenes: "
        f"**{statistics.median(ratios):.2f}x** (range {min(ratios):.2f}-{max(ratios):.2f}x).",
        "",
        "| St | eps | this [ms] | reference [ms] | ratio | steps | Newton | LU | steps ref | "
        "Newton ref | LU ref |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in versus:
        o, n = r["old"], r["new"]
        lines.append(f"| {r['St']:g} | {r['eps']:g} | {n['wall'] * 1e3:.1f} | "
                     f"{o['wall'] * 1e3:.1f} | {r['ratio']:.2f} | {n['steps']} | {n['newton']} | "
                     f"{n['lu']} | {o['steps']} | {o['newton']} | {o['lu']} |")
    lines += ["", "## New physics against the classic film (standard preset)", "",
              "| physics | St | eps | time [ms] | classic [ms] | ratio | steps | Newton | LU | "
              "classic steps | classic LU |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in physics:
        c, o = r["classic"], r["other"]
        lines.append(f"| {r['physics']} | {r['St']:g} | {r['eps']:g} | {o['wall'] * 1e3:.1f} | "
                     f"{c['wall'] * 1e3:.1f} | {r['ratio']:.2f} | {o['steps']} | {o['newton']} | "
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
    parser.add_argument("--quick", action="store_true", help="two scenes, one repeat, into /tmp")
    args = parser.parse_args()
    scenes = [(st, eps) for eps in EPS for st in STOKES]
    repeats, out = REPEATS, HERE / "versus.md"
    physics_scenes = PHYSICS_SCENES
    if args.quick:
        scenes, physics_scenes, repeats = scenes[2:4], PHYSICS_SCENES[:1], 1
        out = Path(tempfile.gettempdir()) / "versus.md"
    versus = versus_reference(args.ref, scenes, repeats)
    physics = physics_against_classic(physics_scenes, repeats)
    text = report(args.ref, versus, physics, repeats)
    print(text)
    out.write_text(text)


if __name__ == "__main__":
    main()
