"""Which compiled functions make numba's reference counts in one classic collision, counted
exactly: ``bench_refcount.py`` says how much of the time they take, this says where they are.

    .venv/bin/python benchmarks/refcount_callers.py [--top 40]
    .venv/bin/python benchmarks/refcount_callers.py --scene St=2 eps=1e-2 beta=1 --out /tmp/barus.md

A child process compiles the solver afresh (an empty cache in a temporary folder: a function
loaded from the cache has no symbols to name it by, so this takes a cold compile, about a minute)
and writes the start address of every compiled function; under gdb, a breakpoint on
``NRT_incref`` and ``NRT_decref`` reads the return address at each hit while the child solves
St 10, eps 1e-4, standard once more, and each return address is named by the function that
contains it (the nearest start below it). Calls that LLVM inlined count for the function they
were inlined into. About a million hits: 5-10 minutes. Needs gdb (Debian's ``gdb`` package);
writes benchmarks/refcount_callers.md and .json (the classic scene above), or ``--out`` and the
.json beside it for another scene (``--scene``: ``Physics`` fields as ``name=value``; the Barus
counts docs/solver.md quotes are ``St=2 eps=1e-2 beta=1``). docs/solver.md, "Reference counting",
says what the counts mean.
"""

from __future__ import annotations

import argparse
import bisect
import collections
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import harness  # noqa: E402

CHILD = textwrap.dedent("""
    import json, os, signal, sys
    from numba.core.registry import CPUDispatcher
    from numba.core.runtime import nrt
    from solver import Physics, collide
    physics = Physics(**json.loads(sys.argv[2]))
    result = collide(physics, save_profiles=False)  # compiles everything it runs
    libraries = [nrt.rtsys.library]
    for name, module in list(sys.modules.items()):
        if name.startswith("solver"):
            for value in vars(module).values():
                if isinstance(value, CPUDispatcher):
                    libraries += [c.library for c in value.overloads.values()]
    starts = set()
    for library in libraries:
        for function in library._final_module.functions:
            if not function.is_declaration:
                address = library.get_pointer_to_function(function.name)
                if address:
                    starts.add((address, function.name))
    with open(sys.argv[1], "w") as out:
        for address, name in sorted(starts):
            out.write(f"{address:x} {name}\\n")
        out.write(f"# newton {result.newton_iterations}\\n")
    os.kill(os.getpid(), signal.SIGTRAP)  # gdb sets its breakpoints here
    collide(physics, save_profiles=False)
    os.kill(os.getpid(), signal.SIGTRAP)  # and writes its counts here
""")

GDB = textwrap.dedent("""
    import collections, gdb
    gdb.execute("set pagination off")
    gdb.execute("handle SIGTRAP stop nopass")
    gdb.execute("run")
    starts = {{}}
    for line in open({functions!r}):
        if not line.startswith("#"):
            address, name = line.rstrip("\\n").split(" ", 1)
            starts.setdefault(name, int(address, 16))
    counts = collections.Counter()
    class Count(gdb.Breakpoint):
        def stop(self):
            sp = int(gdb.parse_and_eval("$sp"))
            ret = int.from_bytes(gdb.selected_inferior().read_memory(sp, 8).tobytes(), "little")
            counts[(self.kind, ret)] += 1
            return False
    for kind in ("NRT_incref", "NRT_decref"):
        Count(f"*{{starts[kind]:#x}}", internal=True).kind = kind
    gdb.execute("continue")
    with open({counts!r}, "w") as out:
        for (kind, ret), n in counts.items():
            out.write(f"{{kind}} {{ret:x}} {{n}}\\n")
    gdb.execute("kill")
""")


def readable(symbol: str) -> str:
    """``solver.model.step.step_residual`` from numba's mangled name (the dotted path only)."""
    rest = symbol.removeprefix("cfunc.")
    if not rest.startswith("_ZN"):
        return rest[:60]
    rest = rest[3:].removeprefix("7cpython")
    parts = []
    while rest[:1].isdigit():
        digits = re.match(r"\d+", rest).group(0)
        parts.append(rest[len(digits):len(digits) + int(digits)])
        rest = rest[len(digits) + int(digits):]
    return ".".join(parts)


def tally(functions: Path, counts: Path):
    """Per compiled function: its increments and decrements; and the Newton iterations."""
    starts, newton = [], 0
    for line in functions.read_text().splitlines():
        if line.startswith("# newton"):
            newton = int(line.split()[-1])
        else:
            address, name = line.split(" ", 1)
            starts.append((int(address, 16), readable(name)))
    starts.sort()
    addresses = [a for a, _ in starts]
    per = collections.defaultdict(lambda: [0, 0])
    for line in counts.read_text().splitlines():
        kind, ret, n = line.split()
        i = bisect.bisect_right(addresses, int(ret, 16)) - 1
        per[starts[i][1] if i >= 0 else "?"][kind == "NRT_decref"] += int(n)
    return dict(per), newton


def report(per: dict, newton: int, top: int, meta: str, scene: str) -> str:
    total = sum(a + b for a, b in per.values())
    rows = sorted(per.items(), key=lambda kv: -sum(kv[1]))[:top]
    lines = ["# Where a collision's reference counts are made", "",
             "Generated by `benchmarks/refcount_callers.py` (every `NRT_incref` and `NRT_decref` "
             f"of one collision, {scene}, standard, named by the compiled function "
             f"that called it). {meta}", "",
             f"{total} counts in all, {total / max(newton, 1):.0f} per Newton iteration "
             f"({newton} iterations).", "",
             "| function | increments | decrements | per Newton iteration |", "|---|---|---|---|"]
    for name, (inc, dec) in rows:
        lines.append(f"| `{name}` | {inc} | {dec} | {(inc + dec) / max(newton, 1):.1f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--top", type=int, default=40, help="functions listed (default 40)")
    harness.add_scene_options(p, HERE / "refcount_callers.md")
    args = p.parse_args(argv)
    if args.top < 1:
        p.error(f"--top {args.top}: list at least one function")
    fields, report_path = harness.scene_options(p, args, HERE / "refcount_callers.md")
    if shutil.which("gdb") is None:
        print("refcount_callers: needs gdb (apt-get install gdb)", file=sys.stderr)
        return 2
    load_start = harness.load_now()
    with tempfile.TemporaryDirectory(prefix="ehd-refcount-") as tmp:
        folder = Path(tmp)
        functions, counts = folder / "functions.txt", folder / "counts.txt"
        (folder / "child.py").write_text(CHILD)
        (folder / "count.py").write_text(GDB.format(functions=str(functions),
                                                    counts=str(counts)))
        env = {**os.environ, "EHD_CACHE_DIR": str(folder / "cache"), "OPENBLAS_NUM_THREADS": "1",
               "PYTHONPATH": str(HERE.parent)}
        log = folder / "gdb.log"
        with log.open("w") as out:
            done = subprocess.run(["gdb", "-batch", "-x", str(folder / "count.py"), "--args",
                                   sys.executable, str(folder / "child.py"), str(functions),
                                   json.dumps(fields)],
                                  env=env, stdout=out, stderr=subprocess.STDOUT)
        if not counts.exists():  # the child failed before its second stop, or gdb could not run
            last = log.read_text().strip().splitlines()[-1:] or ["no output"]
            print(f"refcount_callers: the counted run did not finish (gdb exit {done.returncode}, "
                  f"its last line: {last[0]}); nothing written", file=sys.stderr)
            return 1
        per, newton = tally(functions, counts)
    data = harness.write_json(report_path.with_suffix(".json"),
                              {"scene": fields, "newton_iterations": newton,
                               "counts": {k: {"increments": a, "decrements": b}
                                          for k, (a, b) in per.items()}}, load_start)
    harness.save_report(str(report_path), report(per, newton, args.top, harness.describe(data),
                                         harness.describe_scene(fields)))
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        print("refcount_callers: interrupted; nothing written", file=sys.stderr)
        sys.exit(130)
