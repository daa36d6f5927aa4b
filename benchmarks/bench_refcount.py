"""Where a collision's CPU time goes, by perf samples: numba's runtime reference counting
(``NRT_incref``/``NRT_decref``) and allocation, BLAS/LAPACK, the compiled model code, the
interpreter (issue 30: the reference counting and allocation under 5 % of a collision).

    .venv/bin/python benchmarks/bench_refcount.py [--seconds 8] [--rounds 3]
    .venv/bin/python benchmarks/bench_refcount.py --scene beta=1 --out /tmp/barus.md
    .venv/bin/python benchmarks/bench_refcount.py --functions --rounds 1 --out /tmp/profile.md

A child process solves the same classic collision (St 10, eps 1e-4, standard, the issue's
profile) in a loop from the warm cache; ``perf record`` samples it for ``--seconds`` per round,
after the warm-up. Compiled code is outside perf's view, so the child writes the addresses of
numba's runtime functions and of every function the solver's compiled code defines in perf's map
file (``/tmp/perf-PID.map``): that is how the samples in ``NRT_incref``/``NRT_decref`` get their
names, and those in an entry's own copies of them (``NRT_incref.<digest>``, solver/_jit.py;
before this map named them, from solver 1.15.2 on, this benchmark read 0 % of reference
counting, which a run found to be 4.2 %). Needs Linux ``perf`` with access to
one's own processes (``kernel.perf_event_paranoid <= 2``); writes benchmarks/refcount.json and
refcount.md (the classic scene), or ``--out`` and the .json beside it for another scene
(``--scene``: ``Physics`` fields as ``name=value`` over St 10, eps 1e-4). The shares are of the
child's samples, each round's, then their median and range. ``--functions`` adds each
function's share (from the warm cache too: a loaded entry names its functions, its own copies of
those it links in with them; until solver 1.15.2 this took a cold compile per round); that is
how the in-step extremum's bisection was found to take a fifth of a classic collision
(docs/solver.md, Versions, 1.12.2).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import harness  # noqa: E402

CHILD = textwrap.dedent("""
    import os, sys
    import json, signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is the parent's: it kills this child
    from solver import Physics, collide
    physics = Physics(**json.loads(sys.argv[2]))
    collide(physics, save_profiles=False)  # the cache loaded, the scene warm
    import gc
    from numba.core.registry import CPUDispatcher
    from numba.core.runtime import nrt
    libraries = [nrt.rtsys.library] + [r.library for d in gc.get_objects()
                                       if isinstance(d, CPUDispatcher)
                                       for r in d.overloads.values()]
    found = set()
    for library in libraries:
        # a library loaded from the cache defines its functions in its module for linking
        module = library._final_module
        if not any(not f.is_declaration for f in module.functions):
            module = getattr(library, "_shared_module", None) or module
        for f in module.functions:
            if not f.is_declaration:
                found.add((library.get_pointer_to_function(f.name), f.name))
    found = sorted((a, name) for a, name in found if a)
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as out:  # each up to the next one, <= 4 MiB
        for (a, name), (b, _) in zip(found, found[1:] + [(found[-1][0] + 64, "")]):
            out.write(f"{a:x} {min(b - a, 1 << 22):x} {name}\\n")
    print("ready", flush=True)
    n = 0
    while not os.path.exists(sys.argv[1]):
        collide(physics, save_profiles=False)
        n += 1
    print(n, flush=True)
""")

# a sample's kind, from its symbol and its shared object (first match wins)
KINDS = (
    # NRT_incref / NRT_decref and the atomic add and subtract they are made of
    # (an entry's own copies carry a suffix: NRT_incref.<digest>, solver/_jit.py)
    ("reference counting", lambda sym, dso: sym.split(".")[0] in ("NRT_incref", "NRT_decref",
                                                                  "nrt_atomic_add",
                                                                  "nrt_atomic_sub")),
    ("allocation", lambda sym, dso: sym.startswith(("NRT_MemInfo", "NRT_Allocate", "NRT_Free",
                                                   "nrt_internal", "NRT_dealloc"))
     or sym in ("malloc", "free", "cfree", "_int_malloc", "_int_free", "unlink_chunk.constprop.0",
                "malloc_consolidate", "_int_free_merge_chunk", "_int_free_create_chunk")),
    ("BLAS/LAPACK", lambda sym, dso: "openblas" in dso or "lapack" in dso or "blas" in dso),
    ("Python", lambda sym, dso: "python" in dso or sym.startswith(("_Py", "Py"))),
    ("compiled model code", lambda sym, dso: dso.startswith(("[JIT]", "[unknown]", "perf-",
                                                            "//anon")) or sym.startswith("0x")),
)
# share, shared object, symbol (its first word: perf pads the column to the longest symbol, and
# numba's mangled names run to thousands of characters)
LINE = re.compile(r"^\s*([\d.]+)%\s+(.+?)\s+\[\.\]\s+(\S+)")
TOP_FUNCTIONS = 30  # rows of the by-function table


def _samples(report: str):
    """``(share [%], shared object, symbol)`` of each line of a ``perf report --sort dso,symbol``
    listing."""
    for line in report.splitlines():
        m = LINE.match(line)
        if m:
            yield float(m.group(1)), m.group(2), m.group(3)


def shares(report: str) -> dict:
    """The shares [%] of each kind in a ``perf report --sort dso,symbol`` listing."""
    out = {kind: 0.0 for kind, _ in KINDS} | {"other": 0.0}
    for pct, dso, sym in _samples(report):
        out[next((k for k, test in KINDS if test(sym, dso)), "other")] += pct
    return out


def function_name(symbol: str) -> str:
    """A compiled function's dotted name from numba's mangled symbol (``_ZN6solver11integration7
    stepper6_basisB4v226...`` is ``solver.integration.stepper._basis``: the length-prefixed parts
    after ``_ZN``, up to the ABI tags and argument types); any other symbol as it is."""
    if not symbol.startswith("_ZN"):
        return symbol
    parts, i = [], 3
    while i < len(symbol) and symbol[i].isdigit():
        j = i
        while j < len(symbol) and symbol[j].isdigit():
            j += 1
        size = int(symbol[i:j])
        parts.append(symbol[j:j + size])
        i = j + size
    return ".".join(parts) or symbol


def by_function(report: str, floor: float = 0.2) -> dict:
    """The shares [%] of each function in a ``perf report`` listing (its specialisations
    summed), those of at least ``floor``."""
    out: dict[str, float] = {}
    for pct, _, sym in _samples(report):
        name = function_name(sym)
        out[name] = out.get(name, 0.0) + pct
    return {name: pct for name, pct in out.items() if pct >= floor}


def one_round(seconds: float, folder: Path, fields: dict, functions: bool = False) -> dict:
    """One child solving the scene ``fields`` sampled for ``seconds``: its shares and its
    collisions' count; with ``functions``, also each function's share (``by_function``)."""
    stop, data = folder / "stop", folder / "perf.data"
    stop.unlink(missing_ok=True)
    env = {**os.environ, "PYTHONPATH": str(harness.REPO)}
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(stop), json.dumps(fields)],
                             stdout=subprocess.PIPE, text=True, cwd=harness.REPO, env=env)
    try:
        if child.stdout.readline().strip() != "ready":
            raise RuntimeError("the child did not start")
        subprocess.run(["perf", "record", "-q", "-F", "2000", "-p", str(child.pid), "-o",
                        str(data), "--", "sleep", str(seconds)], check=True,
                       stderr=subprocess.DEVNULL)
        stop.touch()
        collisions = int(child.stdout.readline())
        child.wait(timeout=60)
        report = subprocess.run(["perf", "report", "-i", str(data), "--no-children", "--stdio",
                                 "--sort", "dso,symbol", "--percent-limit", "0", "-g", "none"],
                                capture_output=True, text=True, check=True).stdout
    finally:
        if child.poll() is None:
            child.kill()
        Path(f"/tmp/perf-{child.pid}.map").unlink(missing_ok=True)
    out = {"shares": shares(report), "collisions": collisions}
    if functions:
        out["functions"] = by_function(report)
    return out


def report(data: dict) -> str:
    kinds = list(data["rounds"][0]["shares"])
    lines = ["# Where a collision's CPU time goes", "",
             "Generated by `benchmarks/bench_refcount.py` (perf samples of a child process "
             f"solving {harness.describe_scene(data.get('scene', harness.CLASSIC_SCENE))}, "
             "standard, from the warm cache; "
             f"{len(data['rounds'])} rounds of {data['seconds']:g} s). " + harness.describe(data),
             "", "| kind | share of the samples, median | rounds |", "|---|---|---|"]
    for kind in kinds:
        values = [r["shares"][kind] for r in data["rounds"]]
        lines.append(f"| {kind} | {statistics.median(values):.1f} % | "
                     f"{min(values):.1f}-{max(values):.1f} % |")
    if "functions" in data["rounds"][0]:
        lines += ["", "By function (`--functions`: each compiled function by its name, an "
                  "entry's own copies of the functions it links in by theirs; a function LLVM "
                  "inlined counts for its caller; BLAS's and the interpreter's by their symbols; "
                  "at least 0.2 % in a round):", "",
                  "| function | share, median | rounds |", "|---|---|---|"]
        names = {n for r in data["rounds"] for n in r["functions"]}
        per_round = {n: [r["functions"].get(n, 0.0) for r in data["rounds"]] for n in names}
        medians = {n: statistics.median(values) for n, values in per_round.items()}
        for name in sorted(per_round, key=lambda n: (-medians[n], n))[:TOP_FUNCTIONS]:
            values = per_round[name]
            lines.append(f"| `{name}` | {medians[name]:.1f} % | "
                         f"{min(values):.1f}-{max(values):.1f} % |")
    target = [r["shares"]["reference counting"] + r["shares"]["allocation"] for r in data["rounds"]]
    lines += ["", f"Reference counting and allocation together: {statistics.median(target):.1f} % "
              f"(rounds {min(target):.1f}-{max(target):.1f} %); issue 30's target is under 5 %. "
              "`allocation` counts every malloc and free in the process, the interpreter's too."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=8.0, help="sampling per round (default 8)")
    p.add_argument("--rounds", type=int, default=3, help="rounds (default 3)")
    p.add_argument("--functions", action="store_true",
                   help="also each compiled function's share (a cold compile per round)")
    harness.add_scene_options(p, HERE / "refcount.md")
    args = p.parse_args(argv)
    fields, report_path = harness.scene_options(p, args, HERE / "refcount.md")
    if shutil.which("perf") is None:
        print("bench_refcount: needs Linux perf (apt-get install linux-perf)", file=sys.stderr)
        return 2
    load_start = harness.load_now()
    with tempfile.TemporaryDirectory() as tmp:
        rounds = [one_round(args.seconds, Path(tmp), fields, args.functions)
                  for _ in range(args.rounds)]
    data = harness.write_json(report_path.with_suffix(".json"),
                              {"scene": fields, "seconds": args.seconds, "rounds": rounds},
                              load_start)
    report_path.write_text(report(data))
    print(report(data))
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # one_round's child is killed on the way out
        print("bench_refcount: interrupted; nothing written", file=sys.stderr)
        sys.exit(130)
