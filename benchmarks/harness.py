"""The one harness of the speed benchmarks: timing, alternation, medians and spreads of per-round
ratios, a solver in a process of its own per checkout, and the one JSON writer.

Why a small module and not asv: asv builds an environment per measured commit (a venv with
numpy, scipy, numba, xarray, zarr... installed from the network, then a numba compile per
commit), which on this 2-core machine shared with other work costs more than the benchmarks
themselves, and its runs time each commit separately, so the load of the machine falls on the
two sides of a comparison at different times. Here both sides run in one process tree, in
rounds: each round measures every side once, in a rotated order, and a comparison is the median
of the per-round ratios with the spread of those ratios (a ratio whose rounds spread 0.5-1.8
is noise, not a result). The baseline is another checkout of this repository (``git worktree``)
run with this venv's packages.

Every result file written through :func:`write_json` carries, at its top level, ``solver_version``,
``commit`` (``git rev-parse HEAD``) and ``dirty`` (uncommitted changes in the measured code),
``machine``, ``load`` (``os.getloadavg()`` at the start and the end) and ``date``.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import math
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
# one scene per core, as in the sweeps and make (docs/solver.md): threaded BLAS only slows the
# small dense solves; set before any script imports numpy
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
SCHEMA = 1  # of the provenance keys below; add keys, never rename
# the code a measurement depends on: a change here (uncommitted) marks the result "dirty"
MEASURED_CODE = ("solver", "pipeline", "benchmarks/*.py", "setup.py", "pyproject.toml")
NOT_RECORDED = "not recorded"


# ---------------------------------------------------------------------------------- provenance

def _git(*args: str, repo: Path = REPO) -> str:
    out = subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True)
    return out.stdout.strip() if out.returncode == 0 else ""


def commit_of(repo: Path = REPO) -> tuple[str, bool]:
    """The commit checked out in ``repo`` and whether the measured code differs from it."""
    dirty = _git("status", "--porcelain", "--untracked-files=no", "--", *MEASURED_CODE, repo=repo)
    return _git("rev-parse", "HEAD", repo=repo) or NOT_RECORDED, bool(dirty)


_VERSION = re.compile(r'^SOLVER_VERSION\s*=\s*"([^"]+)"', re.M)


def resolve_commit(ref: str, repo: Path = REPO) -> str:
    """The full hash of ``ref`` ('' when it names no commit of this repository)."""
    return _git("rev-parse", "--verify", "-q", f"{ref}^{{commit}}", repo=repo)


def solver_version(repo: Path = REPO, commit: str | None = None) -> str:
    """SOLVER_VERSION of the checkout in ``repo`` (read from the source, not imported: no numba),
    or of ``commit`` in its history (the constant lived in solver/collision.py before
    solver/result.py)."""
    if commit is None:
        texts = [p.read_text() for p in sorted((repo / "solver").glob("*.py"))]
    else:
        texts = [_git("grep", "-h", "SOLVER_VERSION = ", commit, "--", "solver", repo=repo)]
    for text in texts:
        if m := _VERSION.search(text):
            return m.group(1)
    return NOT_RECORDED


def machine() -> dict:
    return {"system": platform.system(), "machine": platform.machine(),
            "processor": platform.processor() or platform.machine(), "cores": os.cpu_count(),
            "cpu": cpu(), "python": platform.python_version(),
            "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "unset")}


# the instruction sets numba's code generation for the host CPU can use: the solver's last bits
# may differ between machines that differ in them (fused multiply-add, vector width)
_CPU_FLAGS = ("avx", "avx2", "fma", "avx512f")


def cpu() -> str:
    """The CPU's model name and which of ``_CPU_FLAGS`` it has (Linux: /proc/cpuinfo), else
    ``platform.processor()``."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor() or "unknown"
    fields = {}  # the first processor's lines, "key : value"
    for line in text.splitlines():
        key, _, value = line.partition(":")
        fields.setdefault(key.strip(), value.strip())
    model = fields.get("model name") or platform.processor() or "unknown"
    present = [f for f in _CPU_FLAGS if f in fields.get("flags", "").split()]
    return f"{model} ({' '.join(present) or 'none of ' + ' '.join(_CPU_FLAGS)})"


CLASSIC_SCENE = {"St": 10.0, "eps": 1e-4}  # issue 30's profile: the classic film, St 10, eps 1e-4


def scene_fields(items: Sequence[str]) -> dict:
    """``Physics`` fields from ``name=value`` words (a profiling script's ``--scene``), numbers
    where they read as one, over ``CLASSIC_SCENE``."""
    fields = dict(CLASSIC_SCENE)
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise ValueError(f"--scene {item!r}: write each field as name=value, e.g. beta=1")
        try:
            fields[name] = float(value)
        except ValueError:
            fields[name] = value
    return fields


def add_scene_options(parser, default_report: Path) -> None:
    """A profiling script's ``--scene NAME=VALUE ...`` and ``--out FILE`` (``scene_options``)."""
    parser.add_argument("--scene", nargs="+", default=[], metavar="NAME=VALUE",
                        help="Physics fields of the scene (default St=10 eps=1e-4, the classic "
                             "film)")
    parser.add_argument("--out", type=Path, default=None,
                        help=f"the report (the JSON beside it; default "
                             f"benchmarks/{default_report.name}, the default scene only)")


def scene_options(parser, args, default_report: Path) -> tuple[dict, Path]:
    """The scene's fields and the report's path from ``add_scene_options``' options; one line
    through ``parser.error`` for a malformed field, one ``Physics`` refuses (checked here, not
    in the child process that solves the scene), another scene without ``--out`` (the default
    report holds the classic scene) or an ``--out`` whose folder does not exist."""
    from solver import Physics

    try:
        fields = scene_fields(args.scene)
    except ValueError as exc:
        parser.error(str(exc))
    try:
        Physics(**fields)
    except (TypeError, ValueError) as exc:
        parser.error(f"--scene: {exc}")
    report_path = args.out
    if report_path is None:
        if fields != CLASSIC_SCENE:
            parser.error(f"--scene other than the default needs --out "
                         f"(benchmarks/{default_report.name} holds the classic scene)")
        report_path = default_report
    if not report_path.parent.is_dir():
        parser.error(f"--out {report_path}: no folder {report_path.parent}")
    return fields, report_path


def describe_scene(fields: dict) -> str:
    """``St 10, eps 0.0001, the classic film``, or with the fields beyond St and eps."""
    rest = ", ".join(f"{k} {v:g}" if isinstance(v, float) else f"{k} {v}"
                     for k, v in fields.items() if k not in ("St", "eps"))
    return (f"St {fields['St']:g}, eps {fields['eps']:g}, " + (rest or "the classic film"))


def load_now() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


# the checkout as the measuring script started: edits or commits made while it runs are not what
# it measured
_AT_START: dict[Path, tuple[str, bool]] = {}


def _started(repo: Path) -> tuple[str, bool]:
    if repo not in _AT_START:
        _AT_START[repo] = commit_of(repo)
    return _AT_START[repo]


_started(REPO)


def provenance(load_start: list[float], repo: Path = REPO) -> dict:
    """The keys every result file carries; ``load_start`` is :func:`load_now` at the start;
    ``commit`` and ``dirty`` are the checkout's when this module was imported."""
    commit, dirty = _started(repo)
    return {"solver_version": solver_version(repo), "commit": commit, "dirty": dirty,
            "machine": machine(), "load": {"start": load_start, "end": load_now()},
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "harness_schema": SCHEMA}


def historical_provenance(path: Path, repo: Path = REPO) -> dict:
    """What is known of a result file not measured again: the commit that last wrote it and the
    solver version at that commit; machine and load were not recorded."""
    commit = _git("log", "-1", "--format=%H", "--", str(path), repo=repo) or NOT_RECORDED
    date = _git("log", "-1", "--format=%cI", "--", str(path), repo=repo) or NOT_RECORDED
    return {"solver_version": solver_version(repo, commit) if commit != NOT_RECORDED
            else NOT_RECORDED, "commit": commit, "dirty": NOT_RECORDED,
            "machine": NOT_RECORDED, "load": NOT_RECORDED, "date": date,
            "harness_schema": SCHEMA}


def write_json(path: Path, payload: dict, load_start: list[float], default=None) -> dict:
    """Write ``payload`` with the provenance keys added at its top level (the payload's own keys
    and layout stay as they are; a payload key of the same name wins). ``default``: as for
    ``json.dumps``."""
    doc = {**payload, **{k: v for k, v in provenance(load_start).items() if k not in payload}}
    Path(path).write_text(json.dumps(doc, indent=1, default=default) + "\n")
    return doc


def save_results(out: str, payload: dict, load_start: list[float]) -> dict:
    """A benchmark's results with their provenance: written to ``out`` with the suffix ``.json``
    (``write_json``), or only returned when ``out`` is ``-`` (standard output)."""
    if out == "-":
        return {**payload, **{k: v for k, v in provenance(load_start).items() if k not in payload}}
    return write_json(Path(out).with_suffix(".json"), payload, load_start)


def save_report(out: str, text: str) -> None:
    """A benchmark's Markdown report: printed, and written to ``out`` unless it is ``-``."""
    print(text)
    if out != "-":
        Path(out).write_text(text)


def describe(doc: dict) -> str:
    """One line naming where a result came from, for the Markdown reports."""
    commit = doc.get("commit", NOT_RECORDED)
    short = commit[:7] if commit != NOT_RECORDED else commit
    load = doc.get("load")
    load_text = (f"load average {load['start'][0]:.1f} at the start, {load['end'][0]:.1f} at the "
                 "end" if isinstance(load, dict) else "load not recorded")
    m = doc.get("machine")
    where = (f"{m['cores']} cores ({m['machine']}{', ' + m['cpu'] if m.get('cpu') else ''}), "
             f"OPENBLAS_NUM_THREADS={m['blas_threads']}" if isinstance(m, dict)
             else "machine not recorded")
    text = (f"solver {doc.get('solver_version', NOT_RECORDED)}, commit {short}"
            f"{' with uncommitted changes' if doc.get('dirty') is True else ''}, {doc.get('date')}, "
            f"{where}, {load_text}")
    if doc.get("pinned_core") is not None:
        text += (f", the two solver processes pinned together to core {doc['pinned_core']} "
                 "(they take turns on it)")
    if isinstance(load, dict) and isinstance(m, dict) and shared(load, m["cores"]):
        text += (" (a shared machine: absolute times here are longer than on an idle one; the "
                 "results are the ratios measured within this run)")
    return text


def shared(load: dict, cores: int) -> bool:
    """Whether other work held the cores: a load average above half of them at either end."""
    return max(load["start"][0], load["end"][0]) > 0.5 * cores


# ------------------------------------------------------------------------------------- timing

def _child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def time_call(fn: Callable[[], object]) -> dict:
    """Wall and CPU (this process) seconds of one call."""
    wall, cpu = time.perf_counter(), time.process_time()
    fn()
    return {"wall_s": time.perf_counter() - wall, "cpu_s": time.process_time() - cpu}


def time_process(cmd: Sequence[str], env: dict | None = None, cwd: Path = REPO,
                 ok: Sequence[int] = (0,)) -> dict:
    """Wall and CPU (user + system of the child) seconds of one run of ``cmd``; a failing run
    raises (a benchmark of a broken command measures nothing)."""
    cpu, wall = _child_cpu(), time.perf_counter()
    proc = subprocess.run(list(map(str, cmd)), cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - wall
    if proc.returncode not in ok:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({proc.returncode}):\n"
                           f"{proc.stderr[-2000:]}")
    return {"wall_s": wall, "cpu_s": _child_cpu() - cpu}


def rotated(labels: Sequence[str], k: int) -> list[str]:
    """``labels`` started at position ``k`` (mod their count): round k's order."""
    k %= len(labels)
    return [*labels[k:], *labels[:k]]


def alternate(sides: dict[str, Callable[[], dict]], rounds: int, warmup: int = 1
              ) -> dict[str, list[dict]]:
    """Each side measured once per round, the order rotated from round to round so that no side
    always follows another; ``warmup`` rounds first, not kept. Returns ``{side: [one dict of
    figures per round]}``."""
    labels = list(sides)
    for k in range(warmup):
        for label in rotated(labels, k):
            sides[label]()
    runs = {label: [] for label in labels}
    for k in range(rounds):
        for label in rotated(labels, k):
            runs[label].append(sides[label]())
    return runs


# ---------------------------------------------------------------------------------- statistics

def cell(x, spec: str = ".3f") -> str:
    """A number for a markdown table: ``format(x, spec)``, or "-" for None or non-finite."""
    return "-" if x is None or not math.isfinite(x) else format(x, spec)


def spread(values: Sequence[float]) -> dict:
    """Median, smallest and largest value, and how many."""
    values = [float(v) for v in values]
    return {"median": statistics.median(values), "min": min(values), "max": max(values),
            "n": len(values)}


def round_ratios(this: Sequence[float], base: Sequence[float]) -> list[float]:
    """Per-round ratios this / base (round k of one against round k of the other)."""
    if len(this) != len(base):
        raise ValueError(f"{len(this)} rounds against {len(base)}: not alternated in one run")
    return [a / b for a, b in zip(this, base)]


def compare(this: Sequence[float], base: Sequence[float]) -> dict:
    """Both sides' spreads and the spread of their per-round ratios, with the verdict."""
    ratios = round_ratios(this, base)
    ratio = spread(ratios)
    return {"this": spread(this), "baseline": spread(base),
            "ratio": {**ratio, "rounds": ratios}, "moved": moved(ratio)}


# A figure moved when every round's ratio lies on the same side of 1 (with 7 rounds, a chance
# of 2 in 128 for a change that is not there) and the median ratio is off 1 by more than
# TOLERANCE (identical code measures a few per cent apart: where it sits in memory and on disk).
TOLERANCE = 0.03
MIN_ROUNDS = 5


def moved(ratio: dict, tolerance: float = TOLERANCE, min_rounds: int = MIN_ROUNDS) -> str:
    """"slower" / "faster" when every round's ratio lies on the same side of 1 and their median
    is off 1 by more than ``tolerance``; "no" when the change is within the spread the rounds
    measured (or smaller than ``tolerance``); "too few rounds" below ``min_rounds``."""
    if ratio["n"] < min_rounds:
        return "too few rounds"
    if ratio["min"] > 1.0 and ratio["median"] > 1.0 + tolerance:
        return "slower"
    if ratio["max"] < 1.0 and ratio["median"] < 1.0 - tolerance:
        return "faster"
    return "no"


def figure_rows(figures: dict[str, dict], unit_scale: float = 1e3, unit: str = "ms") -> list[str]:
    """The Markdown table of compared figures, ``{name: {"cpu_s": compare(...), "wall_s":
    compare(...)}}``: the verdict on CPU time (on a shared machine the wall time of a round
    depends on what else runs: context, not a result), the wall time's ratios beside it."""
    rows = [f"| figure | this CPU [{unit}] | baseline CPU [{unit}] | CPU ratio | rounds' CPU "
            "ratios | moved | wall ratio | rounds' wall ratios | rounds |",
            "|---|---:|---:|---:|---|---|---:|---|---:|"]

    def verdict(f):
        return f"**{f['moved']}**" if f["moved"] in ("slower", "faster") else f["moved"]

    for name, f in figures.items():
        c, w = f["cpu_s"], f["wall_s"]
        rows.append(f"| {name} | {c['this']['median'] * unit_scale:.4g} | "
                    f"{c['baseline']['median'] * unit_scale:.4g} | {c['ratio']['median']:.2f} | "
                    f"{c['ratio']['min']:.2f}-{c['ratio']['max']:.2f} | {verdict(c)} | "
                    f"{w['ratio']['median']:.2f} | {w['ratio']['min']:.2f}-{w['ratio']['max']:.2f}"
                    f" | {c['ratio']['n']} |")
    return rows


def compare_runs(this: list[dict], base: list[dict], metrics=("cpu_s", "wall_s")) -> dict:
    """:func:`compare` per metric of two sides' rounds (lists of ``{metric: seconds}``)."""
    return {m: compare([r[m] for r in this], [r[m] for r in base]) for m in metrics}


# ------------------------------------------------------------------------------------ checkouts

def bench_folder() -> Path:
    """Where the speed suite keeps its checkouts, stores and compiled kernels between runs, so
    that a second run compiles and builds only what changed: ``<cache root>/numba/bench-suite``
    (the documented cache root, docs/solver.md; ``make clean-cache`` removes it)."""
    from solver._jit import cache_root

    return cache_root() / "numba" / "bench-suite"


def export_commit(sha: str, dest: Path, repo: Path = REPO) -> Path:
    """The tree of commit ``sha`` in ``dest`` (``git archive``: every file stamped with the
    commit's time, so the numba cache of an earlier export stays valid); kept if already there."""
    done = dest / ".exported"
    if done.exists():
        return dest
    shutil.rmtree(dest, ignore_errors=True)
    dest.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(repo), "archive", sha], capture_output=True,
                             check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    done.write_text(sha + "\n")
    return dest


def sync_worktree(dest: Path, repo: Path = REPO) -> Path:
    """This checkout as it is (committed or not, untracked files that git does not ignore
    included) mirrored into ``dest``, time stamps kept: measured from a folder like the
    baseline's, and an unchanged file keeps the numba cache of an earlier run valid."""
    files = subprocess.run(["git", "-C", str(repo), "ls-files", "-z", "--cached", "--others",
                            "--exclude-standard"], capture_output=True, check=True).stdout
    wanted = {name for name in files.decode().split("\0") if name and (repo / name).is_file()}
    for name in wanted:
        src, dst = repo / name, dest / name
        st = src.stat()
        if dst.exists() and (dst.stat().st_size, dst.stat().st_mtime_ns) == (st.st_size,
                                                                             st.st_mtime_ns):
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dst)
    for path in [p for p in dest.rglob("*") if p.is_file()]:
        rel = path.relative_to(dest).as_posix()
        if rel not in wanted and "__pycache__" not in path.parts:
            path.unlink()
    return dest


@contextlib.contextmanager
def checkout(ref: str, repo: Path = REPO) -> Iterator[Path]:
    """The commit ``ref`` of this repository checked out in a temporary folder (``git worktree
    add --detach``), removed on exit."""
    with tempfile.TemporaryDirectory(prefix="ehd-bench-ref-") as tmp:
        tree = Path(tmp) / "tree"
        subprocess.run(["git", "-C", str(repo), "worktree", "add", "--detach", "-q", str(tree),
                        ref], check=True)
        try:
            yield tree
        finally:
            subprocess.run(["git", "-C", str(repo), "worktree", "remove", "--force", str(tree)],
                           check=False)


def source_env(checkout_dir: Path, env: dict | None = None) -> dict:
    """The environment that makes this venv's Python import ``solver`` and ``pipeline`` from
    ``checkout_dir``: PYTHONPATH first (the editable install's finder comes after it)."""
    import sysconfig

    return dict(env if env is not None else os.environ,
                PYTHONPATH=os.pathsep.join([str(Path(checkout_dir).resolve()),
                                            sysconfig.get_paths()["purelib"]]),
                OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")


def cli_launch(checkout_dir: Path, env: dict | None = None) -> tuple[list[str], dict]:
    """``ehd`` of ``checkout_dir`` as ``python -S -P -m pipeline.cli`` with this venv's packages
    (-S: no .pth files, whose editable install would shadow it; -P: nor the working folder)."""
    return [sys.executable, "-S", "-P", "-m", "pipeline.cli"], source_env(checkout_dir, env)


# A solver worker: reads one JSON request a line ({"St", "eps", "fields", "accuracy",
# "repeats"}), solves it once untimed (grid, compile) the first time it sees the scene, then
# "repeats" times, and answers each solve's wall and CPU time and the last solve's counters
# ({"error": ...} when this checkout cannot solve the scene).
# Checkouts without Physics (solver <= 1.2) take (St, eps) and no fields.
_WORKER = r"""
import json, sys, time
import solver
from solver import collide
try:
    from solver import Physics
except ImportError:
    Physics = None
print(json.dumps({"solver_file": solver.__file__}), flush=True)
seen = set()
for line in sys.stdin:
    req = json.loads(line)
    try:
        if req["fields"] and Physics is None:
            raise TypeError("this solver takes St and eps only (no solver.Physics)")
        if req["fields"]:
            scene = (Physics(St=req["St"], eps=req["eps"], **req["fields"]),)
        else:
            scene = (req["St"], req["eps"])
        kw = dict(accuracy=req["accuracy"], save_profiles=False)
        if line not in seen:
            seen.add(line)
            c = collide(*scene, **kw)
    except Exception as exc:  # e.g. an older solver without this physics
        print(json.dumps({"error": f"{type(exc).__name__}: {exc}"}), flush=True)
        continue
    walls, cpus = [], []
    for _ in range(req["repeats"]):
        t, cpu = time.perf_counter(), time.process_time()
        c = collide(*scene, **kw)
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - cpu)
    out = {"wall_s": walls, "cpu_s": cpus, "status": c.status, "steps": c.steps,
           "newton": c.newton_iterations, "lu": c.lu_factorizations, "v_r": c.v_r}
    for k in ("rejected_steps", "e_wet"):
        out[k] = getattr(c, k, None)
    print(json.dumps(out), flush=True)
"""


class SolverProcess:
    """The solver of one checkout in a process of its own, answering one scene at a time.
    ``cache``: the numba cache folder (None: the documented default, which this checkout's
    kernels share with every earlier run)."""

    def __init__(self, checkout_dir: Path, cache: str | None = None):
        env = source_env(checkout_dir)
        if cache is not None:
            env.update(NUMBA_CACHE_DIR=cache, EHD_CACHE_DIR=cache)
        self.checkout = Path(checkout_dir).resolve()
        self.proc = subprocess.Popen([sys.executable, "-c", _WORKER], cwd=self.checkout,
                                     env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True)
        hello = self._answer()
        if not Path(hello["solver_file"]).resolve().is_relative_to(self.checkout):
            self.close()
            raise RuntimeError(f"the worker of {self.checkout} imported {hello['solver_file']}")

    def _answer(self) -> dict:
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"the solver process of {self.checkout} ended (its error above)")
        return json.loads(line)

    def submit(self, st: float, eps: float, fields: dict | None = None,
               accuracy: str = "standard", repeats: int = 1) -> None:
        """Send a scene without waiting (read its answer with :meth:`answer`): several
        processes then compile, or solve, at once."""
        try:
            self.proc.stdin.write(json.dumps({"St": st, "eps": eps, "fields": fields or {},
                                              "accuracy": accuracy, "repeats": repeats}) + "\n")
            self.proc.stdin.flush()
        except BrokenPipeError:
            raise RuntimeError(f"the solver process of {self.checkout} ended (its error above)")

    def answer(self) -> dict:
        return self._answer()

    def solve(self, st: float, eps: float, fields: dict | None = None,
              accuracy: str = "standard", repeats: int = 1) -> dict:
        self.submit(st, eps, fields, accuracy, repeats)
        return self._answer()

    def close(self) -> None:
        if self.proc.stdin and not self.proc.stdin.closed:
            self.proc.stdin.close()
        self.proc.wait()

    def __enter__(self):
        return self

    @staticmethod
    def pin_together(processes) -> int | None:
        """Pin every process to one core, the highest this one may run on, where they take
        turns: a round's two solves then run on the same core, and whatever else the machine
        runs slows both alike. Returns the core, or None where the system cannot pin (no
        ``os.sched_setaffinity``). With the other core of a 2-core host busy, the same code on
        both sides read 0.98-1.01 pinned (per-scene medians of 15 pairs) where its unpinned
        rounds spread 0.7-1.4 (benchmarks/README.md)."""
        if not hasattr(os, "sched_setaffinity"):
            return None
        core = max(os.sched_getaffinity(0))
        for p in processes:
            os.sched_setaffinity(p.proc.pid, {core})
        return core

    @staticmethod
    def compile_all(processes) -> None:
        """One untimed fast solve in each process, sent to all before waiting for any: their
        compilations (or cache loads) run at once."""
        processes = list(processes)
        for p in processes:
            p.submit(5.0, 1e-2, accuracy="fast", repeats=0)
        for p in processes:
            p.answer()

    def __exit__(self, *exc):
        self.close()


def stamp_historical(path: Path, repo: Path = REPO) -> bool:
    """Add :func:`historical_provenance` to a result file that lacks it (its other keys, their
    order and its layout unchanged); False when it already names its commit."""
    path = Path(path)
    text = path.read_text()
    doc = json.loads(text)
    if "commit" in doc:
        return False
    known = historical_provenance(path, repo)
    known["provenance"] = ("not measured again: the commit that last wrote this file (git log) "
                           "and the solver version at that commit")
    doc.update({k: v for k, v in known.items() if k not in doc})
    path.write_text(json.dumps(doc, indent=1) + ("\n" if text.endswith("\n") else ""))
    return True


def main(argv=None) -> int:
    import argparse

    p = argparse.ArgumentParser(description="benchmarks/harness.py: the shared benchmark harness")
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("stamp", help="add the provenance git knows to result files lacking it")
    s.add_argument("files", nargs="+")
    args = p.parse_args(argv)
    for f in args.files:
        print(f"{f}: {'stamped' if stamp_historical(Path(f)) else 'already names its commit'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
